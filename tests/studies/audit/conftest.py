"""The audit tests' shared fixture."""

import importlib

import pytest


@pytest.fixture
def untimed(monkeypatch):
    """The audit's timer (about 2 s of best-of-3 runs per audit) returns one constant: it only fills the wall
    times reported beside each run, while the pick ranks counted work (on the real timer: test_audit.py's
    test_the_pick_is_the_cheapest_in_counted_work_and_no_timer_moves_it). The tests using this read no wall time."""
    module = importlib.import_module("springlab.studies.audit.audit")  # the package's `audit` attribute is the function
    monkeypatch.setattr(module, "cost_per_step", lambda model, start, name, dt: 1e-6)
