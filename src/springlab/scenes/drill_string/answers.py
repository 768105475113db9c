"""The drill string's exact answers shared by its scene and its figure: the drive, the rod, the events.

Everything here reads the compiled model (springlab.scenes.drill_string.lumped for M and K, the numerics for
the rod) and solves exactly: the N-element model's stick-slip solution and the continuum's travelling waves
are cached, since a run's quantities, checks and figure all ask for them.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import math
from typing import Any

import mujoco
import numpy as np
import scipy.linalg

from springlab.exact import events
from springlab.scenes.capabilities.case import CaseView
from springlab.sim.simulate import Trajectory

from . import build, continuum
from .lumped import GRID_PER_PERIOD, LumpedString, ModalFlow, maximum


def _optimize():  # noqa: ANN202 - the module
    """scipy.optimize, imported on first use: every command imports the scene registry, which must stay light."""
    import scipy.optimize

    return scipy.optimize


#: frequencies reported by `modes`
REPORTED_MODES = 5
#: modes of the continuum's series in `spin_up` (its truncation bound is reported beside it)
CONTINUUM_MODES = 4096
#: the continuum's bit speed is compared at most at this many instants of a run
CONTINUUM_SAMPLES = 1500
#: the re-stick, one definition for the run, the exact solutions, the checks and the figure: after breaking free
#: (and once faster than this), the bit's speed falls below this fraction of the top drive's speed. A run can
#: observe nothing sharper (MuJoCo's friction is regularized: a stuck bit creeps), and whether the exact bit then
#: stays stuck or turns on at a crawl is beside the question the scene asks
RESTICK_FRACTION = 0.01
#: the breakaway, likewise one definition: the string's torque on the stuck bit first reaches its friction T_f
#: rad/s per rpm
RPM = 2 * math.pi / 60


@dataclasses.dataclass(frozen=True)
class Drive:
    """The top drive's start-up as a run realizes it: constant acceleration for `ramp_steps` steps.

    Attributes
    ----------
    speed
        the final speed [rad/s].
    ramp_time
        the realized ramp [s] (ramp_steps dt).
    acceleration
        speed / ramp_time [rad/s^2].
    ramp_steps
        steps of the ramp.
    """

    speed: float
    ramp_time: float
    acceleration: float
    ramp_steps: int


def rod_of(model: mujoco.MjModel) -> continuum.Rod:
    """The continuum the model discretizes: L, G, rho, J_p from its numerics, J_b from the bit's inertia."""
    numbers = {name: float(model.numeric(name).data[0]) for name in ("length", "shear_modulus", "density")}
    jp = build.polar_moment(
        float(model.numeric("outer_diameter").data[0]), float(model.numeric("inner_diameter").data[0])
    )
    lumped = LumpedString.of(model)
    elements = lumped.size - 1
    # the bit's node carries half an element of pipe besides the BHA
    half = numbers["density"] * jp * numbers["length"] / elements / 2.0
    return continuum.Rod(numbers["length"], numbers["shear_modulus"], numbers["density"], jp, lumped.mass[-1] - half)


def lumped_of(case: CaseView) -> LumpedString:
    """The case's N-element model (M, K, friction, drive), read back once per case."""
    return case.memo("lumped", lambda: LumpedString.of(case.model))


def modes_of(case: CaseView) -> tuple[np.ndarray, np.ndarray]:
    """(w [rad/s], shapes) of the case's flexible modes (`LumpedString.modes`), solved once per case."""

    def solve() -> tuple[np.ndarray, np.ndarray]:
        omega, shapes = lumped_of(case).modes()
        for array in (omega, shapes):
            array.setflags(write=False)  # shared by the case's reference, checks, quantities and figure
        return omega, shapes

    return case.memo("lumped_modes", solve)


def rod_of_case(case: CaseView) -> continuum.Rod:
    """The continuum the case's model discretizes (`rod_of`), read back once per case."""
    return case.memo("rod", lambda: rod_of(case.model))


def drive_of(model: mujoco.MjModel, dt: float) -> Drive:
    """The top drive's start-up on a step grid of dt [s]."""
    speed = float(model.numeric("top_speed_rpm").data[0]) * RPM
    steps = max(1, round(float(model.numeric("spin_up_time").data[0]) / dt))
    return Drive(speed, steps * dt, speed / (steps * dt), steps)


