"""The chart of a model file's trade-off: error against timestep and against counted work, each error measured
against a converged run of the same model (springlab.studies.model_tradeoff); it never simulates."""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING

from springlab.studies.model_tradeoff import ModelTradeoff

from .charts import _COLORS, _STYLES, _figure, _save
from .settings import Mark, Points, error_cost_panel, legend_beside

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: errors below this are drawn at it (log axes)
FLOOR = 1e-17


def model_tradeoff_figure(result: ModelTradeoff) -> Figure:
    """Two log-log panels: error vs dt (the observed orders in the legend) and error vs counted work (the Pareto
    front, the model's own setting, the recommendation), titled with what the error is measured against."""
    fig, (left, right) = _figure(2, (14, 5), layout="constrained")
    groups = []
    for name in dict.fromkeys(r.integrator for r in result.runs):
        rows = [r for r in result.runs if r.integrator == name]
        valid = [r for r in rows if r.valid]
        groups.append(Points(rows, name, dict(ls=_STYLES[name], marker="o", ms=3, color=_COLORS[name])))
        if valid:
            order = result.orders.get(name)
            label = f"{name} (order {order:.2f})" if order is not None else name
            errors = [max(r.error or 0.0, FLOOR) for r in valid]
            left.loglog(
                [r.dt for r in valid], errors, _STYLES[name], marker="o", ms=3, color=_COLORS[name], label=label
            )
    marks = []
    if result.own.valid and result.own.error is not None:
        marks.append(
            Mark(
                result.own.cost,
                max(result.own.error, FLOOR),
                f"yours: {result.own.integrator}, dt = {result.own.dt:g} s",
                dict(marker="s", ms=9, color="none", markeredgecolor="black"),
            )
        )
    pick = result.recommendation
    if pick is not None and pick.found and pick.cost is not None and pick.error is not None:
        marks.append(
            Mark(
                pick.cost,
                max(pick.error, FLOOR),
                f"tol {pick.tolerance:g}: {pick.integrator}, dt = {pick.dt:g} s (verified)",
                dict(marker="*", ms=14, color="gold", markeredgecolor="black"),
            )
        )
    error_cost_panel(
        right,
        groups,
        result.pareto,
        marks=marks,
        tol=result.tolerance,
        ylabel="error against the converged run [-]",
        title="error vs cost (counted work: steps x evaluations)",
        legend_size=8,
    )
    left.set_xlabel("timestep dt [s]")
    left.set_ylabel("error against the converged run [-]")
    left.set_title("error vs timestep (slope = order)")
    left.grid(True, which="both", alpha=0.3)
    legend_beside(left, 8)
    converged = "converged" if result.converged else "NOT converged"
    fig.suptitle(
        f"{result.model} from {result.start}: {len(result.runs)} runs over {result.duration:g} s against RK4 at"
        f" dt = {result.reference.dt:.3g} s of the same model\n({converged}, its own error"
        f" ~{result.reference.error_estimate:.1g}): integration error only, MuJoCo's model error is invisible to it"
    )
    return fig


def plot_model_tradeoff(result: ModelTradeoff, path: str | pathlib.Path) -> pathlib.Path:
    """Write `model_tradeoff_figure(result)` to `path` (PNG): a model file's tradeoff.png."""
    return _save(model_tradeoff_figure(result), pathlib.Path(path))
