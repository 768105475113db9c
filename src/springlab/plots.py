"""Plots of a run: time series, phase plane, families of runs, and the composite video's panel.

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
and [rad/s].
"""

from __future__ import annotations

import functools
import os
import pathlib
from collections.abc import Sequence
from typing import Any

import matplotlib
import mujoco
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from . import api, outputs, scenes
from .errors import BadInputError, DivergedError
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

SIMULATED = dict(color="C0", lw=1.6)
EXACT = dict(color="k", lw=1.0, ls=(0, (4, 3)))
#: the exact curves of the zeta family: white dashes drawn inside each coloured curve
ZETA_EXACT = dict(color="white", lw=0.9, ls=(0, (4, 4)))
FIELD_COLOR = "0.72"
SEPARATRIX = dict(color="C3", lw=1.1, ls=(0, (6, 3)))

#: matplotlib settings of springlab's figures, applied with rc_context around each figure and save,
#: so the caller's (global) rcParams are never changed
STYLE = {"font.size": 9, "axes.titlesize": 10, "savefig.dpi": 120}


def _styled(function):
    """Run `function` inside matplotlib.rc_context(STYLE): text sizes are read when artists are made."""

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with matplotlib.rc_context(STYLE):
            return function(*args, **kwargs)

    return wrapper


# -- helpers ---------------------------------------------------------------------


def _units(model: mujoco.MjModel, joint: str) -> tuple[str, str]:
    """(position unit, velocity unit) of a joint: m, m/s for slides, rad, rad/s for hinges."""
    if model.joint(joint).type[0] == mujoco.mjtJoint.mjJNT_HINGE:
        return "rad", "rad/s"
    return "m", "m/s"


def _context(result: api.Result):
    """(Scene, Scenario) objects of a Result."""
    scene = scenes.get(result.scene)
    return scene, scene.scenario(result.scenario)


def _title(result: api.Result) -> str:
    return f"{result.scene} / {result.scenario}"


def _positive(values: np.ndarray) -> np.ndarray:
    """Values for a log axis: exact zeros (e.g. at t = 0) become gaps, not -inf."""
    values = np.abs(np.asarray(values, float))
    return np.where(values > 0, values, np.nan)


def _labels(model: mujoco.MjModel, joint: str) -> tuple[str, str]:
    """(position axis label, velocity axis label): the quantity and its unit, e.g. 'position x [m]'."""
    if model.joint(joint).type[0] == mujoco.mjtJoint.mjJNT_HINGE:
        return "angle θ [rad]", "angular velocity ω [rad/s]"
    return "position x [m]", "velocity v [m/s]"


def _legend_outside(ax) -> None:
    """Legend to the right of the axes, so it never hides an equilibrium or an orbit."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7, borderaxespad=0.0)


def _new_figure(width: float, height: float) -> Figure:
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure


@_styled
def save(figure: Figure, output: str | os.PathLike) -> pathlib.Path:
    """Write `figure` to `output` (.png, .svg or .pdf), atomically: a complete file or none.

    Raises:
      BadInputError: unsupported extension or unwritable folder.
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


@_styled
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
    figure = _new_figure(4.2 * len(joints) + 1.2, 2.0 * rows + 0.6)
    axes = np.atleast_2d(figure.subplots(rows, len(joints), sharex=True, squeeze=False))
    tolerance = result.summary.get("tolerance")
    for column, joint in enumerate(joints):
        pos_unit, vel_unit = _units(result.model, joint)
        ax_x, ax_v = axes[0, column], axes[1, column]
        ax_x.plot(result.time, result.pos[joint], label="MuJoCo", **SIMULATED)
        ax_v.plot(result.time, result.vel[joint], label="MuJoCo", **SIMULATED)
        if joint in result.ref_pos:
            ax_x.plot(result.time, result.ref_pos[joint], label="exact", **EXACT)
            ax_v.plot(result.time, result.ref_vel[joint], label="exact", **EXACT)
        pos_label, vel_label = _labels(result.model, joint)
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
        _legend_outside(axes[row, -1])
    if has_error and axes[2, -1].get_legend_handles_labels()[0]:
        _legend_outside(axes[2, -1])
    verdict = ""
    if result.summary.get("passed") is not None:
        verdict = f", {result.summary.get('verdict') or ('PASS' if result.summary['passed'] else 'FAIL')}"
    figure.suptitle(f"{_title(result)}: {result.summary['integrator']}, dt = {result.summary['dt']:g} s{verdict}")
    return figure