def frequencies(lumped: LumpedString) -> np.ndarray:
    """w [rad/s] of the flexible modes, ascending, from the tridiagonal M^-1/2 K M^-1/2 (O(N^2), any N)."""
    scale = 1.0 / np.sqrt(lumped.mass)
    diagonal = np.diag(lumped.stiffness) * scale**2
    off = np.diag(lumped.stiffness, 1) * scale[:-1] * scale[1:]
    values = scipy.linalg.eigh_tridiagonal(diagonal, off, eigvals_only=True)
    return np.sqrt(np.clip(np.sort(values)[1:], 0.0, None))


def measured_frequency(time: np.ndarray, angle: np.ndarray, speed: np.ndarray) -> float:
    """The frequency [Hz] of the bit's free oscillation: zero crossings of its angle, both ways (O(dt^4))."""
    down = events.down_crossings(time, angle, speed)
    up = events.down_crossings(time, -angle, -speed)
    crossings = np.sort(np.concatenate([down, up]))
    if len(crossings) < 2:
        return math.nan
    return float((len(crossings) - 1) / (2 * (crossings[-1] - crossings[0])))


@functools.lru_cache(maxsize=8)
def _stick_slip_cached(key: tuple) -> Any:
    mass, stiffness, friction, gear, duration, control, ramp = key
    size = len(mass)
    lumped = LumpedString(
        tuple(str(i) for i in range(size)),
        np.array(mass),
        np.frombuffer(stiffness).reshape(size, size),
        friction,
        gear,
    )
    return lumped.stick_slip(duration, control, ramp)


def stick_slip(lumped: LumpedString, duration: float, drive: Drive) -> Any:
    """The N-element model's exact stick-slip solution (cached: quantities, checks and figures share it)."""
    key = (
        tuple(float(m) for m in lumped.mass),
        lumped.stiffness.tobytes(),
        lumped.friction,
        lumped.drive_gear,
        float(duration),
        lumped.drive_control(drive.acceleration),
        drive.ramp_time,
    )
    return _stick_slip_cached(key)


_WAVES: dict[tuple, Any] = {}


def wave_solution(rod: continuum.Rod, friction: float, acceleration: float, ramp: float, duration: float) -> Any:
    """(WaveSolution, StickSlip) of the continuum, cached on its inputs to 12 digits (the rod read back from
    models of different sizes differs in the last bits of J_b; the answer does not, to 1e-12)."""
    values = (*dataclasses.astuple(rod), friction, acceleration, ramp, duration)
    key = tuple(float(f"{v:.12g}") for v in values)
    if key not in _WAVES:
        if len(_WAVES) >= 8:
            _WAVES.pop(next(iter(_WAVES)))
        solver = continuum.WaveSolution(rod, friction, acceleration, ramp)
        _WAVES[key] = (solver, solver.solve(duration))
    return _WAVES[key]


def _continuum_restick(solver: continuum.WaveSolution, solution: continuum.StickSlip, speed: float) -> float:
    """When the continuum's bit, after its first breakaway, first falls below RESTICK_FRACTION of the top speed [s]."""
    level = RESTICK_FRACTION * speed
    # the solver's own nodes resolve w; between them its dense output is exact to its tolerance
    times, speeds = solution.time, np.abs(solution.speed)
    start = solution.first("slip")
    above = np.flatnonzero((times > start) & (speeds >= level))
    if not above.size:
        return math.nan
    below = np.flatnonzero((times > times[above[0]]) & (speeds < level))
    if not below.size:
        return math.nan
    i = int(below[0])
    return float(
        _optimize().brentq(lambda t: abs(solver.speed(t)) - level, times[i - 1], times[i], xtol=1e-14, rtol=1e-15)
    )


def _breakaway_twist(exact: Any) -> float:
    """The twist top - bit [rad] of the exact stick-slip solution as its bit first breaks free (nan: never)."""
    slip = next((phase for phase in exact.phases if phase.kind == "slip"), None)
    return math.nan if slip is None else float(slip.q0[0] - slip.q0[-1])


def restick_exact(lumped: LumpedString, exact: Any, drive: Drive) -> float:
    """The exact N-element re-stick [s] (`RESTICK_FRACTION`; nan: none within the solution)."""
    control = lumped.drive_control(drive.acceleration)
    return lumped.slowdown_time(exact, RESTICK_FRACTION * drive.speed, control, drive.ramp_time)


