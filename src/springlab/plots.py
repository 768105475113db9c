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
* `phase_family(scene, scenario)`: the phase trajectories of the same
  scenario released from several initial displacements (Fig. 5.11); where a
  separatrix exists the displacements straddle it, so bounded and escaping
  (or one-well and two-well) orbits appear side by side.
* `zeta_family(scene, scenario)`: the chapter's damping-ratio slider as one
  figure: x(t) and the phase plane for zeta = 0 ... 2, exact curves dashed.

Units follow the joint type: slide joints in [m] and [m/s], hinges in [rad]
and [rad/s]. The look the figures share lives in `plots_style`, what a phase
plane shows in `plots_phase`; the composite video's live phase panel is
`plots_panel.PhasePanel`.
"""

from __future__ import annotations

import os
import pathlib
from collections.abc import Sequence
from typing import Any

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from . import api, outputs, scenes
from .errors import BadInputError, DivergedError
from .plots_phase import (
    draw_phase_background,
    phase_extras,
    phase_limits,
    phase_view,
    separatrix_crossings,
    separatrix_window,
)
from .plots_style import (
    EXACT,
    SIMULATED,
    axis_labels,
    legend_outside,
    new_figure,
    scene_and_scenario,
    styled,
    title,
    units,
)
from .simulate import simulate

#: plot kinds of `springlab plot`, the first is the default
KINDS = ("time", "phase", "family", "zeta")
#: file formats `save` writes, by extension
FORMATS = (".png", ".svg", ".pdf")
#: damping ratios of the zeta family (the chapter's slider from undamped to overdamped)
ZETAS = (0.0, 0.1, 0.25, 0.5, 1.0, 2.0)
#: initial displacements of a family, as fractions of the scenario's (or of the separatrix's)
FAMILY_FRACTIONS = (0.25, 0.5, 0.75, 1.0)
FAMILY_SEPARATRIX_FRACTIONS = (0.3, 0.6, 0.9, 1.1, 1.3)
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
    outputs.prepare_directory(path.parent)
    with outputs.atomic_path(path) as temporary:
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
def time_series(result: api.Result) -> Figure:
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
    tolerance = result.summary.get("tolerance")
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
    verdict = ""
    if result.summary.get("passed") is not None:
        verdict = f", {result.summary.get('verdict') or ('PASS' if result.summary['passed'] else 'FAIL')}"
    figure.suptitle(f"{title(result)}: {result.summary['integrator']}, dt = {result.summary['dt']:g} s{verdict}")
    return figure


# -- phase plane -------------------------------------------------------------------


@styled
def phase_plane(result: api.Result) -> Figure:
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


def _family_displacements(result: api.Result, equilibria, separatrices) -> tuple[float, list[float], bool]:
    """(equilibrium [m], initial displacements [m], straddles a separatrix) for a family."""
    scene, scenario = scene_and_scenario(result)
    joint = next(iter(result.pos))
    x0 = float(result.pos[joint][0])
    stable = [e["x"] for e in equilibria if e.get("stable")] or [e["x"] for e in equilibria]
    center = min(stable, key=lambda xe: abs(xe - x0))
    offset = x0 - center
    if abs(offset) <= 1e-12 * max(1.0, abs(center)):
        # released at the equilibrium (a launch or a forced run): use the largest excursion
        excursion = result.pos[joint] - center
        offset = float(excursion[np.argmax(np.abs(excursion))])
    direction = 1.0 if offset >= 0 else -1.0
    beyond = [c - center for c in separatrix_crossings(separatrices) if (c - center) * direction > 1e-12]
    if beyond:
        boundary = min(beyond, key=abs)
        return center, [center + f * boundary for f in FAMILY_SEPARATRIX_FRACTIONS], True
    return center, [center + f * offset for f in FAMILY_FRACTIONS], False


#: a family member: (start [m], position, velocity, stopped early); None series when it diverged
Member = tuple[float, np.ndarray | None, np.ndarray | None, bool]


def _family_runs(result: api.Result, starts: Sequence[float]) -> list[Member]:
    """[(start [m], position, velocity, stopped)] of the scenario from each initial displacement.

    Each member is the scenario's own model and inputs, released from another
    displacement: through the `x0` parameter where the scene has one (so its
    setup and stop condition, e.g. an escape, see the new start), else by
    moving the joint in the scenario's initial state. Only the trajectory is
    needed, so members run through `simulate` without references or checks;
    a member that diverges is returned with None series.
    """
    scene, scenario = scene_and_scenario(result)
    joint = next(iter(result.pos))
    integrator, dt = result.summary["integrator"], result.summary["dt"]
    steps = result.trajectory.steps
    if result.trajectory.stopped:  # the scenario's own length: bounded members run it all
        steps = max(steps, int(round(scenario.duration / dt)))
    duration = steps * dt
    runs: list[Member] = []
    for start in starts:
        params = dict(result.parameters)
        if "x0" in scene.parameters:
            params["x0"] = start
        try:
            model = scene.build(params, scenario)
            setup = scene.setup(model, params, scenario, steps, dt)
            qpos = np.array(setup.qpos if setup.qpos is not None else model.qpos0, float)
            qvel = setup.qvel
            if "x0" not in scene.parameters:
                qpos[model.joint(joint).qposadr[0]] = start
                qvel = np.array(qvel if qvel is not None else np.zeros(model.nv), float)
                qvel[model.joint(joint).dofadr[0]] = 0.0
            trajectory = simulate(
                model,
                integrator=integrator,
                dt=dt,
                duration=duration,
                qpos=qpos,
                qvel=qvel,
                act=setup.act,
                control=setup.control,
                stop=scene.stop_condition(model, params, scenario),
            )
        except DivergedError:
            runs.append((start, None, None, False))
            continue
        x, v = scene.joint_columns(model, trajectory)[joint]
        runs.append((start, x, v, trajectory.stopped))
    return runs


def phase_family(
    scene: str,
    scenario: str | None = None,
    *,
    integrator: str | None = None,
    dt: float | None = None,
    duration: float | None = None,
    **parameters: Any,
) -> Figure:
    """Phase trajectories of one scenario from several initial displacements (Fig. 5.11).

    The displacements are fractions of the scenario's own initial displacement
    from its nearest stable equilibrium; where a separatrix crosses v = 0 on
    that side, they are fractions (0.3 ... 1.3) of the distance to it, so the
    family shows both sides. Members that a stop condition ends early (an
    escape to infinity) are drawn in red.

    Raises
    ------
    BadInputError
        The scene has no phase plane for this scenario (several joints or a
        time-dependent field) or no equilibrium to start from.
    """
    return family_of(api.run(scene, scenario, integrator=integrator, dt=dt, duration=duration, **parameters))


@styled
def family_of(result: api.Result) -> Figure:
    """`phase_family` of an existing run (its model, parameters, integrator and dt)."""
    field, equilibria, separatrices = phase_extras(result)
    if field is None or not equilibria:
        raise BadInputError(
            f"plot kind 'family' needs one joint, an autonomous phase field and an equilibrium; "
            f"{result.scene}/{result.scenario} has none (use --kind time or phase)"
        )
    joint = next(iter(result.pos))
    center, starts, straddles = _family_displacements(result, equilibria, separatrices)
    runs = _family_runs(result, starts)
    figure = new_figure(8.0, 5.0)
    ax = figure.subplots()
    xs = [r[1] for r in runs if r[1] is not None] + [np.asarray([e["x"] for e in equilibria])]
    vs = [r[2] for r in runs if r[2] is not None] + [np.zeros(len(equilibria))]
    sx, sv = separatrix_window(separatrices, [e["x"] for e in equilibria])
    xlim, vlim = phase_limits(xs + sx, vs + sv)
    draw_phase_background(ax, field, equilibria, separatrices, xlim, vlim)
    bounded = matplotlib.colormaps["viridis"](np.linspace(0.05, 0.8, len(runs)))
    escaping = matplotlib.colormaps["Reds"](np.linspace(0.55, 0.95, len(runs)))
    pos_unit, vel_unit = units(result.model, joint)
    fractions = FAMILY_SEPARATRIX_FRACTIONS if straddles else FAMILY_FRACTIONS
    for i, (start, x, v, stopped) in enumerate(runs):
        color = escaping[i] if stopped else bounded[i]
        label = f"{joint}(0) = {start:.4g} {pos_unit}"
        if x is None or v is None:  # diverged: both series are None
            ax.plot([], [], color="0.5", ls=":", label=f"{label} (diverged)")
            continue
        if stopped:
            label += " (escapes)"
        elif straddles:
            label += " (outside separatrix)" if fractions[i] > 1 else " (inside)"
        ax.plot(x, v, color=color, lw=1.3, zorder=3, label=label)
        ax.plot(x[:1], v[:1], "s", color=color, ms=4, zorder=6)
    pos_label, vel_label = axis_labels(result.model, joint)
    ax.set_xlabel(pos_label)
    ax.set_ylabel(vel_label)
    ax.set_title(f"joint {joint}")
    legend_outside(ax)
    what = "released on both sides of the separatrix" if straddles else "released from several displacements"
    figure.suptitle(f"{title(result)}: phase trajectories {what}")
    return figure


def _damping_per_ratio(scene_name: str, scenario_name: str | None, parameters: dict[str, Any]) -> float:
    """Damping [N s/m] per unit damping ratio of the scene's single mode (zeta is linear in d)."""
    # the number of modes first: a two-mode scenario (car pitch_heave) may not even take 'damping'
    scene, scenario, params = api.prepare(scene_name, scenario_name, parameters)
    count = len(scene.modes(scene.build(params, scenario), params, scenario))
    if count != 1:
        raise BadInputError(
            f"plot kind 'zeta' needs a one-mode scene; {scene.name}/{scenario.name} has {count} modes"
            " (use --kind time or phase)"
        )
    scene, scenario, params = api.prepare(scene_name, scenario_name, {**parameters, "damping": 1.0})
    model = scene.build(params, scenario)
    modes = scene.modes(model, params, scenario)
    if len(modes) < 1 or modes[0][1] <= 0:
        raise BadInputError(
            f"plot kind 'zeta' needs a single damped mode; {scene.name}/{scenario.name} has {len(modes)} modes"
        )
    return 1.0 / modes[0][1]


