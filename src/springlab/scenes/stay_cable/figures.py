"""The stay cable's own figure of a run (`Scene.figure`): shapes, the damper's curve, the RMS envelope, the growth.

Two panels per scenario (springlab.scenes.capabilities.figure.Panel), drawn by springlab.plots.run.scene_figure:

* `modes`: the first three mode shapes of the N-element model (dashed) on the continuum's sin(n pi x / L)
  (dotted); the deflection along the cable at instants of the run.
* `damper`: mode 1's damping ratio against the damper's coefficient (log axis): the continuum's (the
  transcendental equation), the N-element model's (its quadratic eigenproblem) and the universal curve, with
  simulated points: free decays at `SIMULATED_FACTORS` times the best damper, each measured by the modal filter
  (RK4, half a period: POINT_PERIODS), and the run's own; the mid-span deflection against time inside the exact envelope.
* `wind`: the RMS deflection along the cable, measured node by node, on the exact one (and without the damper),
  the 95 % interval at mid-span; the running RMS at mid-span against the record's length, inside the interval
  a record that long falls in (it narrows like one over the square root of the length).
* `rain_wind`: ln(amplitude / start) of the growing mode against time on Re(lambda) t; the growth rate against
  the damper's coefficient (exact), the run's point, the smallest damper that stops it and the universal estimate.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from springlab.exact import random_vibration as rv
from springlab.scenes.capabilities.case import CaseView
from springlab.scenes.capabilities.figure import Curve, Panel
from springlab.sim.simulate import Trajectory, simulate

from . import answers, build, modal, stationary
from .readback import CableModel, cable_model

#: the simulated points of the damper's curve: free decays at these multiples of the best damper
SIMULATED_FACTORS = (0.1, 0.3, 3.0, 10.0)
#: the damper's curves are drawn at this many coefficients, over this many decades either side of the best
CURVE_POINTS, CURVE_DECADES = 41, 1.5
#: a simulated point's run: this many periods of mode 1, RK4 at dt = min(DT_POINT, STABLE_FRACTION x RK4's limit).
#: RK4 keeps a mode a mode (springlab.scenes.stay_cable.modal), so the modal filter measures the same lambda over
#: any length, its round-off 100 eps / dt whatever the length: half a period drew the same points as two periods
#: (2.3e-13 relative) at a quarter of the steps (the stiffest damper's dt is 8.8e-5 s: 11,600 RK4 steps, not 46,400)
POINT_PERIODS, DT_POINT, STABLE_FRACTION = 0.5, 1e-3, 0.5
#: the wind's running RMS is drawn at this many record lengths
RUNNING_POINTS = 40
#: time curves are drawn at most at this many instants
SAMPLES = 1500


def panels(case: CaseView, trajectory: Trajectory) -> tuple[Panel, ...]:
    """The panels of a run of the case's scenario (module docstring).

    Parameters
    ----------
    case
        the case that ran.
    trajectory
        the run.

    Returns
    -------
    tuple[Panel, ...]
        two panels.
    """
    scenario = case.scenario.name
    if scenario == "modes":
        return _shapes(case), _deflection(case, trajectory)
    if scenario == "damper":
        return _damper_curve(case, trajectory), _decay(case, trajectory)
    if scenario == "wind":
        return _envelope(case, trajectory), _running(case, trajectory)
    return _growth(case, trajectory), _growth_curve(case, trajectory)


def _shapes(case: CaseView) -> Panel:
    cable = cable_model(case)
    x = np.concatenate([[0.0], cable.positions, [cable.cable.length]])
    fine = np.linspace(0.0, cable.cable.length, 400)
    curves = []
    for k in range(1, min(3, cable.size) + 1):
        shape = np.concatenate([[0.0], np.sin(np.arange(1, cable.size + 1) * k * math.pi / (cable.size + 1)), [0.0]])
        curves.append(Curve(f"mode {k}: {cable.size} nodes", x, shape, "exact"))
        curves.append(Curve(f"mode {k}: cable", fine, np.sin(k * math.pi * fine / cable.cable.length), "continuum"))
    return Panel(
        "mode shapes: N nodes (dashed) on the cable's (dotted)",
        "x [m from the deck anchor]",
        "deflection, scaled [-]",
        tuple(curves),
    )


def _along(case: CaseView, trajectory: Trajectory, instants: list[float], title: str) -> Panel:
    cable = cable_model(case)
    x = np.concatenate([[0.0], cable.positions, [cable.cable.length]])
    curves = []
    for t in instants:
        i = int(np.argmin(np.abs(trajectory.time - t)))
        curves.append(Curve(f"t = {trajectory.time[i]:.3g} s", x, np.concatenate([[0.0], trajectory.qpos[i], [0.0]])))
    return Panel(title, "x [m from the deck anchor]", "deflection [m]", tuple(curves))


def _deflection(case: CaseView, trajectory: Trajectory) -> Panel:
    period = 1.0 / cable_model(case).cable.frequencies_hz(1)[0]
    return _along(case, trajectory, [0.0, period / 8, period / 4, period / 2], "deflection along the cable (MuJoCo)")


def _mode_1_of(model: mujoco.MjModel, dt: float) -> complex:
    """Mode 1's lambda [1/s] measured by a free RK4 run of `model` started in it (the modal filter)."""
    mode = modal.modes(CableModel.of(model).lumped)[0]
    n = len(mode.right) // 2
    q0, v0, _ = mode.start(int(np.argmax(np.abs(mode.right[:n]))) + 1, 0.5)
    duration = POINT_PERIODS * 2 * math.pi / abs(mode.value)
    run = simulate(model, integrator="rk4", dt=dt, duration=duration, qpos=q0, qvel=v0)
    return modal.measured_value(mode, run.qpos, run.qvel, run.steps * dt)


