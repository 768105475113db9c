"""The printer head's design question (chapter section 5.7): how fast can the carriage be positioned,
and which properties matter? Its declaration (`DESIGN`, the scene's `design`) and the hooks the design
study (springlab.studies.design) calls: the batched move simulation and the analytic estimates.

A configuration is a value of each swept property (belt_stiffness k [N/m], carriage_mass m_c [kg],
damping_ratio zeta [-], drive_force F [N], and, for the Sobol study only, move_distance D [m]) on top
of the scene's `move` parameters; the study builds the configurations, this module runs them.

How the runs are made: one `mujoco.batch.Batch` holds every configuration as
its own simulation, with per-simulation carriage mass (body_mass), belt
stiffness and damping (tendon_stiffness, tendon_damping), force limit
(actuator_ctrlrange) and timestep (opt.timestep). Each simulation gets
dt <= omega_dt / omega_n of its own belt mode (RK4; omega_dt = 0.1: at least 63
steps per period, relative phase error (omega dt)^4 / 120 = 1e-6 per radian), so
every configuration is resolved equally well and slow ones take no more steps
than fast ones; dt also divides the minimum half-move time sqrt(D M / F)
exactly, so every configuration makes the true minimum-time move at its full
force (rounding the switch onto a fixed grid would shift the residual
vibration's phase, and with it the settling time, with the resolution). The runs
advance in chunks of steps through `Batch.rollout` (controls (n, steps, 1), the
bang-bang switches on each simulation's own step grid) and a simulation stops as
soon as its settling is certified: once the move is over the carriage stays
within |X - D| + (m_m / M) sqrt(2 E / k) of the target for ever
(`after_force_bound`), and when that is inside the band its last exit from the
band is final.

The last exit is the continuous motion's, not the samples': each step
interval's largest excursion is that of the cubic Hermite interpolant of the
carriage's position and velocity (`events.hermite_peaks`, O(dt^4): 2.6e-7 of the
amplitude at omega_dt = 0.1), and the exit time that interpolant's root
(`events.band_exit`). Read at the samples a peak reads low by (omega_n dt)^2 / 8
= 1.25e-3 of the amplitude, and whether a peak that passes the band by less
than that counts decides half a period of settling time: 8 of the 2401 default
configurations were early by 1.8-4.9 ms (peaks 1.2e-4 and 7.5e-4 above the
band; tests/scenes/printer_head/test_printer_head_settling.py). Every configuration now settles
within 2.3 us of the exact motion's last exit; between omega_dt = 0.1 and 0.2,
5 differ by more than one step (26 when read at the samples): the peaks
1.2e-4 above the band, within RK4's error at 0.2 (16 times its error at 0.1).

The analytic estimate beside every simulated time:

    T ~= 2 sqrt(D M / F) + ln(A / band) / (zeta omega_n)

the minimum bang-bang move time plus the time for the residual vibration's
envelope A e^(-zeta omega_n t) to shrink into the band, with A the exact
envelope of the carriage's residual vibration after the (grid-aligned) move
(for a release at rest from a0, A = a0 / sqrt(1 - zeta^2): the chapter's
ln(1 / (band / a0 sqrt(1 - zeta^2))) / (zeta omega_n)). A worst-case form needs
no simulation at all: whatever the move's phase on the belt, the damped belt's
residual envelope after the minimum-time move T = 2 sqrt(D M / F) is at most
A_w = (F / M) (1 + e^(-zeta omega_n T / 2))^2 / (omega_n^2 sqrt(1 - zeta^2))
(springlab.exact.positioning.worst_case_envelope; undamped it is the old
4 F m_c m_m / (M^2 k), from 4 sin^2(omega_n T / 4) times the static stretch), so

    T_worst = 2 sqrt(D M / F) + ln(A_w / band) / (zeta omega_n)

(92.1 ms at the defaults; the undamped envelope said 116.5 ms).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from springlab.errors import DivergedError
from springlab.exact import events, positioning
from springlab.scenes.capabilities.case import CaseView
from springlab.scenes.capabilities.design import DesignProperty, DesignSpec, MoveEstimates, MoveRuns
from springlab.sim.simulate import quiet_mujoco

from .moves import (
    after_force_bound,
    belt_damping_for,
    belt_damping_ratio,
    belt_omega,
    minimum_move_time,
    move_profile,
    move_residual_stretch,
    residual_envelope,
    settling_estimate,
)

#: steps per batched rollout call
CHUNK = 256
#: the properties the belt damping of a configuration is computed from
_BELT_PROPERTIES = ("belt_stiffness", "carriage_mass", "damping_ratio")


def belt_damping(values: Mapping[str, np.ndarray], motor_mass: float) -> np.ndarray:
    """Belt damping c = 2 zeta sqrt(k mu) [N s/m] of each configuration.

    Parameters
    ----------
    values
        property -> (n,) values (belt_stiffness [N/m], carriage_mass [kg], damping_ratio [-]).
    motor_mass
        [kg].

    Returns
    -------
    np.ndarray
        (n,) belt damping [N s/m].
    """
    m_c = np.asarray(values["carriage_mass"], float)
    # asarray: belt_damping_for takes floats or arrays; these are arrays
    return np.asarray(
        belt_damping_for(np.asarray(values["damping_ratio"]), np.asarray(values["belt_stiffness"]), m_c, motor_mass)
    )


def config_parameters(base: Mapping[str, float], values: Mapping[str, np.ndarray], i: int) -> dict[str, float]:
    """The scene parameters (SI) of configuration i (belt damping from its damping ratio)."""
    params = dict(base)
    for name in ("belt_stiffness", "carriage_mass", "drive_force", "move_distance"):
        if name in values:  # move_distance: only the Sobol study varies it
            params[name] = float(values[name][i])
    params["belt_damping"] = float(
        belt_damping({n: np.atleast_1d(values[n][i]) for n in _BELT_PROPERTIES}, base["motor_mass"])[0]
    )
    return params


def move_distances(base: Mapping[str, float], values: Mapping[str, np.ndarray]) -> np.ndarray:
    """(n,) move distance [m] per configuration: values["move_distance"] if varied, else the base's."""
    n = len(values["belt_stiffness"])
    return np.broadcast_to(np.asarray(values.get("move_distance", base["move_distance"]), float), (n,)).copy()


