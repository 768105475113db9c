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
    ``z' = A z + B u(t)`` with piecewise-constant ``u`` is solved exactly with
    the matrix exponential of the augmented matrix ``[[A, B], [0, 0]]``
    (:func:`expm`, scaling and squaring with Padé approximants, Al-Mohy &
    Higham 2009).  One exponential is computed per distinct step, so long
    uniform output grids are cheap.

Kinematics
    Polynomial motion, integration of a polynomial acceleration and the exact
    position for a piecewise-linear (tachograph-like) velocity record.

Units are SI throughout: [kg], [N/m], [N s/m], [m], [m/s], [s], [Hz], [rad/s].
All time arguments are evaluated element-wise; the outputs have ``t``'s shape.
"""

from __future__ import annotations

import math

import numpy as np

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
    "expm",
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


def _any_time(t) -> np.ndarray:
    arr = np.asarray(t, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ValueError("t must contain only finite times [s]")
    return arr


# ---------------------------------------------------------------------------
# scalar oscillator: parameters
# ---------------------------------------------------------------------------


def natural_frequency(mass: float, stiffness: float) -> float:
    """Undamped natural angular frequency.

    Args:
        mass: Mass m [kg], > 0.
        stiffness: Spring constant k [N/m], >= 0.

    Returns:
        omega_n = sqrt(k / m) [rad/s].

    Raises:
        ValueError: For non-finite input, m <= 0 or k < 0.
    """
    m, k, _ = _check_oscillator(mass, stiffness, 0.0)
    return math.sqrt(k / m)


def damping_ratio(mass: float, stiffness: float, damping: float) -> float:
    """Dimensionless damping ratio.

    Args:
        mass: Mass m [kg], > 0.
        stiffness: Spring constant k [N/m], >= 0.
        damping: Viscous damping coefficient d [N s/m], >= 0.

    Returns:
        zeta = d / (2 sqrt(k m)) [-]; ``math.inf`` for k = 0 with d > 0 and
        0.0 for d = 0.

    Raises:
        ValueError: For non-physical or non-finite input.
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

    Args:
        mass: Mass m [kg], > 0.
        stiffness: Spring constant k [N/m], >= 0.
        damping: Viscous damping coefficient d [N s/m], >= 0.

    Returns:
        omega_d = omega_n sqrt(1 - zeta^2) [rad/s] for zeta < 1, else 0.0.

    Raises:
        ValueError: For non-physical or non-finite input.
    """
    m, k, d = _check_oscillator(mass, stiffness, damping)
    # Same beta as the time responses: sqrt((wn - sigma)(wn + sigma)), which
    # keeps its relative accuracy as zeta -> 1.
    _, _, b2, beta = _oscillator_constants(m, k, d)
    return beta if b2 > 0.0 else 0.0


def regime(mass: float, stiffness: float, damping: float) -> str:
    """Classify the free motion.

    Args:
        mass: Mass m [kg], > 0.
        stiffness: Spring constant k [N/m], >= 0.
        damping: Viscous damping coefficient d [N s/m], >= 0.

    Returns:
        ``'undamped'`` iff d == 0; otherwise ``'critical'`` when
        |zeta - 1| <= 1e-12, ``'underdamped'`` for smaller zeta and
        ``'overdamped'`` for larger zeta (including k == 0 with d > 0).

    Raises:
        ValueError: For non-physical or non-finite input.
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

    Args:
        mass: Mass m [kg], > 0.
        stiffness: Spring constant k [N/m], >= 0.
        damping: Viscous damping coefficient d [N s/m], >= 0.

    Returns:
        ``(s1, s2)`` [rad/s] as complex numbers.  Underdamped / undamped:
        ``(-sigma + i omega_d, -sigma - i omega_d)``.  Critical (beta^2 == 0
        exactly): both ``-sigma``.  Overdamped: ``(fast, slow)``, i.e. the more
        negative root first; for k == 0 the slow root is exactly 0.

    Raises:
        ValueError: For non-physical or non-finite input.
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
        C[osc] = np.cos(gamma * t[osc])
        S[osc] = np.sin(gamma * t[osc]) / gamma
        exp_branch = np.zeros(t.shape, dtype=bool)
    else:
        # Overdamped: cosh/sinh only while they cannot overflow or cancel.
        hyp = ~series & (z <= 1.0)
        C[hyp] = np.cosh(z[hyp])
        S[hyp] = np.sinh(z[hyp]) / gamma
        exp_branch = z > 1.0

    direct = ~exp_branch
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

    Args:
        t: Time(s) since release [s], finite and >= 0; scalar or array.
        mass: Mass m [kg], > 0.
        stiffness: Spring constant k [N/m], >= 0.
        damping: Viscous damping coefficient d [N s/m], >= 0.
        x0: Initial displacement [m].
        v0: Initial velocity [m/s].

    Returns:
        (x, v): displacement [m] and velocity [m/s], arrays of t's shape.

    Raises:
        ValueError: For non-physical or non-finite input or negative t.
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

    Args:
        t: Time(s) since the force was applied [s], finite and >= 0.
        mass: Mass m [kg], > 0.
        stiffness: Spring constant k [N/m], >= 0.
        damping: Viscous damping coefficient d [N s/m], >= 0.
        force: Constant applied force F [N].
        x0: Initial displacement [m].
        v0: Initial velocity [m/s].

    Returns:
        (x, v): displacement [m] and velocity [m/s], arrays of t's shape.

    Raises:
        ValueError: For non-physical or non-finite input or negative t.
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

    Args:
        mass: Mass m [kg], > 0.
        stiffness: Spring constant k [N/m], >= 0.
        damping: Viscous damping coefficient d [N s/m], >= 0.
        force_amplitude: F0 [N] (the amplitude carries its sign).
        force_frequency: f [Hz], >= 0.

    Returns:
        (amplitude [m], phase lag [rad] in [0, pi]).  At undamped resonance
        (d == 0 and |k - m W^2| <= 1e-12 max(k, m W^2)) the amplitude is
        +-inf (0.0 if F0 == 0) and the phase pi/2.  A static force on a free
        mass (k == 0, f == 0) also gives an infinite amplitude.

    Raises:
        ValueError: For non-physical or non-finite input.
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

    Args:
        t: Time(s) since the force was applied [s], finite and >= 0.
        mass: Mass m [kg], > 0.
        stiffness: Spring constant k [N/m], >= 0.
        damping: Viscous damping coefficient d [N s/m], >= 0.
        force_amplitude: F0 [N].
        force_frequency: f [Hz], >= 0 (f == 0 means zero force).
        x0: Initial displacement [m].
        v0: Initial velocity [m/s].

    Returns:
        (x, v): displacement [m] and velocity [m/s], arrays of t's shape.
        Accuracy is a few ulps relative to the response amplitude (points
        where x itself nearly vanishes, e.g. x ~ t^3 just after switch-on
        from rest, carry that absolute error).

    Raises:
        ValueError: For non-physical or non-finite input or negative t.
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