def _damper_curve(case: CaseView, trajectory: Trajectory) -> Panel:
    cable = cable_model(case)
    best = case.memo("damper_optimum", lambda: answers.damper_optimum(cable))
    coefficients = best.coefficient_continuum * np.logspace(-CURVE_DECADES, CURVE_DECADES, CURVE_POINTS)
    position = cable.damper_node * cable.cable.spacing(cable.size)
    ratio, impedance = position / cable.cable.length, cable.cable.impedance
    bare = cable.without_damper()
    continuum = [
        answers.cb.damping_ratio_of(answers.cb.damped_wavenumber(1, ratio, c / impedance)) for c in coefficients
    ]
    lumped = [answers.mode_1_ratio(bare.with_damper(cable.damper_node, c)) for c in coefficients]
    universal = [answers.cb.universal_damping_ratio(1, ratio, c / impedance) for c in coefficients]
    points_c, points_zeta = [], []
    for factor in SIMULATED_FACTORS:
        c = factor * best.coefficient_continuum
        params = {**case.params, "damper_coefficient": c}
        spec = build.scaffold()
        build.generate(spec, params)
        model = spec.compile()
        fast = c / float(cable.lumped.mass[cable.damper_node - 1]) + 2 * cable.cable.wave_speed / cable.cable.spacing(
            cable.size
        )
        measured = _mode_1_of(model, min(DT_POINT, STABLE_FRACTION * 2.78 / fast))
        points_c.append(c)
        points_zeta.append(-measured.real / abs(measured))
    mode = modal.modes(cable.lumped)[0]
    measured = modal.measured_value(mode, trajectory.qpos, trajectory.qvel, trajectory.steps * trajectory.dt)
    points_c.append(cable.damper_coefficient)
    points_zeta.append(-measured.real / abs(measured))
    order = np.argsort(points_c)
    curves = (
        Curve("cable (transcendental equation)", coefficients, np.array(continuum), "continuum"),
        Curve(f"{cable.size} nodes (eigenproblem)", coefficients, np.array(lumped), "exact"),
        Curve("universal curve kappa / (1 + kappa^2)", coefficients, np.array(universal), "exact"),
        Curve(
            "MuJoCo free decays (this run and 4 more)",
            np.array(points_c)[order],
            np.array(points_zeta)[order],
            "points",
        ),
    )
    marks = ((best.coefficient_continuum, f"best damper {best.coefficient_continuum / 1e3:.4g} kN s/m"),)
    return Panel(
        f"mode 1's damping, damper at {position:.3g} m",
        "damper coefficient c_d [N s/m]",
        "damping ratio [-]",
        curves,
        marks,
        log_x=True,
    )


