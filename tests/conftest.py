"""Shared test settings: off-screen GL for any test that renders, no stray MuJoCo logs; studies shared by
several test files, computed once per run."""

import os

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")


@pytest.fixture(scope="session")
def small_design_study():
    """The printer head's design study on 3^4 = 81 configurations (the grid's corners and centre), with a
    9 x 9 plane and Sobol indices from N = 8 base samples: computed once per test run (per xdist worker)
    and read by tests/test_design.py, test_sobol.py and test_executor.py."""
    from springlab.studies.design import run_study

    return run_study("printer_head", levels=3, plane_levels=9, sobol=8)
