"""Plots of a run: time series, phase plane and families of runs, as static figures.

Matplotlib with the Agg canvas only, through `matplotlib.figure.Figure`
objects: nothing here touches pyplot's global state, so figures never leak
between calls and no display is ever needed.

Figures (each function returns a Figure; `save` writes it atomically):

* `time_series(result)`: per reported joint, position and velocity against
  time with the exact solution dashed on top, and |simulated - exact| on a
  log axis with the run's tolerance (relative, times max |exact|) as a line.
* `phase_plane(result)`: (position, velocity) of every reported joint: the
  simulated trajectory, the exact curve, and for scenes with a phase field
  (one joint, autonomous equations of motion) the normalized vector field,
  the equilibria (stable filled, unstable hollow) and the separatrices.
* `phase_family(family)`: the phase trajectories of one scenario released
  from several initial displacements (Fig. 5.11), bounded and escaping (or
  one-well and two-well) orbits side by side where a separatrix exists.
* `zeta_family(family)`: the chapter's damping-ratio slider as one figure:
  x(t) and the phase plane for zeta = 0 ... 2, exact curves dashed.
* `scene_figure(result)`: the panels a scene declares for its runs (`Scene.figure`, e.g. speeds with
  exact events marked, a profile along a structure, mode shapes beside the continuum's), side by side.

The families are runs, made by springlab.studies.families; nothing here
simulates. Units follow the joint type: slide joints in [m] and [m/s], hinges
in [rad] and [rad/s]. The look the figures share lives in `plots.style`, what a
phase plane shows in `plots.phase`; the composite video's live phase panel is
`plots.panel.PhasePanel`.
"""

from __future__ import annotations

import os
import pathlib
from typing import Any

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from springlab import files
from springlab.errors import BadInputError
from springlab.runs.run import Result
from springlab.studies.families import PhaseFamily, ZetaFamily

from .phase import (
    draw_phase_background,
    phase_extras,
    phase_limits,
    phase_view,
    separatrix_window,
)
from .style import EXACT, SIMULATED, axis_labels, legend_outside, new_figure, styled, title, units

#: file formats `save` writes, by extension
FORMATS = (".png", ".svg", ".pdf")
#: the exact curves of the zeta family: white dashes drawn inside each coloured curve
ZETA_EXACT: dict[str, Any] = dict(color="white", lw=0.9, ls=(0, (4, 4)))

# -- helpers ---------------------------------------------------------------------


def _positive(values: np.ndarray) -> np.ndarray:
    """Values for a log axis: exact zeros (e.g. at t = 0) become gaps, not -inf."""
    values = np.abs(np.asarray(values, float))
    return np.where(values > 0, values, np.nan)


@styled
def save(figure: Figure, output: str | os.PathLike) -> pathlib.Path:
    """Write `figure` to `output` (.png, .svg or .pdf), atomically: a complete file or none.

    Raises
    ------
    BadInputError
        Unsupported extension or unwritable folder.
    """
    path = pathlib.Path(output)
    check_output(path)
    files.prepare_directory(path.parent)
    with files.atomic_path(path) as temporary:
        figure.savefig(temporary, format=path.suffix.lower()[1:])
    return path


def check_output(path: str | os.PathLike) -> None:
    """Raise BadInputError unless `path` ends in a format `save` writes."""
    suffix = pathlib.Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise BadInputError(
            f"unsupported plot format {pathlib.Path(path).suffix or '(none)'!r} for "
            f"{str(path)!r}; use one of: {', '.join(FORMATS)}"
        )


# -- time series -------------------------------------------------------------------


