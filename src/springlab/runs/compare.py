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
as it is (it is computed exactly, not estimated). A column that is a small
difference of large terms (a node's velocity in a stiff chain, whose spring
forces nearly cancel) states the round-off one step may add to it
(`Reference.roundoff`, absolute per column), added once per step.

The range of the estimate (`estimate_range`). The formula keeps the first
term of two expansions and drops the rest; it is a tolerance only where the
dropped terms are small. Take one mode lambda of A (every segment's A), h =
dt, z = h lambda, sigma = -Re(lambda), n steps. With the integrator's one-step
map R(z), the mode's exact global error relative to its size at t = 0 is

    e_n = e^(nz) ((1 + eps)^n - 1),   eps = R(z) e^(-z) - 1,

and the estimate keeps L_n = n C |z|^(p+1) e^(-sigma n h). Two bounds make
e_n computable without R:

* local: R(z) - e^z is minus the exponential's tail from z^(p+1) on (exactly
  so for rk4 and explicit Euler, the model of the first-order integrators'
  local error the estimate already uses), whose terms shrink by at least
  r = |z| / (p + 2) each, so |eps| <= a = C |z|^(p+1) e^(sigma h) / (1 - r);
* accumulation: |(1 + eps)^n - 1| <= (1 + a)^n - 1.

So max_n |e_n| <= max_n e^(-sigma n h) ((1 + a)^n - 1), and the ratio F of
that bound to max_n L_n (both maxima in closed form over n = 1..N) bounds how
far the whole error can exceed the kept term. The run is inside the range
when F <= SAFETY for every mode: the dropped terms then fit inside the factor
the tolerance already allows. Outside it the formula is no tolerance
(`springlab run slider undamped --integrator euler --dt 0.05 --duration 20`
predicts 1e2 for a measured error of 1.86) and the run is "not validated".
F grows with h, so the largest dt inside is found by bisection and reported.

A PASS without --tol never certifies more than CERTIFIED_CAP: the tolerance
of a compared column is min(2 x prediction + round-off, CERTIFIED_CAP).

What a run is, judged by these rules, is a `Verdict`; it lives here, in the
run layer, so the run, the studies that sweep runs and everything that shows
them (plots, the command line, the demo) name the same four values.
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import math
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np
import scipy.linalg

from springlab.errors import BadInputError
from springlab.scenes.base import Reference
from springlab.sim.simulate import ERROR_CONSTANTS, ORDERS, ROUNDOFF_PER_STEP, SAFETY

#: the most relative error [-] a PASS certifies without a requested tolerance
CERTIFIED_CAP = 1e-2


class Verdict(enum.StrEnum):
    """What a run held to a tolerance is; each value is the string summary.json's `verdict` holds.

    A `StrEnum`: `Verdict.PASS == "PASS"`, and `str()`, f-strings and JSON give the value.
    """

    #: every compared column (and check) within its tolerance, inside the range of the error estimate
    PASS = "PASS"
    #: a compared column or a check outside its tolerance
    FAIL = "FAIL"
    #: the run is outside the range of its error estimate: the tolerance certifies nothing there
    NOT_VALIDATED = "not validated: outside the range of the error estimate"
    #: the run left the equations its scene models (Scene.model_limits), whatever its errors
    OUTSIDE_MODEL = "not validated: outside the scene's model"

    @property
    def validated(self) -> bool:
        """Whether the tolerance means something for the run (PASS or FAIL)."""
        return self in (Verdict.PASS, Verdict.FAIL)


@dataclasses.dataclass(frozen=True)
class ColumnError:
    """The error of one compared column (`<joint>_pos` or `<joint>_vel`) against its exact reference.

    Attributes
    ----------
    max_abs
        max |sim - ref| over the run [m or m/s; rad or rad/s for hinges].
    max_rel
        max_abs / max |ref| [-] (max_abs where the reference is 0 throughout).
    """

    max_abs: float
    max_rel: float

    def to_dict(self) -> dict[str, float]:
        """summary.json's form: {"max_abs", "max_rel"}."""
        return {"max_abs": self.max_abs, "max_rel": self.max_rel}


def check_tolerance(tol: Any) -> float:
    """A requested relative tolerance [-] as a float, or BadInputError saying what is valid."""
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not math.isfinite(tol) or tol <= 0:
        raise BadInputError(f"tol must be a finite number > 0 (relative error), got {tol!r}")
    return float(tol)


