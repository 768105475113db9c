"""What a friction run did, read from its samples: turning points, the stop, creep and acceleration.

MuJoCo's dry friction is a soft constraint, so its block never stops the way the exact one does:
where the exact motion ends at rest, MuJoCo's keeps a small velocity toward the net force (the
creep), and where the exact velocity reverses, MuJoCo's friction turns round a little early. The
measurements below are defined so that they mean the same thing for both:

* a turning point is where a motion in one direction ends: the velocity changes sign, or falls to
  (numerically) zero, between two samples; its time is the linear zero of the velocity between
  them, its position the cubic Hermite interpolant of (x, v) there (springlab.exact.events);
* the stop is the last turning point of a run (for MuJoCo's soft friction: where the sliding ends
  and the creep begins, which moves on toward the net force and never reverses again);
* the creep velocity is the mean velocity from the stop to the end of the run (no stop: over the
  second half of the run, where a held block creeps);
* the acceleration of a slide is the least-squares slope of v(t) over the run.
"""

from __future__ import annotations

import math

import numpy as np

from springlab.exact import events

#: velocities below this fraction of the run's peak speed count as rest [-] (MuJoCo's NoSlip pass
#: leaves ~1e-19 m/s where the exact block stops)
REST_FRACTION = 1e-9


def turning_points(time: np.ndarray, x: np.ndarray, v: np.ndarray) -> list[tuple[float, float]]:
    """[(t [s], x [m])] where a motion in one direction ends, in order (see the module docstring).

    Parameters
    ----------
    time
        (n,) sample times [s].
    x, v
        (n,) positions [m] and velocities [m/s].
    """
    peak = float(np.max(np.abs(v))) if len(v) else 0.0
    if peak == 0.0:
        return []
    rest = REST_FRACTION * peak
    sign = np.where(np.abs(v) <= rest, 0, np.sign(v)).astype(int)
    # a motion in one direction ends where the sign leaves it: to the other direction, or to rest
    ends = np.flatnonzero((sign[:-1] != 0) & (sign[1:] != sign[:-1])) + 1
    out: list[tuple[float, float]] = []
    for i in ends:
        last = i - 1
        t0, t1, v0 = time[last], time[i], v[last]
        v1 = v[i] if sign[i] != 0 else 0.0
        t = t0 + (t1 - t0) * v0 / (v0 - v1) if v0 != v1 else t1
        out.append((float(t), events.hermite_value(t0, t1, x[last], x[i], v[last], v[i], t)))
    return out


def stop(time: np.ndarray, x: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """(time [s], position [m]) of the last turning point, or (nan, nan) if the block never turned."""
    points = turning_points(time, x, v)
    return points[-1] if points else (math.nan, math.nan)


def creep_velocity(time: np.ndarray, x: np.ndarray, after: float) -> float:
    """Mean velocity [m/s] from `after` [s] to the end of the run (after nan: over its second half)."""
    end = float(time[-1])
    start = end / 2.0 if not math.isfinite(after) else after
    if start >= end:
        return math.nan
    return float((x[-1] - np.interp(start, time, x)) / (end - start))


def acceleration(time: np.ndarray, v: np.ndarray) -> float:
    """Least-squares slope of v(t) [m/s^2] over the run."""
    if len(time) < 2:
        return math.nan
    return float(np.polyfit(time, v, 1)[0])