# -- phase plane -------------------------------------------------------------------


def _phase_limits(xs: Sequence[np.ndarray], vs: Sequence[np.ndarray], pad: float = 0.12):
    x = np.concatenate([np.ravel(a) for a in xs])
    v = np.concatenate([np.ravel(a) for a in vs])
    x, v = x[np.isfinite(x)], v[np.isfinite(v)]
    limits = []
    for values in (x, v):
        low, high = (float(values.min()), float(values.max())) if values.size else (-1.0, 1.0)
        span = high - low
        if span <= 1e-12 * max(1.0, abs(high)):
            span = max(abs(high), 1e-3)
        limits.append((low - pad * span, high + pad * span))
    return limits


def _separatrix_crossings(curves) -> list[float]:
    """Positions where the separatrices meet v = 0 (branch ends at zero velocity) [m]."""
    out = []
    for x, v in curves:
        scale = max(float(np.max(np.abs(v))), 1e-300)
        for i in (0, -1):
            if abs(v[i]) <= 1e-6 * scale:
                out.append(float(x[i]))
    return sorted(set(out))


def _phase_extras(result: api.Result):
    """(field, equilibria, separatrices) of a result's scene, or (None, [], []) for several joints."""
    scene, scenario = _context(result)
    if len(result.pos) != 1:
        return None, [], []
    field = scene.phase_field(result.model, result.parameters, scenario)
    if field is None:
        return None, [], []
    return (
        field,
        scene.equilibria(result.model, result.parameters, scenario),
        scene.separatrices(result.model, result.parameters, scenario),
    )


def _separatrix_window(curves, center_xs: Sequence[float]):
    """Separatrix points worth keeping in view: those within the span of the crossings."""
    crossings = _separatrix_crossings(curves) + list(center_xs)
    if not crossings or not curves:
        return [], []
    low, high = min(crossings), max(crossings)
    margin = 0.1 * max(high - low, 1e-9)
    xs, vs = [], []
    for x, v in curves:
        keep = (x >= low - margin) & (x <= high + margin)
        xs.append(x[keep])
        vs.append(v[keep])
    return xs, vs


def draw_phase_background(ax, field, equilibria, separatrices, xlim, vlim, *, arrows: int = 21) -> None:
    """Vector field (normalized arrows, grey), separatrices and equilibria on `ax` within the limits."""
    if field is not None:
        gx, gv = np.meshgrid(np.linspace(xlim[0], xlim[1], arrows), np.linspace(vlim[0], vlim[1], int(arrows * 0.8)))
        with np.errstate(all="ignore"):
            dx, dv = field(gx, gv)
            dx, dv = np.broadcast_to(dx, gx.shape), np.broadcast_to(dv, gx.shape)
            # direction on screen: scale by the axis spans before normalizing
            sx, sv = dx / (xlim[1] - xlim[0]), dv / (vlim[1] - vlim[0])
            norm = np.hypot(sx, sv)
            norm = np.where(norm > 0, norm, 1.0)
        ax.quiver(
            gx,
            gv,
            sx / norm,
            sv / norm,
            color=FIELD_COLOR,
            angles="uv",
            pivot="mid",
            scale=arrows * 1.4,
            width=0.0035,
            headwidth=3.5,
            headlength=4,
            zorder=1,
            label="equations of motion",
        )
    for i, (x, v) in enumerate(separatrices):
        ax.plot(x, v, zorder=2, label="separatrix" if i == 0 else None, **SEPARATRIX)
    stable = [e["x"] for e in equilibria if e.get("stable")]
    unstable = [e["x"] for e in equilibria if not e.get("stable")]
    if stable:
        ax.plot(stable, np.zeros(len(stable)), "o", color="k", ms=7, zorder=5, label="stable equilibrium")
    if unstable:
        ax.plot(
            unstable,
            np.zeros(len(unstable)),
            "o",
            mfc="white",
            mec="k",
            mew=1.5,
            ms=7,
            zorder=5,
            label="unstable equilibrium",
        )
    ax.set_xlim(*xlim)
    ax.set_ylim(*vlim)