def column_errors(
    simulated: dict[str, np.ndarray], reference: dict[str, np.ndarray], scales: dict[str, float] | None = None
) -> dict[str, ColumnError]:
    """Per column: max_abs = max |sim - ref| and max_rel = max_abs / max |ref|.

    Parameters
    ----------
    simulated, reference
        column name -> series (same length).
    scales
        column -> the scale [its unit] of max_rel where the reference is 0 throughout (a block
        held at rest; `Reference.scales`); without one such a column's max_rel is its max_abs.
    """
    errors = {}
    for name, ref in reference.items():
        max_abs = float(np.max(np.abs(simulated[name] - ref)))
        scale = float(np.max(np.abs(ref))) or float((scales or {}).get(name, 0.0))
        errors[name] = ColumnError(max_abs, max_abs / scale if scale > 0 else max_abs)
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
    """Relative tolerance per compared column (see module docstring); kept on the reference per setting."""
    key = ("tolerances", integrator, float(dt), len(time), float(time[0]), float(time[-1]))
    if key not in reference.derived:
        reference.derived[key] = _tolerances(reference, integrator, dt, time)
    return dict(reference.derived[key])


def _tolerances(reference: Reference, integrator: str, dt: float, time: np.ndarray) -> dict[str, float]:
    floor = ROUNDOFF_PER_STEP * (len(time) - 1)
    predicted = predicted_error(reference, integrator, dt, time)
    out: dict[str, float] = {}
    for joint in reference.rows:
        for kind, series in (("pos", reference.pos[joint]), ("vel", reference.vel[joint])):
            column = f"{joint}_{kind}"
            scale = float(np.max(np.abs(series)))
            rel = predicted[column] / scale if scale > 0 else predicted[column]
            known = reference.input_error.get(column, 0.0) + reference.roundoff.get(column, 0.0) * (len(time) - 1)
            out[column] = SAFETY * rel + (known / scale if scale > 0 else known) + floor
    return out


TOLERANCE_BASIS = (
    "2 x the leading-order global error C h^p t |A^(p+1) z(t)| of an order-p integrator"
    " (C = 1/120 for rk4, 1/2 for first-order) + 100 eps per step"
)


@dataclasses.dataclass(frozen=True)
class EstimateRange:
    """Whether the leading-order error estimate holds for a run (see module docstring).

    Attributes
    ----------
    inside
        the dropped terms fit inside the safety factor: the tolerance means something.
    factor
        the worst mode's bound F on (whole error) / (kept term) [-] (inf: no bound).
    rate
        that mode's eigenvalue lambda [1/s] (0 when A has no other).
    dt
        the run's timestep [s].
    largest_dt
        the largest timestep [s] inside the range for the same duration (2 significant
        digits, rounded down; inf when every dt is).
    """

    inside: bool
    factor: float
    rate: complex
    dt: float
    largest_dt: float

    def reason(self) -> str:
        """One line: why the run is outside (or inside) the range, and which dt is inside."""
        if self.inside:
            return f"inside the range of the error estimate (the error can reach at most {self.factor:.3g} x it)"
        rate = self.rate
        mode = f"the {abs(rate):.4g} 1/s mode (damping ratio {-rate.real / abs(rate) + 0.0:.3g})"
        bound = f"{self.factor:.3g} x" if math.isfinite(self.factor) else "any multiple of"
        line = (
            f"h|lambda| = {self.dt * abs(rate):.3g} on {mode}: its error can reach {bound} the leading-order"
            f" estimate, over the safety factor {SAFETY:g}"
        )
        return f"{line}; dt <= {self.largest_dt:.2g} s is inside" if math.isfinite(self.largest_dt) else line

    def to_dict(self) -> dict[str, Any]:
        """summary.json's `estimate_range`: inside, error_bound_factor, largest_dt_inside_s [s], reason.

        null, never a string, for what does not exist: an infinite factor (a diverging tail) and no
        largest dt (every dt is inside).
        """
        return {
            "inside": self.inside,
            "error_bound_factor": self.factor if math.isfinite(self.factor) else None,
            "largest_dt_inside_s": self.largest_dt if math.isfinite(self.largest_dt) else None,
            "reason": self.reason(),
        }


#: halvings in log h of the bracket around the largest dt inside the range: a decade to 1e-7 relative
BISECTIONS = 24
#: halvings evaluated per batch of midpoints (`_bisect_ahead`): 2^_AHEAD - 1 timesteps at once, BISECTIONS / _AHEAD
#: batches instead of BISECTIONS calls, each mostly numpy's per-call overhead (estimate_range, a call of every run,
#: sweep row and fit timestep: 2.2 -> 1.3 ms for 2 modes, 3.7 -> 2.6 ms for 100) ...
_AHEAD = 4
#: ... up to this many modes (beyond, the 15 timesteps' arithmetic outweighs the calls saved: one at a time)
_AHEAD_MODES = 100