# ---------------------------------------------------------------------------
# matrix exponential (Al-Mohy & Higham 2009, Algorithm 5.1)
# ---------------------------------------------------------------------------

_PADE = {
    3: (120.0, 60.0, 12.0, 1.0),
    5: (30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0),
    7: (17297280.0, 8648640.0, 1995840.0, 277200.0, 25200.0, 1512.0, 56.0, 1.0),
    9: (17643225600.0, 8821612800.0, 2075673600.0, 302702400.0, 30270240.0, 2162160.0, 110880.0, 3960.0, 90.0, 1.0),
    13: (
        64764752532480000.0,
        32382376266240000.0,
        7771770303897600.0,
        1187353796428800.0,
        129060195264000.0,
        10559470521600.0,
        670442572800.0,
        33522128640.0,
        1323241920.0,
        40840800.0,
        960960.0,
        16380.0,
        182.0,
        1.0,
    ),
}
# Backward-error bounds theta_m for degree m (Al-Mohy & Higham 2009, Table 3.1).
_THETA = {3: 1.495585217958292e-2, 5: 2.539398330063230e-1, 7: 9.504178996162932e-1, 9: 2.097847961257068e0, 13: 4.25}


def _onenorm(a: np.ndarray) -> float:
    return float(np.abs(a).sum(axis=0).max()) if a.size else 0.0


