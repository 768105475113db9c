"""The friction-settings study drawn, and its files written: error vs cost per case, model error vs timestep.

Reads a springlab.studies.friction_settings.FrictionSettings and never simulates. One row of two
log-log panels per case:

* error vs counted work of every run (grey), the Pareto front (black steps), MuJoCo's defaults (red
  square), the verified pick for the tolerance (gold star) and the tolerance (dashed): the shared
  panel, springlab.plots.settings.error_cost_panel;
* error vs timestep for RK4 at three settings (MuJoCo's defaults, the pick's, the best model), titled
  by what the curves show: flat as dt -> 0 (what is left is MuJoCo's model error) or still falling
  (integration error remains). Legends stand beside the axes, clear of every point and label.
"""

from __future__ import annotations

import pathlib
from collections.abc import Sequence
from typing import TYPE_CHECKING

from springlab import files
from springlab.studies.friction_settings import MODEL_INTEGRATOR, CaseStudy, FrictionSettings, ModelError

from .settings import Mark, Points, error_cost_panel, legend_beside
from .style import new_figure, styled

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: drawn instead of an error of exactly 0 on a log axis (NoSlip can make a creep vanish) [-]
FLOOR = 1e-12


def _shown(value: float) -> float:
    return max(value, FLOOR)


def _cost_panel(case: CaseStudy, axis, tol: float | None) -> None:
    """Error vs counted work of every run, the front, MuJoCo's defaults and the pick (the shared panel)."""
    marks = []
    if case.default is not None and case.default.max_rel_error is not None:
        marks.append(
            Mark(
                case.default.cost,
                _shown(case.default.error),
                f"MuJoCo's defaults ({case.default.integrator}, dt = {case.default.dt:g} s)",
                dict(marker="s", ms=7, color="C3"),
            )
        )
    pick = case.pick
    if pick is not None and pick.row is not None:
        marks.append(
            Mark(
                pick.row.cost,
                _shown(pick.row.error),
                f"cheapest for tol: {pick.row.integrator}, dt = {pick.row.dt:g} s",
                dict(marker="*", ms=14, color="gold", markeredgecolor="k"),
            )
        )
    error_cost_panel(
        axis,
        [Points(case.runs, "every run", dict(marker=".", ms=2.5, color="0.65", ls="none"))],
        case.pareto,
        marks=marks,
        tol=tol,
        title=f"{case.scenario}: error vs cost ({len(case.runs)} runs)",
        legend_size=6.5,
    )


def model_error_title(curves: Sequence[tuple[ModelError, str]]) -> str:
    """The model-error panel's title, from what its curves show: flat as dt -> 0 (the two smallest timesteps
    agree: what is left is MuJoCo's model error) or still falling (integration error remains), per curve."""
    if not curves:
        return f"no {MODEL_INTEGRATOR} runs: no model error measured"
    flat = [label for model, label in curves if model.converged]
    falling = [label for model, label in curves if not model.converged]
    if not falling:
        return "flat as dt → 0: what is left is MuJoCo's model error"
    if not flat:
        return "still falling as dt → 0: integration error remains at the smallest dt"
    return f"flat as dt → 0 for {', '.join(flat)}; still falling for {', '.join(falling)}"


def _dt_panel(case: CaseStudy, axis, tol: float | None) -> None:
    """RK4's error vs dt at three settings (MuJoCo's defaults, the pick's, the best model), titled by the data."""
    shown: list[tuple[ModelError, str]] = []
    for label, model, style in (
        ("MuJoCo's defaults", case.default_model, "C3"),
        ("the pick's settings", _pick_model(case), "goldenrod"),
        ("best model", case.best_model, "C2"),
    ):
        if model is None or any(m is model for m, _ in shown):
            continue
        points = [(d, e) for d, e in zip(model.dts, model.errors) if e is not None]
        if not points:
            continue
        shown.append((model, label))
        settings = case.describe(model.settings)
        axis.loglog(
            [d for d, _ in points],
            [_shown(e) for _, e in points],
            "o-",
            ms=4,
            color=style,
            label=label if settings == label else f"{label}: {settings}",
        )
    if tol is not None:
        axis.axhline(tol, color="0.4", lw=0.8, ls="--", label=f"tol {tol:g}")
    axis.set_xlabel("timestep dt [s]")
    axis.set_ylabel(f"max relative error of {MODEL_INTEGRATOR} [-]")
    axis.set_title(model_error_title(shown), fontsize=9)
    axis.grid(True, which="both", alpha=0.3)
    legend_beside(axis, 6.5)


def _pick_model(case: CaseStudy) -> ModelError | None:
    if case.pick is None or case.pick.row is None:
        return None
    return next((m for m in case.model_errors if m.settings == case.pick.row.settings), None)


@styled
def plot(study: FrictionSettings, path: str | pathlib.Path) -> pathlib.Path:
    """Write the study's figure (see the module docstring) to `path` (.png); return the path."""
    figure = friction_figure(study)
    path = pathlib.Path(path)
    files.prepare_directory(path.parent)
    with files.atomic_path(path) as temporary:
        figure.savefig(temporary, format="png")
    return path


@styled
def friction_figure(study: FrictionSettings) -> Figure:
    """The study's figure (see the module docstring): per case, error vs cost and error vs dt."""
    figure = new_figure(15.0, 3.6 * len(study.cases) + 0.6)
    axes = figure.subplots(len(study.cases), 2, squeeze=False)
    for case, (cost_ax, dt_ax) in zip(study.cases, axes):
        _cost_panel(case, cost_ax, study.tol)
        _dt_panel(case, dt_ax, study.tol)
    figure.suptitle(f"{study.scene}: MuJoCo's friction settings, error vs cost ({study.runs} runs)")
    return figure
