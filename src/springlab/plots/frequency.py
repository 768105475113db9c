"""bode.png, frequency.json and frequency.csv: what `springlab frequency` writes (reads a FrequencyResponse,
never simulates).

bode.png has three panels sharing the log-frequency axis: the magnitude (exact: black; the integrator's
discrete-time response: coloured, dashed; the sinestream's MuJoCo estimates: circles), the phase [deg], and the relative error |H_d / H - 1| with the
held input's own floor (grey, dotted) and the tolerance (dotted line). Resonances are marked (triangles,
labelled with frequency and damping ratio), anti-resonances (circles); the band within tol is shaded.
Several sinestream amplitudes: one set of circles each (a colour per amplitude). A sweep: its branches as
triangles pointing the way they were swept (up: ^, down: v), their jumps marked, and for a cubic oscillator
the first-order harmonic-balance curve (every root over the band, grey) in the magnitude panel.
"""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING

import numpy as np

from springlab.studies.frequency import FrequencyResponse

from .charts import _COLORS, _save
from .settings import legend_beside

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def plot_bode(result: FrequencyResponse, path: str | pathlib.Path) -> pathlib.Path:
    """Draw bode.png (module docstring) into `path`.

    Parameters
    ----------
    result
        the frequency response to draw.
    path
        the PNG to write.

    Returns
    -------
    pathlib.Path
        the written file.
    """
    return _save(bode_figure(result), path)


def bode_figure(result: FrequencyResponse) -> Figure:
    """The figure of bode.png (module docstring) for `result`."""
    from matplotlib.figure import Figure  # no pyplot: a caller's backend and figures stay untouched

    fig = Figure(figsize=(9, 10), layout="constrained")
    mag_ax, phase_ax, err_ax = fig.subplots(3, 1, sharex=True)
    f = result.frequencies_hz
    rows = result.rows()
    setting = f"{result.integrator} at dt = {result.dt:.3g} s"
    color = _COLORS.get(result.integrator, "#1f77b4")
    mag_ax.loglog(f, rows["exact_magnitude"], color="k", label="exact (linearization)")
    mag_ax.loglog(f, rows["discrete_magnitude"], "--", color=color, label=f"{setting} (one-step map)")
    phase_ax.semilogx(f, rows["exact_phase_deg"], color="k")
    phase_ax.semilogx(f, rows["discrete_phase_deg"], "--", color=color)
    err_ax.loglog(f, np.maximum(rows["relative_error"], 1e-17), color=color, label=f"{setting}")
    err_ax.loglog(f, np.maximum(rows["hold_error"], 1e-17), ":", color="0.5", label="held input alone (exact ZOH)")
    err_ax.axhline(result.tol, color="k", linestyle=":", linewidth=1, label=f"tol {result.tol:g}")
    stream = result.sinestream
    if len(result.sinestreams) > 1:
        _draw_amplitudes(result, mag_ax, phase_ax)
        stream = None
    if result.sweeps:
        _draw_sweeps(result, mag_ax, phase_ax)
    if stream is not None:
        estimate = stream.estimate
        mag_ax.loglog(
            stream.frequencies_hz,
            np.abs(estimate),
            "o",
            color=color,
            fillstyle="none",
            label="sinestream (MuJoCo runs)",
        )
        phase = np.degrees(np.angle(estimate))
        reference = np.interp(stream.frequencies_hz, f, rows["discrete_phase_deg"])
        phase = phase + 360.0 * np.round((reference - phase) / 360.0)  # on the unwrapped curve's branch
        phase_ax.semilogx(stream.frequencies_hz, phase, "o", color=color, fillstyle="none")
        err_ax.loglog(
            stream.frequencies_hz,
            np.maximum(np.abs(estimate / stream.exact - 1.0), 1e-17),
            "o",
            color=color,
            fillstyle="none",
            label="sinestream vs exact",
        )
    for resonance in result.resonances:
        zeta = "" if resonance.damping_ratio is None else f"\nzeta {resonance.damping_ratio:.3g}"
        mag_ax.plot(resonance.frequency_hz, resonance.magnitude, "v", color="k")
        mag_ax.annotate(
            f"{resonance.frequency_hz:.4g} Hz{zeta}",
            (resonance.frequency_hz, resonance.magnitude),
            textcoords="offset points",
            xytext=(6, 4),
            fontsize=8,
        )
    for anti in result.anti_resonances:
        mag_ax.plot(anti.frequency_hz, anti.magnitude, "o", color="#2ca02c", fillstyle="none")
        mag_ax.annotate(
            f"{anti.frequency_hz:.4g} Hz",
            (anti.frequency_hz, anti.magnitude),
            xytext=(6, -12),
            fontsize=8,
            textcoords="offset points",
        )
    if result.within_tol_hz is not None:
        for ax in (mag_ax, phase_ax, err_ax):
            ax.axvspan(*result.within_tol_hz, color=color, alpha=0.08, linewidth=0)
    mag_ax.set_ylabel(f"|H| [{result.units['response']} / {result.units['input']}]")
    phase_ax.set_ylabel("phase [deg]")
    err_ax.set_ylabel("relative error |H_d / H - 1| [-]")
    err_ax.set_xlabel("frequency [Hz]")
    legend_beside(mag_ax, 8)
    legend_beside(err_ax, 8)
    shaded = "" if result.within_tol_hz is None else f"; shaded: within tol up to {result.within_tol_hz[1]:.4g} Hz"
    fig.suptitle(f"{result.description}\n{result.source}, {setting}{shaded}", fontsize=10)
    return fig