def _phase_view(result: api.Result, joint: str):
    """Everything a phase plane of one joint needs: field, equilibria, separatrices, limits."""
    field, equilibria, separatrices = _phase_extras(result)
    xs = [result.pos[joint]]
    vs = [result.vel[joint]]
    if joint in result.ref_pos:
        xs.append(result.ref_pos[joint])
        vs.append(result.ref_vel[joint])
    eq_x = [e["x"] for e in equilibria]
    if eq_x:
        xs.append(np.asarray(eq_x))
        vs.append(np.zeros(len(eq_x)))
    sx, sv = _separatrix_window(separatrices, eq_x)
    xlim, vlim = _phase_limits(xs + sx, vs + sv)
    return field, equilibria, separatrices, xlim, vlim


@_styled
def phase_plane(result: api.Result) -> Figure:
    """The phase plane (position, velocity) of every reported joint (see the module docstring)."""
    joints = list(result.pos)
    figure = _new_figure(5.0 * len(joints) + 1.8, 4.6)
    axes = figure.subplots(1, len(joints), squeeze=False)[0]
    for ax, joint in zip(axes, joints):
        field, equilibria, separatrices, xlim, vlim = _phase_view(result, joint)
        draw_phase_background(ax, field, equilibria, separatrices, xlim, vlim)
        ax.plot(result.pos[joint], result.vel[joint], zorder=3, label="MuJoCo", **SIMULATED)
        if joint in result.ref_pos:
            ax.plot(result.ref_pos[joint], result.ref_vel[joint], zorder=4, label="exact", **EXACT)
        ax.plot(result.pos[joint][:1], result.vel[joint][:1], "s", color="C0", ms=5, zorder=6, label="start")
        pos_label, vel_label = _labels(result.model, joint)
        ax.set_xlabel(pos_label)
        ax.set_ylabel(vel_label)
        ax.set_title(f"phase plane of joint {joint}")
    _legend_outside(axes[-1])
    figure.suptitle(f"{_title(result)}: phase plane")
    return figure


# -- families ----------------------------------------------------------------------


def _family_displacements(result: api.Result, equilibria, separatrices) -> tuple[float, list[float], bool]:
    """(equilibrium [m], initial displacements [m], straddles a separatrix) for a family."""
    scene, scenario = _context(result)
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
    beyond = [c - center for c in _separatrix_crossings(separatrices) if (c - center) * direction > 1e-12]
    if beyond:
        boundary = min(beyond, key=abs)
        return center, [center + f * boundary for f in FAMILY_SEPARATRIX_FRACTIONS], True
    return center, [center + f * offset for f in FAMILY_FRACTIONS], False


