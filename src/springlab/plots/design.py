"""The design study's charts: design.png (positioning time over the two most influential properties,
and the analytic estimates against every simulated time) and sobol.png (the Sobol indices).

Reads a springlab.studies.design.Study or SobolStudy (never re-simulates); the axis labels are the
scene's declared ones. Times are drawn in [ms].
"""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING

import numpy as np

from springlab import files
from springlab.plots.settings import legend_beside
from springlab.studies.design.sobol import CONFIDENCE, SobolStudy
from springlab.studies.design.study import Study

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _save(fig: Figure, path: str | pathlib.Path) -> pathlib.Path:
    path = pathlib.Path(path)
    files.prepare_directory(path.parent)
    with files.atomic_path(path) as temporary:
        fig.savefig(temporary, dpi=110, format="png")
    return path


def plot(study: Study, path: str | pathlib.Path) -> pathlib.Path:
    """Write `design_figure(study)` to `path` (PNG)."""
    return _save(design_figure(study), path)


def design_figure(study: Study) -> Figure:
    """Positioning time over the two most influential properties (the others at their
    defaults; the dense plane if the study has one, else the grid's slice), and simulated vs
    analytic positioning time of every configuration."""
    import matplotlib.colors
    import matplotlib.ticker
    from matplotlib.figure import Figure  # no pyplot: a caller's backend and figures stay untouched

    first, second = study.ranking[:2]
    axes_order = list(study.grids)
    centre = study.levels // 2
    estimate_plane = None
    if study.plane is not None:
        x, y = study.plane.x, study.plane.y
        plane = study.plane.positioning_time_s * 1e3  # ms, rows: the most influential property
        estimate_plane = study.plane.estimate_s * 1e3
        first, second = study.plane.y_name, study.plane.x_name
    else:
        shape = (study.levels,) * len(axes_order)
        index: list[int | slice] = [centre] * len(shape)
        index[axes_order.index(first)] = slice(None)
        index[axes_order.index(second)] = slice(None)
        plane = study.positioning_time_s.reshape(shape)[tuple(index)] * 1e3  # ms
        if axes_order.index(first) > axes_order.index(second):
            plane = plane.T  # rows: first property
        x, y = study.grids[second], study.grids[first]
    fig = Figure(figsize=(12.5, 5.2), layout="constrained")
    left, right = fig.subplots(1, 2)
    norm = matplotlib.colors.LogNorm(vmin=float(np.min(plane)), vmax=float(np.max(plane)))
    mesh = left.pcolormesh(x, y, plane, shading="nearest", cmap="viridis", norm=norm)
    candidates = np.array([50, 100, 200, 400, 800, 1600])  # few, so the phase stripes stay readable
    levels = candidates[(candidates > np.min(plane)) & (candidates < np.max(plane))]
    if levels.size:
        contours = left.contour(x, y, plane, levels=levels, colors="white", linewidths=0.8)
        left.clabel(contours, fmt="%.0f ms", fontsize=8)
        if estimate_plane is not None:
            left.contour(x, y, estimate_plane, levels=levels, colors="white", linewidths=0.6, linestyles="dashed")
    default = study.defaults
    left.plot(default[second], default[first], "w*", markersize=14, markeredgecolor="k", label="default")
    if estimate_plane is not None:
        left.plot([], [], "w--", linewidth=0.6, label="analytic estimate (contours)")
    left.set_xscale("log")
    left.set_yscale("log")
    for axis in (left.xaxis, left.yaxis):  # plain numbers at 1, 2, 5 x 10^n: scientific minor labels collide
        axis.set_major_locator(matplotlib.ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda value, _: f"{value:g}"))
        axis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    left.set_xlabel(study.design.get(second).label)
    left.set_ylabel(study.design.get(first).label)
    elasticity = study.elasticities
    others = [p for p in axes_order if p not in (first, second)]
    left.set_title(
        f"{study.design.merit} [ms], {study.setting}\n" + ", ".join(f"{p} = {default[p]:.3g}" for p in others),
        fontsize=10,
    )
    bar = fig.colorbar(mesh, ax=left, label=f"{study.design.merit} [ms]")
    # below the map, beside its colour bar: a legend over the map would hide configurations
    left.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), fontsize=8, ncols=2, borderaxespad=0.0)
    bar.ax.yaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%.0f"))
    bar.ax.yaxis.set_minor_formatter(matplotlib.ticker.FormatStrFormatter("%.0f"))

    finite = np.isfinite(study.positioning_time_s)
    sim, est = study.positioning_time_s[finite] * 1e3, study.estimate_s[finite] * 1e3
    right.loglog(sim, est, ".", markersize=3, alpha=0.5, label="analytic estimate")
    right.loglog(
        sim, study.worst_case_estimate_s[finite] * 1e3, ".", markersize=2, alpha=0.3, label="worst-case estimate"
    )
    span = [min(sim.min(), est.min()) * 0.9, max(sim.max(), est.max()) * 1.1]
    right.plot(span, span, "k-", linewidth=0.8, label="equal")
    right.set_xlabel(f"simulated {study.design.merit} [ms] (MuJoCo, batched)")
    right.set_ylabel(f"estimated {study.design.merit} [ms]")
    for axis in (right.xaxis, right.yaxis):  # plain numbers at 1, 2, 5 x 10^n
        axis.set_major_locator(matplotlib.ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda value, _: f"{value:g}"))
        axis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    right.set_title(
        f"{study.size} configurations; elasticities d ln T / d ln p:\n"
        + ", ".join(f"{p.split('_')[0]} {elasticity[p]:+.2f}" for p in study.ranking),
        fontsize=10,
    )
    legend_beside(right, 8)
    return fig