_AMPLITUDE_COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b")


def _draw_amplitudes(result: FrequencyResponse, mag_ax, phase_ax) -> None:
    """One set of circles per sinestream amplitude."""
    unit = result.units["input"]
    for i, stream in enumerate(result.sinestreams):
        color = _AMPLITUDE_COLORS[i % len(_AMPLITUDE_COLORS)]
        f = stream.frequencies_hz
        mag_ax.loglog(
            f,
            np.abs(stream.estimate),
            "o",
            color=color,
            fillstyle="none",
            label=f"sinestream at {stream.amplitude:g} {unit}",
        )
        phase_ax.semilogx(f, np.degrees(np.angle(stream.estimate)), "o", color=color, fillstyle="none")


def _draw_sweeps(result: FrequencyResponse, mag_ax, phase_ax) -> None:
    """The sweeps' branches, their jumps and, for a cubic oscillator, the harmonic-balance curve."""
    from springlab.exact import harmonic_balance as hb

    unit = result.units["input"]
    amplitudes = sorted({b.amplitude for b in result.sweeps})
    for branch in result.sweeps:
        color = _AMPLITUDE_COLORS[amplitudes.index(branch.amplitude) % len(_AMPLITUDE_COLORS)]
        marker = "^" if branch.direction == "up" else "v"
        mag_ax.loglog(
            branch.frequencies_hz,
            np.abs(branch.estimate),
            marker,
            color=color,
            fillstyle="none" if branch.direction == "down" else "full",
            markersize=5,
            label=f"sweep {branch.direction} at {branch.amplitude:g} {unit}",
        )
        phase_ax.semilogx(
            branch.frequencies_hz,
            np.degrees(np.angle(branch.estimate)),
            marker,
            color=color,
            fillstyle="none" if branch.direction == "down" else "full",
            markersize=5,
        )
        if branch.jump_hz is not None:
            for f in branch.jump_hz:
                mag_ax.axvline(f, color=color, linestyle=":", linewidth=0.8)
    duffing = result.duffing
    if duffing is None:
        return
    lo, hi = result.band_hz
    grid = np.geomspace(lo, hi, 600)
    for amplitude in amplitudes:
        force = duffing.gain * amplitude
        f_points, h_points = [], []
        for f in grid:
            for a in hb.amplitudes(duffing, force, 2 * np.pi * f):
                f_points.append(f)
                h_points.append(a / amplitude)
        mag_ax.loglog(
            f_points, h_points, ".", color="0.5", markersize=1.5, label=f"harmonic balance at {amplitude:g} {unit}"
        )