def _family_runs(result: api.Result, starts: Sequence[float]):
    """[(start [m], position, velocity, stopped)] of the scenario from each initial displacement.

    Each member is the scenario's own model and inputs, released from another
    displacement: through the `x0` parameter where the scene has one (so its
    setup and stop condition, e.g. an escape, see the new start), else by
    moving the joint in the scenario's initial state. Only the trajectory is
    needed, so members run through `simulate` without references or checks;
    a member that diverges is returned with None series.
    """
    scene, scenario = _context(result)
    joint = next(iter(result.pos))
    integrator, dt = result.summary["integrator"], result.summary["dt"]
    steps = result.trajectory.steps
    if result.trajectory.stopped:  # the scenario's own length: bounded members run it all
        steps = max(steps, int(round(scenario.duration / dt)))
    duration = steps * dt
    runs = []
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

    Raises:
      BadInputError: the scene has no phase plane for this scenario (several
        joints or a time-dependent field) or no equilibrium to start from.
    """
    return family_of(api.run(scene, scenario, integrator=integrator, dt=dt, duration=duration, **parameters))


@_styled
def family_of(result: api.Result) -> Figure:
    """`phase_family` of an existing run (its model, parameters, integrator and dt)."""
    field, equilibria, separatrices = _phase_extras(result)
    if field is None or not equilibria:
        raise BadInputError(
            f"plot kind 'family' needs one joint, an autonomous phase field and an equilibrium; "
            f"{result.scene}/{result.scenario} has none (use --kind time or phase)"
        )
    joint = next(iter(result.pos))
    center, starts, straddles = _family_displacements(result, equilibria, separatrices)
    runs = _family_runs(result, starts)
    figure = _new_figure(8.0, 5.0)
    ax = figure.subplots()
    xs = [r[1] for r in runs if r[1] is not None] + [np.asarray([e["x"] for e in equilibria])]
    vs = [r[2] for r in runs if r[2] is not None] + [np.zeros(len(equilibria))]
    sx, sv = _separatrix_window(separatrices, [e["x"] for e in equilibria])
    xlim, vlim = _phase_limits(xs + sx, vs + sv)
    draw_phase_background(ax, field, equilibria, separatrices, xlim, vlim)
    bounded = matplotlib.colormaps["viridis"](np.linspace(0.05, 0.8, len(runs)))
    escaping = matplotlib.colormaps["Reds"](np.linspace(0.55, 0.95, len(runs)))
    pos_unit, vel_unit = _units(result.model, joint)
    fractions = FAMILY_SEPARATRIX_FRACTIONS if straddles else FAMILY_FRACTIONS
    for i, (start, x, v, stopped) in enumerate(runs):
        color = escaping[i] if stopped else bounded[i]
        label = f"{joint}(0) = {start:.4g} {pos_unit}"
        if x is None:
            ax.plot([], [], color="0.5", ls=":", label=f"{label} (diverged)")
            continue
        if stopped:
            label += " (escapes)"
        elif straddles:
            label += " (outside separatrix)" if fractions[i] > 1 else " (inside)"
        ax.plot(x, v, color=color, lw=1.3, zorder=3, label=label)
        ax.plot(x[:1], v[:1], "s", color=color, ms=4, zorder=6)
    pos_label, vel_label = _labels(result.model, joint)
    ax.set_xlabel(pos_label)
    ax.set_ylabel(vel_label)
    ax.set_title(f"joint {joint}")
    _legend_outside(ax)
    what = "released on both sides of the separatrix" if straddles else "released from several displacements"
    figure.suptitle(f"{_title(result)}: phase trajectories {what}")
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


@_styled
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

    Raises:
      BadInputError: the scene has no `damping` parameter, no exact linear
        reference for this scenario, or more than one mode.
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
    figure = _new_figure(10.0, 4.4)
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
    pos_label, vel_label = _labels(runs[0][1].model, joint)
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


# -- the composite video's panel ------------------------------------------------------


class PhasePanel:
    """`render_video(panel=...)` callback: the phase plane with the trace drawn as time advances.

    The static background (axes, vector field, equilibria, separatrices, the
    exact curve in light dashes) is drawn once by matplotlib into an image;
    each frame then only draws the new piece of the trace and the current
    point into it with Pillow (a few hundred microseconds per frame), so the
    panel costs far less than the 3D view beside it.

    Args:
      result: the run being rendered.
      height: panel height [px] (= the 3D view's height).
      width: panel width [px] (default: `height`, a square panel).
      joints: joints to show, one phase plane each, stacked (default: every
        reported joint, at most 3).
    """

    @_styled
    def __init__(self, result: api.Result, height: int, width: int | None = None, joints: Sequence[str] | None = None):
        from PIL import Image, ImageDraw

        self.result = result
        self.height = int(height)
        self.width = int(width or height)
        self.joints = list(joints or list(result.pos)[:3])
        dpi = 100.0
        scale = min(1.6, max(0.5, self.height / 400.0))  # labels legible at 360 px, not crowding 120 px
        figure = Figure(figsize=(self.width / dpi, self.height / dpi), dpi=dpi, layout="constrained")
        canvas = FigureCanvasAgg(figure)
        axes = figure.subplots(len(self.joints), 1, squeeze=False)[:, 0]
        for ax, joint in zip(axes, self.joints):
            field, equilibria, separatrices, xlim, vlim = _phase_view(result, joint)
            draw_phase_background(ax, field, equilibria, separatrices, xlim, vlim, arrows=17)
            if joint in result.ref_pos:
                ax.plot(
                    result.ref_pos[joint],
                    result.ref_vel[joint],
                    color="0.45",
                    lw=0.8,
                    ls=(0, (3, 3)),
                    zorder=2,
                    label="exact",
                )
            pos_label, vel_label = _labels(result.model, joint)
            ax.set_xlabel(pos_label, fontsize=8 * scale)
            ax.set_ylabel(vel_label, fontsize=8 * scale)
            ax.tick_params(labelsize=7 * scale)
            ax.set_title(f"phase plane: {joint}", fontsize=9 * scale)
        canvas.draw()
        self._background = Image.fromarray(np.asarray(canvas.buffer_rgba())[:, :, :3].copy())
        if self._background.size != (self.width, self.height):  # Agg rounds the figure size
            self._background = self._background.resize((self.width, self.height))
        # data -> pixel maps of each axes (display y is bottom-up; image rows are top-down)
        self._maps = [ax.transData.frozen() for ax in axes]
        self._canvas = self._background.copy()
        self._draw = ImageDraw.Draw(self._canvas)
        self._ImageDraw = ImageDraw
        self._last: list[np.ndarray | None] = [None] * len(self.joints)  # each joint's newest pixel
        self._next_sample = 0
        self._line = max(2, round(2 * scale))
        self._dot = max(4, round(5 * scale))
        self._color = tuple(int(255 * c) for c in matplotlib.colors.to_rgb("C0"))

    def _pixels(self, index: int, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        points = self._maps[index].transform(np.column_stack([x, v]))
        points[:, 1] = self.height - points[:, 1]
        return points

    def __call__(self, frame: int, t: float) -> np.ndarray:
        """The panel image (height x width x 3 uint8) at time t [s]; frames must come in time order."""
        time = self.result.time
        end = int(np.searchsorted(time, t, side="right"))  # samples with time <= t
        for index, joint in enumerate(self.joints):
            x, v = self.result.pos[joint], self.result.vel[joint]
            xt, vt = float(np.interp(t, time, x)), float(np.interp(t, time, v))
            new = self._pixels(
                index, np.append(x[self._next_sample : end], xt), np.append(v[self._next_sample : end], vt)
            )
            previous = self._last[index]
            if previous is not None:
                new = np.vstack([previous, new])
            if len(new) > 1:
                self._draw.line([tuple(p) for p in new], fill=self._color, width=self._line, joint="curve")
            self._last[index] = new[-1:]
        self._next_sample = end
        image = self._canvas.copy()
        draw = self._ImageDraw.Draw(image)
        for last in self._last:
            assert last is not None  # every joint got its newest pixel in the loop above
            cx, cy = last[0]
            r = self._dot
            draw.ellipse((cx - r, cy - r, cx + r, cy + r), fill=(214, 39, 40), outline=(0, 0, 0))
        return np.asarray(image)
