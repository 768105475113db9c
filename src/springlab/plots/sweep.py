"""Files of a parameter sweep: sweep.csv (one row per configuration) and sweep.png (a quantity over the parameters).

Reads a finished springlab.studies.sweeps.Sweep; never simulates. The figure is a bare
matplotlib Figure (no pyplot), saved atomically.
"""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING

import numpy as np

from springlab import files
from springlab.errors import BadInputError
from springlab.studies.sweeps import Sweep

from .settings import BEYOND_STYLE, legend_beside

#: a configuration that ran but failed its check: hollow and grey, as a run beyond its stability limit
FAILED_STYLE = BEYOND_STYLE

if TYPE_CHECKING:  # matplotlib is imported only when a figure is drawn
    from matplotlib.cm import ScalarMappable
    from matplotlib.figure import Figure


def default_quantity(sweep: Sweep) -> str:
    """The quantity sweep.png shows by default: the scenario's last numeric quantity that every
    configuration that ran has (its headline result, e.g. max_displacement_m), else the first error column."""
    if sweep.headline is None:
        raise BadInputError("the sweep has no numeric quantity to plot (every configuration diverged?)")
    return sweep.headline


def plot(sweep: Sweep, path: str | pathlib.Path, quantity: str | None = None) -> pathlib.Path:
    """Write `sweep_figure(sweep, quantity)` to `path` (PNG)."""
    fig = sweep_figure(sweep, quantity)
    path = pathlib.Path(path)
    files.prepare_directory(path.parent)
    with files.atomic_path(path) as temporary:
        fig.savefig(temporary, dpi=110, format="png")
    return path


def sweep_figure(sweep: Sweep, quantity: str | None = None) -> Figure:
    """`quantity` over the varied parameters.

    One varied parameter: the quantity against it (diverged configurations as red crosses on the
    axis). Two or more: a colour map over the first two (a grid: the other axes at their middle
    value; random samples: every point coloured). Log axes where the range is log-spaced.
    """
    from matplotlib.figure import Figure

    quantity = default_quantity(sweep) if quantity is None else quantity
    known = list(sweep.values) + sweep.quantity_names() + [f"{c}_max_rel" for row in sweep.rows for c in row.errors]
    if quantity not in known:
        raise BadInputError(f"unknown quantity {quantity!r} of this sweep; valid: {', '.join(dict.fromkeys(known))}")
    z = sweep.column(quantity)
    diverged = np.array([bool(r.diverged) for r in sweep.rows])
    # a configuration that ran but failed its check (outside its tolerance or the estimate's range, invalid) is
    # no valid result: drawn apart as a hollow grey circle, never on the curve or in the colour map
    failed = np.array([r.passed is False and not r.diverged for r in sweep.rows]) & np.isfinite(z)
    valid = ~failed
    axes = sweep.axes
    fig = Figure(figsize=(7.5, 5.0), layout="constrained")
    ax = fig.subplots()
    title = f"{sweep.scene} / {sweep.scenario}: {quantity} ({sweep.size} configurations, {sweep.integrator}"
    title += f", dt = {sweep.dt:g} s)"
    if len(axes) == 1:
        x = sweep.values[axes[0].name]
        order = np.argsort(x, kind="stable")
        order = order[valid[order]]
        ax.plot(x[order], z[order], ".-" if sweep.samples is None else ".", label=quantity)
        if failed.any():
            ax.plot(x[failed], z[failed], **FAILED_STYLE, label=f"failed its check ({failed.sum()}): not valid")
        if diverged.any():
            ax.plot(x[diverged], np.zeros(diverged.sum()), "rx", label="diverged")
        if failed.any() or diverged.any():
            legend_beside(ax, 8)
        ax.set_xlabel(axes[0].name)
        ax.set_ylabel(quantity)
        if axes[0].log:
            ax.set_xscale("log")
    else:
        a, b = axes[0], axes[1]
        x, y = sweep.values[b.name], sweep.values[a.name]
        keep = np.ones(sweep.size, bool)
        if sweep.samples is None and len(axes) > 2:
            for other in axes[2:]:
                grid = other.values()
                keep &= sweep.values[other.name] == grid[len(grid) // 2]
            title += "\n" + ", ".join(f"{o.name} = {o.values()[len(o.values()) // 2]:g}" for o in axes[2:])
        finite = keep & np.isfinite(z) & valid
        mesh: ScalarMappable
        if sweep.samples is None:
            assert a.count is not None and b.count is not None, "a grid sweep's axes all have N"
            shape = (a.count, b.count)
            plane = np.where(finite, z, np.nan)[keep].reshape(shape)
            mesh = ax.pcolormesh(b.values(), a.values(), plane, shading="nearest", cmap="viridis")
        else:
            mesh = ax.scatter(x[finite], y[finite], c=z[finite], s=12, cmap="viridis")
        fig.colorbar(mesh, ax=ax, label=quantity)
        bad = keep & diverged
        if bad.any():
            ax.plot(x[bad], y[bad], "rx", markersize=5, label="diverged")
        if (keep & failed).any():
            shown = keep & failed
            ax.plot(x[shown], y[shown], **FAILED_STYLE, label=f"failed its check ({shown.sum()}): not valid")
        if bad.any() or (keep & failed).any():
            legend_beside(ax, 8)
        ax.set_xlabel(b.name)
        ax.set_ylabel(a.name)
        if b.log:
            ax.set_xscale("log")
        if a.log:
            ax.set_yscale("log")
    ax.set_title(title, fontsize=9)
    return fig
