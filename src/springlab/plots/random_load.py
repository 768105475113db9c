"""The charts of `springlab rms`: many seeded records against the exact RMS, and what an accurate RMS costs.

* `ensemble_figure` (rms.png): each record's RMS against its seed, the band a record of this length falls in at
  the study's level around the exact held value, the exact values (continuous, held, the integrator's map) and
  the records' pooled RMS with its own, narrower band; beside it the records' variances as a histogram over the
  scaled chi-square the interval comes from.
* `settings_figure` (rms_settings.png): the bound (discretization + hold and integrator + record) of every
  setting against its counted work (springlab.plots.settings.error_cost_panel), the front and the verified pick;
  beside it the pick's three parts against the number of records.

Both draw what they are given; they never simulate.
"""

from __future__ import annotations

import math
import pathlib
from typing import TYPE_CHECKING

import numpy as np

from springlab.studies.random_load import Ensemble
from springlab.studies.rms_settings import RmsSettings

from .charts import _COLORS, _figure, _save
from .settings import Mark, Points, error_cost_panel, legend_beside

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def ensemble_figure(result: Ensemble) -> Figure:
    """Each record's RMS with the interval and the exact values; the variances' histogram (module docstring)."""
    import scipy.stats

    fig, (left, right) = _figure(2, (14, 4.8), layout="constrained")
    unit = result.unit
    seeds = np.asarray(result.seeds)
    rms = result.rms
    low, high = result.interval.rms_interval()
    pooled_low, pooled_high = result.mean_interval.rms_interval()
    inside = np.array([result.interval.contains(v) for v in result.variances])
    left.axhspan(low, high, color="0.85", label=f"{result.level:.0%} interval of one {result.record_s:g} s record")
    left.axhspan(pooled_low, pooled_high, color="#9ecae1", alpha=0.7, label=f"{result.level:.0%} interval of the pool")
    left.plot(seeds[inside], rms[inside], "o", color="#1f77b4", ms=4, label=f"records inside ({inside.sum()})")
    if (~inside).any():
        left.plot(seeds[~inside], rms[~inside], "x", color="#d62728", ms=6, label=f"outside ({(~inside).sum()})")
    left.axhline(
        math.sqrt(result.held), color="k", lw=1.2, label=f"exact, held load: {math.sqrt(result.held):.4g} {unit}"
    )
    left.axhline(math.sqrt(result.continuous), color="k", lw=1.0, ls="--", label="exact, continuous white noise")
    left.axhline(
        math.sqrt(result.integrated), color="#2ca02c", lw=1.0, ls=":", label=f"exact, {result.integrator}'s map"
    )
    left.axhline(math.sqrt(result.mean_variance), color="#ff7f0e", lw=1.2, label="the records pooled")
    left.set_xlabel("seed")
    left.set_ylabel(f"RMS [{unit}]")
    left.set_title(f"{result.scene} / {result.scenario}: {result.integrator} at dt = {result.dt:g} s", fontsize=9)
    legend_beside(left)
    nu = result.interval.degrees_of_freedom
    scaled = np.asarray(result.variances) / result.held * nu
    right.hist(scaled, bins=max(5, len(scaled) // 4), density=True, color="#9ecae1", edgecolor="w", label="records")
    grid = np.linspace(max(0.0, nu - 5 * math.sqrt(2 * nu)), nu + 5 * math.sqrt(2 * nu), 400)
    right.plot(grid, scipy.stats.chi2.pdf(grid, nu), "k", lw=1.2, label=f"chi-square, {nu:.3g} degrees of freedom")
    right.set_xlabel("record variance / exact held variance x degrees of freedom [-]")
    right.set_ylabel("density [-]")
    right.set_title("a record's variance scatters as the exact autocovariance says")
    legend_beside(right)
    return fig


def settings_figure(result: RmsSettings) -> Figure:
    """The bound of every setting against counted work; the pick's parts against the records (module docstring)."""
    fig, (left, right) = _figure(2, (16, 5.2), layout="constrained")
    names = list(dict.fromkeys(r.integrator for r in result.rows))
    groups = [
        Points(
            [r for r in result.rows if r.integrator == name],
            name,
            dict(marker="o", color=_COLORS.get(name, "0.3"), ms=3, alpha=0.7, ls="none"),
        )
        for name in names
    ]
    pick = result.recommendation
    marks = []
    if pick.found and pick.row is not None and pick.error is not None:
        marks.append(
            Mark(pick.row.cost, pick.error, "verified pick (its run's error)", dict(marker="*", color="k", ms=12))
        )
    error_cost_panel(
        left,
        groups,
        result.front,
        marks=marks,
        tol=result.tol,
        ylabel="bound on the RMS's relative error [-]",
        title=f"{result.scene}: {result.description} to {result.tol:g} at {result.level:.0%}",
    )
    row = pick.row if pick.row is not None else (result.front[-1] if result.front else None)
    if row is not None:
        same = sorted(
            (r for r in result.rows if (r.size, r.integrator, r.dt) == (row.size, row.integrator, row.dt)),
            key=lambda r: r.seeds,
        )
        counts = [r.seeds for r in same]
        right.loglog(counts, [r.error for r in same], "k-o", ms=4, label="bound")
        right.loglog(counts, [r.record for r in same], "-s", color="#1f77b4", ms=4, label="record (at the level)")
        right.loglog(
            counts, [max(r.bias or 0.0, 1e-17) for r in same], "--", color="#2ca02c", label="hold and integrator"
        )
        right.loglog(counts, [max(r.discretization, 1e-17) for r in same], ":", color="#9467bd", label="discretization")
        right.axhline(result.tol, color="0.4", lw=0.8, ls="--", label=f"tol {result.tol:g}")
        right.set_title(
            f"{result.size_parameter} = {row.size}, {row.integrator} at dt = {row.dt:.3g} s: the bound's parts"
        )
    right.set_xlabel(f"records of {result.record_s:g} s [-]")
    right.set_ylabel("relative error of the RMS [-]")
    right.grid(True, which="both", alpha=0.3)
    legend_beside(right)
    return fig


def plot_ensemble(result: Ensemble, path: str | pathlib.Path) -> pathlib.Path:
    """Write `ensemble_figure(result)` to `path` (PNG): rms.png."""
    return _save(ensemble_figure(result), pathlib.Path(path))


def plot_settings(result: RmsSettings, path: str | pathlib.Path) -> pathlib.Path:
    """Write `settings_figure(result)` to `path` (PNG): rms_settings.png."""
    return _save(settings_figure(result), pathlib.Path(path))