def timesteps(values: Mapping[str, np.ndarray], base: Mapping[str, float], omega_dt: float) -> np.ndarray:
    """Each configuration's timestep [s]: at most omega_dt / omega_n of its belt mode, and a whole
    fraction of its minimum half-move time sqrt(D M / F), so the bang-bang switches fall on the step
    grid exactly and every configuration makes the true minimum-time move at its full force (a
    rounded switch time would shift the residual vibration's phase with the resolution)."""
    m_c = np.asarray(values["carriage_mass"], float)
    motor_mass = base["motor_mass"]
    total = m_c + motor_mass
    largest = omega_dt / belt_omega(np.asarray(values["belt_stiffness"]), m_c, motor_mass)
    half = np.sqrt(move_distances(base, values) * total / np.asarray(values["drive_force"], float))
    return half / np.ceil(half / largest)


def move_profiles(
    base: Mapping[str, float], values: Mapping[str, np.ndarray], dt: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(steps per half-move, force [N]) per configuration, as the scene's `move_profile`."""
    half_steps = np.empty(len(dt), int)
    force = np.empty(len(dt))
    for i in range(len(dt)):
        half_steps[i], force[i] = move_profile(config_parameters(base, values, i), float(dt[i]))
    return half_steps, force


def simulate_moves(
    model: mujoco.MjModel,
    base: Mapping[str, float],
    values: Mapping[str, np.ndarray],
    *,
    omega_dt: float,
    nthread: int = 0,
    chunk: int = CHUNK,
    max_duration: float,
) -> MoveRuns:
    """Run the `move` scenario for every configuration in one mujoco.batch.Batch.

    Parameters
    ----------
    model
        the `move` scenario compiled at `base` (not changed: the batch runs a copy set to RK4).
    base
        scene parameters (move_distance [m], positioning_band [m], motor_mass [kg], ...).
    values
        property -> (n,) values (the declared properties).
    omega_dt
        omega_n dt [-] of every simulation (RK4).
    nthread
        batch threads (0: one per CPU).
    chunk
        steps per rollout call.
    max_duration
        simulated time [s] after which an unsettled configuration is given up.

    Returns
    -------
    MoveRuns
        per configuration: move, settling and positioning time [s], residual amplitude [m], dt [s], steps.

    Raises
    ------
    DivergedError
        a simulation blew up (MuJoCo's warning counters rose).
    """
    params = dict(base)
    model = copy.copy(model)
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    n = len(values["belt_stiffness"])
    m_m = params["motor_mass"]
    m_c = np.asarray(values["carriage_mass"], float)
    total = m_c + m_m
    stiffness = np.asarray(values["belt_stiffness"], float)
    limit = np.asarray(values["drive_force"], float)
    distance, band = move_distances(params, values), params["positioning_band"]
    dt = timesteps(values, params, omega_dt)
    half_steps, force = move_profiles(params, values, dt)
    move_steps = 2 * half_steps

    stretch0 = params["deflection"]
    batch = _move_batch(model, n, nthread, m_c, m_m, stiffness, belt_damping(values, m_m), limit, dt, stretch0)
    carriage = model.joint("carriage").qposadr[0]
    motor = model.joint("motor").qposadr[0]

    steps = np.zeros(n, int)  # steps taken by each simulation
    # the current state's carriage deviation from the target [m] and velocity [m/s]
    deviation_now = np.full(n, -m_m * stretch0 / total - distance)
    velocity_now = np.zeros(n)
    # the last step interval in which the carriage is outside the band, between samples too: its first
    # state index and the Hermite data (deviation, velocity at both ends); -1: none yet
    exit_step = np.full(n, -1)
    exit_data = np.zeros((n, 4))
    residual = np.zeros(n)
    settled = np.zeros(n, bool)
    active = np.arange(n)
    offsets = np.arange(chunk)
    while active.size:
        taken = steps[active][:, None] + offsets[None, :]  # index of each step about to be taken
        half = half_steps[active][:, None]
        f = force[active][:, None]
        control = np.where(taken < half, f, np.where(taken < 2 * half, -f, 0.0))[..., None]
        with quiet_mujoco():
            record = batch.rollout(chunk, control, record=("qpos", "qvel"), ids=active)
        if np.any(batch.warning[active, :, 1] > 0):
            bad = active[np.any(batch.warning[active, :, 1] > 0, axis=1)]
            raise DivergedError(f"design sweep: {len(bad)} simulations diverged (first: configuration {bad[0]})")
        qpos, qvel = record["qpos"], record["qvel"]
        # the chunk's step intervals [current state, chunk end]: each one's largest excursion from the
        # target between its samples (cubic Hermite in position and velocity, O(dt^4)): a peak that crosses
        # the band between two samples inside it is an exit (read at the samples it reads low by about
        # (omega dt)^2 / 8 = 1.25e-3 of the amplitude, and the positioning time early by half a period)
        y = np.column_stack([deviation_now[active], qpos[:, :, carriage] - distance[active][:, None]])
        v = np.column_stack([velocity_now[active], qvel[:, :, carriage]])
        peaks, _ = events.hermite_peaks(dt[active][:, None], y[:, :-1], y[:, 1:], v[:, :-1], v[:, 1:])
        outside = peaks > band
        rows = np.flatnonzero(outside.any(axis=1))
        col = chunk - 1 - np.argmax(outside[rows, ::-1], axis=1)  # the last interval outside
        exit_step[active[rows]] = steps[active[rows]] + col
        exit_data[active[rows]] = np.column_stack([y[rows, col], y[rows, col + 1], v[rows, col], v[rows, col + 1]])
        # the residual vibration: the intervals after the end of the move (force off)
        after = taken >= move_steps[active][:, None]
        residual[active] = np.maximum(residual[active], np.max(np.where(after, peaks, 0.0), axis=1))
        deviation_now[active], velocity_now[active] = y[:, -1], v[:, -1]
        steps[active] += chunk
        # certify: force off, and the energy bound inside the band
        q_c, q_m = qpos[:, -1, carriage], qpos[:, -1, motor]
        v_c, v_m = qvel[:, -1, carriage], qvel[:, -1, motor]
        centre = (m_c[active] * q_c + m_m * q_m) / total[active]
        bound = after_force_bound(centre - distance[active], q_m - q_c, v_m - v_c, m_c[active], m_m, stiffness[active])
        certified = (steps[active] >= move_steps[active]) & (bound <= band)
        settled[active[certified]] = True
        active = active[~certified & (steps[active] * dt[active] <= max_duration)]

    # the last exit from the band: the root of the last interval outside (a certified run ends inside)
    last_exit = _last_exits(settled, exit_step, exit_data, dt, band)
    move_time = move_steps * dt
    settling = np.where(settled, np.maximum(last_exit - move_time, 0.0), np.inf)
    return MoveRuns(
        move_time_s=move_time,
        settling_time_s=settling,
        positioning_time_s=move_time + settling,
        residual_amplitude_m=residual,
        dt_s=dt,
        steps=steps,
        nthread=int(batch.nthread),
    )


def _move_batch(
    model: mujoco.MjModel,
    n: int,
    nthread: int,
    carriage_mass: np.ndarray,
    motor_mass: float,
    stiffness: np.ndarray,
    damping: np.ndarray,
    limit: np.ndarray,
    dt: np.ndarray,
    stretch0: float,
) -> Any:
    """The mujoco.batch.Batch of `simulate_moves`: one simulation per configuration, its carriage mass [kg],
    belt stiffness [N/m] and damping [N s/m], drive limit [N] and timestep [s], started with the belt
    stretched by `stretch0` [m] and the centre of mass at rest at 0 (as the scene)."""
    from mujoco import batch as mjbatch  # here: importing the scenes must not load mujoco.batch

    total = carriage_mass + motor_mass
    with quiet_mujoco():
        batch = mjbatch.Batch(model, nsim=n, nthread=nthread)
        batch.body("carriage").mass = carriage_mass[:, None]
        belt = model.tendon("belt").id
        batch.expand("tendon_stiffness")[:, belt] = stiffness
        batch.expand("tendon_damping")[:, belt] = damping
        batch.actuator("drive").ctrlrange = np.column_stack([-limit, limit])
        batch.expand("opt.timestep")[:] = dt
        batch.set_const()
        batch.joint("carriage").qpos = (-motor_mass * stretch0 / total)[:, None]
        batch.joint("motor").qpos = (carriage_mass * stretch0 / total)[:, None]
    return batch


def _last_exits(
    settled: np.ndarray, exit_step: np.ndarray, exit_data: np.ndarray, dt: np.ndarray, band: float
) -> np.ndarray:
    """The time [s] of each settled configuration's last exit from the band: the root of its last step
    interval outside it (Hermite data in `exit_data`); 0 where it never left or never settled."""
    last_exit = np.zeros(len(settled))
    for i in np.flatnonzero(settled & (exit_step >= 0)):
        t0 = exit_step[i] * dt[i]
        y0, y1, v0, v1 = exit_data[i]
        last_exit[i] = events.band_exit(t0, t0 + dt[i], y0, y1, v0, v1, band)
    return last_exit


def estimates(base: Mapping[str, float], values: Mapping[str, np.ndarray], dt: np.ndarray) -> MoveEstimates:
    """(estimate [s], worst-case estimate [s], natural frequency [Hz]) per configuration.

    estimate: realized move time + ln(A / band) / (zeta omega_n), A the exact
    residual envelope after the grid-aligned move; worst case: the minimum move
    time T = 2 sqrt(D M / F) + ln(A_w / band) / (zeta omega_n), A_w the damped belt's
    largest envelope after a move of T whatever its phase (module docstring).
    """
    n = len(dt)
    estimate, worst, frequency = np.empty(n), np.empty(n), np.empty(n)
    m_m, band = base["motor_mass"], base["positioning_band"]
    for i in range(n):
        params = config_parameters(base, values, i)
        m_c, k, force = params["carriage_mass"], params["belt_stiffness"], params["drive_force"]
        total = m_c + m_m
        omega = float(belt_omega(k, m_c, m_m))
        zeta = float(values["damping_ratio"][i])
        frequency[i] = omega / (2 * math.pi)
        half_steps, _ = move_profile(params, float(dt[i]))
        stretch, rate = move_residual_stretch(params, float(dt[i]))
        envelope = residual_envelope(stretch, rate, m_c, m_m, omega, zeta)
        estimate[i] = 2 * half_steps * dt[i] + settling_estimate(envelope, band, zeta, omega)
        shortest = minimum_move_time(params["move_distance"], total, force)
        worst_envelope = positioning.worst_case_envelope(omega, zeta, params["move_distance"], shortest)
        worst[i] = shortest + settling_estimate(worst_envelope, band, zeta, omega)
    return MoveEstimates(estimate_s=estimate, worst_case_estimate_s=worst, natural_frequency_hz=frequency)


class PrinterHeadDesign:
    """The printer head's `DesignHooks`: the belt formulas of .moves and the batched move above."""

    def defaults(self, base: Mapping[str, float]) -> dict[str, float]:
        """The properties at `base` (SI): the damping ratio from the belt damping."""
        m_c, m_m = base["carriage_mass"], base["motor_mass"]
        return {
            "belt_stiffness": base["belt_stiffness"],
            "carriage_mass": m_c,
            "damping_ratio": belt_damping_ratio(base["belt_damping"], base["belt_stiffness"], m_c, m_m),
            "drive_force": base["drive_force"],
            "move_distance": base["move_distance"],
        }

    def parameters_for(self, name: str, value: float, base: Mapping[str, float]) -> dict[str, float]:
        """The belt damping c = 2 zeta sqrt(k m_c m_m / (m_c + m_m)) [N s/m] of damping ratio zeta [-].

        Raises
        ------
        KeyError
            `name` is not the derived property damping_ratio.
        """
        if name != "damping_ratio":
            raise KeyError(name)
        reduced = base["carriage_mass"] * base["motor_mass"] / (base["carriage_mass"] + base["motor_mass"])
        return {"belt_damping": 2.0 * value * math.sqrt(base["belt_stiffness"] * reduced)}

    def simulate(
        self, case: CaseView, values: Mapping[str, np.ndarray], *, omega_dt: float, nthread: int, max_duration: float
    ) -> MoveRuns:
        """`simulate_moves` of the case's model at its parameters (module docstring)."""
        return simulate_moves(
            case.model, case.params, values, omega_dt=omega_dt, nthread=nthread, max_duration=max_duration
        )

    def estimates(self, base: Mapping[str, float], values: Mapping[str, np.ndarray], dt: np.ndarray) -> MoveEstimates:
        """`estimates` (module docstring)."""
        return estimates(base, values, dt)

    def setting(self, base: Mapping[str, float]) -> str:
        """The move and its band, e.g. '25.4 mm to +-10 um'."""
        return f"{base['move_distance'] * 1e3:.4g} mm to +-{base['positioning_band'] * 1e6:.3g} um"

    def answer(self, summary: Mapping[str, Any]) -> str:
        """The two design questions answered in words, with the study's numbers."""
        d = summary["default"]
        e = summary["elasticities"]
        fixed = summary["fixed"]
        return (
            f"How fast? With the defaults (carriage {d['properties']['carriage_mass']:.3g} kg, motor side "
            f"{fixed['motor_mass']:.3g} kg, belt {d['properties']['belt_stiffness']:.3g} N/m at zeta = "
            f"{d['properties']['damping_ratio']:.3g}, belt mode {d['natural_frequency_hz']:.0f} Hz, "
            f"{d['properties']['drive_force']:.3g} N) a {fixed['move_distance'] * 1e3:.4g} mm move to "
            f"±{fixed['positioning_band'] * 1e6:.3g} µm takes {d['positioning_time_s'] * 1e3:.1f} ms: "
            f"{d['move_time_s'] * 1e3:.1f} ms of bang-bang move (the minimum at this force) and "
            f"{d['settling_time_s'] * 1e3:.1f} ms of settling (estimate {d['estimate_s'] * 1e3:.1f} ms total, "
            f"worst case {d['worst_case_estimate_s'] * 1e3:.1f} ms). Over the {summary['configurations']} "
            f"configurations it ranges from {summary['positioning_time_s']['min'] * 1e3:.1f} ms to "
            f"{summary['positioning_time_s']['max'] * 1e3:.0f} ms. Which properties? By elasticity d ln T / d ln p: "
            + ", ".join(f"{p} {e[p]:+.2f}" for p in summary["ranking"])
            + "."
        )


#: the printer head's design question (`PrinterHead.design`): the spans go from softer/narrower to
#: steel-cord belts (x/4..x4), a bare head to a head with large cartridges (x/2..x2), belt rubber to an
#: added damper (x/3..x3), a weaker motor to a stronger one (x/4..x4), and, for the Sobol study, a
#: quarter inch to four inches of move (x/4..x4)
DESIGN = DesignSpec(
    question="How fast can the print head be positioned, and which system properties play an important role?",
    scenario="move",
    properties=(
        DesignProperty("belt_stiffness", "N/m", 4.0, "belt stiffness k [N/m]"),
        DesignProperty("carriage_mass", "kg", 2.0, "carriage mass m_c [kg]"),
        DesignProperty(
            "damping_ratio",
            "-",
            3.0,
            "belt damping ratio zeta [-]",
            parameter="belt_damping",
            description="damping ratio",
            minimum=0.0,
        ),
        DesignProperty("drive_force", "N", 4.0, "drive force F [N]"),
    ),
    fixed=("motor_mass", "move_distance", "positioning_band"),
    hooks=PrinterHeadDesign(),
    merit="positioning time",
    extra=(DesignProperty("move_distance", "m", 4.0, "move distance D [m]"),),
    sobol=("carriage_mass", "belt_stiffness", "damping_ratio", "drive_force", "move_distance"),
)
