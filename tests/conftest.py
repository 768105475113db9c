"""Shared test settings: off-screen GL for any test that renders, no stray MuJoCo logs; studies that several
tests read are computed once per test session (session-scoped fixtures; their results are immutable, so
sharing them cannot couple the tests)."""

import os

import mujoco
import pytest

os.environ.setdefault("MUJOCO_GL", "egl")


def _ignore_warning(message: str) -> None:
    """Tests that load a model themselves (e.g. dm_control's suite, which still uses the deprecated
    `settotalmass`) would otherwise leave MUJOCO_LOG.TXT in the working directory; springlab's own code
    routes warnings itself (springlab.sim.simulate.quiet_mujoco), and tests that count warnings use it."""


mujoco.set_mju_user_warning(_ignore_warning)


@pytest.fixture(scope="session")
def stability_report():
    """`springlab stability`'s default report (a springlab.studies.stability.StabilityReport), computed once."""
    from springlab.studies import stability

    return stability.stability_report()


@pytest.fixture(scope="session")
def shipped_audit():
    """`audit(scene, tol=1e-3)` of a shipped scene (the demo's and the command's default tol), computed once per
    scene: call the fixture with the scene's name."""
    from springlab.studies.audit.audit import audit

    done = {}

    def get(scene):
        if scene not in done:
            done[scene] = audit(scene, tol=1e-3)
        return done[scene]

    return get
