"""printer_head's inputs and what follows them: the scenarios' variants, the move, the settling.

Each scenario carries its variant (`Scenario.variant`), as the car's do: `Move` (the bang-bang
move, then settling), `ShapedMove` (the same move convolved with an input shaper), `StepForce` (a
held force) and `Settle` (a release from a stretched belt); feedback.py and resonance_test.py hold
the closed-loop and the resonance test's. A variant gives the run's setup, its exact reference and
the quantities that differ; these open-loop ones share `Segmented`, which builds both from the
motor's force segments. The formulas of the move and of the residual vibration live here too; the
design study shares them.
Masses [kg], stiffness [N/m], damping [N s/m], forces [N], times [s], positions [m].
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.exact import analytic, events, positioning, shaping
from springlab.scenes.declarations import Reference
from springlab.sim.simulate import Setup, Trajectory

if TYPE_CHECKING:
    from springlab.scenes.base import Case


def move_profile(params: dict[str, float], dt: float) -> tuple[int, float]:
    """(steps per half-move n, force [N]) of the bang-bang move on a grid of dt [s].

    The half-move time is the minimum sqrt(D M / F) rounded up to whole steps,
    and the force is lowered to M D / (n dt)^2 so the centre of mass stops at D.
    """
    total = params["carriage_mass"] + params["motor_mass"]
    half = math.sqrt(params["move_distance"] * total / params["drive_force"])
    n = max(1, math.ceil(half / dt - 1e-9))
    force = min(params["drive_force"], total * params["move_distance"] / (n * dt) ** 2)
    return n, force


@dataclasses.dataclass(frozen=True)
class BeltRun:
    """What a variant's quantities read of one run: its parameters, the belt mode and the joints' columns.

    Masses [kg], stiffness [N/m], omega_n [rad/s], zeta [-], dt and time [s], positions [m], velocities [m/s];
    the case and the trajectory for what a variant reads beyond them (its sensors, its exact loop).
    """

    params: dict[str, float]
    m_c: float
    m_m: float
    k: float
    omega_n: float
    zeta: float
    dt: float
    time: np.ndarray
    q_c: np.ndarray
    v_c: np.ndarray
    q_m: np.ndarray
    v_m: np.ndarray
    case: Case | None = None
    trajectory: Trajectory | None = None


def belt_matrices(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass [kg], damping [N s/m] and stiffness [N/m] matrices in (q_c, q_m) of `model`."""
    belt = model.tendon("belt").id  # (MjModel's tendon view names these _stiffness, _damping)
    m_c, m_m = float(model.body("carriage").mass[0]), float(model.body("motor").mass[0])
    k, c = float(model.tendon_stiffness[belt]), float(model.tendon_damping[belt])
    coupling = np.array([[1.0, -1.0], [-1.0, 1.0]])  # the belt stretches by q_m - q_c
    return np.diag([m_c, m_m]), c * coupling, k * coupling