def plot_sobol(study: SobolStudy, path: str | pathlib.Path) -> pathlib.Path:
    """Write `sobol_figure(study)` to `path` (PNG)."""
    return _save(sobol_figure(study), path)


def sobol_figure(study: SobolStudy) -> Figure:
    """Two panels: first-order and total Sobol indices with their confidence intervals per property
    (total minus first-order is the interactions' share), and the elasticities |d ln T / d ln p| from the
    same runs, for the ranking they would give."""
    from matplotlib.figure import Figure  # no pyplot: a caller's backend and figures stay untouched

    fig = Figure(figsize=(12, 4.8), layout="constrained")
    left, right = fig.subplots(1, 2)
    names = list(study.ranking)
    x = np.arange(len(names))
    s1, st = study.indices["S1"], study.indices["ST"]
    left.bar(
        x - 0.2,
        [s1[n] for n in names],
        0.4,
        yerr=[study.indices["S1_conf"][n] for n in names],
        capsize=3,
        label="first order S1 (alone)",
        color="#1f77b4",
    )
    left.bar(
        x + 0.2,
        [st[n] for n in names],
        0.4,
        yerr=[study.indices["ST_conf"][n] for n in names],
        capsize=3,
        label="total ST (alone + interactions)",
        color="#d62728",
    )
    left.axhline(0.0, color="k", linewidth=0.6)
    left.set_xticks(x, [n.replace("_", "\n") for n in names])
    left.set_ylabel(f"share of Var({study.merit}) [-]")
    left.set_title(
        f"Sobol indices, {study.runs} runs ({study.base_samples} x {len(names) + 2}),"
        f" {int(round(100 * CONFIDENCE))}% bootstrap intervals;\nsum S1 = {sum(s1.values()):.2f}",
        fontsize=10,
    )
    left.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), fontsize=8, ncols=2, borderaxespad=0.0)
    elastic = [abs(study.elasticities[n]) for n in names]
    right.bar(x, elastic, 0.5, color="#7f7f7f")
    right.set_xticks(x, [n.replace("_", "\n") for n in names])
    right.set_ylabel("|elasticity d ln T / d ln p| [-]")
    right.set_title(f"elasticities from the same runs (log-log fit, R^2 = {study.regression_r2:.2f})", fontsize=10)
    return fig
