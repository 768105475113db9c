"""Error against cost: the one panel every settings study draws (springlab.studies.settings).

`error_cost_panel` draws a study's runs on log-log axes of counted work (the cost the studies rank by, never
a timer) against error: the runs in the study's groups (by integrator, by model size, every run), the Pareto
front as black steps, the tolerance, and the marked points (the verified recommendation, a baseline). Only
valid runs are points of a group: a run beyond its integrator's stability limit is drawn as a hollow grey
circle labelled as such (it ended before its blow-up showed), and diverged runs are counted in the legend,
never drawn. The legend stands outside the axes, right of them: it can cover no point and no axis label.
springlab.plots.charts (tradeoff.png), springlab.plots.refine (refine.png) and
springlab.plots.friction_settings (friction_settings.png) call it; it never simulates.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from springlab.studies.settings import COST_UNIT, HasRun

if TYPE_CHECKING:
    from matplotlib.axes import Axes

#: drawn instead of an error of exactly 0 on a log axis [-] (NoSlip can make a creep vanish)
FLOOR = 1e-17

#: the style of a run beyond its integrator's stability limit: hollow, grey
BEYOND_STYLE: dict[str, Any] = dict(marker="o", ms=6, mfc="none", mec="0.45", mew=1.0, ls="none")


@dataclasses.dataclass(frozen=True)
class Points:
    """A group of runs drawn alike.

    Attributes
    ----------
    rows
        the study's rows (each holds a springlab.studies.settings.Run).
    label
        the legend's words (None: no entry).
    style
        matplotlib line keywords (color, marker, ms, ls ...).
    """

    rows: Sequence[HasRun]
    label: str | None
    style: dict[str, Any]


@dataclasses.dataclass(frozen=True)
class Mark:
    """A marked point (the recommendation, a baseline): counted work [DOF-evaluations], error [-], words, style."""

    cost: float
    error: float
    label: str
    style: dict[str, Any]


def _shown(error: float) -> float:
    return max(error, FLOOR)


def error_cost_panel(
    axis: Axes,
    groups: Sequence[Points],
    front: Sequence[HasRun],
    *,
    marks: Sequence[Mark] = (),
    tol: float | None = None,
    ylabel: str = "max relative error [-]",
    title: str = "error vs cost",
    legend_size: float = 7.0,
) -> None:
    """Draw error against counted work on `axis` (see the module docstring).

    Parameters
    ----------
    axis
        matplotlib Axes.
    groups
        the runs, in groups drawn alike; only valid runs are their points.
    front
        the Pareto front (springlab.studies.settings.pareto_front), drawn as black steps.
    marks
        labelled points drawn on top (the recommendation, a baseline).
    tol
        the tolerance [-], a dashed line (None: none).
    ylabel, title
        the axis label and the panel's title.
    legend_size
        the legend's font size [pt].
    """
    beyond, diverged = [], 0
    for group in groups:
        valid = [r.run for r in group.rows if r.run.valid]
        if valid:
            axis.loglog(
                [r.cost for r in valid], [_shown(r.error or 0.0) for r in valid], label=group.label, **group.style
            )
        beyond += [r.run for r in group.rows if r.run.beyond_limit and not r.run.diverged and r.run.error is not None]
        diverged += sum(r.run.diverged for r in group.rows)
    if beyond:
        axis.loglog(
            [r.cost for r in beyond],
            [_shown(r.error or 0.0) for r in beyond],
            label=f"beyond the stability limit ({len(beyond)}): not valid",
            **BEYOND_STYLE,
        )
    if front:
        axis.step(
            [r.run.cost for r in front],
            [_shown(r.run.error or 0.0) for r in front],
            where="post",
            color="k",
            lw=1.1,
            alpha=0.8,
            label="Pareto front",
        )
    if tol is not None:
        axis.axhline(tol, color="0.4", lw=0.8, ls="--", label=f"tol {tol:g}")
    for mark in marks:
        axis.plot([mark.cost], [_shown(mark.error)], label=mark.label, ls="none", **mark.style)
    if diverged:
        axis.plot([], [], " ", label=f"{diverged} diverged runs, not drawn")
    axis.set_xscale("log")
    axis.set_yscale("log")
    axis.set_xlabel(f"counted work [{COST_UNIT}]")
    axis.set_ylabel(ylabel)
    axis.set_title(title)
    axis.grid(True, which="both", alpha=0.3)
    legend_beside(axis, legend_size)


def legend_beside(axis: Axes, size: float = 7.0) -> None:
    """The axis' legend right of it, outside the axes: it covers no point and no label (nothing to show: none)."""
    if axis.get_legend_handles_labels()[0]:
        axis.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=size, borderaxespad=0.0)