@styled
def zeta_family(
    scene: str,
    scenario: str | None = None,
    *,
    zetas: Sequence[float] = ZETAS,
    integrator: str | None = None,
    dt: float | None = None,
    duration: float | None = None,
    **parameters: Any,
) -> Figure:
    """The scenario at several damping ratios: x(t) and the phase plane, exact curves dashed.

    Damping d = zeta x (d per unit zeta), found from the scene's single mode
    (zeta is linear in d for fixed mass and stiffness), so any linear scene
    with a `damping` parameter and one mode works.

    Raises
    ------
    BadInputError
        The scene has no `damping` parameter, no exact linear reference for
        this scenario, or more than one mode.
    """
    scene_obj = scenes.get(scene)
    chosen = scene_obj.scenario(scenario)
    if "damping" not in scene_obj.parameters or not chosen.exact:
        raise BadInputError(
            f"plot kind 'zeta' needs a 'damping' parameter and an exact reference; "
            f"{scene}/{chosen.name} has not (use --kind time or phase)"
        )
    if "damping" in parameters:
        raise BadInputError("plot kind 'zeta' sets the damping itself; drop --set damping=...")
    per_ratio = _damping_per_ratio(scene, chosen.name, parameters)
    runs = []
    for zeta in zetas:
        run = api.run(
            scene, chosen.name, integrator=integrator, dt=dt, duration=duration, damping=zeta * per_ratio, **parameters
        )
        if len(run.pos) != 1 or not run.ref_pos:
            raise BadInputError(
                f"plot kind 'zeta' needs one joint with an exact reference; "
                f"{scene}/{chosen.name} reports {', '.join(run.pos)}"
            )
        runs.append((zeta, run))
    joint = next(iter(runs[0][1].pos))
    figure = new_figure(10.0, 4.4)
    ax_t, ax_p = figure.subplots(1, 2, width_ratios=[1.5, 1])
    # distinct hues in order (tab10), so neighbouring ratios (0 and 0.1) never look alike; the exact
    # solution is a thin white dash inside each coloured curve: it shows agreement without hiding the colour
    colors = [matplotlib.colormaps["tab10"](i) for i in range(len(runs))]
    for (zeta, run), color in zip(runs, colors):
        regime = run.summary["quantities"].get("regime", "")
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
    figure.suptitle(
        f"{scene} / {chosen.name}: the damping ratio ζ from 0 to {max(zetas):g} (d = {per_ratio:.4g} ζ N s/m)"
    )
    return figure


def figure_for(
    kind: str,
    scene: str,
    scenario: str | None = None,
    *,
    integrator: str | None = None,
    dt: float | None = None,
    duration: float | None = None,
    **parameters: Any,
) -> Figure:
    """The figure of one plot kind (see KINDS) for a scene's scenario."""
    if kind not in KINDS:
        raise BadInputError(f"unknown plot kind {kind!r}; valid: {', '.join(KINDS)}")
    timing: dict[str, Any] = dict(integrator=integrator, dt=dt, duration=duration)
    if kind == "family":
        return phase_family(scene, scenario, **timing, **parameters)
    if kind == "zeta":
        return zeta_family(scene, scenario, **timing, **parameters)
    result = api.run(scene, scenario, **timing, **parameters)
    return time_series(result) if kind == "time" else phase_plane(result)
