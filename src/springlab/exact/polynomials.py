"""Exact kinematics of polynomial and piecewise-linear motion (the chapter's section 5.1).

The references the kinematics scene is validated against: position, velocity and acceleration
of a polynomial x(t), the double integral of a polynomial acceleration, and the exact position
under a piecewise-linear (tachograph-like) velocity record.  Pure NumPy, exact up to rounding:
polynomials are differentiated and integrated term by term, and a linear velocity's area is a
trapezoid.  :mod:`springlab.analytic` re-exports these names, where the scenes first found them.

Units are SI: [m], [m/s], [m/s^2], [m/s^3], [s].  Time arguments are evaluated element-wise.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.polynomial import Polynomial

__all__ = ["polynomial_motion", "integrate_acceleration", "piecewise_linear_velocity"]

ArrayLike = float | np.ndarray | list | tuple


def _finite_scalar(name: str, value: object) -> float:
    """`value` as a finite float; ValueError naming `name` otherwise."""
    try:
        out = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real scalar, got {value!r}") from None
    if not math.isfinite(out):
        raise ValueError(f"{name} must be finite, got {out!r}")
    return out


def _any_time(t: ArrayLike) -> np.ndarray:
    """Times [s] as a float array; ValueError if any is not finite."""
    arr = np.asarray(t, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ValueError("t must contain only finite times [s]")
    return arr


def _coefficients(name: str, coefficients) -> np.ndarray:
    c = np.atleast_1d(np.asarray(coefficients, dtype=float))
    if c.ndim != 1 or c.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D sequence")
    if not np.all(np.isfinite(c)):
        raise ValueError(f"{name} must be finite")
    return c


def polynomial_motion(t: ArrayLike, coefficients: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity and acceleration of x(t) = sum_i c_i t^i.

    Parameters
    ----------
    t
        Time(s) [s], finite; scalar or array.
    coefficients
        c_0 [m], c_1 [m/s], c_2 [m/s^2], ... (increasing power).

    Returns
    -------
    tuple[ndarray, ndarray, ndarray]
        (x [m], v [m/s], a [m/s^2]) by exact differentiation, arrays of t's shape.

    Raises
    ------
    ValueError
        For empty or non-finite coefficients or non-finite t.
    """
    tt = _any_time(t)
    c = _coefficients("coefficients", coefficients)
    x = Polynomial(c)
    v = x.deriv()
    return x(tt), v(tt), v.deriv()(tt)


def integrate_acceleration(
    t: ArrayLike, accel_coefficients: ArrayLike, x0: float, v0: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Motion under a polynomial acceleration a(t) = sum_i a_i t^i.

    v(t) = v0 + sum a_i t^{i+1} / (i+1) and
    x(t) = x0 + v0 t + sum a_i t^{i+2} / ((i+1)(i+2)), i.e. the chapter's
    x(t) = x0 + v0 t + int_0^t int_0^s a dr ds (eq. 5.5); for example
    a = 1.2 t + 3.0, v(0) = 15, x(0) = 150 gives v = 15 + 3 t + 0.6 t^2 and
    x = 150 + 15 t + 1.5 t^2 + 0.2 t^3.

    Parameters
    ----------
    t
        Time(s) [s], finite; scalar or array.
    accel_coefficients
        a_0 [m/s^2], a_1 [m/s^3], ... (increasing power).
    x0
        Position at t = 0 [m].
    v0
        Velocity at t = 0 [m/s].

    Returns
    -------
    tuple[ndarray, ndarray, ndarray]
        (x [m], v [m/s], a [m/s^2]), arrays of t's shape.

    Raises
    ------
    ValueError
        For empty or non-finite input.
    """
    acc = _coefficients("accel_coefficients", accel_coefficients)
    x0 = _finite_scalar("x0", x0)
    v0 = _finite_scalar("v0", v0)
    i = np.arange(acc.size)
    pos = np.concatenate([[x0, v0], acc / ((i + 1.0) * (i + 2.0))])
    return polynomial_motion(t, pos)


def piecewise_linear_velocity(
    t: ArrayLike, knot_times: ArrayLike, knot_velocities: ArrayLike, x0: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact motion for a piecewise-linear velocity record (tachograph).

    Parameters
    ----------
    t
        Time(s) [s] within [knot_times[0], knot_times[-1]].
    knot_times
        Strictly increasing knot times (>= 2) [s].
    knot_velocities
        Velocities at the knots [m/s].
    x0
        Position [m] at knot_times[0].

    Returns
    -------
    tuple[ndarray, ndarray, ndarray]
        (x [m], v [m/s], a [m/s^2]): position is x0 plus the exact area under
        v; acceleration is the segment slope, taken from the segment to the
        right at an interior knot (and from the last segment at the final knot).

    Raises
    ------
    ValueError
        For bad knots, non-finite input or t outside the knot range.
    """
    tk = np.asarray(knot_times, dtype=float)
    vk = np.asarray(knot_velocities, dtype=float)
    if tk.ndim != 1 or tk.size < 2:
        raise ValueError("knot_times must be a 1-D array with at least two knots [s]")
    if vk.shape != tk.shape:
        raise ValueError("knot_velocities must have the same shape as knot_times")
    if not (np.all(np.isfinite(tk)) and np.all(np.isfinite(vk))):
        raise ValueError("knots must be finite")
    if np.any(np.diff(tk) <= 0.0):
        raise ValueError("knot_times must be strictly increasing")
    x0 = _finite_scalar("x0", x0)
    tt = _any_time(t)
    if np.any(tt < tk[0]) or np.any(tt > tk[-1]):
        raise ValueError(f"t must lie within [{tk[0]}, {tk[-1]}] [s]")
    dt = np.diff(tk)
    slope = np.diff(vk) / dt
    # Position at each knot: trapezoid areas are exact for linear v.
    xk = x0 + np.concatenate([[0.0], np.cumsum(0.5 * (vk[:-1] + vk[1:]) * dt)])
    seg = np.clip(np.searchsorted(tk, tt, side="right") - 1, 0, tk.size - 2)
    tau = tt - tk[seg]
    a = slope[seg]
    v = vk[seg] + a * tau
    x = xk[seg] + tau * (vk[seg] + 0.5 * a * tau)
    return x, v, a
