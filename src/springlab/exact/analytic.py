"""Exact (closed-form or exponential-integrator) solutions for linear vibration.

Everything here is pure NumPy and is meant to be the *reference* that the
physics-engine scenes are validated against, so the emphasis is on formulas
that stay accurate to a few ulps in every regime rather than on the shortest
textbook expression.

Single degree of freedom
    ``m x'' + d x' + k x = F(t)`` with ``m > 0``, ``k >= 0``, ``d >= 0``.
    Free, step and harmonic responses are evaluated with formulas that are
    continuous across critical damping, survive extreme overdamping (the slow
    root ``-k/d`` is computed without cancellation), ``k = 0`` (a free mass)
    and exact undamped resonance.

Many degrees of freedom / general LTI systems
    ``z' = A z + B u(t)`` live in :mod:`springlab.exact.linear` (matrix exponentials);
    :func:`state_matrix`, :func:`linear_response` and :func:`lti_response` are
    re-exported here, where the scenes first found them.

Kinematics
    Polynomial motion, integration of a polynomial acceleration and the exact
    position for a piecewise-linear (tachograph-like) velocity record live in
    :mod:`springlab.exact.polynomials`; they are re-exported here as well.

Units are SI throughout: [kg], [N/m], [N s/m], [m], [m/s], [s], [Hz], [rad/s].
All time arguments are evaluated element-wise; the outputs have ``t``'s shape.
"""

from __future__ import annotations

import math

import numpy as np

# re-exported: the scenes reach the multi-DOF and kinematics references through analytic
from .linear import linear_response, lti_response, state_matrix
from .polynomials import integrate_acceleration, piecewise_linear_velocity, polynomial_motion

__all__ = [
    "natural_frequency",
    "damping_ratio",
    "damped_frequency",
    "regime",
    "characteristic_roots",
    "free_response",
    "step_response",
    "harmonic_response",
    "steady_state_amplitude",
    "state_matrix",
    "linear_response",
    "lti_response",
    "polynomial_motion",
    "integrate_acceleration",
    "piecewise_linear_velocity",
]

ArrayLike = float | np.ndarray | list | tuple

#: |zeta - 1| at or below this is reported as critical damping by :func:`regime`.
CRITICAL_TOLERANCE = 1e-12
#: Relative detuning |k - m W^2| / max(k, m W^2) treated as exact undamped
#: resonance by :func:`steady_state_amplitude`.
RESONANCE_TOLERANCE = 1e-12


# ---------------------------------------------------------------------------
# input validation
# ---------------------------------------------------------------------------


def _finite_scalar(name: str, value) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real scalar, got {value!r}") from None
    if not math.isfinite(out):
        raise ValueError(f"{name} must be finite, got {out!r}")
    return out


def _check_oscillator(mass, stiffness, damping) -> tuple[float, float, float]:
    m = _finite_scalar("mass", mass)
    k = _finite_scalar("stiffness", stiffness)
    d = _finite_scalar("damping", damping)
    if m <= 0.0:
        raise ValueError(f"mass must be > 0 [kg], got {m!r}")
    if k < 0.0:
        raise ValueError(f"stiffness must be >= 0 [N/m], got {k!r}")
    if d < 0.0:
        raise ValueError(f"damping must be >= 0 [N s/m], got {d!r}")
    return m, k, d


