"""Positioning a rigid body that carries one damped mode: exact ring-down after any piecewise-constant move.

The model is the printer head's (scenes/printer_head): a body of total mass M driven by a force F(t), with a
flexible mode of natural frequency omega [rad/s] and damping ratio zeta [-] between the drive and the
carriage. The carriage's deviation x from the centre of mass obeys

    x'' + 2 zeta omega x' + omega^2 x = -a(t),      a = F / M, the centre of mass's acceleration [m/s^2],

(mu s'' + c s' + k s = (m_c / M) F for the belt stretch s, x = -(m_m / M) s), so the ring-down depends only
on omega, zeta and the acceleration profile, not on the masses apart.

A command a(t) that is piecewise constant is a sum of steps Delta a_j at t_j. The step response of the mode
is -(Delta a / omega^2) (1 - Re((1 - i sigma / omega_d) e^{s (t - t_j)})), s = -sigma + i omega_d,
sigma = zeta omega, omega_d = omega sqrt(1 - zeta^2); once every step has been applied and the steps sum to
zero (the body coasts or stands), the carriage rings as x = Re(Z e^{s tau}), tau after the command's end
t_e, with the phasor

    Z = (1 - i sigma / omega_d) / omega^2  sum_j Delta a_j e^{s (t_e - t_j)}.

A bang-bang move of D in T has a = 4 D / T^2, steps +a, -2a, +a at 0, T/2, T: Z = (1 - i sigma / omega_d)
a (1 - e^{s T / 2})^2 / omega^2. Undamped, |Z| = 4 sin^2(omega T / 4) a / omega^2 <= 16 D / (omega T)^2,
whence the undamped worst case T >= (4 / omega) sqrt(D / band) of a move that cannot ring beyond the band.
Damped, |1 - e^{s T / 2}| <= 1 + e^{-sigma T / 2} bounds every phase (`worst_case_envelope`), and the exact
largest deviation after a move of T (`peak_after`) decides the shortest T beyond which every move stays in
the band (`quietest_move_time`).

A shaped command (exact.shaping) multiplies Z by sum_i A_i e^{s (t_N - t_i)}, whose modulus is the shaper's
residual vibration V.

Positions [m], times [s], accelerations [m/s^2], omega [rad/s], zeta [-].
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from . import events
from .shaping import Shaper, shape_command

__all__ = [
    "bang_bang",
    "carriage_deviation",
    "fastest_shaper",
    "last_exit_after",
    "peak_after",
    "positioning_time",
    "quietest_move_time",
    "residual_phasor",
    "shaped_positioning_time",
    "undamped_quiet_time",
    "worst_case_envelope",
]


def _static_gain(s: complex) -> complex:
    """1 - i sigma / omega_d of the root s = -sigma + i omega_d: the step response's phasor factor [-]."""
    return complex(1.0, s.real / s.imag)


def _root(omega: float, zeta: float) -> complex:
    """The mode's root s = -zeta omega + i omega sqrt(1 - zeta^2) [1/s] (underdamped only)."""
    if not (omega > 0 and 0 <= zeta < 1):
        raise ValueError(f"an underdamped mode needs omega > 0 and 0 <= zeta < 1, got omega={omega!r}, zeta={zeta!r}")
    return complex(-zeta * omega, omega * math.sqrt(1 - zeta * zeta))


def bang_bang(distance: float, duration: float) -> tuple[np.ndarray, np.ndarray]:
    """(breakpoints [s], centre-of-mass acceleration per segment [m/s^2]) of a bang-bang move of D in T.

    +4 D / T^2 for the first half, -4 D / T^2 for the second, 0 after: the body starts and ends at rest, D apart.
    """
    a = 4 * distance / duration**2
    return np.array([0.0, duration / 2, duration]), np.array([a, -a, 0.0])


def residual_phasor(omega: float, zeta: float, breaks: np.ndarray, accelerations: np.ndarray) -> complex:
    """Phasor Z [m]: after the command's last breakpoint the carriage deviates by Re(Z e^{s tau}) (module docstring).

    Parameters
    ----------
    omega, zeta
        The mode [rad/s], [-].
    breaks
        Breakpoints [s] of the centre-of-mass acceleration, increasing, from rest before breaks[0].
    accelerations
        Acceleration [m/s^2] on each segment; the last must be 0 (the command has ended).
    """
    a = np.asarray(accelerations, dtype=float)
    if a[-1] != 0.0:
        raise ValueError("the command must end with zero acceleration (its last segment)")
    s = _root(omega, zeta)
    t = np.asarray(breaks, dtype=float)
    steps = np.diff(np.concatenate([[0.0], a]))
    return complex(_static_gain(s) / omega**2 * np.sum(steps * np.exp(s * (t[-1] - t))))


