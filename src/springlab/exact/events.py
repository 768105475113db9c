"""Events between output steps: extrema, level crossings and Richardson error estimates.

A run is sampled once per physics step, but its peaks and events fall between
samples. Reading them at the samples costs O(dt) in time and O(dt^2) in the
value of an extremum, whatever the integrator's order. Cubic Hermite
interpolation of a signal with its derivative (position with velocity,
velocity with acceleration, ...) is O(dt^4) between the samples, so extrema and
crossings measured through it keep up with RK4 (the same rule as
`scipy.integrate.solve_ivp`'s dense output and event location).

Every function takes the samples y [unit] and their time derivatives dy
[unit/s] of one smooth stretch of a run. Where an input switches on a step
boundary the derivatives jump: measure each side separately (the switch
sample with its left-hand derivatives on the first, right-hand on the second).

Band exits: where a motion settles into a band +-level, its last exit is the
interpolant's too (`hermite_peaks` bounds each interval's excursion, `band_exit`
finds the exit, `last_exit` does both over a record): read at the samples a
vibration peak that passes the band between two samples inside it goes unseen,
and the settling time comes out early by half a period.

Richardson: a quantity Q(h) measured at step h with an integrator of order p
has error ~ C h^p, so Q(h) - Q(h/2) ~ C h^p (1 - 2^-p) and the error of Q(h)
is 2^p / (2^p - 1) |Q(h) - Q(h/2)|.
"""

from __future__ import annotations

import math

import numpy as np

#: a float or an array of them (elementwise)
_Values = float | np.ndarray


def _hermite(s: _Values, h: _Values, y0: _Values, y1: _Values, dy0: _Values, dy1: _Values) -> _Values:
    """The cubic Hermite interpolant at the fraction s of an interval of length h [s] (floats or arrays alike)."""
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * y0 + h10 * h * dy0 + h01 * y1 + h11 * h * dy1


def hermite_value(t0: float, t1: float, y0: float, y1: float, dy0: float, dy1: float, t: float) -> float:
    """The cubic Hermite interpolant of (y, dy) on [t0, t1] [s] at time t [s]."""
    return float(_hermite((t - t0) / (t1 - t0), t1 - t0, y0, y1, dy0, dy1))


def hermite_root(
    t0: float, t1: float, y0: float, y1: float, dy0: float, dy1: float, target: float = 0.0, *, last: bool = False
) -> float:
    """Time in [t0, t1] [s] where the cubic Hermite interpolant of y (slopes dy) equals `target`.

    Of several roots in the interval, the one nearest the linear interpolant's root, or with
    `last` the latest one (where the interpolant leaves `target` for the last time).
    """
    h = t1 - t0
    p0, p1, m0, m1 = y0 - target, y1 - target, dy0 * h, dy1 * h
    # cubic in s: (2s^3 - 3s^2 + 1) p0 + (s^3 - 2s^2 + s) m0 + (-2s^3 + 3s^2) p1 + (s^3 - s^2) m1
    coefficients = [2 * p0 + m0 - 2 * p1 + m1, -3 * p0 - 2 * m0 + 3 * p1 - m1, m0, p0]
    roots = np.roots(coefficients) if any(coefficients[:3]) else np.array([])
    real = [r.real for r in roots if abs(r.imag) < 1e-9 and -1e-9 <= r.real <= 1 + 1e-9]
    if not real:  # fall back to the linear interpolant
        s = p0 / (p0 - p1) if p0 != p1 else 0.0
    elif last:
        s = max(real)
    else:
        s = min(real, key=lambda r: abs(r - p0 / (p0 - p1)) if p0 != p1 else r)
    return t0 + min(max(s, 0.0), 1.0) * h


