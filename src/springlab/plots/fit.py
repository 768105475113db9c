"""fit.png: the record, the fitted response, the residuals over time and a phase-plane view.

Reads a springlab.studies.fit.results.FitResult (never re-simulates): the fitted signal at the
recorded times and, for the phase plane, the identified scene's own run.
"""

from __future__ import annotations

import os
import pathlib
import textwrap
from typing import TYPE_CHECKING

import numpy as np

from . import charts
from .settings import legend_beside

if TYPE_CHECKING:  # annotations only: the fit machinery is not needed to draw
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from springlab.studies.fit.results import FitResult

_DATA, _FIT, _BAND = "#7f7f7f", "#d62728", "#f4a6a6"
#: samples drawn at most per series: a 12-inch figure at 110 dpi is about 1300 pixels wide, and 2 million points
#: cost Agg about 400 MB and 10 s for the same picture (a longer record is thinned evenly, `shown`)
DRAWN = 40_000
_SIGNAL = {"pos": "position", "vel": "velocity", "acc": "acceleration"}


def plot_fit(result: FitResult, path: str | os.PathLike) -> pathlib.Path:
    """Write fit.png for a FitResult (`fit_figure`)."""
    return charts._save(fit_figure(result), pathlib.Path(path))


def fit_figure(result: FitResult) -> Figure:
    """A FitResult's figure: data and fit, residuals, and the phase plane (or v(t), a(t) for a polynomial)."""
    record = result.record
    from matplotlib.figure import Figure  # a bare Figure: the caller's pyplot state stays untouched

    fig = Figure(figsize=(13, 8), layout="constrained")  # constrained: room for the legends beside the panels
    grid = fig.add_gridspec(2, 2, height_ratios=(3, 2))
    top, phase = fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1])
    bottom = fig.add_subplot(grid[1, :])
    label = f"{record.column} [{record.unit}]"
    n = record.time.size
    kept = shown(n)
    thinned = f", 1 in {kept.step} drawn" if kept.step > 1 else ""
    top.plot(record.time[kept], record.values[kept], ".", ms=2, color=_DATA, label=f"data ({n} samples{thinned})")
    top.plot(record.time[kept], result.fitted[kept], "-", lw=1.2, color=_FIT, label="fitted model (MuJoCo)")
    top.set_xlabel("time [s]")
    top.set_ylabel(f"{_SIGNAL[record.signal]}: {label}")
    top.set_title(f"{result.scene} / {result.scenario}: {_SIGNAL[record.signal]} of {record.joint}")
    legend_beside(top, 8)
    residual = record.values[kept] - result.fitted[kept]
    bottom.plot(record.time[kept], residual, ".", ms=2, color=_DATA)
    bottom.axhline(0.0, color="k", lw=0.6)
    for sign in (-1, 1):
        bottom.axhline(sign * 2 * result.residual_rms, color=_FIT, lw=0.6, ls="--")
    bottom.set_xlabel("time [s]")
    bottom.set_ylabel(f"data - fit [{record.unit}]")
    bottom.set_title(f"residuals: RMS {result.residual_rms:.3g} {record.unit} (dashed: ±2 RMS)")
    if result.kind == "polynomial" and result.curves:
        _polynomial_panel(phase, result)
    else:
        _phase_panel(phase, result)
    fig.suptitle(textwrap.fill(result.verdict, 140), fontsize=9)
    return fig


def _phase_panel(ax: Axes, result: FitResult) -> None:
    """Velocity vs position of the identified scene's run, with the data's positions on it when it has them."""
    run = result.run
    if run is None:
        ax.text(
            0.5, 0.5, "no scene run\n" + result.run_note, ha="center", va="center", transform=ax.transAxes, fontsize=8
        )
        ax.set_axis_off()
        return
    joint = result.record.joint
    x, v = run.pos[joint], run.vel[joint]
    ax.plot(x, v, "-", lw=1.0, color=_FIT, label="identified scene")
    if result.record.signal == "pos":
        offset = result.estimates.get("offset", {}).get("value", 0.0)
        delay = result.estimates.get("delay", {}).get("value", 0.0)
        record = result.record
        kept = shown(record.time.size)
        speed = np.interp(record.time[kept] - record.origin - delay, run.time, v)
        ax.plot(record.values[kept] - offset, speed, ".", ms=2, color=_DATA, label="data position, model velocity")
    ax.set_xlabel(f"{joint} position [m]")
    ax.set_ylabel(f"{joint} velocity [m/s]")
    ax.set_title("phase plane")
    legend_beside(ax, 8)


def shown(size: int, most: int = DRAWN) -> slice:
    """The samples of a series of `size` to draw: all of at most `most`, else every k-th (at most `most`): an even
    thinning keeps the density of the dots (the noise band reads true; bins' extremes would paint false edges)."""
    return slice(None, None, max(1, -(-size // most)))


def _polynomial_panel(ax: Axes, result: FitResult) -> None:
    """v(t) and a(t) of the fitted polynomial with their 95 % bands."""
    c = result.curves
    t = np.array(c["time_s"])
    for key, colour, name in (("v_m_s", "#1f77b4", "v(t) [m/s]"), ("a_m_s2", "#2ca02c", "a(t) [m/s²]")):
        value, half = np.array(c[key]), np.array(c[key + "_ci95_halfwidth"])
        ax.fill_between(t, value - half, value + half, color=colour, alpha=0.25, lw=0)
        ax.plot(t, value, "-", color=colour, label=f"{name} ± 95 %")
    ax.set_xlabel("time [s]")
    ax.set_title("velocity and acceleration of the fitted polynomial")
    legend_beside(ax, 8)