def peak_after(phasor: complex, omega: float, zeta: float) -> float:
    """Largest |Re(Z e^{s tau})| [m] over tau >= 0: at tau = 0 or at the first extremum (later ones decay)."""
    s = _root(omega, zeta)
    first = ((math.pi / 2 - np.angle(phasor * s)) % math.pi) / s.imag
    return max(abs(phasor.real), abs((phasor * np.exp(s * first)).real))


def last_exit_after(phasor: complex, omega: float, zeta: float, band: float) -> float:
    """Time tau [s] after which |Re(Z e^{s tau})| stays <= band for good (0 if it never leaves; inf undamped).

    The extrema of the free vibration are a half damped period apart; the last one beyond the band is found in
    closed form, the exit is the root between it and the next zero (where |x| decreases monotonically).
    """
    import scipy.optimize  # here: scipy.optimize costs every command start-up time (tests/cli/test_cli_usage.py)

    if peak_after(phasor, omega, zeta) <= band:
        return 0.0
    s = _root(omega, zeta)
    if s.real == 0.0:
        return math.inf
    half = math.pi / s.imag
    first = ((math.pi / 2 - np.angle(phasor * s)) % math.pi) / s.imag
    # beyond the envelope's own exit no extremum can lie outside the band
    count = int(math.ceil(math.log(abs(phasor) / band) / -s.real / half)) + 2
    starts = np.concatenate([[0.0], first + half * np.arange(count)])
    values = np.abs((phasor * np.exp(s * starts)).real)
    start = float(starts[np.flatnonzero(values > band)[-1]])
    zero = start + ((math.pi / 2 - np.angle(phasor) - s.imag * start) % math.pi) / s.imag

    def excess(tau: float) -> float:
        return abs((phasor * np.exp(s * tau)).real) - band

    return float(scipy.optimize.brentq(excess, start, zero, xtol=1e-15, rtol=4 * np.finfo(float).eps))


def worst_case_envelope(omega: float, zeta: float, distance: float, duration: float) -> float:
    """Largest ring-down envelope |Z| [m] a bang-bang move of D in T can leave, whatever its phase on the mode.

    |Z| = |1 - i sigma / omega_d| a |1 - e^{s T/2}|^2 / omega^2 <= a (1 + e^{-sigma T / 2})^2 / (omega^2
    sqrt(1 - zeta^2)), a = 4 D / T^2: reached when each half-move lasts an odd number of half damped periods.
    Undamped, 16 D / (omega T)^2.
    """
    a = 4 * distance / duration**2
    return a * (1 + math.exp(-zeta * omega * duration / 2)) ** 2 / (omega**2 * math.sqrt(1 - zeta * zeta))


def undamped_quiet_time(omega: float, distance: float, band: float) -> float:
    """(4 / omega) sqrt(D / band) [s]: beyond it no bang-bang move rings beyond the band on an UNDAMPED mode."""
    return 4.0 / omega * math.sqrt(distance / band)


def quietest_move_time(omega: float, zeta: float, distance: float, band: float) -> float:
    """Shortest T [s] such that every bang-bang move of D lasting T or longer stays within +-band after it ends.

    g(T) = `peak_after` of the move's phasor is continuous in T; beyond the damped worst case
    (`worst_case_envelope` = band) it is below the band for good, so the answer is g's last crossing of the
    band below that bound: found on a grid of 1/400 of a damped period, refined by Brent's method.

    Parameters
    ----------
    omega, zeta
        The mode [rad/s], [-].
    distance
        Move distance D [m].
    band
        Half-width of the positioning band [m].
    """
    import scipy.optimize  # here: scipy.optimize costs every command start-up time (tests/cli/test_cli_usage.py)

    s = _root(omega, zeta)
    bound = scipy.optimize.brentq(
        lambda t: worst_case_envelope(omega, zeta, distance, t) - band,
        1e-9,
        10 * undamped_quiet_time(omega, distance, band),
    )

    def excess(duration: float) -> float:
        return peak_after(residual_phasor(omega, zeta, *bang_bang(distance, duration)), omega, zeta) - band

    grid = np.arange(bound, 0.0, -2 * math.pi / s.imag / 400)
    above = next((i for i, t in enumerate(grid) if excess(float(t)) > 0), None)
    if above is None or above == 0:
        return float(bound)
    return float(scipy.optimize.brentq(excess, grid[above], grid[above - 1], xtol=1e-15, rtol=4 * np.finfo(float).eps))