def _ell(a: np.ndarray, m: int) -> int:
    """Extra squarings needed to keep the backward error at unit roundoff."""
    p = 2 * m + 1
    # |c_{2m+1}|^-1 = (2m)! (2m+1)! / (m!)^2: leading coefficient of the
    # backward-error series of the [m/m] Padé approximant.
    c_recip = float(math.comb(2 * m, m) * math.factorial(2 * m + 1))
    abs_a = np.abs(a)
    # ||abs(A)^p||_1 exactly, via p vector-matrix products on the row of ones.
    row = np.ones(a.shape[0])
    for _ in range(p):
        row = row @ abs_a
    power_norm = float(row.max())
    a_norm = _onenorm(a)
    if power_norm == 0.0 or a_norm == 0.0:
        return 0
    alpha = power_norm / (a_norm * c_recip)
    value = math.ceil(math.log2(alpha / 2.0**-53) / (2 * m))
    return max(value, 0)


def _pade_uv(m: int, a: np.ndarray, powers: dict, ident: np.ndarray):
    b = _PADE[m]
    if m == 13:
        a2, a4, a6 = powers[2], powers[4], powers[6]
        u = a @ (a6 @ (b[13] * a6 + b[11] * a4 + b[9] * a2) + b[7] * a6 + b[5] * a4 + b[3] * a2 + b[1] * ident)
        v = a6 @ (b[12] * a6 + b[10] * a4 + b[8] * a2) + b[6] * a6 + b[4] * a4 + b[2] * a2 + b[0] * ident
        return u, v
    u_sum = b[1] * ident
    v_sum = b[0] * ident
    for j in range(1, m // 2 + 1):
        pj = powers[2 * j]
        u_sum = u_sum + b[2 * j + 1] * pj
        v_sum = v_sum + b[2 * j] * pj
    return a @ u_sum, v_sum


def _pade_scaled(arr: np.ndarray):
    """Degree and scaling of Al-Mohy & Higham 2009, Algorithm 5.1.

    Returns (u, v, s): odd and even parts of the Padé approximant of
    2^-s A, so that exp(A) ~ ((v - u)^-1 (v + u))^(2^s).
    """
    n = arr.shape[0]
    ident = np.eye(n, dtype=arr.dtype)
    a2 = arr @ arr
    a4 = a2 @ a2
    a6 = a2 @ a4
    d4 = _onenorm(a4) ** 0.25
    d6 = _onenorm(a6) ** (1.0 / 6.0)
    eta1 = max(d4, d6)
    powers = {2: a2, 4: a4, 6: a6}
    for m in (3, 5):
        if eta1 <= _THETA[m] and _ell(arr, m) == 0:
            return (*_pade_uv(m, arr, powers, ident), 0)
    a8 = a4 @ a4
    powers[8] = a8
    d8 = _onenorm(a8) ** 0.125
    eta3 = max(d6, d8)
    for m in (7, 9):
        if eta3 <= _THETA[m] and _ell(arr, m) == 0:
            return (*_pade_uv(m, arr, powers, ident), 0)
    d10 = _onenorm(a4 @ a6) ** 0.1
    eta5 = min(eta3, max(d8, d10))
    s = 0 if eta5 == 0.0 else max(math.ceil(math.log2(eta5 / _THETA[13])), 0)
    s += _ell(arr * 2.0**-s, 13)
    scaled = arr * 2.0**-s
    powers = {2: a2 * 4.0**-s, 4: a4 * 16.0**-s, 6: a6 * 64.0**-s}
    return (*_pade_uv(13, scaled, powers, ident), s)


def _square_matrix(name: str, a) -> np.ndarray:
    arr = np.asarray(a)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1]:
        raise ValueError(f"{name} needs a square 2-D matrix, got shape {arr.shape}")
    arr = arr.astype(np.result_type(arr.dtype, np.float64))
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} needs a finite matrix")
    return arr


