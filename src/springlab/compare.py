"""Errors against the exact reference, and the tolerance each run is held to.

The tolerance is not tuned: it is the integrator's leading-order global error,
predicted from its order p and the timestep h, times a safety factor of 2.

For a linear scene the reference comes from an autonomous system z' = A z
(forcing included as exact generator states: a constant, a sine/cosine pair).
A one-step method of order p commits a local error C h^(p+1) A^(p+1) z per
step; for a linear time-invariant system these errors add up without
interfering, so after time t the global error is, to leading order,

    e(t) = C h^p t A^(p+1) z(t)

exactly for RK4 (C = 1/120, from R(hA) = e^(hA) - (hA)^5/120 + ...). For the
first-order integrators (euler, implicit, implicitfast, discrete) the same
form with C = 1/2, the local error constant of a first-order method, is an
upper estimate: the symplectic ones keep the energy bounded, so their real
error grows more slowly than t. The bound on column `<joint>_pos` is

    tol = 2 max_t |e_x(t)| / max_t |x_ref(t)| + 100 eps N

(velocity columns likewise, in the scaled norm |(x, v / rho)| with rho the
spectral radius of A), the last term the round-off of N steps.

Piecewise-constant systems: an input switched on or off on a step boundary
changes A at that instant (`Reference.switches`). The errors committed before
the switch are then carried on by the exact flow of the new system, and the
new segment adds its own, so on segment j (from s_j, matrix A_j)

    e(t) = exp(A_j (t - s_j)) e(s_j) + C h^p (t - s_j) A_j^(p+1) z(t)

which reduces to the formula above when nothing switches. A scene whose model
can only approximate its true input states the exact size of the difference
(`Reference.input_error`, absolute per column); it is added to the tolerance
as it is (it is computed exactly, not estimated).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.linalg

from .errors import BadInputError
from .scene import Reference
from .simulate import ORDERS

#: safety factor on the predicted leading-order error
SAFETY = 2.0
#: leading local-error constants C: first-order methods 1/2, RK4 1/120
ERROR_CONSTANTS = {name: (1.0 / 120.0 if order == 4 else 0.5) for name, order in ORDERS.items()}
#: round-off allowance per step, relative
ROUNDOFF_PER_STEP = 100 * np.finfo(float).eps


def check_tolerance(tol: Any) -> float:
    """A requested relative tolerance [-] as a float, or BadInputError saying what is valid."""
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not math.isfinite(tol) or tol <= 0:
        raise BadInputError(f"tol must be a finite number > 0 (relative error), got {tol!r}")
    return float(tol)


def column_errors(simulated: dict[str, np.ndarray], reference: dict[str, np.ndarray]) -> dict[str, dict]:
    """Per column: max_abs = max |sim - ref| and max_rel = max_abs / max |ref|.

    Parameters
    ----------
    simulated, reference
        column name -> series (same length).
    """
    errors = {}
    for name, ref in reference.items():
        max_abs = float(np.max(np.abs(simulated[name] - ref)))
        scale = float(np.max(np.abs(ref)))
        errors[name] = {"max_abs": max_abs, "max_rel": max_abs / scale if scale > 0 else max_abs}
    return errors


def predicted_error(reference: Reference, integrator: str, dt: float, time: np.ndarray) -> dict[str, float]:
    """Leading-order max absolute error per column [m or m/s] (see module docstring).

    Parameters
    ----------
    reference
        exact solution with its `system` matrix A, `states` z(t) and
        optional `switches` (A changes on step boundaries).
    integrator
        integrator name.
    dt
        timestep [s].
    time
        (n,) times of the states [s], uniformly dt apart.
    """
    z = reference.states
    assert z is not None, "tolerances() needs a linear reference (states and system)"
    order = ORDERS[integrator]
    scale = ERROR_CONSTANTS[integrator] * dt**order
    segments = [(float(time[0]), np.asarray(reference.system, float))]
    segments += [(float(s), np.asarray(a, float)) for s, a in reference.switches if time[0] < s < time[-1]]
    error = np.zeros_like(z)  # signed leading-order global error vectors e(t)
    carried = np.zeros(z.shape[1])
    for j, (start, a) in enumerate(segments):
        first = int(np.argmin(np.abs(time - start)))
        if abs(time[first] - start) > 1e-6 * dt:  # MuJoCo accumulates time by t += dt
            raise ValueError(f"system switch at t = {start} s is not on the step grid (dt = {dt} s)")
        last = int(np.argmin(np.abs(time - segments[j + 1][0]))) if j + 1 < len(segments) else len(time) - 1
        rows = slice(first, last + 1)
        elapsed = time[rows] - start
        error[rows] = scale * elapsed[:, None] * (z[rows] @ np.linalg.matrix_power(a, order + 1).T)
        if carried.any():
            step = scipy.linalg.expm(a * dt)
            propagated = np.empty((last + 1 - first, z.shape[1]))
            propagated[0] = carried
            for i in range(1, len(propagated)):
                propagated[i] = step @ propagated[i - 1]
            error[rows] += propagated
        carried = error[last].copy()
    rho = max(max(float(np.max(np.abs(np.linalg.eigvals(a)))) for _, a in segments), 1.0 / max(float(time[-1]), 1e-300))
    out = {}
    for joint, (ip, iv) in reference.rows.items():
        scaled = np.hypot(error[:, ip], error[:, iv] / rho)
        out[f"{joint}_pos"] = float(np.max(scaled))
        out[f"{joint}_vel"] = float(np.max(scaled)) * rho
    return out


def tolerances(reference: Reference, integrator: str, dt: float, time: np.ndarray) -> dict[str, float]:
    """Relative tolerance per compared column (see module docstring)."""
    floor = ROUNDOFF_PER_STEP * (len(time) - 1)
    predicted = predicted_error(reference, integrator, dt, time)
    out: dict[str, float] = {}
    for joint in reference.rows:
        for kind, series in (("pos", reference.pos[joint]), ("vel", reference.vel[joint])):
            column = f"{joint}_{kind}"
            scale = float(np.max(np.abs(series)))
            rel = predicted[column] / scale if scale > 0 else predicted[column]
            known = reference.input_error.get(column, 0.0)
            out[column] = SAFETY * rel + (known / scale if scale > 0 else known) + floor
    return out


TOLERANCE_BASIS = (
    "2 x the leading-order global error C h^p t |A^(p+1) z(t)| of an order-p integrator"
    " (C = 1/120 for rk4, 1/2 for first-order) + 100 eps per step"
)
