"""The audit tests' shared fixture."""

import pytest

from helpers.audit import stub_the_timer


@pytest.fixture
def untimed(monkeypatch):
    """The audit's timer returns one constant (helpers/audit.py: stub_the_timer); the test reads no wall time."""
    stub_the_timer(monkeypatch)
