"""Shared test settings: off-screen GL for any test that renders, no stray MuJoCo logs; studies shared by
several test files, computed once per run."""

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
def small_design_study():
    """The printer head's design study on 3^4 = 81 configurations (the grid's corners and centre), with a
    9 x 9 plane and Sobol indices from N = 8 base samples: computed once per test run (per xdist worker)
    and read by tests/test_design.py, test_sobol.py and test_executor.py."""
    from springlab.studies.design import run_study

    return run_study("printer_head", levels=3, plane_levels=9, sobol=8)
