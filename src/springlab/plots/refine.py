"""The chart of the three-axis trade (springlab.studies.refine): how much model a question needs.

Three log-log panels of a `Refinement`, never simulating:

* the error bound (discretization + integration) vs counted work of every run (colour: the size, marker:
  the integrator; springlab.plots.settings.error_cost_panel), the Pareto front, the tolerance and the
  verified recommendation; runs beyond their stability limit hollow and apart;
* the discretization error vs the size with its observed order, and each size's best integration error;
* what refining costs: wall time per step and per simulated second at each integrator's stability limit.
"""

from __future__ import annotations

import math
import pathlib
from typing import TYPE_CHECKING

from springlab.studies.refine import Refinement

from .charts import _COLORS, _figure, _save
from .settings import Mark, Points, error_cost_panel, legend_beside

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: marker per integrator
_MARKERS = {"euler": "o", "implicit": "s", "implicitfast": "D", "rk4": "^", "discrete": "v"}


def plot_refine(result: Refinement, path: str | pathlib.Path) -> pathlib.Path:
    """Write the three panels (see the module docstring) to `path` (.png)."""
    return _save(refine_figure(result), path)


def refine_figure(result: Refinement) -> Figure:
    """The three panels (see the module docstring)."""
    from matplotlib import colormaps

    fig, (left, middle, right) = _figure(3, (20, 5.4), layout="constrained")
    sizes = [c.size for c in result.sizes]
    cmap = colormaps["viridis"]
    shade = {size: cmap(i / max(len(sizes) - 1, 1)) for i, size in enumerate(sizes)}
    names = list(dict.fromkeys(r.integrator for r in result.runs))
    # the legend's keys first: a marker per integrator, a colour per size (the groups draw unlabelled)
    for name in names:
        left.plot([], [], _MARKERS.get(name, "o"), color="0.3", ms=4, label=name)
    for size in sizes:
        left.plot([], [], "o", color=shade[size], ms=4, label=f"{result.size_parameter} = {size}")
    groups = [
        Points(
            [r for r in result.runs if r.size == size and r.integrator == name],
            None,
            dict(marker=_MARKERS.get(name, "o"), color=shade[size], ms=4, alpha=0.8, ls="none"),
        )
        for size in sizes
        for name in names
    ]
    marks = []
    pick = result.recommendation
    if pick is not None and pick.found and pick.cost is not None and pick.error is not None:
        marks.append(
            Mark(
                pick.cost,
                pick.error,
                f"cheapest: {result.size_parameter} = {pick.details['size']}, {pick.integrator}, dt = {pick.dt:g} s",
                dict(marker="*", color="#d62728", ms=14, markeredgecolor="k"),
            )
        )
    error_cost_panel(
        left,
        groups,
        result.pareto,
        marks=marks,
        tol=None if pick is None else pick.tolerance,
        ylabel=f"{result.quantity}: discretization + integration error [-]",
        title=f"{result.description}: error vs cost",
        legend_size=6.5,
    )

    discretization = [(c.size, c.discretization_error) for c in result.sizes if c.discretization_error]
    if discretization:
        middle.loglog(*zip(*discretization), "ko-", label="discretization (exact model vs continuum)")
        first_size, first_error = discretization[0]
        guide = [first_error * (s / first_size) ** -result.expected_order for s, _ in discretization]
        middle.loglog(
            [s for s, _ in discretization],
            guide,
            color="0.6",
            ls="--",
            lw=0.8,
            label=f"order {result.expected_order:g}",
        )
    for name in dict.fromkeys(r.integrator for r in result.runs):
        best = []
        for size in sizes:
            errors = [  # valid runs only: one beyond its stability limit ended before its blow-up showed
                r.integration_error
                for r in result.runs
                if r.size == size and r.integrator == name and r.integration_error and r.run.valid
            ]
            if errors:
                best.append((size, min(errors)))
        if best:
            middle.loglog(
                *zip(*best),
                marker=_MARKERS.get(name, "o"),
                color=_COLORS.get(name),
                lw=0.8,
                label=f"{name}: best integration error",
            )
    order = result.discretization_order
    middle.set_title(f"discretization: observed order {order:.2f}" if order is not None else "discretization")
    middle.set_xlabel(f"{result.size_parameter} ({result.size_description})")
    middle.set_ylabel("relative error [-]")
    legend_beside(middle, 6.5)

    step_cost = [(c.size, min(c.cost_per_step_s.values())) for c in result.sizes if c.cost_per_step_s]
    if step_cost:
        growth = result.step_cost_growth
        right.loglog(
            *zip(*step_cost),
            "k--",
            marker="o",
            ms=3,
            label="per step (cheapest integrator)" + (f", ~N^{growth:.2f}" if growth is not None else ""),
        )
    for name, exponent in result.cost_growth.items():
        points = [(c.size, c.cost_per_simulated_second_s.get(name)) for c in result.sizes]
        points = [(s, v) for s, v in points if v is not None and math.isfinite(v)]
        if points:
            right.loglog(
                *zip(*points),
                marker=_MARKERS.get(name, "o"),
                color=_COLORS.get(name),
                label=f"{name}: per simulated s at its stability limit"
                + (f", ~N^{exponent:.2f}" if exponent is not None else ""),
            )
    right.set_xlabel(f"{result.size_parameter} ({result.size_description})")
    right.set_ylabel("wall time [s]")
    right.set_title("refining costs twice: per step x steps per second")
    legend_beside(right, 6.5)
    fig.suptitle(f"{result.scene} / {result.scenario}: how much model does {result.quantity} need?")
    return fig
