"""Charts of the studies: the speed-accuracy trade, the stability map and the energy of each integrator.

They read results (springlab.studies.tradeoff's Tradeoff, springlab.studies.stability's
StabilityReport, AmplificationMap and EnergyHistories) and never simulate; each figure is a bare matplotlib Figure (no pyplot), saved atomically.
"""

from __future__ import annotations

import math
import pathlib
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from springlab import files
from springlab.exact.limits import stability_limit
from springlab.runs import compare
from springlab.studies.stability import AmplificationMap, EnergyHistories, StabilityReport
from springlab.studies.tradeoff import Tradeoff

from .settings import Mark, Points, error_cost_panel, legend_beside

if TYPE_CHECKING:
    from matplotlib.figure import Figure

_COLORS = {
    "euler": "#1f77b4",
    "implicit": "#17becf",
    "implicitfast": "#2ca02c",
    "rk4": "#d62728",
    "discrete": "#9467bd",
}
_STYLES = {"euler": "-", "implicit": "--", "implicitfast": ":", "rk4": "-", "discrete": "-"}


def _figure(ncols: int, figsize: tuple[float, float], **options):
    """A bare matplotlib Figure and its axes: no pyplot, so a caller's backend and figures stay untouched."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout=options.pop("layout", None))
    return fig, fig.subplots(1, ncols, **options)


def _save(fig, path: str | pathlib.Path) -> pathlib.Path:
    path = pathlib.Path(path)
    files.prepare_directory(path.parent)
    with files.atomic_path(path) as temporary:
        fig.savefig(temporary, dpi=110, format="png")
    return path


def plot_tradeoff(result: Tradeoff, path: str | pathlib.Path) -> pathlib.Path:
    """Write `tradeoff_figure(result)` to `path` (PNG)."""
    return _save(tradeoff_figure(result), path)


def tradeoff_figure(result: Tradeoff) -> Figure:
    """Two log-log panels: error vs dt (with the observed orders) and error vs counted work (Pareto front,
    the recommendation; springlab.plots.settings.error_cost_panel)."""
    fig, (left, right) = _figure(2, (14, 5), layout="constrained")
    floor = 1e-17
    groups = []
    for name in dict.fromkeys(r.integrator for r in result.runs):
        rows = [r for r in result.runs if r.integrator == name]
        runs = [r for r in rows if r.run.valid]
        groups.append(Points(rows, name, dict(ls=_STYLES[name], marker="o", ms=3, color=_COLORS[name])))
        if not runs:
            continue
        order = result.orders.get(name)
        label = f"{name} (order {order:.2f})" if order is not None else name
        errors = [max(r.error, floor) for r in runs]
        left.loglog([r.dt for r in runs], errors, _STYLES[name], marker="o", ms=3, color=_COLORS[name], label=label)
        # runs outside the range of their error estimate: `springlab run` calls them not validated
        outside = [(r, e) for r, e in zip(runs, errors) if not r.validated]
        left.plot([r.dt for r, _ in outside], [e for _, e in outside], "x", ms=8, mew=1.5, color=_COLORS[name])
    if any(r.run.valid and not r.validated for r in result.runs):
        left.plot([], [], "x", ms=8, mew=1.5, color="gray", label="not validated (outside the estimate's range)")
    marks = []
    pick = result.recommendation
    if pick is not None and pick.found and pick.cost is not None and pick.error is not None:
        marks.append(
            Mark(
                pick.cost,
                pick.error,
                f"tol {pick.tolerance:g}: {pick.integrator}, dt = {pick.dt:g} s (verified)",
                dict(marker="*", ms=14, color="gold", markeredgecolor="black"),
            )
        )
    error_cost_panel(
        right,
        groups,
        result.pareto,
        marks=marks,
        tol=None if pick is None else pick.tolerance,
        title="error vs cost (counted work: steps x evaluations)",
        legend_size=8,
    )
    left.set_xlabel("timestep dt [s]")
    left.set_ylabel("max relative error [-]")
    left.set_title("error vs timestep (slope = order)")
    left.grid(True, which="both", alpha=0.3)
    legend_beside(left, 8)
    unvalidated = sum(r.run.valid and not r.validated for r in result.runs)
    diverged = sum(r.diverged for r in result.runs)
    note = f"; {diverged} diverged runs not shown" if diverged else ""
    note += f"; x: {unvalidated} not validated" if unvalidated else ""
    fig.suptitle(f"{result.scene} / {result.scenario}: {len(result.runs)} runs over {result.duration:g} s{note}")
    return fig


#: run length [natural periods] of the estimate-range line drawn on the stability map
RANGE_PERIODS = 10
_RANGE = f"validated below ({RANGE_PERIODS} periods)"


def estimate_range_line(integrator: str, zetas: Sequence[float] | np.ndarray) -> list[float]:
    """Largest omega*dt [-] inside the range of the error estimate for a run of RANGE_PERIODS periods, per zeta.

    On the unit oscillator (omega = 1 rad/s): its roots -zeta +- sqrt(zeta^2 - 1) are the modes
    `compare.estimate_range` judges; above the line `springlab run` says "not validated".
    """
    out = []
    for zeta in zetas:
        root = np.sqrt(complex(zeta * zeta - 1.0))
        rates = [-zeta + root, -zeta - root]
        out.append(compare.estimate_range(rates, integrator, 0.1, RANGE_PERIODS * 2 * math.pi).largest_dt)
    return out


def plot_stability(report: StabilityReport, amplification: AmplificationMap, path: str | pathlib.Path) -> pathlib.Path:
    """Write `stability_figure(report, amplification)` to `path` (PNG)."""
    return _save(stability_figure(report, amplification), path)


def stability_figure(report: StabilityReport, amplification: AmplificationMap) -> Figure:
    """Per integrator: measured per-step amplification over (zeta, omega*dt), theory boundary, measured boundary.

    Parameters
    ----------
    report
        `stability.stability_report` (its measured boundaries are drawn).
    amplification
        `stability.amplification_map` (the colour map).
    """
    from matplotlib.colors import TwoSlopeNorm

    zetas, omega_dts = amplification.zetas, amplification.omega_dts
    names = list(amplification.radius)
    fig, axes = _figure(len(names), (3.4 * len(names) + 1.5, 4.4), sharey=True, layout="constrained")
    axes = np.atleast_1d(axes)
    norm = TwoSlopeNorm(vmin=-3.0, vcenter=0.0, vmax=3.0)
    theory_zetas = np.concatenate([[0.0], np.geomspace(1e-2, 100.0, 200)])
    image = None
    for axis, name in zip(axes, names):
        log_radius = np.log10(np.clip(amplification.radius[name], 1e-300, None))
        image = axis.pcolormesh(
            zetas, omega_dts, np.clip(log_radius, -3, 3).T, cmap="RdBu_r", norm=norm, shading="nearest"
        )
        theory = [stability_limit(name, z) for z in theory_zetas]
        if all(math.isinf(t) for t in theory):
            axis.text(0.5, 0.5, "no limit: never unstable", transform=axis.transAxes, ha="center", fontsize=9)
        else:
            axis.plot(theory_zetas, theory, color="black", lw=1.2, label="theory")
        # below this line a run of RANGE_PERIODS periods is inside the range of its error estimate (springlab.runs.compare)
        range_zetas = theory_zetas[::5]
        axis.plot(range_zetas, estimate_range_line(name, range_zetas), color="black", lw=1.0, ls="--", label=_RANGE)
        rows = [r for r in report.boundaries if r.integrator == name and math.isfinite(r.measured_omega_dt)]
        axis.plot(
            [r.zeta for r in rows],
            [r.measured_omega_dt for r in rows],
            "o",
            mfc="none",
            color="gold",
            mew=1.5,
            label="measured (growth test)",
        )
        axis.set_xscale("symlog", linthresh=0.01)
        axis.set_yscale("log")
        axis.set_ylim(omega_dts[0], omega_dts[-1])
        axis.set_xlabel("damping ratio zeta [-]")
        axis.set_title(name)
    # one legend for the panels (the same lines on each), below them: over a panel it would hide the map
    handles, labels = max((axis.get_legend_handles_labels() for axis in axes), key=lambda found: len(found[1]))
    fig.legend(handles, labels, loc="outside lower center", ncols=len(labels), fontsize=8)
    axes[0].set_ylabel("omega * dt [-]")
    fig.colorbar(image, ax=list(axes), label="log10 per-step amplification (> 0: grows)", shrink=0.85)
    fig.suptitle("stability map: MuJoCo's measured one-step amplification, theory (line), measured boundary (o)")
    return fig


def plot_energy(series: EnergyHistories, path: str | pathlib.Path) -> pathlib.Path:
    """Write `energy_figure(series)` to `path` (PNG)."""
    return _save(energy_figure(series), path)


def energy_figure(series: EnergyHistories) -> Figure:
    """E/E0 over time of every integrator on the undamped oscillator, each against its exact formula.

    Three panels: the integrators that keep an invariant (`series.bounds`, the euler family) between
    their bounds, and rk4 and discrete against their per-step formulas (`series.exact`).
    """
    fig, (euler, rk4, discrete) = _figure(3, (17, 4.4), layout="constrained")  # room for the legends beside
    t = series.time_periods
    y = series.omega_dt
    first = t <= 3.0
    for name in series.bounds:
        euler.plot(t[first], series.ratio[name][first] - 1, _STYLES[name], color=_COLORS[name], lw=1.2, label=name)
    low, high = next(iter(series.bounds.values()))  # one map, one pair of bounds
    euler.axhline(high - 1, color="black", lw=0.8, ls="--", label="1/(1 - y/2) - 1 (sharp bound)")
    euler.axhline(low - 1, color="black", lw=0.8, ls=":", label="1/(1 + y/2) - 1")
    euler.set_title("euler family: bounded oscillation (first 3 periods)")
    stride = max(1, len(t) // 4000)
    rk4.plot(t[::stride], series.ratio["rk4"][::stride] - 1, color=_COLORS["rk4"], lw=2.5, alpha=0.6, label="rk4")
    rk4.plot(
        t,
        series.exact["rk4"] - 1,
        color="black",
        lw=0.8,
        ls="--",
        label="(1 - y^6/72 + y^8/576)^n - 1",
    )
    rk4.set_title("rk4: slow decay")
    discrete.semilogy(
        t[::stride],
        series.ratio["discrete"][::stride],
        color=_COLORS["discrete"],
        lw=2.5,
        alpha=0.6,
        label="discrete",
    )
    discrete.semilogy(t, series.exact["discrete"], color="black", lw=0.8, ls="--", label="(1 + y^2)^-n")
    discrete.set_title("discrete: decay by 1/(1 + y^2) per step")
    euler.set_ylabel("E/E0 - 1 [-]")
    rk4.set_ylabel("E/E0 - 1 [-]")
    discrete.set_ylabel("E/E0 [-]")
    for axis in (euler, rk4, discrete):
        axis.set_xlabel("time [periods]")
        axis.grid(True, alpha=0.3)
        legend_beside(axis, 8)
    fig.suptitle(
        f"undamped {series.scene}, omega*dt = y = {y:g}: energy from qpos/qvel vs each step map's exact formula"
    )
    return fig
