"""Shared test settings: off-screen GL for any test that renders, no stray MuJoCo logs."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