@styled
def time_series(result: Result) -> Figure:
    """Position, velocity and (where an exact solution exists) the error on a log axis, per joint.

    One column per reported joint; rows: position [m or rad], velocity, and
    |simulated - exact| of both with the run's tolerance line (the tolerance
    is relative to max |exact|, so the line is tolerance x max |exact| per
    column).
    """
    joints = list(result.pos)
    has_error = bool(result.ref_pos)
    rows = 3 if has_error else 2
    figure = new_figure(4.2 * len(joints) + 1.2, 2.0 * rows + 0.6)
    axes = np.atleast_2d(figure.subplots(rows, len(joints), sharex=True, squeeze=False))
    tolerance = result.tolerance
    for column, joint in enumerate(joints):
        pos_unit, vel_unit = units(result.model, joint)
        ax_x, ax_v = axes[0, column], axes[1, column]
        ax_x.plot(result.time, result.pos[joint], label="MuJoCo", **SIMULATED)
        ax_v.plot(result.time, result.vel[joint], label="MuJoCo", **SIMULATED)
        if joint in result.ref_pos:
            ax_x.plot(result.time, result.ref_pos[joint], label="exact", **EXACT)
            ax_v.plot(result.time, result.ref_vel[joint], label="exact", **EXACT)
        pos_label, vel_label = axis_labels(result.model, joint)
        ax_x.set_ylabel(pos_label)
        ax_v.set_ylabel(vel_label)
        ax_x.set_title(f"joint {joint}")
        if has_error:
            ax_e = axes[2, column]
            if joint in result.ref_pos:
                for name, sim, ref, color, unit in (
                    ("position", result.pos[joint], result.ref_pos[joint], "C0", pos_unit),
                    ("velocity", result.vel[joint], result.ref_vel[joint], "C1", vel_unit),
                ):
                    ax_e.plot(result.time, _positive(sim - ref), color=color, lw=1.0, label=f"|{name} error| [{unit}]")
                    if tolerance is not None:
                        ax_e.axhline(
                            tolerance * float(np.max(np.abs(ref))),
                            color=color,
                            lw=0.9,
                            ls=":",
                            label=f"{name} tolerance",
                        )
                ax_e.set_yscale("log")
                ax_e.set_ylabel("|MuJoCo - exact| [m, m/s]" if pos_unit == "m" else "|MuJoCo - exact| [rad, rad/s]")
            else:
                ax_e.set_axis_off()
        axes[-1, column].set_xlabel("time t [s]")
    for row in range(rows - 1 if has_error else 1):  # legends beside the last column, never over a curve
        legend_outside(axes[row, -1])
    if has_error and axes[2, -1].get_legend_handles_labels()[0]:
        legend_outside(axes[2, -1])
    verdict = f", {result.verdict}" if result.verdict is not None else ""
    figure.suptitle(f"{title(result)}: {result.integrator}, dt = {result.dt:g} s{verdict}")
    return figure


# -- a scene's own figure --------------------------------------------------------------

#: line styles of a declared panel's curves, by Curve.kind
CURVE_STYLES: dict[str, dict[str, Any]] = {
    "simulated": dict(lw=1.5),
    "exact": dict(lw=1.1, ls=(0, (4, 3))),
    "continuum": dict(lw=1.3, ls=(0, (1, 1.5))),
    "points": dict(ls="none", marker="o", ms=6, mfc="none", mew=1.5),
}


@styled
def scene_figure(result: Result) -> Figure:
    """The panels the run's scene declares (`Scene.figure`), one beside the other.

    Raises
    ------
    BadInputError
        the scene declares no figure of its own.
    """
    scene = result.case.scene
    if scene.figure is None:
        raise BadInputError(f"{result.scene} declares no figure of its own; use --kind time or --kind phase")
    panels = scene.figure(result.case, result.trajectory)
    figure = new_figure(5.6 * len(panels) + 1.0, 4.8)
    axes = figure.subplots(1, len(panels), squeeze=False)[0]
    for ax, panel in zip(axes, panels):
        for curve in panel.curves:
            ax.plot(curve.x, curve.y, label=curve.label, **CURVE_STYLES.get(curve.kind, {}))
        for x, label in panel.marks:
            ax.axvline(x, color="0.25", lw=0.9, ls="-.")
            ax.annotate(
                label,
                (x, 1.0),
                xycoords=("data", "axes fraction"),
                rotation=90,
                va="top",
                ha="right",
                fontsize=7,
                color="0.25",
            )
        if panel.log_x:
            ax.set_xscale("log")
        ax.set_title(panel.title)
        ax.set_xlabel(panel.xlabel)
        ax.set_ylabel(panel.ylabel)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)
    verdict = f", {result.verdict}" if result.verdict is not None else ""
    figure.suptitle(f"{title(result)}: {result.integrator}, dt = {result.dt:g} s{verdict}")
    return figure


# -- phase plane -------------------------------------------------------------------


@styled
def phase_plane(result: Result) -> Figure:
    """The phase plane (position, velocity) of every reported joint (see the module docstring)."""
    joints = list(result.pos)
    figure = new_figure(5.0 * len(joints) + 1.8, 4.6)
    axes = figure.subplots(1, len(joints), squeeze=False)[0]
    for ax, joint in zip(axes, joints):
        field, equilibria, separatrices, xlim, vlim = phase_view(result, joint)
        draw_phase_background(ax, field, equilibria, separatrices, xlim, vlim)
        ax.plot(result.pos[joint], result.vel[joint], zorder=3, label="MuJoCo", **SIMULATED)
        if joint in result.ref_pos:
            ax.plot(result.ref_pos[joint], result.ref_vel[joint], zorder=4, label="exact", **EXACT)
        ax.plot(result.pos[joint][:1], result.vel[joint][:1], "s", color="C0", ms=5, zorder=6, label="start")
        pos_label, vel_label = axis_labels(result.model, joint)
        ax.set_xlabel(pos_label)
        ax.set_ylabel(vel_label)
        ax.set_title(f"phase plane of joint {joint}")
    legend_outside(axes[-1])
    figure.suptitle(f"{title(result)}: phase plane")
    return figure