def _response_time(t) -> np.ndarray:
    arr = np.asarray(t, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ValueError("t must contain only finite times [s]")
    if np.any(arr < 0.0):
        raise ValueError("t must be >= 0 [s] (time since the initial condition)")
    return arr


# ---------------------------------------------------------------------------
# scalar oscillator: parameters
# ---------------------------------------------------------------------------


def natural_frequency(mass: float, stiffness: float) -> float:
    """Undamped natural angular frequency.

    Parameters
    ----------
    mass
        Mass m [kg], > 0.
    stiffness
        Spring constant k [N/m], >= 0.

    Returns
    -------
    float
        omega_n = sqrt(k / m) [rad/s].

    Raises
    ------
    ValueError
        For non-finite input, m <= 0 or k < 0.
    """
    m, k, _ = _check_oscillator(mass, stiffness, 0.0)
    return math.sqrt(k / m)


def damping_ratio(mass: float, stiffness: float, damping: float) -> float:
    """Dimensionless damping ratio.

    Parameters
    ----------
    mass
        Mass m [kg], > 0.
    stiffness
        Spring constant k [N/m], >= 0.
    damping
        Viscous damping coefficient d [N s/m], >= 0.

    Returns
    -------
    float
        zeta = d / (2 sqrt(k m)) [-]; ``math.inf`` for k = 0 with d > 0 and
        0.0 for d = 0.

    Raises
    ------
    ValueError
        For non-physical or non-finite input.
    """
    m, k, d = _check_oscillator(mass, stiffness, damping)
    if d == 0.0:
        return 0.0
    if k == 0.0:
        return math.inf
    km = k * m
    # sqrt(k) * sqrt(m) only if k * m over/underflows (it rounds twice).
    root = math.sqrt(km) if 0.0 < km < math.inf else math.sqrt(k) * math.sqrt(m)
    return d / (2.0 * root)


def damped_frequency(mass: float, stiffness: float, damping: float) -> float:
    """Damped natural angular frequency.

    Parameters
    ----------
    mass
        Mass m [kg], > 0.
    stiffness
        Spring constant k [N/m], >= 0.
    damping
        Viscous damping coefficient d [N s/m], >= 0.

    Returns
    -------
    float
        omega_d = omega_n sqrt(1 - zeta^2) [rad/s] for zeta < 1, else 0.0.

    Raises
    ------
    ValueError
        For non-physical or non-finite input.
    """
    m, k, d = _check_oscillator(mass, stiffness, damping)
    # Same beta as the time responses: sqrt((wn - sigma)(wn + sigma)), which
    # keeps its relative accuracy as zeta -> 1.
    _, _, b2, beta = _oscillator_constants(m, k, d)
    return beta if b2 > 0.0 else 0.0


def regime(mass: float, stiffness: float, damping: float) -> str:
    """Classify the free motion.

    Parameters
    ----------
    mass
        Mass m [kg], > 0.
    stiffness
        Spring constant k [N/m], >= 0.
    damping
        Viscous damping coefficient d [N s/m], >= 0.

    Returns
    -------
    str
        ``'undamped'`` iff d == 0; otherwise ``'critical'`` when
        |zeta - 1| <= 1e-12, ``'underdamped'`` for smaller zeta and
        ``'overdamped'`` for larger zeta (including k == 0 with d > 0).

    Raises
    ------
    ValueError
        For non-physical or non-finite input.
    """
    zeta = damping_ratio(mass, stiffness, damping)
    if damping == 0.0:
        return "undamped"
    if abs(zeta - 1.0) <= CRITICAL_TOLERANCE:
        return "critical"
    return "underdamped" if zeta < 1.0 else "overdamped"


def _oscillator_constants(m: float, k: float, d: float):
    """sigma [1/s], omega_n^2 [1/s^2], beta^2 = omega_n^2 - sigma^2 [1/s^2], |beta| [1/s]."""
    sigma = d / (2.0 * m)
    wn2 = k / m
    wn = math.sqrt(wn2)
    # Factored difference: exact sign and no overflow of sigma**2 for huge d.
    b2 = (wn - sigma) * (wn + sigma)
    return sigma, wn2, b2, math.sqrt(abs(b2))


def _overdamped_roots(sigma: float, wn2: float, gamma: float) -> tuple[float, float]:
    """(fast, slow) real roots; the slow one from the product of roots (no cancellation)."""
    fast = -(sigma + gamma)
    slow = -wn2 / (sigma + gamma) + 0.0  # + 0.0 turns -0.0 into 0.0 for k == 0
    return fast, slow


def characteristic_roots(mass: float, stiffness: float, damping: float) -> tuple[complex, complex]:
    """Roots of the characteristic polynomial m s^2 + d s + k = 0.

    Overdamped roots use the cancellation-free pair q/m and k/q with
    q = -(d + sqrt(d^2 - 4 m k)) / 2 (evaluated in scaled form so that d^2
    cannot overflow), so the slow root is accurate to a few ulps even for
    m = 1, k = 1, d = 1e9 (slow root ~ -1e-9).

    Parameters
    ----------
    mass
        Mass m [kg], > 0.
    stiffness
        Spring constant k [N/m], >= 0.
    damping
        Viscous damping coefficient d [N s/m], >= 0.

    Returns
    -------
    tuple[complex, complex]
        ``(s1, s2)`` [rad/s] as complex numbers.  Underdamped / undamped:
        ``(-sigma + i omega_d, -sigma - i omega_d)``.  Critical (beta^2 == 0
        exactly): both ``-sigma``.  Overdamped: ``(fast, slow)``, i.e. the more
        negative root first; for k == 0 the slow root is exactly 0.

    Raises
    ------
    ValueError
        For non-physical or non-finite input.
    """
    m, k, d = _check_oscillator(mass, stiffness, damping)
    sigma, wn2, b2, beta = _oscillator_constants(m, k, d)
    if b2 >= 0.0:
        re = -sigma + 0.0  # no -0.0 for the undamped case
        return complex(re, beta), complex(re, -beta)
    fast, slow = _overdamped_roots(sigma, wn2, beta)
    return complex(fast, 0.0), complex(slow, 0.0)


# ---------------------------------------------------------------------------
# scalar oscillator: time responses
# ---------------------------------------------------------------------------

# Below this |beta| t the trigonometric / hyperbolic kernels are replaced by
# their Taylor series, which also covers beta == 0 (critical damping) exactly.
_SERIES_Z = 1e-3


# gamma t -> inf only selects the exponential branch; cos(inf) is masked below.
@np.errstate(over="ignore", invalid="ignore")
def _fundamental(t: np.ndarray, sigma: float, wn2: float, b2: float, gamma: float):
    """Fundamental solutions of x'' + 2 sigma x' + wn2 x = 0 and their derivatives.

    Returns ``P, Q, dP, dQ`` with P(0)=1, P'(0)=0, Q(0)=0, Q'(0)=1, so that
    x = x0 P + v0 Q and v = x0 dP + v0 dQ.  Also returns the pieces
    ``E = exp(-sigma t)``, ``C`` (cos/cosh/1), ``S`` (sin/sinh/t over beta)
    and the mask of points evaluated through exponentials of the real roots
    (where E, C and S are not formed because cosh would overflow).
    """
    z = gamma * t
    P = np.empty_like(t)
    Q = np.empty_like(t)
    dP = np.empty_like(t)
    dQ = np.empty_like(t)
    C = np.full_like(t, np.nan)
    S = np.full_like(t, np.nan)
    E = np.exp(-sigma * t)

    series = z < _SERIES_Z
    if np.any(series):
        ts = t[series]
        u = np.copysign(z[series] ** 2, b2)  # beta^2 t^2 with the sign of beta^2
        # cos(sqrt u) and sin(sqrt u)/sqrt(u); the u^4 term is < 1e-24 here.
        C[series] = 1.0 - u / 2.0 * (1.0 - u / 12.0 * (1.0 - u / 30.0 * (1.0 - u / 56.0)))
        S[series] = ts * (1.0 - u / 6.0 * (1.0 - u / 20.0 * (1.0 - u / 42.0 * (1.0 - u / 72.0))))

    if b2 > 0.0:
        osc = ~series
        zo = z[osc]  # gamma t, formed once
        C[osc] = np.cos(zo)
        S[osc] = np.sin(zo) / gamma
        exp_branch = np.zeros(t.shape, dtype=bool)
    else:
        # Overdamped: cosh/sinh only while they cannot overflow or cancel.
        hyp = ~series & (z <= 1.0)
        C[hyp] = np.cosh(z[hyp])
        S[hyp] = np.sinh(z[hyp]) / gamma
        exp_branch = z > 1.0

    direct = ~exp_branch
    if np.all(direct):  # every point (always so with beta^2 >= 0): the same products without gathering them
        P[:] = E * (C + sigma * S)
        Q[:] = E * S
        dP[:] = -wn2 * (E * S)
        dQ[:] = E * (C - sigma * S)
    else:
        Ed, Cd, Sd = E[direct], C[direct], S[direct]
        P[direct] = Ed * (Cd + sigma * Sd)
        Q[direct] = Ed * Sd
        dP[direct] = -wn2 * (Ed * Sd)
        dQ[direct] = Ed * (Cd - sigma * Sd)
    # Fully decayed points (e^{-sigma t} == 0) are exactly at rest even when
    # the phase beta t has overflowed.
    gone = direct & (E == 0.0)
    P[gone] = Q[gone] = dP[gone] = dQ[gone] = 0.0

    if np.any(exp_branch):
        # Large gamma t: e^{-sigma t} cosh(gamma t) would overflow and cancel;
        # use the two real exponentials with the stable (fast, slow) roots.
        fast, slow = _overdamped_roots(sigma, wn2, gamma)
        te = t[exp_branch]
        es = np.exp(slow * te)
        ef = np.exp(fast * te)
        two_g = 2.0 * gamma
        P[exp_branch] = ((sigma + gamma) * es + slow * ef) / two_g
        Q[exp_branch] = (es - ef) / two_g
        dP[exp_branch] = -wn2 * ((es - ef) / two_g)
        dQ[exp_branch] = (slow * es - fast * ef) / two_g
    return P, Q, dP, dQ, E, C, S, exp_branch


def free_response(
    t: ArrayLike, mass: float, stiffness: float, damping: float, x0: float, v0: float
) -> tuple[np.ndarray, np.ndarray]:
    """Exact free vibration of m x'' + d x' + k x = 0, x(0) = x0, x'(0) = v0.

    Uses x = e^{-sigma t} [x0 (C + sigma S) + v0 S] with sigma = d / (2 m),
    beta^2 = k/m - sigma^2 and C, S = (cos, sin/beta), (cosh, sinh/|beta|) or
    (1, t); C and S switch to Taylor series for |beta| t < 1e-3, so the result
    is smooth and accurate across critical damping (no 1/omega_d or
    1/(s1 - s2) factors).  For |beta| t > 1 in the overdamped case the
    solution is written with e^{s_fast t} and e^{s_slow t} using the
    cancellation-free roots, so nothing overflows and the slow creep
    x ~ x0 e^{-k t / d} of a heavily damped spring is exact.  Covers k = 0
    (free mass, with or without damping).

    Parameters
    ----------
    t
        Time(s) since release [s], finite and >= 0; scalar or array.
    mass
        Mass m [kg], > 0.
    stiffness
        Spring constant k [N/m], >= 0.
    damping
        Viscous damping coefficient d [N s/m], >= 0.
    x0
        Initial displacement [m].
    v0
        Initial velocity [m/s].

    Returns
    -------
    tuple[ndarray, ndarray]
        (x, v): displacement [m] and velocity [m/s], arrays of t's shape.

    Raises
    ------
    ValueError
        For non-physical or non-finite input or negative t.
    """
    m, k, d = _check_oscillator(mass, stiffness, damping)
    x0 = _finite_scalar("x0", x0)
    v0 = _finite_scalar("v0", v0)
    tt = _response_time(t)
    flat = tt.reshape(-1)
    sigma, wn2, b2, gamma = _oscillator_constants(m, k, d)
    P, Q, dP, dQ = _fundamental(flat, sigma, wn2, b2, gamma)[:4]
    # Skip zero terms so that 0 * inf cannot appear for huge t.
    x = (x0 * P if x0 else 0.0) + (v0 * Q if v0 else 0.0)
    v = (x0 * dP if x0 else 0.0) + (v0 * dQ if v0 else 0.0)
    x = np.broadcast_to(x, flat.shape).astype(float)
    v = np.broadcast_to(v, flat.shape).astype(float)
    return x.reshape(tt.shape), v.reshape(tt.shape)


# Number of Taylor terms for the unit-step response where max(sigma, wn) t <= 1.
_STEP_SERIES_TERMS = 30


@np.errstate(over="ignore")
def _unit_step_displacement(
    t: np.ndarray, m: float, k: float, sigma: float, wn2: float, b2: float, gamma: float, fund
) -> np.ndarray:
    """h(t): displacement for a unit force from rest, m h'' + d h' + k h = 1.

    The textbook (1 - e^{-sigma t}(cos + ...)) / k cancels catastrophically
    for small t, small k or near critical damping, so the value is taken from
    whichever of four expressions is cancellation-free at each point:

    * Taylor series in tau = max(sigma, wn) t for tau <= 1;
    * (1 - E_x) / k when the free response E_x from x0 = 1 is <= 1/2;
    * overdamped: (phi1(s_slow) - phi1(s_fast)) / (2 m gamma) with
      phi1(s) = (e^{s t} - 1) / s (via expm1) for gamma t >= 1/2;
    * otherwise [(1 - e^{-sigma t}) - e^{-sigma t} sigma S - e^{-sigma t}(C - 1)] / k,
      whose grouped terms have equal signs in that region.
    """
    P, Q, dP, dQ, E, C, S, exp_branch = fund
    h = np.empty_like(t)
    wn = math.sqrt(wn2)
    lam = max(sigma, wn)
    todo = np.ones(t.shape, dtype=bool)

    series = lam * t <= 1.0
    if np.any(series):
        ts = t[series]
        if lam == 0.0:
            h[series] = ts * ts / (2.0 * m)
        else:
            s_ = 2.0 * sigma / lam
            w_ = wn2 / (lam * lam)
            c = np.zeros(_STEP_SERIES_TERMS)
            c[0] = 1.0
            for j in range(1, _STEP_SERIES_TERMS):
                prev2 = c[j - 2] if j >= 2 else 0.0
                c[j] = -(s_ * (j + 1) * c[j - 1] + w_ * prev2) / ((j + 2) * (j + 1))
            tau = lam * ts
            acc = np.full_like(ts, c[-1])
            for cj in c[-2::-1]:
                acc = acc * tau + cj
            h[series] = ts * ts / (2.0 * m) * acc
        todo &= ~series

    small_E = todo & (P <= 0.5)
    if np.any(small_E):
        h[small_E] = (1.0 - P[small_E]) / k  # k > 0 here: for k == 0, P == 1
        todo &= ~small_E

    if b2 < 0.0:
        phi = todo & (gamma * t >= 0.5)
        if np.any(phi):
            fast, slow = _overdamped_roots(sigma, wn2, gamma)
            tp = t[phi]
            phi_slow = tp if slow == 0.0 else np.expm1(slow * tp) / slow
            phi_fast = np.expm1(fast * tp) / fast
            h[phi] = (phi_slow - phi_fast) / (2.0 * m * gamma)
            todo &= ~phi

    if np.any(todo):
        # Remaining points have k > 0 and cosh/cos kernels available (no exp branch).
        tr = t[todo]
        Er, Sr = E[todo], S[todo]
        z = gamma * tr
        cm = np.empty_like(tr)
        ser = z < _SERIES_Z
        u = np.copysign(z[ser] ** 2, b2)
        cm[ser] = -u / 2.0 * (1.0 - u / 12.0 * (1.0 - u / 30.0 * (1.0 - u / 56.0)))
        if b2 > 0.0:
            cm[~ser] = -2.0 * np.sin(z[~ser] / 2.0) ** 2
        else:
            cm[~ser] = 2.0 * np.sinh(z[~ser] / 2.0) ** 2
        h[todo] = ((-np.expm1(-sigma * tr) - Er * (sigma * Sr)) - Er * cm) / k
    return h


def step_response(
    t: ArrayLike, mass: float, stiffness: float, damping: float, force: float, x0: float = 0.0, v0: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Exact response to a constant force switched on at t = 0.

    Mathematically x = F/k + free response from (x0 - F/k, v0) for k > 0, and
    for k == 0: x = x0 + (m/d)(v0 - F/d)(1 - e^{-d t/m}) + F t / d (d > 0) or
    x0 + v0 t + F t^2 / (2 m) (d == 0).  It is evaluated as
    free_response(x0, v0) + F h(t), where h, the unit-force response from
    rest, is computed without the F/k - F/k cancellation (see
    ``_unit_step_displacement``), so tiny k and k == 0 are exact too.

    Parameters
    ----------
    t
        Time(s) since the force was applied [s], finite and >= 0.
    mass
        Mass m [kg], > 0.
    stiffness
        Spring constant k [N/m], >= 0.
    damping
        Viscous damping coefficient d [N s/m], >= 0.
    force
        Constant applied force F [N].
    x0
        Initial displacement [m].
    v0
        Initial velocity [m/s].

    Returns
    -------
    tuple[ndarray, ndarray]
        (x, v): displacement [m] and velocity [m/s], arrays of t's shape.

    Raises
    ------
    ValueError
        For non-physical or non-finite input or negative t.
    """
    m, k, d = _check_oscillator(mass, stiffness, damping)
    force = _finite_scalar("force", force)
    x0 = _finite_scalar("x0", x0)
    v0 = _finite_scalar("v0", v0)
    tt = _response_time(t)
    flat = tt.reshape(-1)
    sigma, wn2, b2, gamma = _oscillator_constants(m, k, d)
    fund = _fundamental(flat, sigma, wn2, b2, gamma)
    P, Q, dP, dQ = fund[:4]
    x = np.zeros_like(flat)
    v = np.zeros_like(flat)
    if x0:
        x += x0 * P
        v += x0 * dP
    if v0:
        x += v0 * Q
        v += v0 * dQ
    if force:
        h = _unit_step_displacement(flat, m, k, sigma, wn2, b2, gamma, fund)
        x += force * h
        v += (force / m) * Q  # unit-force velocity is the impulse response Q / m
    return x.reshape(tt.shape), v.reshape(tt.shape)


def steady_state_amplitude(
    mass: float, stiffness: float, damping: float, force_amplitude: float, force_frequency: float
) -> tuple[float, float]:
    """Steady-state amplitude and phase lag under F(t) = F0 sin(2 pi f t).

    x_ss(t) = X sin(W t - phi) with W = 2 pi f,
    X = F0 / sqrt((k - m W^2)^2 + (d W)^2), phi = atan2(d W, k - m W^2).

    Parameters
    ----------
    mass
        Mass m [kg], > 0.
    stiffness
        Spring constant k [N/m], >= 0.
    damping
        Viscous damping coefficient d [N s/m], >= 0.
    force_amplitude
        F0 [N] (the amplitude carries its sign).
    force_frequency
        f [Hz], >= 0.

    Returns
    -------
    tuple[float, float]
        (amplitude [m], phase lag [rad] in [0, pi]).  At undamped resonance
        (d == 0 and |k - m W^2| <= 1e-12 max(k, m W^2)) the amplitude is
        +-inf (0.0 if F0 == 0) and the phase pi/2.  A static force on a free
        mass (k == 0, f == 0) also gives an infinite amplitude.

    Raises
    ------
    ValueError
        For non-physical or non-finite input.
    """
    m, k, d = _check_oscillator(mass, stiffness, damping)
    f0 = _finite_scalar("force_amplitude", force_amplitude)
    freq = _finite_scalar("force_frequency", force_frequency)
    if freq < 0.0:
        raise ValueError(f"force_frequency must be >= 0 [Hz], got {freq!r}")
    w = 2.0 * math.pi * freq
    re = k - m * w * w
    im = d * w
    if im == 0.0 and abs(re) <= RESONANCE_TOLERANCE * max(k, m * w * w):
        return (math.copysign(math.inf, f0) if f0 else 0.0), math.pi / 2.0
    return f0 / math.hypot(re, im), math.atan2(im, re)


def _phi1_series(z: np.ndarray) -> np.ndarray:
    """(e^z - 1) / z for |z| < 0.5 (complex), Taylor series to ~1e-21."""
    n_terms = 18
    acc = np.full(z.shape, 1.0 / math.factorial(n_terms + 1), dtype=complex)
    for n in range(n_terms - 1, -1, -1):
        acc = acc * z + 1.0 / math.factorial(n + 1)
    return acc


@np.errstate(over="ignore")
def _duhamel_exp(t: np.ndarray, w: complex, r: complex) -> np.ndarray:
    """J = integral_0^t e^{r (t - s)} e^{w s} ds, stable when w ~ r (resonance)."""
    dz = (w - r) * t
    out = np.empty(t.shape, dtype=complex)
    small = np.abs(dz) < 0.5
    if np.any(small):
        ts = t[small]
        out[small] = ts * np.exp(r * ts) * _phi1_series(dz[small])
    big = ~small
    if np.any(big):
        tb = t[big]
        out[big] = (np.exp(w * tb) - np.exp(r * tb)) / (w - r)
    return out


# Underdamped systems with zeta below this use the Duhamel (divided-difference)
# form of the forced response; above it the resonance is broad and the
# particular + transient split is well conditioned.
_DUHAMEL_MAX_ZETA = 0.5


def harmonic_response(
    t: ArrayLike,
    mass: float,
    stiffness: float,
    damping: float,
    force_amplitude: float,
    force_frequency: float,
    x0: float = 0.0,
    v0: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Exact response to F(t) = F0 sin(2 pi f t) switched on at t = 0.

    Full solution = steady-state particular solution + transient chosen to
    meet x(0) = x0, v(0) = v0.

    For lightly damped systems (zeta <= 0.5, including d == 0) the
    particular and transient parts are huge and nearly cancel near resonance,
    so the forced part is evaluated instead as the Duhamel integral
    x_F = (F0/m) Im int_0^t g(t-s) e^{i W s} ds with the impulse response
    g = (e^{s1 t} - e^{s2 t}) / (s1 - s2); each exponential integral is
    (e^{i W t} - e^{s t}) / (i W - s), switched to t e^{s t} phi1((iW - s) t)
    (Taylor series) when |iW - s| t < 1/2.  This is the same function, exact
    for every W, and it reduces identically to the secular solution
    x_F = F0/(2 k) sin(wn t) - F0/(2 m wn) t cos(wn t) at exact undamped
    resonance, so no band switching is needed and the result is continuous
    through resonance.  For zeta > 0.5, overdamped and k == 0 the direct
    particular + transient form is used.

    Parameters
    ----------
    t
        Time(s) since the force was applied [s], finite and >= 0.
    mass
        Mass m [kg], > 0.
    stiffness
        Spring constant k [N/m], >= 0.
    damping
        Viscous damping coefficient d [N s/m], >= 0.
    force_amplitude
        F0 [N].
    force_frequency
        f [Hz], >= 0 (f == 0 means zero force).
    x0
        Initial displacement [m].
    v0
        Initial velocity [m/s].

    Returns
    -------
    tuple[ndarray, ndarray]
        (x, v): displacement [m] and velocity [m/s], arrays of t's shape.
        Accuracy is a few ulps relative to the response amplitude (points
        where x itself nearly vanishes, e.g. x ~ t^3 just after switch-on
        from rest, carry that absolute error).

    Raises
    ------
    ValueError
        For non-physical or non-finite input or negative t.
    """
    m, k, d = _check_oscillator(mass, stiffness, damping)
    f0 = _finite_scalar("force_amplitude", force_amplitude)
    freq = _finite_scalar("force_frequency", force_frequency)
    if freq < 0.0:
        raise ValueError(f"force_frequency must be >= 0 [Hz], got {freq!r}")
    x0 = _finite_scalar("x0", x0)
    v0 = _finite_scalar("v0", v0)
    tt = _response_time(t)
    if f0 == 0.0 or freq == 0.0:
        return free_response(tt, m, k, d, x0, v0)
    flat = tt.reshape(-1)
    w = 2.0 * math.pi * freq
    sigma, wn2, b2, gamma = _oscillator_constants(m, k, d)
    zeta = damping_ratio(m, k, d)

    if b2 > 0.0 and zeta <= _DUHAMEL_MAX_ZETA:
        s1 = complex(-sigma, gamma)
        s2 = complex(-sigma, -gamma)
        iw = complex(0.0, w)
        j1 = _duhamel_exp(flat, iw, s1)
        j2 = _duhamel_exp(flat, iw, s2)
        # Im(X / (2 i beta)) = -Re(X) / (2 beta)
        scale = -f0 / (m * 2.0 * gamma)
        xf = scale * (j1 - j2).real
        vf = scale * (s1 * j1 - s2 * j2).real
        xh, vh = free_response(flat, m, k, d, x0, v0)
        x = xh + xf
        v = vh + vf
    else:
        re = k - m * w * w
        im = d * w
        r = math.hypot(re, im)  # > 0 here: either d > 0 or (k == 0 and w > 0)
        p_sin = f0 * (re / r) / r
        p_cos = -f0 * (im / r) / r
        sw, cw = np.sin(w * flat), np.cos(w * flat)
        xh, vh = free_response(flat, m, k, d, x0 - p_cos, v0 - p_sin * w)
        x = p_sin * sw + p_cos * cw + xh
        v = w * (p_sin * cw - p_cos * sw) + vh
    return x.reshape(tt.shape), v.reshape(tt.shape)