def spin_up(
    rod: continuum.Rod,
    lumped: LumpedString,
    drive: Drive,
    trajectory: Trajectory,
    top: tuple[np.ndarray, np.ndarray],
    bit: tuple[np.ndarray, np.ndarray],
) -> dict[str, Any]:
    """The start-up's quantities: the bit's peak speed and the wind-up, simulated, exact and continuum.

    The exact values are continuous maxima over the run (`lumped.maximum`: a grid finer than the fastest mode,
    refined by a bounded Brent search), never the largest of a sampled grid; the run's are its own peaks
    between steps (events.peak_magnitude).
    """
    time = trajectory.time
    duration = float(time[-1])
    flow = ModalFlow.of(np.diag(lumped.mass), lumped.stiffness)
    every = max(1, len(time) // CONTINUUM_SAMPLES)
    sample = time[::every]
    exact_q, exact_v = linear_samples(lumped, flow, drive, sample)
    continuum_speed = rod.modal_spin_up_speed(sample, rod.length, drive.acceleration, drive.ramp_time, CONTINUUM_MODES)
    _, bound = rod.modal_tail_bound(CONTINUUM_MODES, drive.acceleration)
    peak = events.peak_magnitude(time, bit[1], np.gradient(bit[1], time))
    spacing = 2 * math.pi / float(flow.omega[-1]) / GRID_PER_PERIOD
    bit_rows, twist_rows = np.array([lumped.size - 1]), np.array([0, lumped.size - 1])
    _, peak_exact = maximum(
        lambda t: np.abs(linear_samples(lumped, flow, drive, t, bit_rows)[1][:, 0]), 0.0, duration, spacing
    )

    def twist(t: np.ndarray) -> np.ndarray:
        q, _ = linear_samples(lumped, flow, drive, t, twist_rows)
        return q[:, 0] - q[:, 1]

    _, windup_exact = maximum(twist, 0.0, duration, spacing)
    return {
        "bit_peak_speed_rad_s": peak,
        "bit_peak_speed_rpm": peak / RPM,
        "bit_peak_speed_rad_s_exact": peak_exact,
        "bit_peak_speed_rad_s_continuum": continuum_peak(rod, drive, time),
        "windup_turns": float(np.max(top[0] - bit[0]) / (2 * math.pi)),
        "windup_turns_exact": windup_exact / (2 * math.pi),
        "bit_speed_error_vs_exact_rad_s": float(np.max(np.abs(bit[1][::every] - exact_v[:, -1]))),
        "bit_speed_error_vs_continuum_rad_s": float(np.max(np.abs(bit[1][::every] - continuum_speed))),
        "bit_speed_discretization_error_rad_s": float(np.max(np.abs(exact_v[:, -1] - continuum_speed))),
        "continuum_modes": CONTINUUM_MODES,
        "continuum_truncation_bound_rad_s": bound,
    }


def continuum_peak(rod: continuum.Rod, drive: Drive, time: np.ndarray) -> float:
    """The largest |speed| [rad/s] of the continuum's free bit over `time` [s]: the modal series of CONTINUUM_MODES
    modes searched on the run's steps, its best refined by a bounded Brent search between the neighbouring steps
    (the series' value to round-off; it differs from the rod's by at most `modal_tail_bound`)."""

    times = np.ascontiguousarray(time, dtype=float)
    key = (
        rod,
        float(drive.acceleration),
        float(drive.ramp_time),
        times.shape,
        hashlib.blake2b(times.tobytes()).digest(),
    )
    if key not in _CONTINUUM_PEAKS:  # the same rod and run grid: the same peak (kept for the next verdict)
        if len(_CONTINUUM_PEAKS) >= 8:
            _CONTINUUM_PEAKS.pop(next(iter(_CONTINUUM_PEAKS)))
        _CONTINUUM_PEAKS[key] = _continuum_peak(rod, drive, times)
    return _CONTINUUM_PEAKS[key]


#: the last few `continuum_peak` answers, by rod, drive and run grid
_CONTINUUM_PEAKS: dict[tuple, float] = {}


def _continuum_peak(rod: continuum.Rod, drive: Drive, time: np.ndarray) -> float:
    """`continuum_peak` computed: the series' largest |speed| on the run's steps, refined between the neighbours.

    The series is evaluated on every step only where its peak can be. It is first evaluated on every `every`-th
    step (the grid `spin_up` compares the run on, kept), and |w| cannot rise faster than
    L = |alpha| + 2 sum_n |A_n| w_n^2 (the derivative of every term of the series, after the ramp two of them), so
    a step between two coarse ones, at distances d1 and d2, has |w| <= min(|w1| + L d1, |w2| + L d2): only the
    steps whose bound reaches the coarse maximum are evaluated (92 of 5001 at the defaults). The largest of
    those and the coarse values is the largest on every step, as if every step had been evaluated.
    """

    def speed(t: np.ndarray) -> np.ndarray:
        w = rod.modal_spin_up_speed(t, rod.length, drive.acceleration, drive.ramp_time, CONTINUUM_MODES)
        return np.abs(w)

    every = max(1, len(time) // CONTINUUM_SAMPLES)
    values = np.full(len(time), -np.inf)
    values[::every] = speed(time[::every])
    bound = _slope_bound(rod, drive)
    coarse = np.arange(0, len(time), every)
    left = np.repeat(coarse, every)[: len(time)]  # each step's coarse step at or before it
    right = np.minimum(left + every, coarse[-1])  # and after it (the last coarse one past the end)
    reach = np.minimum(
        values[left] + bound * (time - time[left]),
        np.where(right > left, values[right] + bound * np.abs(time[right] - time), np.inf),
    )
    best = float(np.max(values[coarse]))
    # a margin of round-off on the bound: a step it lets through is only evaluated, never wrongly skipped
    open_steps = np.flatnonzero((reach >= best * (1 - 1e-9)) & np.isneginf(values))
    if open_steps.size:
        values[open_steps] = speed(time[open_steps])
    i = int(np.argmax(values))
    low, high = float(time[max(i - 1, 0)]), float(time[min(i + 1, len(time) - 1)])
    found = _optimize().minimize_scalar(
        lambda s: -float(speed(np.array([s]))[0]), bounds=(low, high), method="bounded", options={"xatol": 1e-13}
    )
    return max(float(values[i]), float(-found.fun))


def _slope_bound(rod: continuum.Rod, drive: Drive) -> float:
    """L [rad/s^2]: no |d/dt| of the CONTINUUM_MODES-mode series of the bit's speed exceeds it (`_continuum_peak`).

    The speed is alpha min(t, T_r) - sum_n A_n w_n [sin w_n t - H(t - T_r) sin w_n (t - T_r)] (A_n the angle's
    modal amplitudes at the bit, as `continuum.Rod.modal_spin_up`), so |w'| <= |alpha| + 2 sum_n |A_n| w_n^2.
    """
    betas = rod.betas(CONTINUUM_MODES)
    omegas = rod.wave_speed * betas
    modal = rod.density * rod.polar_moment / betas / (omegas**2 * rod.modal_masses(betas))
    amplitudes = np.abs(drive.acceleration * modal * np.sin(betas * rod.length))
    return abs(drive.acceleration) + 2.0 * float(np.sum(amplitudes * omegas**2))


def linear_samples(
    lumped: LumpedString, flow: ModalFlow, drive: Drive, time: np.ndarray, rows: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The exact friction-free start-up (q, v) at `time` [s] of the hinges `rows` (None: every hinge), two
    closed-form segments: the drive's torque until the ramp's end, none after."""
    force = lumped.drive_torque(lumped.drive_control(drive.acceleration))
    n = lumped.size
    time = np.asarray(time, float)
    width = n if rows is None else len(rows)
    q, v = np.zeros((len(time), width)), np.zeros((len(time), width))
    on = time < drive.ramp_time
    q[on], v[on] = flow.state(time[on], np.zeros(n), np.zeros(n), force, rows)
    q_end, v_end = flow.state(np.array([drive.ramp_time]), np.zeros(n), np.zeros(n), force)
    if (~on).any():
        q[~on], v[~on] = flow.state(time[~on] - drive.ramp_time, q_end[0], v_end[0], np.zeros(n), rows)
    return q, v


def simulated_events(
    lumped: LumpedString, drive: Drive, trajectory: Trajectory, top: tuple, bit: tuple
) -> dict[str, float]:
    """Breakaway, peak speed and re-stick measured from a run (see `_breakaway`)."""
    time = trajectory.time
    stiffness_row = lumped.stiffness[-1]
    torque = -(trajectory.qpos @ stiffness_row)
    torque_rate = -(trajectory.qvel @ stiffness_row)
    breakaway = events.first_crossing(time, torque, torque_rate, lumped.friction) if lumped.friction > 0 else 0.0
    after = time >= (breakaway if math.isfinite(breakaway) else time[-1])
    speed = bit[1]
    # while slipping the bit's acceleration is exact from the positions: (string torque - T_f sign(w)) / J
    acceleration = (torque - lumped.friction * np.sign(speed)) / lumped.mass[-1]
    peak = events.peak_magnitude(time[after], speed[after], acceleration[after]) if after.sum() > 1 else math.nan
    level = RESTICK_FRACTION * drive.speed
    restick = math.nan
    if after.sum() > 1:
        started = np.flatnonzero(after & (speed > level))
        if started.size:
            first = int(started[0])
            restick = events.first_below(time[first:], speed[first:], acceleration[first:], level)
    return {"breakaway": breakaway, "peak": peak, "restick": restick}


def breakaway(
    rod: continuum.Rod,
    lumped: LumpedString,
    drive: Drive,
    trajectory: Trajectory,
    top: tuple,
    bit: tuple,
    twist: np.ndarray,
) -> dict[str, Any]:
    """The breakaway's quantities, simulated, exact (N elements) and continuum."""
    duration = float(trajectory.time[-1])
    measured = simulated_events(lumped, drive, trajectory, top, bit)
    exact = stick_slip(lumped, duration, drive)
    solver, wave = wave_solution(rod, lumped.friction, drive.acceleration, drive.ramp_time, duration)
    t_b = measured["breakaway"]
    exact_b = exact.first("slip")
    continuum_b = continuum.stuck_breakaway_time(rod, lumped.friction, drive.acceleration, drive.ramp_time)
    top_angle = float(np.interp(t_b, trajectory.time, top[0])) if math.isfinite(t_b) else math.nan
    bit_angle = float(np.interp(t_b, trajectory.time, bit[0])) if math.isfinite(t_b) else math.nan

    def top_angle_at(t: float) -> float:  # the top drive's ideal ramp (the bit is at 0 while it is stuck)
        if not math.isfinite(t):
            return math.nan
        ramp = drive.ramp_time
        return drive.acceleration * (0.5 * min(t, ramp) ** 2 + ramp * max(t - ramp, 0.0))

    exact_restick = restick_exact(lumped, exact, drive)
    restick = measured["restick"]
    out = {
        "breakaway_time_s": t_b,
        "breakaway_time_s_exact": exact_b,
        "breakaway_time_s_continuum": continuum_b,
        "windup_turns": (top_angle - bit_angle) / (2 * math.pi),
        # the exact solution's own twist top - bit as the bit breaks free (the top drive's inertia is finite)
        "windup_turns_exact": _breakaway_twist(exact) / (2 * math.pi),
        "windup_turns_continuum": top_angle_at(continuum_b) / (2 * math.pi),
        "windup_turns_static": lumped.friction / rod.stiffness / (2 * math.pi),
        "peak_bit_speed_rad_s": measured["peak"],
        "peak_bit_speed_rad_s_exact": exact.peak_speed,
        "peak_bit_speed_rad_s_continuum": wave.peak_speed,
        "peak_bit_speed_rpm": measured["peak"] / RPM,
        "peak_speed_ratio": measured["peak"] / drive.speed,
        "restick_time_s": restick,
        "restick_time_s_exact": exact_restick,
        "restick_time_s_continuum": _continuum_restick(solver, wave, drive.speed),
        # the same event as restick_time_s_exact (RESTICK_FRACTION), never a second definition
        "sticks_again": bool(math.isfinite(exact_restick)),
        "slip_duration_s": restick - t_b if math.isfinite(restick) else math.nan,
        "restick_speed_rad_s": RESTICK_FRACTION * drive.speed,
    }
    out["max_twist_turns"] = float(np.max(np.abs(twist)) / (2 * math.pi))
    return out
