"""The stay cable's own figure of a run (`Scene.figure`)."""

from __future__ import annotations

from springlab.scenes.capabilities.case import CaseView
from springlab.scenes.capabilities.figure import Panel
from springlab.sim.simulate import Trajectory


def panels(case: CaseView, trajectory: Trajectory) -> tuple[Panel, ...]:
    """The panels of a run of the case's scenario."""
    return ()