# -- families ----------------------------------------------------------------------


@styled
def phase_family(family: PhaseFamily) -> Figure:
    """The phase trajectories of a family of releases (studies.families.run_phase_family), Fig. 5.11.

    Members that a stop condition ends early (an escape to infinity) are drawn in red,
    diverged ones are listed in the legend only.
    """
    result, joint, equilibria, separatrices = family.result, family.joint, family.equilibria, family.separatrices
    field = phase_extras(result)[0]
    members = family.members
    figure = new_figure(8.0, 5.0)
    ax = figure.subplots()
    xs = [m.x for m in members if m.x is not None] + [np.asarray([e["x"] for e in equilibria])]
    vs = [m.v for m in members if m.v is not None] + [np.zeros(len(equilibria))]
    sx, sv = separatrix_window(separatrices, [e["x"] for e in equilibria])
    xlim, vlim = phase_limits(xs + sx, vs + sv)
    draw_phase_background(ax, field, equilibria, separatrices, xlim, vlim)
    bounded = matplotlib.colormaps["viridis"](np.linspace(0.05, 0.8, len(members)))
    escaping = matplotlib.colormaps["Reds"](np.linspace(0.55, 0.95, len(members)))
    pos_unit, vel_unit = units(result.model, joint)
    for i, member in enumerate(members):
        color = escaping[i] if member.stopped else bounded[i]
        label = f"{joint}(0) = {member.start:.4g} {pos_unit}"
        if member.x is None or member.v is None:
            ax.plot([], [], color="0.5", ls=":", label=f"{label} (diverged)")
            continue
        if member.stopped:
            label += " (escapes)"
        elif family.straddles:
            label += " (outside separatrix)" if member.fraction > 1 else " (inside)"
        ax.plot(member.x, member.v, color=color, lw=1.3, zorder=3, label=label)
        ax.plot(member.x[:1], member.v[:1], "s", color=color, ms=4, zorder=6)
    pos_label, vel_label = axis_labels(result.model, joint)
    ax.set_xlabel(pos_label)
    ax.set_ylabel(vel_label)
    ax.set_title(f"joint {joint}")
    legend_outside(ax)
    what = "released on both sides of the separatrix" if family.straddles else "released from several displacements"
    figure.suptitle(f"{title(result)}: phase trajectories {what}")
    return figure


@styled
def zeta_family(family: ZetaFamily) -> Figure:
    """x(t) and the phase plane of a scenario at several damping ratios (studies.families.run_zeta_family),
    the exact curves dashed inside the simulated ones: the chapter's damping-ratio slider as one figure."""
    runs, joint = family.runs, family.joint
    figure = new_figure(10.0, 4.4)
    ax_t, ax_p = figure.subplots(1, 2, width_ratios=[1.5, 1])
    # distinct hues in order (tab10), so neighbouring ratios (0 and 0.1) never look alike; the exact
    # solution is a thin white dash inside each coloured curve: it shows agreement without hiding the colour
    colors = [matplotlib.colormaps["tab10"](i) for i in range(len(runs))]
    for (zeta, run), color in zip(runs, colors):
        regime = run.quantities.get("regime", "")
        label = f"ζ = {zeta:g}" + (f" ({regime})" if regime else "")
        ax_t.plot(run.time, run.pos[joint], color=color, lw=2.4, label=label)
        ax_t.plot(run.time, run.ref_pos[joint], **ZETA_EXACT)
        ax_p.plot(run.pos[joint], run.vel[joint], color=color, lw=2.0)
        ax_p.plot(run.ref_pos[joint], run.ref_vel[joint], **ZETA_EXACT)
    handles, labels = ax_t.get_legend_handles_labels()
    (under,) = ax_t.plot([], [], color="0.45", lw=2.4)
    (dashes,) = ax_t.plot([], [], **ZETA_EXACT)
    handles.append((under, dashes))  # a tuple is drawn overlaid: the white dash inside a curve
    labels.append("exact (white dashes)")
    pos_label, vel_label = axis_labels(runs[0][1].model, joint)
    ax_t.set_xlabel("time t [s]")
    ax_t.set_ylabel(pos_label)
    ax_p.set_xlabel(pos_label)
    ax_p.set_ylabel(vel_label)
    ax_p.set_title(f"phase plane of joint {joint}")
    ax_t.set_title(f"response of joint {joint}")
    figure.legend(handles, labels, loc="outside right upper", fontsize=7)
    top = max(zeta for zeta, _ in runs)
    figure.suptitle(
        f"{family.scene} / {family.scenario}: the damping ratio ζ from 0 to {top:g}"
        f" (d = {family.damping_per_ratio:.4g} ζ N s/m)"
    )
    return figure