def initial_state(params: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """(q0 [m], v0 [m/s]) in (q_c, q_m): belt stretched by `deflection`, centre of mass at rest at 0."""
    m_c, m_m = params["carriage_mass"], params["motor_mass"]
    s0 = params["deflection"]
    return np.array([-m_m * s0, m_c * s0]) / (m_c + m_m), np.zeros(2)


def initial_qpos_qvel(case: Case) -> tuple[np.ndarray, np.ndarray]:
    """The model's (qpos, qvel) of `initial_state` (the joints `carriage` and `motor`)."""
    model = case.model
    q0, v0 = initial_state(case.params)
    qpos, qvel = np.zeros(model.nq), np.zeros(model.nv)
    for joint, q, v in zip(("carriage", "motor"), q0, v0):
        qpos[model.joint(joint).qposadr[0]] = q
        qvel[model.joint(joint).dofadr[0]] = v
    return qpos, qvel


class Variant:
    """What a printer_head scenario's variant gives (PrinterHead delegates to it).

    `parameters`: the scene parameters only this variant reads (others' are refused, check_consistency);
    `instruments`: whether its model carries the encoders and the accelerometer (control.add_instruments);
    `derive(params, explicit)`: presets computed from the other parameters (Scenario.derive);
    `check(params)`: non-physical combinations (ParameterError); `setup`, `reference`, `quantities`.
    """

    parameters: frozenset[str] = frozenset()
    instruments = False

    def derive(self, params: dict[str, float], explicit: set[str]) -> dict[str, float]:
        """Presets from the other parameters (none by default)."""
        return {}

    def check(self, params: dict[str, float]) -> None:
        """Raise ParameterError for a combination the variant cannot run (none by default)."""

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        """The run's initial state and inputs."""
        raise NotImplementedError

    def reference(self, case: Case, time: np.ndarray, dt: float) -> Reference:
        """The exact solution at `time` [s] of a run with timestep dt [s]."""
        raise NotImplementedError

    def quantities(self, out: dict, run: BeltRun) -> dict:
        """The variant's quantities added to the scene's `out`."""
        raise NotImplementedError


class Segmented(Variant):
    """An open-loop variant: the motor's force is piecewise constant, switched on step boundaries (`segments`).

    Its run holds segment i from step round(breaks[i] / dt) on (exact for every integrator's order), and its
    reference is the two-mass model's exact response (analytic.linear_response), with the state matrix of
    z = (q_c, q_m, v_c, v_m, F) for the derived tolerance (the force a generator state, constant within each step).
    """

    def segments(self, params: dict[str, float], dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(breakpoints [s], motor force per segment [N])."""
        raise NotImplementedError

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        """The initial state (`initial_state`) and the force segments as per-step controls."""
        qpos, qvel = initial_qpos_qvel(case)
        breaks, forces = self.segments(case.params, dt)
        # segment i holds from step round(breaks[i]/dt): switches on step boundaries are exact
        first = np.round(breaks / dt).astype(int)
        control = np.zeros((steps, case.model.nu))
        for start, force in zip(first, forces):
            control[min(start, steps) :, 0] = force
        return Setup(qpos=qpos, qvel=qvel, control=control)

    def reference(self, case: Case, time: np.ndarray, dt: float) -> Reference:
        """The exact response to the segments from `initial_state` (class docstring)."""
        mass, damping, stiffness = belt_matrices(case.model)
        q0, v0 = initial_state(case.params)
        breaks, forces = self.segments(case.params, dt)  # the move switches on the run's own grid
        values = np.column_stack([np.zeros_like(forces), forces])  # the motor joint carries the force
        q, v = analytic.linear_response(time, mass, damping, stiffness, q0, v0, force=(breaks, values))
        inverse = np.linalg.inv(mass)
        system = np.zeros((5, 5))
        system[0:2, 2:4] = np.eye(2)
        system[2:4, 0:2] = -inverse @ stiffness
        system[2:4, 2:4] = -inverse @ damping
        system[2:4, 4] = inverse @ np.array([0.0, 1.0])
        segment = np.clip(np.searchsorted(breaks, time, side="right") - 1, 0, len(forces) - 1)
        states = np.column_stack([q, v, forces[segment]])
        return Reference(
            pos={"carriage": q[:, 0], "motor": q[:, 1]},
            vel={"carriage": v[:, 0], "motor": v[:, 1]},
            system=system,
            states=states,
            rows={"carriage": (0, 2), "motor": (1, 3)},
        )


class StepForce(Segmented):
    """step_force's variant (Scenario.variant): drive_force [N] from rest, held; no settling."""

    def segments(self, params: dict[str, float], dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(breakpoints [s], motor force per segment [N]): one step at t = 0."""
        return np.array([0.0]), np.array([params["drive_force"]])

    def quantities(self, out: dict, run: BeltRun) -> dict:
        """The rigid-body acceleration [m/s^2] and the belt's static and largest stretch [m]."""
        total = run.m_c + run.m_m
        force = run.params["drive_force"]
        out["rigid_acceleration_m_s2"] = force / total
        out["static_belt_stretch_m"] = force * run.m_c / (total * run.k)
        out["max_belt_stretch_m"] = float(np.max(np.abs(run.q_m - run.q_c)))
        return out


class _Settling(Segmented):
    """A variant whose force ends, after which the carriage settles about a target (move, settle).

    `quantities` measures the settling into +-positioning_band from the step `release` returns,
    certified by the belt-energy bound, and the analytic estimate; the subclasses say what came before.
    """

    def segments(self, params: dict[str, float], dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(breakpoints [s], motor force per segment [N]) of the scenario's input."""
        raise NotImplementedError

    def release(self, out: dict, run: BeltRun) -> tuple[float, int]:
        """(target [m], first step of the force-free motion); records what the input did in `out`."""
        raise NotImplementedError

    def residual_stretch(self, run: BeltRun, start: int) -> tuple[float, float]:
        """Belt stretch [m] and rate [m/s] once the force is off, for the estimate: the measured ones."""
        return run.q_m[start] - run.q_c[start], run.v_m[start] - run.v_c[start]

    def positioning(self, out: dict, settling: float) -> float | None:
        """Positioning time [s] of a settling time [s] (None: no move to add it to)."""
        return None

    def quantities(self, out: dict, run: BeltRun) -> dict:
        """Residual amplitude [m], settling time [s] (inf unless settled for good) and their estimates."""
        m_c, m_m, k, q_c, q_m = run.m_c, run.m_m, run.k, run.q_c, run.q_m
        total = m_c + m_m
        band = run.params["positioning_band"]
        out["settling_band_m"] = band
        target, start = self.release(out, run)
        if start >= len(q_c):
            out["settled_for_good"] = False
            out["settling_time_s"] = math.inf
            return out
        time, deviation, velocity = run.time[start:] - run.time[start], q_c[start:] - target, run.v_c[start:]
        # force off from `start` on: the motion is smooth there, its peaks between samples interpolated
        out["residual_amplitude_m"] = events.peak_magnitude(time, deviation, velocity)
        centre = (m_c * q_c[-1] + m_m * q_m[-1]) / total
        stretch, stretch_rate = q_m[-1] - q_c[-1], run.v_m[-1] - run.v_c[-1]
        bound = after_force_bound(centre - target, stretch, stretch_rate, m_c, m_m, k)
        out["final_deviation_bound_m"] = float(bound)
        out["settled_for_good"] = bool(bound <= band)
        settle = settling_time(time, deviation, velocity, band)
        out["settling_time_s"] = settle if out["settled_for_good"] else math.inf
        positioning = self.positioning(out, out["settling_time_s"])
        if positioning is not None:
            out["positioning_time_s"] = positioning
        # the analytic estimate: envelope of the residual vibration down to the band
        if run.zeta < 1.0 and k > 0:
            s0, s0_rate = self.residual_stretch(run, start)
            envelope = residual_envelope(s0, s0_rate, m_c, m_m, run.omega_n, run.zeta)
            out["residual_envelope_m"] = envelope
            out["settling_time_estimate_s"] = settling_estimate(envelope, band, run.zeta, run.omega_n)
            positioning = self.positioning(out, out["settling_time_estimate_s"])
            if positioning is not None:
                out["positioning_time_estimate_s"] = positioning
        return out


class Move(_Settling):
    """move's variant (Scenario.variant): the bang-bang move of move_distance on the step grid, then settling."""

    def segments(self, params: dict[str, float], dt: float) -> tuple[np.ndarray, np.ndarray]:
        """+F for n steps, -F for n steps, then 0 (PrinterHead.move_profile)."""
        n, force = move_profile(params, dt)
        return np.array([0.0, n * dt, 2 * n * dt]), np.array([force, -force, 0.0])

    def release(self, out: dict, run: BeltRun) -> tuple[float, int]:
        """The move's distance [m], force [N] and times [s]; it ends at move_distance after 2 n steps."""
        params, dt = run.params, run.dt
        n, force = move_profile(params, dt)
        end = 2 * n
        out["move_distance_m"] = params["move_distance"]
        out["move_force_n"] = force
        out["move_time_s"] = end * dt
        out["minimum_move_time_s"] = minimum_move_time(
            params["move_distance"], run.m_c + run.m_m, params["drive_force"]
        )
        # an undamped belt is left vibrating at 4 sin^2(omega_n T / 4) times the static stretch:
        # nothing when each half of the move lasts a whole number of belt periods
        out["half_move_belt_periods"] = n * dt * run.omega_n / (2 * math.pi)
        return params["move_distance"], end

    def residual_stretch(self, run: BeltRun, start: int) -> tuple[float, float]:
        """The exact stretch [m] and rate [m/s] at the end of the move (move_residual_stretch)."""
        return move_residual_stretch(run.params, run.dt)

    def positioning(self, out: dict, settling: float) -> float | None:
        """Move time + settling time [s]."""
        return out["move_time_s"] + settling


#: the shaped moves' own parameters: the shaper's design point (defaults: the belt mode's own)
SHAPER_PARAMETERS = frozenset({"shaper_frequency_hz", "shaper_damping_ratio"})


@functools.lru_cache(maxsize=64)
def applied_shaper(name: str, frequency_hz: float, damping_ratio: float, dt: float) -> shaping.Shaper:
    """The shaper `name` designed at (frequency_hz [Hz], damping_ratio [-]) as a command held over steps of dt [s]
    applies it (shaping.on_grid: impulses split onto the step grid, its defining equations restored)."""
    return shaping.on_grid(shaping.make_shaper(name, frequency_hz, damping_ratio), dt)


class ShapedMove(Move):
    """move_zv, move_mzv, move_zvd, move_ei's variant: the bang-bang move convolved with an input shaper.

    The shaper is designed at `shaper_frequency_hz` and `shaper_damping_ratio` (defaults: the belt mode's own,
    from the masses and the belt) and applied on the step grid (`applied_shaper`): the shaped force
    (shaping.shape_command) switches on step boundaries, so every integrator keeps its order, and the
    quantities report the shaper actually applied (`shaper_times_s`, `shaper_amplitudes`).

    Exact, per run: the carriage rings after the shaped command as Re(Z S e^(s tau)), Z the unshaped move's
    phasor and S = sum_i A_i e^(s (t_N - t_i)) the shaper's factor on the true belt mode (|S| = V, its residual
    vibration): `residual_amplitude_m_exact` is the largest deviation of that ring-down (positioning.peak_after)
    beside MuJoCo's `residual_amplitude_m`, `residual_vibration` is V, and `positioning_time_s` (the carriage
    inside +-band for good, from t = 0: a shaped move is often inside before its command ends) has its exact
    `positioning_time_s_exact` (positioning.positioning_time of the same command).
    """

    parameters = SHAPER_PARAMETERS

    def __init__(self, shaper: str) -> None:
        self.shaper = shaper

    def derive(self, params: dict[str, float], explicit: set[str]) -> dict[str, float]:
        """The shaper's design point: the belt mode's natural frequency [Hz] and damping ratio [-]."""
        m_c, m_m, k = params["carriage_mass"], params["motor_mass"], params["belt_stiffness"]
        return {
            "shaper_frequency_hz": float(belt_omega(k, m_c, m_m)) / (2 * math.pi),
            "shaper_damping_ratio": belt_damping_ratio(params["belt_damping"], k, m_c, m_m),
        }

    def check(self, params: dict[str, float]) -> None:
        """The design point must give a shaper (shaping's ranges: zeta < 1, EI's zeta <= 0.3)."""
        try:
            shaping.make_shaper(self.shaper, params["shaper_frequency_hz"], params["shaper_damping_ratio"])
        except ValueError as error:
            raise ParameterError(str(error)) from None

    def applied(self, params: dict[str, float], dt: float) -> shaping.Shaper:
        """The shaper on the grid of dt [s] (ParameterError: a dt too coarse for it)."""
        try:
            return applied_shaper(self.shaper, params["shaper_frequency_hz"], params["shaper_damping_ratio"], dt)
        except ValueError as error:
            raise ParameterError(str(error)) from None

    def segments(self, params: dict[str, float], dt: float) -> tuple[np.ndarray, np.ndarray]:
        """The bang-bang move's segments convolved with the applied shaper (all on the step grid)."""
        breaks, forces = shaping.shape_command(*super().segments(params, dt), self.applied(params, dt))
        return np.round(breaks / dt) * dt, forces  # on the grid to round-off, as the run switches them

    def release(self, out: dict, run: BeltRun) -> tuple[float, int]:
        """The move's quantities, the shaper's, and the command's end: 2 n steps plus the shaper's last impulse."""
        target, end = super().release(out, run)
        shaper = self.applied(run.params, run.dt)
        delay = int(round(shaper.duration / run.dt))
        out["shaper"] = self.shaper
        out["shaper_frequency_hz"] = shaper.frequency_hz
        out["shaper_damping_ratio"] = shaper.damping_ratio
        out["shaper_duration_s"] = delay * run.dt
        out["shaper_times_s"] = [float(t) for t in shaper.times]
        out["shaper_amplitudes"] = [float(a) for a in shaper.amplitudes]
        out["command_time_s"] = end * run.dt + delay * run.dt
        out["residual_vibration"] = float(
            shaping.residual_vibration(shaper.amplitudes, shaper.times, run.omega_n, run.zeta)
        )
        return target, end + delay

    def residual_stretch(self, run: BeltRun, start: int) -> tuple[float, float]:
        """The measured stretch [m] and rate [m/s] at the command's end (the estimate's starting point)."""
        return _Settling.residual_stretch(self, run, start)

    def positioning(self, out: dict, settling: float) -> float | None:
        """The shaped command's time + settling time [s]."""
        return out["command_time_s"] + settling

    def quantities(self, out: dict, run: BeltRun) -> dict:
        """Move's quantities, the exact ring-down of the shaped command, and positioning counted from t = 0."""
        out = super().quantities(out, run)
        breaks, forces = self.segments(run.params, run.dt)
        total = run.m_c + run.m_m
        accelerations = forces / total
        if run.zeta < 1.0:
            phasor = positioning.residual_phasor(run.omega_n, run.zeta, breaks, accelerations)
            out["residual_amplitude_m_exact"] = positioning.peak_after(phasor, run.omega_n, run.zeta)
            out["residual_envelope_m_exact"] = abs(phasor)
            band = run.params["positioning_band"]
            out["positioning_time_s_exact"] = positioning.positioning_time(
                run.omega_n, run.zeta, breaks, accelerations, band
            )
            if out["settled_for_good"]:
                deviation = run.q_c - run.params["move_distance"]
                out["positioning_time_s"] = events.last_exit(run.time, deviation, run.v_c, band)
        return out


class Settle(_Settling):
    """settle's variant (Scenario.variant): no force; released at rest from the belt stretch `deflection`."""

    def segments(self, params: dict[str, float], dt: float) -> tuple[np.ndarray, np.ndarray]:
        """No force at all."""
        return np.array([0.0]), np.array([0.0])

    def release(self, out: dict, run: BeltRun) -> tuple[float, int]:
        """Released at t = 0: the centre of mass stays at 0; the carriage starts `initial_deviation_m` off it."""
        out["initial_deviation_m"] = abs(float(run.q_c[0]))
        return 0.0, 0


# -- formulas shared with the design study ------------------------------------------


def reduced_mass(carriage_mass: float | np.ndarray, motor_mass: float | np.ndarray) -> float | np.ndarray:
    """Reduced mass mu = m_c m_m / (m_c + m_m) [kg] of the belt mode (floats or arrays)."""
    return carriage_mass * motor_mass / (carriage_mass + motor_mass)


def belt_damping_for(
    damping_ratio: float | np.ndarray,
    stiffness: float | np.ndarray,
    carriage_mass: float | np.ndarray,
    motor_mass: float | np.ndarray,
) -> float | np.ndarray:
    """Belt damping c = 2 zeta sqrt(k mu) [N s/m] giving the belt mode `damping_ratio` [-] (floats or arrays)."""
    return 2.0 * damping_ratio * np.sqrt(stiffness * reduced_mass(carriage_mass, motor_mass))


def belt_damping_ratio(damping: float, stiffness: float, carriage_mass: float, motor_mass: float) -> float:
    """The belt mode's damping ratio zeta = c / (2 sqrt(k mu)) [-] of belt damping c [N s/m]."""
    return damping / (2.0 * math.sqrt(stiffness * reduced_mass(carriage_mass, motor_mass)))


def belt_omega(
    stiffness: float | np.ndarray, carriage_mass: float | np.ndarray, motor_mass: float | np.ndarray
) -> float | np.ndarray:
    """The belt mode's undamped natural frequency omega_n = sqrt(k / mu) [rad/s] (floats or arrays)."""
    return np.sqrt(stiffness / reduced_mass(carriage_mass, motor_mass))


def residual_envelope(
    stretch: float, stretch_rate: float, carriage_mass: float, motor_mass: float, omega_n: float, zeta: float
) -> float:
    """Envelope A [m] of the carriage's residual vibration A e^(-zeta omega_n t) once the force is off.

    The carriage moves (m_m / M) times the belt stretch s; a damped free vibration from (s, s') has
    amplitude hypot(s, (s' + zeta omega_n s) / omega_d), omega_d = omega_n sqrt(1 - zeta^2).
    """
    omega_d = omega_n * math.sqrt(1 - zeta * zeta)
    share = motor_mass / (carriage_mass + motor_mass)
    return share * math.hypot(stretch, (stretch_rate + zeta * omega_n * stretch) / omega_d)


def minimum_move_time(distance: float, mass: float, force: float) -> float:
    """Minimum time [s] of a rigid move of `distance` [m] of `mass` [kg] at force limit `force` [N].

    Bang-bang: accelerate for half the time at +F, decelerate at -F: T = 2 sqrt(D m / F).
    """
    return 2.0 * math.sqrt(distance * mass / force)


def settling_estimate(envelope: float, band: float, zeta: float, omega_n: float) -> float:
    """Time [s] for a vibration envelope `envelope` e^(-zeta omega_n t) [m] to shrink into `band` [m].

    ln(envelope / band) / (zeta omega_n), 0 if already inside, inf if undamped. For a
    release at rest from amplitude a0 the envelope is a0 / sqrt(1 - zeta^2), giving
    the chapter-style ln(1 / (band / a0 sqrt(1 - zeta^2))) / (zeta omega_n).
    """
    if envelope <= band:
        return 0.0
    if zeta <= 0.0:
        return math.inf
    return math.log(envelope / band) / (zeta * omega_n)


def after_force_bound(
    centre_offset: float | np.ndarray,
    stretch: float | np.ndarray,
    stretch_rate: float | np.ndarray,
    carriage_mass: float | np.ndarray,
    motor_mass: float | np.ndarray,
    stiffness: float | np.ndarray,
) -> float | np.ndarray:
    """Bound [m] on the carriage's future distance from the target once the force is off.

    The carriage is q_c = X - (m_m / M) s; with no force the centre of mass X
    stays where it is (at rest after a bang-bang move or a release) and the belt
    energy E = mu s'^2 / 2 + k s^2 / 2 cannot grow, so |s| <= sqrt(2 E / k) for
    ever and |q_c - target| <= |X - target| + (m_m / M) sqrt(2 E / k).

    Every argument may be a float or an array (elementwise).

    Parameters
    ----------
    centre_offset
        X - target [m].
    stretch, stretch_rate
        Belt stretch s [m] and its rate s' [m/s].
    carriage_mass, motor_mass
        [kg].
    stiffness
        Belt stiffness k [N/m].
    """
    total = carriage_mass + motor_mass
    reduced = carriage_mass * motor_mass / total
    energy = 0.5 * reduced * stretch_rate**2 + 0.5 * stiffness * stretch**2
    return np.abs(centre_offset) + (motor_mass / total) * np.sqrt(2.0 * energy / stiffness)


def settling_time(time: np.ndarray, deviation: np.ndarray, velocity: np.ndarray, band: float) -> float:
    """Time [s] after which |deviation| [m] stays within `band` [m] in this record, between samples too.

    The last exit of the continuous motion from the band: the cubic Hermite interpolant of
    the deviation and its velocity [m/s] (`events.last_exit`, O(dt^4)), so a vibration peak
    that crosses the band between two samples inside it counts (read at the samples it would
    not: a peak reads low by about (omega_n dt)^2 / 8 of the amplitude, and the settling time
    early by half a belt period). time[0] if the record never leaves the band.
    """
    return events.last_exit(time, deviation, velocity, band)


def move_residual_stretch(params: dict[str, float], dt: float) -> tuple[float, float]:
    """Exact belt stretch [m] and rate [m/s] at the end of the bang-bang move on a grid of dt [s].

    The belt mode obeys mu s'' + c s' + k s = (m_c / M) F(t) with F = +F', -F', 0 on
    [0, T/2), [T/2, T), [T, ...): superposed step responses (analytic), from the
    initial stretch `deflection` at rest.
    """
    m_c, m_m = params["carriage_mass"], params["motor_mass"]
    k, c = params["belt_stiffness"], params["belt_damping"]
    total, reduced = m_c + m_m, m_c * m_m / (m_c + m_m)
    n, force = move_profile(params, dt)
    half = n * dt
    modal = force * m_c / total
    t = np.array([2 * half])
    s, v = analytic.step_response(t, reduced, k, c, modal, params["deflection"], 0.0)
    s2, v2 = analytic.step_response(t - half, reduced, k, c, -2.0 * modal)
    return float(s[0] + s2[0]), float(v[0] + v2[0])
