"""Shared test settings: off-screen GL for any test that renders, no stray MuJoCo logs."""

import os

import mujoco

os.environ.setdefault("MUJOCO_GL", "egl")


def _ignore_warning(message: str) -> None:
    """Tests that load a model themselves (e.g. dm_control's suite, which still uses the deprecated
    `settotalmass`) would otherwise leave MUJOCO_LOG.TXT in the working directory; springlab's own code
    routes warnings itself (springlab.sim.simulate.quiet_mujoco), and tests that count warnings use it."""


mujoco.set_mju_user_warning(_ignore_warning)