def _decay(case: CaseView, trajectory: Trajectory) -> Panel:
    cable = cable_model(case)
    mid = cable.midspan
    every = max(1, len(trajectory.time) // SAMPLES)
    time = trajectory.time[::every]
    mode = modal.modes(cable.lumped)[0]
    start = float(trajectory.qpos[0, mid - 1])
    envelope = abs(start) * np.exp(mode.value.real * time)
    return Panel(
        "mid-span deflection: the free decay",
        "time t [s]",
        "deflection [m]",
        (
            Curve("MuJoCo", time, trajectory.qpos[::every, mid - 1]),
            Curve("exact envelope exp(Re(lambda) t)", time, envelope, "exact"),
            Curve("", time, -envelope, "exact"),
        ),
    )


def _envelope(case: CaseView, trajectory: Trajectory) -> Panel:
    cable = cable_model(case)
    exact = stationary.wind_exact(case, trajectory.integrator, trajectory.dt)
    n = cable.size
    x = np.concatenate([[0.0], cable.positions, [cable.cable.length]])

    def padded(values: np.ndarray) -> np.ndarray:
        return np.concatenate([[0.0], values, [0.0]])

    measured = np.sqrt(np.mean(trajectory.qpos[1:] ** 2, axis=0))
    intensity = float(case.params["wind_intensity"])
    bare = case.memo(
        "wind_no_damper",
        lambda: stationary.continuous_covariance(cable, intensity, damping=cable.without_damper().damping),
    )
    mid = cable.midspan - 1
    interval = stationary.record_interval(exact, mid, trajectory.steps, stationary.REPORT_LEVEL)
    low, high = interval.rms_interval()
    return Panel(
        "RMS deflection along the cable",
        "x [m from the deck anchor]",
        "RMS deflection [m]",
        (
            Curve(f"MuJoCo, this {trajectory.steps * trajectory.dt:g} s record", x, padded(measured)),
            Curve("exact (with the damper)", x, padded(np.sqrt(np.diag(exact.continuous)[:n])), "exact"),
            Curve("exact without the damper", x, padded(np.sqrt(np.clip(np.diag(bare)[:n], 0, None))), "continuum"),
            Curve(
                "95 % interval of this record at mid-span", np.array([x[mid + 1]] * 2), np.array([low, high]), "points"
            ),
        ),
    )


def _running(case: CaseView, trajectory: Trajectory) -> Panel:
    cable = cable_model(case)
    exact = stationary.wind_exact(case, trajectory.integrator, trajectory.dt)
    mid = cable.midspan - 1
    steps = np.unique(np.geomspace(max(10, trajectory.steps // 1000), trajectory.steps, RUNNING_POINTS).astype(int))
    squares = np.cumsum(trajectory.qpos[1:, mid] ** 2)
    running = np.sqrt(squares[steps - 1] / steps)
    row = np.zeros(2 * cable.size)
    row[mid] = 1.0
    spreads = np.sqrt(np.clip(rv.record_variances(exact.held, exact.transition, row, list(steps)), 0.0, None))
    bounds = [
        rv.variance_interval(float(exact.held[mid, mid]), s, stationary.REPORT_LEVEL).rms_interval() for s in spreads
    ]
    lengths = steps * trajectory.dt
    held = math.sqrt(float(exact.held[mid, mid]))
    return Panel(
        "running RMS at mid-span: the record's scatter shrinks like 1 / sqrt(length)",
        "record length [s]",
        "RMS deflection [m]",
        (
            Curve("MuJoCo, the record so far", lengths, running),
            Curve("exact (held load)", lengths, np.full(len(lengths), held), "exact"),
            Curve("95 % interval of a record this long", lengths, np.array([b[0] for b in bounds]), "continuum"),
            Curve("", lengths, np.array([b[1] for b in bounds]), "continuum"),
        ),
        log_x=True,
    )


def _growth(case: CaseView, trajectory: Trajectory) -> Panel:
    cable = cable_model(case)
    found = modal.modes(cable.lumped)
    mode = modal.fastest_growing(found)
    every = max(1, len(trajectory.time) // SAMPLES)
    time = trajectory.time[::every]
    z = np.concatenate([trajectory.qpos[::every], trajectory.qvel[::every]], axis=1) @ np.conj(mode.left)
    return Panel(
        f"mode {mode.number}'s amplitude (modal filter)",
        "time t [s]",
        "ln(amplitude / start) [-]",
        (
            Curve("MuJoCo", time, np.log(np.abs(z) / abs(z[0]))),
            Curve(
                f"exact: Re(lambda) t, Re(lambda) = {mode.growth_rate:.4g} 1/s", time, mode.growth_rate * time, "exact"
            ),
        ),
    )


def _growth_curve(case: CaseView, trajectory: Trajectory) -> Panel:
    cable = cable_model(case)
    stop = case.memo("stabilising", lambda: answers.stabilising(cable))
    bare = cable.without_damper()
    # around mode 1's optimum on the universal curve: the stopping damper lies below it, the pinned cable above
    reference = cable.cable.impedance / (math.pi * cable.damper_position / cable.cable.length)
    coefficients = reference * np.logspace(-2.5, 1.0, CURVE_POINTS)
    rates = [bare.with_damper(cable.damper_node, c).growth_rate() for c in coefficients]
    marks = []
    if math.isfinite(stop.coefficient) and stop.coefficient > 0:
        estimate = f" (universal curve {stop.universal / 1e3:.4g})" if math.isfinite(stop.universal) else ""
        marks.append((stop.coefficient, f"least that stops it: {stop.coefficient / 1e3:.4g} kN s/m{estimate}"))
    mode = modal.fastest_growing(modal.modes(cable.lumped))
    measured = modal.measured_value(mode, trajectory.qpos, trajectory.qvel, trajectory.steps * trajectory.dt)
    here = max(cable.damper_coefficient, coefficients[0])
    return Panel(
        "growth rate against the damper",
        "damper coefficient c_d [N s/m]",
        "growth rate max Re(lambda) [1/s]",
        (
            Curve(f"{cable.size} nodes (eigenvalues)", coefficients, np.array(rates), "exact"),
            Curve("zero: neither grows nor decays", coefficients, np.zeros(len(coefficients)), "continuum"),
            Curve(
                "this run (MuJoCo)"
                + (" without a damper, drawn at the left edge" if here > cable.damper_coefficient else ""),
                np.array([here]),
                np.array([measured.real]),
                "points",
            ),
        ),
        tuple(marks),
        log_x=True,
    )
