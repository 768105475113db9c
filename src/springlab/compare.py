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

The range of the estimate (`estimate_range`). The formula keeps the first
term of two expansions and drops the rest; it is a tolerance only where the
dropped terms are small. Per mode lambda of A (every segment), with h = dt,
z = h lambda and eps = C |z|^(p+1) the leading local error relative to the
mode:

* local: the one-step error is a series in z whose terms shrink by at most
  r_loc = K |z| each (the exponential's tail: K = 1/(p + 2), 1/6 for rk4 and
  1/3 for the first-order integrators, modelled like explicit Euler), so the
  whole local error is at most eps / (1 - r_loc);
* accumulation: n steps turn a per-step error eps into (1 + eps)^n - 1 =
  n eps + C(n, 2) eps^2 + ..., whose terms shrink by at most r_acc, the ratio
  of the largest second term to the largest first term over the run:
  r_acc = eps' / (2 h) u2^2 e^(-sigma u2) / (u1 e^(-sigma u1)), sigma =
  -Re(lambda), u1 = min(T, 1/sigma), u2 = min(T, 2/sigma) (the times where
  t e^(-sigma t) and t^2 e^(-sigma t) peak; u = T for an undamped mode, where
  r_acc = n eps' / 2), eps' = eps / (1 - r_loc).

Both tails geometric, the whole error is at most the leading term times
1 / ((1 - r_loc)(1 - r_acc)). The estimate is trusted (the run is inside the
range) when that factor is at most SAFETY, the factor the tolerance already
allows: the dropped terms then fit inside the tolerance. Outside it, the
formula is no tolerance (`springlab run slider undamped --integrator euler
--dt 0.05 --duration 20` predicts 1e2 for a measured error of 1.86), and the
run is "not validated". Both ratios grow with h, so the largest dt inside is
found by bisection and reported.

A PASS without --tol never certifies more than CERTIFIED_CAP: the tolerance
of a compared column is min(2 x prediction + round-off, CERTIFIED_CAP).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable
from typing import Any

import numpy as np

from . import analytic
from .errors import BadInputError
from .scene import Reference
from .simulate import ORDERS

#: safety factor on the predicted leading-order error
SAFETY = 2.0
#: leading local-error constants C: first-order methods 1/2, RK4 1/120
ERROR_CONSTANTS = {name: (1.0 / 120.0 if order == 4 else 0.5) for name, order in ORDERS.items()}
#: round-off allowance per step, relative
ROUNDOFF_PER_STEP = 100 * np.finfo(float).eps
#: ratio bound K of consecutive local-error terms per unit |h lambda|: 1/(p + 2) (the exponential's tail)
NEXT_TERM_RATIOS = {name: 1.0 / (order + 2) for name, order in ORDERS.items()}
#: the most relative error [-] a PASS certifies without a requested tolerance
CERTIFIED_CAP = 1e-2
#: the verdicts of a run held to a tolerance
PASS, FAIL, NOT_VALIDATED = "PASS", "FAIL", "not validated: outside the range of the error estimate"


def check_tolerance(tol: Any) -> float:
    """A requested relative tolerance [-] as a float, or BadInputError saying what is valid."""
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not math.isfinite(tol) or tol <= 0:
        raise BadInputError(f"tol must be a finite number > 0 (relative error), got {tol!r}")
    return float(tol)


def column_errors(simulated: dict[str, np.ndarray], reference: dict[str, np.ndarray]) -> dict[str, dict]:
    """Per column: max_abs = max |sim - ref| and max_rel = max_abs / max |ref|.

    Args:
      simulated, reference: column name -> series (same length).
    """
    errors = {}
    for name, ref in reference.items():
        max_abs = float(np.max(np.abs(simulated[name] - ref)))
        scale = float(np.max(np.abs(ref)))
        errors[name] = {"max_abs": max_abs, "max_rel": max_abs / scale if scale > 0 else max_abs}
    return errors


def predicted_error(reference: Reference, integrator: str, dt: float, time: np.ndarray) -> dict[str, float]:
    """Leading-order max absolute error per column [m or m/s] (see module docstring).

    Args:
      reference: exact solution with its `system` matrix A, `states` z(t) and
        optional `switches` (A changes on step boundaries).
      integrator: integrator name.
      dt: timestep [s].
      time: (n,) times of the states [s], uniformly dt apart.
    """
    z = reference.states
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
            step = analytic.expm(a * dt)
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
    out = {}
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


@dataclasses.dataclass(frozen=True)
class EstimateRange:
    """Whether the leading-order error estimate holds for a run (see module docstring).

    Attributes:
      inside: the dropped terms fit inside the safety factor: the tolerance means something.
      factor: worst mode's bound on (whole error) / (leading term) [-], inf when a tail diverges.
      rate: that mode's eigenvalue lambda [1/s] (0 when A has none but 0).
      local_ratio, accumulation_ratio: that mode's r_loc and r_acc [-].
      dt: the run's timestep [s].
      largest_dt: the largest timestep [s] inside the range for the same duration (2 significant
        digits, rounded down; inf when every dt is).
    """

    inside: bool
    factor: float
    rate: complex
    local_ratio: float
    accumulation_ratio: float
    dt: float
    largest_dt: float

    def reason(self) -> str:
        """One line: why the run is outside (or inside) the range, and which dt is inside."""
        if self.inside:
            return f"inside the range of the error estimate (dropped terms at most {self.factor - 1:.2g} x the kept)"
        rate = self.rate
        mode = f"the {abs(rate):.4g} 1/s mode (damping ratio {-rate.real / abs(rate) + 0.0:.3g})"
        line = (
            f"h|lambda| = {self.dt * abs(rate):.3g} on {mode}: the terms the estimate drops (local"
            f" {self.local_ratio:.2g}, accumulated {self.accumulation_ratio:.2g} x the kept one) exceed its"
            f" safety factor {SAFETY:g}"
        )
        return f"{line}; dt <= {self.largest_dt:.2g} s is inside" if math.isfinite(self.largest_dt) else line


def _round_down(value: float, digits: int = 2) -> float:
    """`value` > 0 rounded down to `digits` significant digits."""
    unit = 10.0 ** (math.floor(math.log10(value)) - digits + 1)
    out = math.floor(value / unit * (1 + 1e-12)) * unit
    out = float(f"{out:.{digits - 1}e}")
    return out if out <= value else float(f"{out - unit:.{digits - 1}e}")


def mode_ratios(rate: complex, integrator: str, dt: float, duration: float) -> tuple[float, float, float]:
    """(r_loc, r_acc, factor) [-] of one mode lambda = `rate` [1/s] at timestep dt [s] over duration [s].

    factor = 1 / ((1 - r_loc)(1 - r_acc)) bounds the whole error over its leading term (inf when
    either ratio reaches 1: the tail no longer converges). See the module docstring.
    """
    order = ORDERS[integrator]
    size = dt * abs(rate)
    local = NEXT_TERM_RATIOS[integrator] * size
    if local >= 1.0:
        return local, math.inf, math.inf
    per_step = ERROR_CONSTANTS[integrator] * size ** (order + 1) / (1.0 - local)
    sigma = -float(np.real(rate))
    first = duration if sigma <= 1.0 / duration else 1.0 / sigma
    second = duration if sigma <= 2.0 / duration else 2.0 / sigma
    accumulated = per_step / (2.0 * dt) * second**2 / first * math.exp(-sigma * (second - first))
    if accumulated >= 1.0:
        return local, accumulated, math.inf
    return local, accumulated, 1.0 / ((1.0 - local) * (1.0 - accumulated))


def system_rates(reference: Reference) -> list[complex]:
    """Eigenvalues lambda [1/s] of every system matrix of the reference (segments included), 0 dropped."""
    systems = [reference.system] + [a for _, a in reference.switches]
    rates = []
    for a in systems:
        values = np.linalg.eigvals(np.asarray(a, float))
        scale = max(float(np.max(np.abs(values))), 1e-300)
        rates.extend(complex(v) for v in values if abs(v) > 1e-12 * scale)
    return rates


def estimate_range(rates: Iterable[complex], integrator: str, dt: float, duration: float) -> EstimateRange:
    """Whether a run at dt [s] over duration [s] is inside the range of the error estimate.

    Args:
      rates: eigenvalues lambda [1/s] of the run's linear system (`system_rates`).
      integrator: integrator name.
      dt: timestep [s].
      duration: simulated time [s].
    """
    rates = list(rates)
    if not rates:
        return EstimateRange(True, 1.0, 0j, 0.0, 0.0, dt, math.inf)

    def worst(h: float) -> tuple[float, complex, float, float]:
        ratios = [(mode_ratios(r, integrator, h, duration), r) for r in rates]
        (local, accumulated, factor), rate = max(ratios, key=lambda item: item[0][2])
        return factor, rate, local, accumulated

    factor, rate, local, accumulated = worst(dt)
    inside = factor <= SAFETY
    # the factor grows with h (r_loc ~ h, r_acc ~ h^p): bracket the boundary by decades, then bisect in log h
    low, high = (dt, 10.0 * dt) if inside else (dt / 10.0, dt)
    while worst(high)[0] <= SAFETY and high < dt * 1e12:
        low, high = high, 10.0 * high
    while worst(low)[0] > SAFETY and low > dt * 1e-12:
        low, high = low / 10.0, low
    for _ in range(60):
        mid = math.sqrt(low * high)
        low, high = (mid, high) if worst(mid)[0] <= SAFETY else (low, mid)
    return EstimateRange(inside, factor, rate, local, accumulated, dt, _round_down(low))