def carriage_deviation(
    omega: float, zeta: float, breaks: np.ndarray, accelerations: np.ndarray, time: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The carriage's position [m] and velocity [m/s] relative to its final resting place, at `time` [s].

    The centre of mass's exact piecewise-quadratic motion plus the mode's exact step responses (module
    docstring); the command ends (last acceleration 0), so the final place is where the centre of mass stops.
    """
    s = _root(omega, zeta)
    t = np.asarray(time, dtype=float)[:, None]
    b = np.asarray(breaks, dtype=float)[None, :]
    steps = np.diff(np.concatenate([[0.0], np.asarray(accelerations, dtype=float)]))[None, :]
    since = np.maximum(t - b, 0.0)
    on = t >= b
    final = float(np.sum(steps * (b[0, -1] - b) ** 2 / 2))
    final_rate = float(np.sum(steps * (b[0, -1] - b)))
    centre = np.sum(steps * since**2 / 2, axis=1) - (final + final_rate * np.maximum(t[:, 0] - b[0, -1], 0.0))
    centre_rate = np.sum(steps * since, axis=1) - final_rate
    transient = np.exp(s * since)
    x = np.sum(np.where(on, steps / omega**2 * (_static_gain(s) * transient).real - steps / omega**2, 0.0), axis=1)
    v = np.sum(np.where(on, -steps / s.imag * transient.imag, 0.0), axis=1)
    return centre + x, centre_rate + v


def positioning_time(omega: float, zeta: float, breaks: np.ndarray, accelerations: np.ndarray, band: float) -> float:
    """Time [s] from the command's start after which the carriage stays within +-band of where it comes to rest.

    After the command's end the closed form (`last_exit_after`); before it, the exact motion
    (`carriage_deviation`) on a grid of 1/256 of a damped period, its last exit located on the cubic Hermite
    interpolant (exact.events) and refined on the exact motion by Brent's method.
    """
    import scipy.optimize  # here: scipy.optimize costs every command start-up time (tests/cli/test_cli_usage.py)

    end = float(breaks[-1])
    after = last_exit_after(residual_phasor(omega, zeta, breaks, accelerations), omega, zeta, band)
    if after > 0:
        return end + after
    s = _root(omega, zeta)
    time = np.linspace(0.0, end, max(2, int(math.ceil(end / (2 * math.pi / s.imag / 256))) + 1))
    x, v = carriage_deviation(omega, zeta, breaks, accelerations, time)
    exit_time = events.last_exit(time, x, v, band)
    if exit_time <= 0.0:
        return 0.0
    h = time[1] - time[0]

    def excess(t: float) -> float:
        return abs(float(carriage_deviation(omega, zeta, breaks, accelerations, np.array([t]))[0][0])) - band

    low, high = max(0.0, exit_time - h), min(end, exit_time + h)
    if excess(low) > 0 >= excess(high):
        return float(scipy.optimize.brentq(excess, low, high, xtol=1e-15, rtol=4 * np.finfo(float).eps))
    return exit_time


def shaped_positioning_time(
    omega: float, zeta: float, shaper: Shaper, distance: float, duration: float, band: float
) -> float:
    """Positioning time [s] of the bang-bang move of D in T shaped by `shaper`, on a mode (omega, zeta) [rad/s], [-].

    The shaped command (exact.shaping.shape_command) lasts T + t_N; the carriage's exact motion decides
    (`positioning_time`), so a shaper designed for another frequency pays for its residual here.
    """
    return positioning_time(omega, zeta, *shape_command(*bang_bang(distance, duration), shaper), band)


def fastest_shaper(
    shapers: Sequence[Shaper],
    frequencies_hz: Sequence[float],
    zeta: float,
    distance: float,
    duration: float,
    band: float,
) -> tuple[Shaper, dict[str, float]]:
    """The shaper whose worst positioning time over the possible belt frequencies is the shortest.

    What a firmware engineer asks of a measured resonance: the frequency is known to an interval (the resonance
    test's 95 % interval, widened by whatever drift is expected), so each candidate is judged by its worst
    positioning time [s] over `frequencies_hz` [Hz] (e.g. the interval's ends and points between), not at the
    estimate alone.

    Returns
    -------
    tuple
        (the chosen shaper, {shaper name: worst positioning time [s]}).
    """
    worst = {
        shaper.name: max(
            shaped_positioning_time(2 * math.pi * f, zeta, shaper, distance, duration, band) for f in frequencies_hz
        )
        for shaper in shapers
    }
    chosen = min(shapers, key=lambda shaper: worst[shaper.name])
    return chosen, worst