def expm(a) -> np.ndarray:
    """Matrix exponential by scaling and squaring with Padé approximants.

    Al-Mohy & Higham (2009), "A new scaling and squaring algorithm for the
    matrix exponential", Algorithm 5.1: Padé degree 3, 5, 7, 9 or 13 chosen
    from exact 1-norms of powers of A (d_k = ||A^k||^{1/k}), the scaling s
    from theta_13 = 4.25 plus the ell() correction that avoids overscaling,
    followed by s squarings (the Higham 2005 degree-13 approximant and
    constants).  Pure NumPy; agrees with scipy.linalg.expm to roundoff.

    Args:
        a: Square matrix (n, n), real or complex, finite.  Entries carry
            whatever units make A dimensionless (e.g. A [1/s] times t [s]).

    Returns:
        exp(A) as an (n, n) ndarray (float for real input).

    Raises:
        ValueError: If ``a`` is not a finite square matrix.
    """
    arr = _square_matrix("expm", a)
    n = arr.shape[0]
    if n == 0:
        return np.zeros((0, 0), dtype=arr.dtype)
    if n == 1:
        return np.exp(arr)
    u, v, s = _pade_scaled(arr)
    x = np.linalg.solve(v - u, v + u)
    for _ in range(s):
        x = x @ x
    return x


def _expm_minus_identity(arr: np.ndarray) -> np.ndarray:
    """exp(A) - I with the same Padé/scaling, squared in the form D <- 2 D + D^2.

    r(X) - I = (V - U)^-1 2 U is accurate relative to its own (small) size,
    and carrying D = exp(X) - I through the squarings keeps modes with
    exp(lambda) ~ 1 (e.g. the creep mode -k/d of a stiff damper, or
    rigid-body modes) exact: squaring exp(X) itself would round them to
    1 - ulp and then amplify that by 2^s.
    """
    n = arr.shape[0]
    if n == 1:
        return np.expm1(arr)
    u, v, s = _pade_scaled(arr)
    dx = np.linalg.solve(v - u, 2.0 * u)
    for _ in range(s):
        dx = 2.0 * dx + dx @ dx
    return dx


# ---------------------------------------------------------------------------
# linear time-invariant systems
# ---------------------------------------------------------------------------