def _round_down(value: float, digits: int = 2) -> float:
    """`value` > 0 rounded down to `digits` significant digits."""
    unit = 10.0 ** (math.floor(math.log10(value)) - digits + 1)
    out = float(f"{math.floor(value / unit * (1 + 1e-12)) * unit:.{digits - 1}e}")
    return out if out <= value else float(f"{out - unit:.{digits - 1}e}")


def _max_over_steps(values, steps: np.ndarray, peak: np.ndarray) -> np.ndarray:
    """Per mode, the max of values(n) over the integers n in [1, steps] next to its real peak (unimodal)."""
    floor = np.clip(np.floor(peak), 1, steps)
    candidates = np.stack(
        [np.ones_like(peak), np.broadcast_to(steps, peak.shape), floor, np.clip(np.ceil(peak), 1, steps)]
    )
    return np.max(values(candidates), axis=0)


def mode_factors(rates: np.ndarray, integrator: str, dt: float, duration: float) -> np.ndarray:
    """F [-] of every mode at once: its whole error's bound over the estimate's kept term; inf where none.

    Parameters
    ----------
    rates
        (modes,) eigenvalues lambda [1/s].
    integrator
        integrator name.
    dt
        timestep [s].
    duration
        simulated time [s].
    """
    factors, failure = _factors_at(np.asarray(rates, complex), integrator, [dt], duration)
    if failure[0] is not None:
        raise failure[0]
    return factors[0]


def _factors_at(
    rates: np.ndarray, integrator: str, dts: Sequence[float], duration: float
) -> tuple[np.ndarray, list[ArithmeticError | None]]:
    """`mode_factors` at several timesteps [s] at once: ((len(dts), modes) F [-], per dt the exception
    `mode_factors` raises there or None). Every number is the one `mode_factors` computes at that dt alone
    (the same elementwise operations, one row per dt)."""
    order = ORDERS[integrator]
    steps = np.array([float(max(1, round(duration / dt))) for dt in dts])[:, None]
    dt_column = np.array([float(dt) for dt in dts])[:, None]
    size = dt_column * np.abs(rates)
    decay = -rates.real * dt_column  # sigma h
    tail = size / (order + 2)
    bounded = tail < 1.0
    with np.errstate(all="ignore"):
        kept = ERROR_CONSTANTS[integrator] * size ** (order + 1)
        local = np.where(bounded, kept * np.exp(decay) / (1.0 - tail), 0.0)  # bound a on |eps|
        growth = np.log1p(local)

        def whole(n: np.ndarray) -> np.ndarray:
            # e^(-sigma h n) ((1 + a)^n - 1) in logs: log(expm1(x)) = x + log1p(-e^-x), no overflow
            x = growth * n
            log_expm1 = np.where(x < 30.0, np.log(np.expm1(np.minimum(x, 30.0))), x + np.log1p(-np.exp(-x)))
            return np.where(x > 0.0, np.exp(np.minimum(-decay * n + log_expm1, 700.0)), 0.0)

        # e^(-sigma h n) ((1 + a)^n - 1) peaks where its derivative vanishes (or at the end if it never decays)
        rate_of_change = growth - decay
        rising = (rate_of_change >= 0.0) | (decay <= 0.0)
        peak = np.where(rising, steps, np.log(decay / -rate_of_change) / np.where(rising, 1.0, growth))
        # a decaying mode whose local error bound underflows to 0 has no peak in double precision: the
        # same exceptions as the arithmetic per mode (runs.run turns them into "cannot be computed")
        underflow = np.any(bounded & ~rising & (growth <= 0.0), axis=1)
        overflow = np.any(bounded & ~np.isfinite(peak), axis=1)
        numerator = _max_over_steps(whole, steps, peak)
        kept_peak = np.where(decay > 0, 1.0 / decay, steps)
        denominator = _max_over_steps(lambda n: n * kept * np.exp(-decay * n), steps, kept_peak)
        factor = numerator / denominator
    failure: list[ArithmeticError | None] = [
        ZeroDivisionError("float division by zero")
        if under
        else OverflowError("cannot convert float infinity to integer")
        if over
        else None
        for under, over in zip(underflow, overflow)
    ]
    return np.where(bounded & (denominator > 0.0) & np.isfinite(numerator), factor, np.inf), failure


