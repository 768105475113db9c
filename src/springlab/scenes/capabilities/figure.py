"""The scene's own figure of a run (`Scene.figure`, drawn by springlab.plots.run.scene_figure): panels of curves."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import TypeAlias

import numpy as np

from springlab.sim.simulate import Trajectory

from .case import CaseView


@dataclasses.dataclass(frozen=True)
class Curve:
    """One curve of a declared panel.

    Attributes
    ----------
    label
        legend text.
    x, y
        the points, in the panel's units.
    kind
        'simulated' (solid), 'exact' (dashed), 'continuum' (dotted) or 'points' (markers, no line: runs at
        chosen values, e.g. simulated points on an exact curve).
    """

    label: str
    x: np.ndarray
    y: np.ndarray
    kind: str = "simulated"


@dataclasses.dataclass(frozen=True)
class Panel:
    """One panel of a scene's own figure.

    Attributes
    ----------
    title
        one line.
    xlabel, ylabel
        axis labels with units.
    curves
        what is drawn.
    marks
        vertical lines: (x, label), e.g. an exact event time.
    log_x
        a logarithmic x axis (e.g. a damper coefficient over decades).
    """

    title: str
    xlabel: str
    ylabel: str
    curves: tuple[Curve, ...]
    marks: tuple[tuple[float, str], ...] = ()
    log_x: bool = False


#: hook: (the case that ran, its trajectory) -> the panels of the run's own figure
FigureHook: TypeAlias = Callable[[CaseView, Trajectory], tuple[Panel, ...]]