def _matrix(name: str, value, n: int | None = None) -> np.ndarray:
    arr = np.atleast_2d(np.asarray(value, dtype=float))
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1]:
        raise ValueError(f"{name} must be a square matrix, got shape {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise ValueError(f"{name} must be {n}x{n}, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return arr


def state_matrix(mass_matrix, damping_matrix, stiffness_matrix) -> np.ndarray:
    """First-order state matrix of M q'' + C q' + K q = f.

    Args:
        mass_matrix: M (n, n) [kg], symmetric positive definite.
        damping_matrix: C (n, n) [N s/m].
        stiffness_matrix: K (n, n) [N/m] (may be singular, e.g. rigid-body modes).

    Returns:
        A = [[0, I], [-M^-1 K, -M^-1 C]] (2n, 2n) for the state z = (q, q')
        (upper-right block dimensionless, lower blocks [1/s^2] and [1/s]).

    Raises:
        ValueError: For non-finite or mis-shaped matrices or an M that is not
            symmetric positive definite.
    """
    mm = _matrix("mass_matrix", mass_matrix)
    n = mm.shape[0]
    cc = _matrix("damping_matrix", damping_matrix, n)
    kk = _matrix("stiffness_matrix", stiffness_matrix, n)
    _check_spd(mm)
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -np.linalg.solve(mm, kk)
    a[n:, n:] = -np.linalg.solve(mm, cc)
    return a


def _check_spd(mm: np.ndarray) -> None:
    scale = float(np.abs(mm).max()) if mm.size else 0.0
    if not np.allclose(mm, mm.T, rtol=0.0, atol=1e-12 * scale):
        raise ValueError("mass_matrix must be symmetric")
    try:
        np.linalg.cholesky(mm)
    except np.linalg.LinAlgError:
        raise ValueError("mass_matrix must be positive definite") from None


class _Propagator:
    """Exact one-step maps for z' = A z + B u with u constant over the step.

    A step of length h maps z -> e^{A h} z + G u with G = int_0^h e^{A s} ds B.
    Two representations of e^{A h} are used:

    * ``z + (D z + G u)`` with D = e^{A h} - I from ``_expm_minus_identity``
      for ordinary steps.  Keeping D apart from the identity means reusing the
      same step 1e5 times does not accumulate the rounding of I + small, and
      slow modes of stiff systems stay exact.
    * ``Phi z + G u`` with Phi = e^{A h} from :func:`expm` when the step is
      strongly contracting (||Phi||_1 <= 1/2), where I + D would keep only
      absolute accuracy while Phi keeps the decaying state relatively exact.
    """

    def __init__(self, a: np.ndarray, b: np.ndarray):
        self.a = a
        self.b = b
        self.n = a.shape[0]
        self.norm_a = _onenorm(a)
        self._cache: dict = {}

    def maps(self, h: float):
        """(contracting, M, G) for step h [s]; M is Phi if contracting else D."""
        hit = self._cache.get(h)
        if hit is not None:
            return hit
        n = self.n
        if h == 0.0:
            out = (False, np.zeros((n, n)), np.zeros_like(self.b))
        else:
            aug = np.zeros((2 * n, 2 * n))
            aug[:n, :n] = h * self.a
            aug[:n, n:] = np.eye(n)
            # exp([[hA, I], [0, 0]]) = [[e^{hA}, phi1(hA)], [0, I]],
            # phi1(hA) = sum (hA)^j / (j+1)!, so G = h phi1(hA) B.
            dx = _expm_minus_identity(aug)
            gmat = h * (dx[:n, n:] @ self.b)
            phi = expm(aug[:n, :n])
            if _onenorm(phi) <= 0.5:
                out = (True, phi, gmat)
            else:
                out = (False, dx[:n, :n], gmat)
        self._cache[h] = out
        return out

    def step(self, z: np.ndarray, h: float, u: np.ndarray) -> np.ndarray:
        if h == 0.0:
            return z
        contracting, mmat, gmat = self.maps(h)
        if contracting:
            return mmat @ z + gmat @ u
        return z + (mmat @ z + gmat @ u)

    def run(self, z_start: np.ndarray, s_start: float, s: np.ndarray, u: np.ndarray) -> np.ndarray:
        """States at the non-decreasing times s >= s_start, from z(s_start)."""
        n_out = s.size
        out = np.empty((n_out, self.n))
        if n_out == 0:
            return out
        bu = self.b @ u
        span = s[-1] - s_start
        h = span / n_out
        grid = s_start + h * np.arange(1, n_out + 1)
        delta = s - grid
        max_delta = float(np.abs(delta).max())
        if n_out >= 8 and max_delta * self.norm_a <= 1e-4:
            self._run_uniform(out, z_start, h, u)
            if max_delta > 0.0:
                # Times deviate from the uniform grid by ulps: exact Taylor
                # correction z(g + delta) (the 4th-order term is < 1e-17).
                zd = out @ self.a.T + bu
                z2 = zd @ self.a.T
                z3 = z2 @ self.a.T
                dl = delta[:, None]
                out += dl * (zd + dl / 2.0 * (z2 + dl / 3.0 * z3))
            return out
        # Irregular grid: exact step by step, one exponential per distinct step.
        z = z_start
        prev = s_start
        for i in range(n_out):
            z = self.step(z, float(s[i] - prev), u)
            prev = s[i]
            out[i] = z
        return out

    def _run_uniform(self, out: np.ndarray, z_start: np.ndarray, h: float, u: np.ndarray) -> None:
        n_out = out.shape[0]
        block = min(n_out, 256)
        contracting, mmat, gmat = self.maps(h)
        # Maps for 1..block steps by doubling (j steps followed by L steps):
        #   Phi form: Phi_{j+L} = Phi_L Phi_j,          g_{j+L} = Phi_L g_j + g_L
        #   D form:   D_{j+L} = D_j + D_L + D_L D_j,    g_{j+L} = g_j + g_L + D_L g_j
        ms = mmat[None, :, :].copy()
        gs = (gmat @ u)[None, :].copy()
        while ms.shape[0] < block:
            ml, gl = ms[-1], gs[-1]
            if contracting:
                ms = np.concatenate([ms, ml @ ms])
                gs = np.concatenate([gs, gs @ ml.T + gl])
            else:
                ms = np.concatenate([ms, ms + ml + ml @ ms])
                gs = np.concatenate([gs, gs + gl + gs @ ml.T])
        ms, gs = ms[:block], gs[:block]
        if not contracting:
            # z + D_j z is only relatively exact while e^{A j h} = I + D_j has
            # not contracted the state; cap the block before that happens.
            norms = np.abs(ms + np.eye(self.n)).sum(axis=1).max(axis=1)
            small = np.flatnonzero(norms < 0.5)
            if small.size:
                block = max(1, int(small[0]))
                ms, gs = ms[:block], gs[:block]
        zb = z_start
        for b0 in range(0, n_out, block):
            cnt = min(block, n_out - b0)
            if contracting:
                out[b0 : b0 + cnt] = ms[:cnt] @ zb + gs[:cnt]
            else:
                out[b0 : b0 + cnt] = zb + (ms[:cnt] @ zb + gs[:cnt])
            zb = out[b0 + cnt - 1]


def _output_times(t) -> np.ndarray:
    times = np.atleast_1d(np.asarray(t, dtype=float))
    if times.ndim != 1:
        raise ValueError(f"t must be a 1-D array of times [s], got shape {times.shape}")
    if not np.all(np.isfinite(times)):
        raise ValueError("t must contain only finite times [s]")
    if times.size and times[0] < 0.0:
        raise ValueError("t must start at t[0] >= 0 [s]")
    if np.any(np.diff(times) < 0.0):
        raise ValueError("t must be non-decreasing")
    return times


def _parse_input(b, u, n: int):
    """-> (B (n, p), breakpoints (K,), values (K, p))."""
    if u is None:
        return np.zeros((n, 0)), np.zeros(1), np.zeros((1, 0))
    if b is None:
        raise ValueError("an input u needs an input matrix b")
    bmat = np.asarray(b, dtype=float)
    if bmat.ndim == 1:
        bmat = bmat[:, None]
    if bmat.ndim != 2 or bmat.shape[0] != n:
        raise ValueError(f"b must have shape ({n}, p), got {bmat.shape}")
    if not np.all(np.isfinite(bmat)):
        raise ValueError("b must be finite")
    p = bmat.shape[1]
    if isinstance(u, tuple) and len(u) == 2 and np.ndim(u[0]) == 1:
        bp = np.asarray(u[0], dtype=float)
        vals = np.asarray(u[1], dtype=float)
        if vals.ndim == 1 and p == 1:
            vals = vals[:, None]
        if bp.size == 0 or not np.all(np.isfinite(bp)):
            raise ValueError("breakpoints must be a non-empty finite 1-D array [s]")
        if bp[0] != 0.0:
            raise ValueError("the first breakpoint must be 0 [s]")
        if np.any(np.diff(bp) < 0.0):
            raise ValueError("breakpoints must be sorted")
        if vals.shape != (bp.size, p):
            raise ValueError(f"input values must have shape ({bp.size}, {p}), got {vals.shape}")
    else:
        vals = np.atleast_1d(np.asarray(u, dtype=float))
        if vals.shape != (p,):
            raise ValueError(f"constant input must have shape ({p},), got {vals.shape}")
        bp = np.zeros(1)
        vals = vals[None, :]
    if not np.all(np.isfinite(vals)):
        raise ValueError("input values must be finite")
    return bmat, bp, vals


def lti_response(t, a, z0, b=None, u=None) -> np.ndarray:
    """Exact solution of z' = A z + B u(t) with piecewise-constant input.

    Over each interval of constant input the exact map is read off
    expm([[A h, I], [0, 0]]) = [[e^{A h}, phi1(A h)], [0, I]], with
    int_0^h e^{A s} ds B = h phi1(A h) B; this needs no inverse of A, so
    singular A (rigid-body modes, harmonic generators) is exact.  The state is
    propagated segment by segment and between output times.  Runs of
    (near-)uniformly spaced output times reuse one exponential: maps for
    1..256 steps are built by doubling and applied block-wise (vectorised),
    and times that deviate from the uniform grid by roundoff are corrected
    with an exact short Taylor step.  Irregular grids take one exponential
    per distinct step size (slow if every step differs).

    Args:
        t: Output times [s], 1-D, non-decreasing, t[0] >= 0 (need not be uniform).
        a: State matrix A (N, N) [1/s].
        z0: State at t = 0, shape (N,).
        b: Input matrix B (N, p); required iff u is given.
        u: None (no input), a constant input (p,) applied for t >= 0, or a
            tuple ``(breakpoints, values)``: sorted switch times (K,) [s] with
            breakpoints[0] == 0, and values (K, p), value i acting on
            [breakpoints[i], breakpoints[i+1]).

    Returns:
        z: states at the output times, shape (len(t), N).

    Raises:
        ValueError: For mis-shaped or non-finite input, unsorted times or
            breakpoints, or a first breakpoint other than 0.
    """
    times = _output_times(t)
    amat = _matrix("a", a)
    n = amat.shape[0]
    z = np.asarray(z0, dtype=float).reshape(-1)
    if z.shape != (n,):
        raise ValueError(f"z0 must have shape ({n},), got {np.shape(z0)}")
    if not np.all(np.isfinite(z)):
        raise ValueError("z0 must be finite")
    bmat, bp, vals = _parse_input(b, u, n)
    prop = _Propagator(amat, bmat)
    out = np.empty((times.size, n))
    if times.size == 0:
        return out

    tau = 0.0
    j = 0
    n_seg = bp.size
    for seg in range(n_seg):
        u_seg = vals[seg]
        last = seg == n_seg - 1
        j2 = times.size if last else int(np.searchsorted(times, bp[seg + 1], side="left"))
        if j2 > j:
            # First output of the segment separately, so the rest can form a
            # uniform run even when the breakpoint is off the output grid.
            z = prop.step(z, float(times[j] - tau), u_seg)
            out[j] = z
            if j2 > j + 1:
                out[j + 1 : j2] = prop.run(z, float(times[j]), times[j + 1 : j2], u_seg)
            z = out[j2 - 1]
            tau = float(times[j2 - 1])
            j = j2
        if j >= times.size or last:
            break
        z = prop.step(z, float(bp[seg + 1] - tau), u_seg)
        tau = float(bp[seg + 1])
    return out


def linear_response(
    t, mass_matrix, damping_matrix, stiffness_matrix, q0, v0, force=None
) -> tuple[np.ndarray, np.ndarray]:
    """Exact response of M q'' + C q' + K q = f(t) for an n-DOF linear system.

    Thin wrapper over :func:`lti_response` with A from :func:`state_matrix`
    and B = [[0], [M^-1]], so singular K (free rigid-body modes) is exact.

    Args:
        t: Output times [s], 1-D, non-decreasing, t[0] >= 0.
        mass_matrix: M (n, n) [kg], symmetric positive definite.
        damping_matrix: C (n, n) [N s/m].
        stiffness_matrix: K (n, n) [N/m].
        q0: Initial displacements (n,) [m] at t = 0.
        v0: Initial velocities (n,) [m/s] at t = 0.
        force: None (free vibration), a constant force vector (n,) [N] for
            t >= 0 (pass an array or list), or ``(breakpoints, values)`` with
            breakpoints (K,) [s] starting at 0 and values (K, n) [N], value i
            acting on [breakpoints[i], breakpoints[i+1]).

    Returns:
        (q, v): displacements [m] and velocities [m/s], each (len(t), n).

    Raises:
        ValueError: For non-physical, mis-shaped or non-finite input.
    """
    amat = state_matrix(mass_matrix, damping_matrix, stiffness_matrix)
    n = amat.shape[0] // 2
    q0 = np.asarray(q0, dtype=float).reshape(-1)
    v0 = np.asarray(v0, dtype=float).reshape(-1)
    if q0.shape != (n,) or v0.shape != (n,):
        raise ValueError(f"q0 and v0 must have shape ({n},)")
    bmat = None
    if force is not None:
        mm = np.atleast_2d(np.asarray(mass_matrix, dtype=float))
        bmat = np.zeros((2 * n, n))
        bmat[n:] = np.linalg.inv(mm)
    z = lti_response(t, amat, np.concatenate([q0, v0]), bmat, force)
    return z[:, :n], z[:, n:]


# ---------------------------------------------------------------------------
# kinematics
# ---------------------------------------------------------------------------


def _coefficients(name: str, coefficients) -> np.ndarray:
    c = np.atleast_1d(np.asarray(coefficients, dtype=float))
    if c.ndim != 1 or c.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D sequence")
    if not np.all(np.isfinite(c)):
        raise ValueError(f"{name} must be finite")
    return c


def _derivative(c: np.ndarray) -> np.ndarray:
    if c.size == 1:
        return np.zeros(1)
    return c[1:] * np.arange(1, c.size)


def _polyval(t: np.ndarray, c: np.ndarray) -> np.ndarray:
    acc = np.full(t.shape, c[-1])
    for ci in c[-2::-1]:
        acc = acc * t + ci
    return acc


def polynomial_motion(t: ArrayLike, coefficients) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity and acceleration of x(t) = sum_i c_i t^i.

    Args:
        t: Time(s) [s], finite; scalar or array.
        coefficients: c_0 [m], c_1 [m/s], c_2 [m/s^2], ... (increasing power).

    Returns:
        (x [m], v [m/s], a [m/s^2]) by exact differentiation, arrays of t's shape.

    Raises:
        ValueError: For empty or non-finite coefficients or non-finite t.
    """
    tt = _any_time(t)
    c = _coefficients("coefficients", coefficients)
    dc = _derivative(c)
    ddc = _derivative(dc)
    return _polyval(tt, c), _polyval(tt, dc), _polyval(tt, ddc)


def integrate_acceleration(
    t: ArrayLike, accel_coefficients, x0: float, v0: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Motion under a polynomial acceleration a(t) = sum_i a_i t^i.

    v(t) = v0 + sum a_i t^{i+1} / (i+1) and
    x(t) = x0 + v0 t + sum a_i t^{i+2} / ((i+1)(i+2)), i.e. the chapter's
    x(t) = x0 + v0 t + int_0^t int_0^s a dr ds (eq. 5.5); for example
    a = 1.2 t + 3.0, v(0) = 15, x(0) = 150 gives v = 15 + 3 t + 0.6 t^2 and
    x = 150 + 15 t + 1.5 t^2 + 0.2 t^3.

    Args:
        t: Time(s) [s], finite; scalar or array.
        accel_coefficients: a_0 [m/s^2], a_1 [m/s^3], ... (increasing power).
        x0: Position at t = 0 [m].
        v0: Velocity at t = 0 [m/s].

    Returns:
        (x [m], v [m/s], a [m/s^2]), arrays of t's shape.

    Raises:
        ValueError: For empty or non-finite input.
    """
    acc = _coefficients("accel_coefficients", accel_coefficients)
    x0 = _finite_scalar("x0", x0)
    v0 = _finite_scalar("v0", v0)
    i = np.arange(acc.size)
    pos = np.concatenate([[x0, v0], acc / ((i + 1.0) * (i + 2.0))])
    return polynomial_motion(t, pos)


def piecewise_linear_velocity(
    t: ArrayLike, knot_times, knot_velocities, x0: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact motion for a piecewise-linear velocity record (tachograph).

    Args:
        t: Time(s) [s] within [knot_times[0], knot_times[-1]].
        knot_times: Strictly increasing knot times (>= 2) [s].
        knot_velocities: Velocities at the knots [m/s].
        x0: Position at knot_times[0] [m].

    Returns:
        (x [m], v [m/s], a [m/s^2]): position is x0 plus the exact area under
        v; acceleration is the segment slope, taken from the segment to the
        right at an interior knot (and from the last segment at the final knot).

    Raises:
        ValueError: For bad knots, non-finite input or t outside the knot range.
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