def mode_factor(rate: complex, integrator: str, dt: float, duration: float) -> float:
    """F [-]: bound on a mode's whole error over the estimate's kept term (module docstring); inf if none.

    Parameters
    ----------
    rate
        the mode's eigenvalue lambda [1/s].
    integrator
        integrator name.
    dt
        timestep [s].
    duration
        simulated time [s].
    """
    return float(mode_factors(np.array([rate]), integrator, dt, duration)[0])


def system_rates(reference: Reference) -> list[complex]:
    """Eigenvalues lambda [1/s] of every system matrix of the reference (segments included), 0 dropped."""
    if "system_rates" not in reference.derived:
        reference.derived["system_rates"] = tuple(_system_rates(reference))
    return list(reference.derived["system_rates"])


def _system_rates(reference: Reference) -> list[complex]:
    systems = [reference.system] + [a for _, a in reference.switches]
    rates: list[complex] = []
    for a in systems:
        values = np.linalg.eigvals(np.asarray(a, float))
        scale = max(float(np.max(np.abs(values))), 1e-300)
        rates.extend(complex(v) for v in values if abs(v) > 1e-12 * scale)
    return rates


def estimate_range(rates: Iterable[complex], integrator: str, dt: float, duration: float) -> EstimateRange:
    """Whether a run at dt [s] over duration [s] is inside the range of the error estimate.

    Parameters
    ----------
    rates
        eigenvalues lambda [1/s] of the run's linear system (`system_rates`).
    integrator
        integrator name.
    dt
        timestep [s].
    duration
        simulated time [s].
    """
    rates = list(rates)
    if not rates:
        return EstimateRange(True, 1.0, 0j, dt, math.inf)
    return _estimate_range(tuple(complex(r) for r in rates), integrator, float(dt), float(duration))


@functools.lru_cache(maxsize=256)
def _estimate_range(rates: tuple[complex, ...], integrator: str, dt: float, duration: float) -> EstimateRange:
    """`estimate_range` of modes that are there, kept per (modes, setting): it depends on nothing else."""
    modes = np.array(rates, complex)

    def worst(h: float) -> tuple[float, complex]:
        factors = mode_factors(modes, integrator, h, duration)
        which = int(np.argmax(factors))  # the first of equal factors, as max() over the modes
        return float(factors[which]), rates[which]

    factor, rate = worst(dt)
    inside = factor <= SAFETY
    # F grows with h: bracket the boundary by decades, then bisect in log h
    low, high = (dt, 10.0 * dt) if inside else (dt / 10.0, dt)
    while worst(high)[0] <= SAFETY and high < dt * 1e12:
        low, high = high, 10.0 * high
    while worst(low)[0] > SAFETY and low > dt * 1e-12:
        low, high = low / 10.0, low
    ahead = _AHEAD if len(rates) <= _AHEAD_MODES else 1
    for _ in range(BISECTIONS // ahead):  # a decade to 1e-7 relative: far below the 2 digits reported
        low, high = _bisect_ahead(modes, integrator, duration, low, high, worst, ahead)
    return EstimateRange(inside, factor, rate, dt, _round_down(low))


def _bisect_ahead(
    modes: np.ndarray,
    integrator: str,
    duration: float,
    low: float,
    high: float,
    worst: Callable[[float], tuple[float, complex]],
    ahead: int,
) -> tuple[float, float]:
    """`ahead` halvings in log h of [low, high] [s] (inside at low, outside at high): every midpoint those halvings
    may reach is evaluated in one `_factors_at` call (2^ahead - 1 of them, breadth first: node i's halves are
    2i + 1, the lower, and 2i + 2), then the path is walked. The midpoints and their factors are the ones the
    halvings one at a time compute, so the bracket is the same; where a midpoint off the path would raise, the
    halvings run one at a time (`worst`), as before."""
    mids: list[float] = []
    level = [(low, high)]
    for _ in range(ahead):
        halves = []
        for lo, hi in level:
            mid = math.sqrt(lo * hi)
            mids.append(mid)
            halves += [(lo, mid), (mid, hi)]
        level = halves
    factors, failure = _factors_at(modes, integrator, mids, duration)
    if any(f is not None for f in failure):
        for _ in range(ahead):
            mid = math.sqrt(low * high)
            low, high = (mid, high) if worst(mid)[0] <= SAFETY else (low, mid)
        return low, high
    # the worst mode's factor per midpoint, as `worst`: the first of equal factors (a NaN first, as argmax)
    worst_factors = factors[np.arange(len(mids)), np.argmax(factors, axis=1)]
    node = 0
    for _ in range(ahead):
        if worst_factors[node] <= SAFETY:
            low, node = mids[node], 2 * node + 2
        else:
            high, node = mids[node], 2 * node + 1
    return low, high