def down_crossings(time: np.ndarray, y: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """Times [s] where y crosses zero downwards (y > 0 then y <= 0), to O(dt^4) by cubic Hermite interpolation.

    With y a velocity and dy its acceleration these are the times of the position maxima.
    """
    down = np.flatnonzero((y[:-1] > 0) & (y[1:] <= 0))
    return np.array([hermite_root(time[i], time[i + 1], y[i], y[i + 1], dy[i], dy[i + 1]) for i in down])


def first_crossing(time: np.ndarray, y: np.ndarray, dy: np.ndarray, level: float) -> float:
    """First time [s] |y| reaches `level` (> 0), to O(dt^4) by cubic Hermite interpolation (nan: never)."""
    beyond = np.flatnonzero(np.abs(y) >= level)
    if not beyond.size or beyond[0] == 0:
        return math.nan if not beyond.size else float(time[0])
    i = int(beyond[0]) - 1
    target = math.copysign(level, y[i + 1])
    return hermite_root(time[i], time[i + 1], y[i], y[i + 1], dy[i], dy[i + 1], target)


def first_below(time: np.ndarray, y: np.ndarray, dy: np.ndarray, level: float = 0.0) -> float:
    """First time [s] y drops below `level`, to O(dt^4) by cubic Hermite interpolation (nan: never)."""
    below = np.flatnonzero(y < level)
    if not below.size:
        return math.nan
    if below[0] == 0:
        return float(time[0])
    i = int(below[0]) - 1
    return hermite_root(time[i], time[i + 1], y[i], y[i + 1], dy[i], dy[i + 1], level)


def extrema(
    time: np.ndarray,
    y: np.ndarray,
    dy: np.ndarray,
    ddy: np.ndarray | None = None,
) -> np.ndarray:
    """Interior extrema (t [s], value) of y, from the sign changes of dy, as rows of an (k, 2) array.

    The time is dy's zero: cubic Hermite in (dy, ddy) when ddy is given, else linear in dy
    (O(dt^2) in time; an extremum's value is second order in its time error, so still O(dt^4)).
    The value is the cubic Hermite interpolant of (y, dy) there: O(dt^4). A series starting at
    rest (dy[0] == 0) counts its first sample as an extremum.
    """
    out = [(float(time[0]), float(y[0]))] if dy[0] == 0.0 else []
    crossings = np.flatnonzero(np.sign(dy[:-1]) * np.sign(dy[1:]) < 0)
    for i in crossings:
        t0, t1 = time[i], time[i + 1]
        v0, v1 = dy[i], dy[i + 1]
        if ddy is None:
            t = t0 + (t1 - t0) * v0 / (v0 - v1)
        else:
            t = hermite_root(t0, t1, v0, v1, ddy[i], ddy[i + 1])
        out.append((float(t), hermite_value(t0, t1, y[i], y[i + 1], v0, v1, t)))
    return np.array(out).reshape(-1, 2)


def peak_magnitude(
    time: np.ndarray,
    y: np.ndarray,
    dy: np.ndarray,
    ddy: np.ndarray | None = None,
) -> float:
    """max |y| over the run: the samples (ends, kinks at switches) and the interpolated interior extrema."""
    found = extrema(time, y, dy, ddy)
    interior = float(np.max(np.abs(found[:, 1]))) if len(found) else 0.0
    return max(float(np.max(np.abs(y))), interior)


def hermite_peaks(
    h: np.ndarray | float, y0: np.ndarray, y1: np.ndarray, dy0: np.ndarray, dy1: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Largest |y| of the cubic Hermite interpolant on each interval, to O(h^4) (arrays of any shape).

    Each interval (length h [s], ends y0, y1 [unit], slopes dy0, dy1 [unit/s]) peaks at an end
    or, where dy changes sign, at its interior extremum: its time linear in dy (O(h^2)), its
    value the interpolant there (O(h^4), as `extrema`). A sampled peak reads low by about
    (omega h)^2 / 8 of the amplitude; this is what lies between the samples.

    Returns
    -------
    tuple[np.ndarray, np.ndarray]
        (peak |y| [unit], the interior extremum's signed value [unit], nan where dy keeps its sign).
    """
    arrays = np.broadcast_arrays(*(np.asarray(a, float) for a in (y0, y1, dy0, dy1, h)))
    shape = arrays[0].shape
    y0, y1, dy0, dy1, h = (np.atleast_1d(a) for a in arrays)
    turns = dy0 * dy1 < 0  # few: about omega h / pi of the intervals
    v0, v1 = dy0[turns], dy1[turns]
    interior = np.full(y0.shape, np.nan)
    interior[turns] = _hermite(v0 / (v0 - v1), h[turns], y0[turns], y1[turns], v0, v1)
    peak = np.maximum(np.abs(y0), np.abs(y1))
    peak[turns] = np.maximum(peak[turns], np.abs(interior[turns]))
    return peak.reshape(shape), interior.reshape(shape)


def band_exit(t0: float, t1: float, y0: float, y1: float, dy0: float, dy1: float, level: float) -> float:
    """The time in [t0, t1] [s] the cubic Hermite interpolant of (y, dy) leaves |y| > `level` for the last time.

    For an interval that is outside somewhere and ends inside (|y1| <= level): the exit is the
    latest root of y = +-level, the sign that of the latest excursion (the interior extremum
    when it lies outside, else y0). O(h^4) in value, so the time is accurate to that error
    divided by the slope |dy| at the exit.
    """
    _, interior = hermite_peaks(t1 - t0, np.array(y0), np.array(y1), np.array(dy0), np.array(dy1))
    outside = float(interior) if abs(float(interior)) > level else y0  # nan compares False
    return hermite_root(t0, t1, y0, y1, dy0, dy1, math.copysign(level, outside), last=True)


def last_exit(time: np.ndarray, y: np.ndarray, dy: np.ndarray, level: float) -> float:
    """Time [s] after which |y| stays <= `level` on the cubic Hermite interpolant of (y, dy) in this record.

    The continuous motion's last exit from the band +-level, not the samples': the excursions
    between samples are the interpolant's (`hermite_peaks`), the exit its root (`band_exit`).
    time[0] if the record never leaves the band, time[-1] if it ends outside.
    """
    peaks, _ = hermite_peaks(np.diff(time), y[:-1], y[1:], dy[:-1], dy[1:])
    outside = np.flatnonzero(peaks > level)
    if abs(y[-1]) > level:
        return float(time[-1])
    if outside.size == 0:
        return float(time[0])
    i = int(outside[-1])
    return band_exit(time[i], time[i + 1], y[i], y[i + 1], dy[i], dy[i + 1], level)


def richardson_error(coarse: float, fine: float, order: int) -> float:
    """Estimated error [unit of the values] of `coarse`, measured at step h, from `fine` at h/2 (order p)."""
    return 2**order / (2**order - 1) * abs(coarse - fine)


def richardson_extrapolate(coarse: float, fine: float, order: int) -> float:
    """The order-p error term of a value at h cancelled with its value at h/2: fine + (fine - coarse) / (2^p - 1)."""
    return (2**order * fine - coarse) / (2**order - 1)
