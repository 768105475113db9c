"""Tests for springlab.exact.analytic.

Every assertion compares against a reference that does not share the code
path under test: textbook closed forms worked by hand, a 60-digit
``decimal`` evaluation of the plain textbook formulas (where their
cancellation is harmless), scipy's ``solve_ivp`` at tight tolerance,
or the equation of motion itself (finite differences).
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from springlab.exact import analytic as an

# ---------------------------------------------------------------------------
# 60-digit reference: the plain textbook formulas (distinct roots, complex
# roots, repeated root).  Their 1/(s1 - s2) and F/k - F/k cancellations cost
# at most ~20 digits here, leaving > 35 correct digits.
# ---------------------------------------------------------------------------

_PREC = 60
_PI = Decimal("3.14159265358979323846264338327950288419716939937510582097494459230781640628620899")


def _sin_cos(x: Decimal):
    n = (x / (2 * _PI)).to_integral_value()
    y = x - n * 2 * _PI
    y2 = y * y
    term_c, term_s = Decimal(1), y
    c, s = term_c, term_s
    k = 1
    eps = Decimal(10) ** -(_PREC + 5)
    while abs(term_c) > eps or abs(term_s) > eps:
        term_c = -term_c * y2 / ((2 * k - 1) * (2 * k))
        term_s = -term_s * y2 / ((2 * k) * (2 * k + 1))
        c += term_c
        s += term_s
        k += 1
    return s, c


def _free_decimal(t, m, k, d, x0, v0):
    """Textbook free response in Decimal (inputs already Decimal)."""
    sig = d / (2 * m)
    b2 = k / m - sig * sig
    if b2 > 0:
        b = b2.sqrt()
        s, c = _sin_cos(b * t)
        e = (-sig * t).exp()
        x = e * (x0 * c + (v0 + sig * x0) * s / b)
        v = e * (v0 * c - (k / m * x0 + sig * v0) * s / b)
    elif b2 == 0:
        e = (-sig * t).exp()
        x = e * (x0 + (v0 + sig * x0) * t)
        v = e * (v0 - (k / m * x0 + sig * v0) * t)
    else:
        g = (-b2).sqrt()
        r1, r2 = -sig + g, -sig - g
        a = (v0 - r2 * x0) / (r1 - r2)
        b = (r1 * x0 - v0) / (r1 - r2)
        x = a * (r1 * t).exp() + b * (r2 * t).exp()
        v = a * r1 * (r1 * t).exp() + b * r2 * (r2 * t).exp()
    return x, v


def ref_free(ts, m, k, d, x0, v0):
    out = []
    with localcontext() as ctx:
        ctx.prec = _PREC
        m_, k_, d_, x0_, v0_ = (Decimal(float(q)) for q in (m, k, d, x0, v0))
        for t in np.ravel(ts):
            x, v = _free_decimal(Decimal(float(t)), m_, k_, d_, x0_, v0_)
            out.append((float(x), float(v)))
    arr = np.array(out)
    return arr[:, 0], arr[:, 1]


def ref_step(ts, m, k, d, force, x0, v0):
    """x = F/k + free(x0 - F/k, v0), in 60 digits (k > 0 only)."""
    out = []
    with localcontext() as ctx:
        ctx.prec = _PREC
        m_, k_, d_, f_ = (Decimal(float(q)) for q in (m, k, d, force))
        xs = f_ / k_
        for t in np.ravel(ts):
            x, v = _free_decimal(Decimal(float(t)), m_, k_, d_, Decimal(float(x0)) - xs, Decimal(float(v0)))
            out.append((float(x + xs), float(v)))
    arr = np.array(out)
    return arr[:, 0], arr[:, 1]


def ref_harmonic(ts, m, k, d, f0, freq, x0, v0):
    """Particular + transient, in 60 digits (Omega taken as the same double)."""
    omega = 2.0 * math.pi * freq
    out = []
    with localcontext() as ctx:
        ctx.prec = _PREC
        m_, k_, d_, f_, w_ = (Decimal(float(q)) for q in (m, k, d, f0, omega))
        re = k_ - m_ * w_ * w_
        im = d_ * w_
        den = re * re + im * im
        p_sin, p_cos = f_ * re / den, -f_ * im / den
        for t in np.ravel(ts):
            t_ = Decimal(float(t))
            x, v = _free_decimal(t_, m_, k_, d_, Decimal(float(x0)) - p_cos, Decimal(float(v0)) - p_sin * w_)
            s, c = _sin_cos(w_ * t_)
            out.append((float(x + p_sin * s + p_cos * c), float(v + w_ * (p_sin * c - p_cos * s))))
    arr = np.array(out)
    return arr[:, 0], arr[:, 1]


EPS = np.finfo(float).eps


def exp_rtol(largest_exponent):
    """Relative accuracy of x(t) built from e^{s t}: exp's condition number is |s t|, so the rounding of the
    argument s t (eps |s t|) becomes that relative error; 8 eps covers exp itself and the few operations
    around it, in the code and in the reference alike."""
    return 8 * EPS * (1 + abs(largest_exponent))


def poly_atol(t, coefficients):
    """Pointwise bound on two evaluations of sum c_i t^i (Horner, and a hand-written sum with powers): each
    errs by at most gamma_2n sum |c_i| |t|^i (Higham 2002, eq. 5.3), gamma_2n ~ 2 n eps for degree n."""
    t = np.abs(np.asarray(t, dtype=float))
    size = sum(abs(c) * t**i for i, c in enumerate(coefficients))
    return 2 * (2 * len(coefficients)) * EPS * size


def assert_within(actual, desired, bound):
    """|actual - desired| <= bound pointwise (bound an array, e.g. from poly_atol)."""
    excess = np.abs(np.asarray(actual) - np.asarray(desired)) / bound
    assert np.all(excess <= 1.0), f"error up to {float(np.max(excess)):.3g} x the bound"


def rel_err(a, b):
    """Max error relative to the largest magnitude of the reference (absolute if it is 0)."""
    b = np.asarray(b)
    err = float(np.max(np.abs(np.asarray(a) - b)))
    scale = float(np.max(np.abs(b)))
    return err / scale if scale > 0 else err


def eom_residual(response, t, m, k, d, forcing, h):
    """m a + d v + k x - F, with a from central differences of the analytic v."""
    x, v = response(t)
    _, v_plus = response(t + h)
    _, v_minus = response(t - h)
    acc = (v_plus - v_minus) / (2 * h)
    residual = float(np.max(np.abs(m * acc + d * v + k * x - forcing(t))))
    scale = float(np.max(np.abs(m * acc) + np.abs(d * v) + np.abs(k * x) + np.abs(forcing(t))))
    return residual / scale if scale > 0 else residual


# Representative oscillators: (mass, stiffness, damping); zeta for m = 1.3, k = 2.7.
M0, K0 = 1.3, 2.7
WN0 = math.sqrt(K0 / M0)


def d_for(zeta):
    return zeta * 2.0 * math.sqrt(K0 * M0)


REGIMES = {
    "undamped": (M0, K0, 0.0),
    "d=1e-9": (M0, K0, 1e-9),
    "light": (M0, K0, d_for(0.02)),
    "moderate": (M0, K0, d_for(0.4)),
    "near-critical-under": (M0, K0, d_for(0.999)),
    "critical": (1.0, 1.0, 2.0),
    "overdamped": (M0, K0, d_for(3.0)),
    "very-overdamped": (M0, K0, d_for(1e4)),
    "free-mass": (M0, 0.0, 0.0),
    "free-mass-damped": (M0, 0.0, 0.9),
}


# ---------------------------------------------------------------------------
# parameters and roots
# ---------------------------------------------------------------------------


def test_frequencies_and_damping_ratio_follow_their_definitions():
    m, k, d = 2.0, 8.0, 2.0
    assert an.natural_frequency(m, k) == pytest.approx(2.0, rel=1e-15)
    assert an.damping_ratio(m, k, d) == pytest.approx(0.25, rel=1e-15)
    assert an.damped_frequency(m, k, d) == pytest.approx(2.0 * math.sqrt(1 - 0.0625), rel=1e-15)
    assert an.damped_frequency(m, k, 8.0) == 0.0  # critical: no oscillation
    assert an.damped_frequency(m, k, 20.0) == 0.0


def test_damping_ratio_limits_for_free_mass_and_no_damping():
    assert an.damping_ratio(1.0, 0.0, 0.5) == math.inf
    assert an.damping_ratio(1.0, 0.0, 0.0) == 0.0
    assert an.damping_ratio(1.0, 5.0, 0.0) == 0.0


@pytest.mark.parametrize(
    "m, k, d, expected",
    [
        (1.0, 4.0, 0.0, "undamped"),
        (1.0, 0.0, 0.0, "undamped"),
        (1.0, 4.0, 1.0, "underdamped"),
        (1.0, 4.0, 4.0, "critical"),
        (1.0, 4.0, 4.0 * (1 + 5e-13), "critical"),
        (1.0, 4.0, 4.0 * (1 - 1e-9), "underdamped"),
        (1.0, 4.0, 4.0 * (1 + 1e-9), "overdamped"),
        (1.0, 0.0, 0.3, "overdamped"),
    ],
)
def test_regime_classifies_by_damping_ratio(m, k, d, expected):
    assert an.regime(m, k, d) == expected


@pytest.mark.parametrize("name", list(REGIMES))
def test_characteristic_roots_are_roots_of_the_characteristic_polynomial(name):
    m, k, d = REGIMES[name]
    s1, s2 = an.characteristic_roots(m, k, d)
    for s in (s1, s2):
        scale = m * abs(s) ** 2 + d * abs(s) + k
        assert abs(m * s * s + d * s + k) <= 1e-14 * max(scale, 1e-300)
    # Vieta: s1 + s2 = -d/m, s1 s2 = k/m
    assert abs((s1 + s2) + d / m) <= 1e-14 * max(d / m, abs(s1), 1e-300)
    assert abs(s1 * s2 - k / m) <= 1e-14 * max(k / m, abs(s1) * abs(s2), 1e-300)


def test_slow_root_survives_extreme_overdamping():
    m, k, d = 1.0, 1.0, 1e9
    fast, slow = an.characteristic_roots(m, k, d)
    with localcontext() as ctx:
        ctx.prec = 60
        dd = Decimal(d)
        disc = (dd * dd - 4).sqrt()
        exact_slow = float((-dd + disc) / 2)
        exact_fast = float((-dd - disc) / 2)
    assert slow.imag == 0.0 and fast.imag == 0.0
    assert abs(slow.real - exact_slow) <= 1e-15 * abs(exact_slow)
    assert abs(fast.real - exact_fast) <= 1e-15 * abs(exact_fast)
    # The textbook formula loses every digit of the slow root here.
    naive = (-d + math.sqrt(d * d - 4 * m * k)) / (2 * m)
    assert abs(naive - exact_slow) > 0.1 * abs(exact_slow)


def test_free_mass_with_damping_has_a_zero_root():
    fast, slow = an.characteristic_roots(2.0, 0.0, 3.0)
    assert fast == complex(-1.5, 0.0)
    assert slow == 0.0


# ---------------------------------------------------------------------------
# free response
# ---------------------------------------------------------------------------


def test_undamped_release_is_a_cosine():
    # Chapter eq. 5.9: x(t) = x0 cos(omega t).
    m, k, x0 = 0.5, 18.0, 0.03
    w = math.sqrt(k / m)
    t = np.linspace(0.0, 20.0, 2001)
    x, v = an.free_response(t, m, k, 0.0, x0, 0.0)
    assert rel_err(x, x0 * np.cos(w * t)) < 1e-13
    assert rel_err(v, -x0 * w * np.sin(w * t)) < 1e-13


def test_undamped_release_with_initial_velocity_adds_a_sine():
    m, k, x0, v0 = 2.0, 50.0, -0.1, 0.7
    w = 5.0
    t = np.linspace(0.0, 10.0, 1001)
    x, v = an.free_response(t, m, k, 0.0, x0, v0)
    assert rel_err(x, x0 * np.cos(w * t) + v0 / w * np.sin(w * t)) < 1e-13
    assert rel_err(v, -x0 * w * np.sin(w * t) + v0 * np.cos(w * t)) < 1e-13


def test_underdamped_release_from_rest_matches_exact_form():
    # The chapter's eq. 5.14 drops the sine term (valid only for zeta << 1);
    # the exact solution for v0 = 0 is x0 e^{-zeta wn t}(cos wd t + zeta/sqrt(1-zeta^2) sin wd t).
    m, k, d, x0 = 1.5, 60.0, 3.0, 0.2
    wn = math.sqrt(k / m)
    zeta = d / (2 * math.sqrt(k * m))
    wd = wn * math.sqrt(1 - zeta**2)
    t = np.linspace(0.0, 5.0, 1001)
    exact = x0 * np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))
    x, _ = an.free_response(t, m, k, d, x0, 0.0)
    assert rel_err(x, exact) < 1e-13


def test_overdamped_exercise_matches_textbook_answer():
    # 'Under or overdamped?' exercise: d/m = 3, k/m = 2, x0 = 5 m, v0 = 0
    # -> x(t) = 10 e^{-t} - 5 e^{-2t}.
    m = 4.0
    t = np.linspace(0.0, 30.0, 601)
    x, v = an.free_response(t, m, 2.0 * m, 3.0 * m, 5.0, 0.0)
    # the fast root -2 over 30 s: exponents up to 60 (x and v stay positive, no cancellation)
    np.testing.assert_allclose(x, 10 * np.exp(-t) - 5 * np.exp(-2 * t), rtol=exp_rtol(-2 * t[-1]), atol=0)
    np.testing.assert_allclose(v[1:], -10 * np.exp(-t[1:]) + 10 * np.exp(-2 * t[1:]), rtol=1e-13, atol=0)
    assert an.regime(m, 2.0 * m, 3.0 * m) == "overdamped"


def test_critically_damped_release_matches_closed_form():
    m, k = 2.0, 8.0
    wn = 2.0
    d = 2 * math.sqrt(k * m)
    x0, v0 = 0.4, -3.0
    t = np.linspace(0.0, 15.0, 1501)
    x, v = an.free_response(t, m, k, d, x0, v0)
    exact_x = (x0 + (v0 + wn * x0) * t) * np.exp(-wn * t)
    exact_v = (v0 - wn * (v0 + wn * x0) * t) * np.exp(-wn * t)
    assert rel_err(x, exact_x) < 1e-14
    assert rel_err(v, exact_v) < 1e-14


@pytest.mark.parametrize("name", list(REGIMES))
def test_free_response_matches_60_digit_reference(name):
    m, k, d = REGIMES[name]
    rate = max(math.sqrt(k / m), d / (2 * m), 0.1)
    t = np.concatenate([[0.0], np.geomspace(1e-6 / rate, 30.0 / rate, 80)])
    for x0, v0 in [(1.0, 0.0), (0.0, 1.0), (0.3, -0.8)]:
        x, v = an.free_response(t, m, k, d, x0, v0)
        xr, vr = ref_free(t, m, k, d, x0, v0)
        assert rel_err(x, xr) < 2e-14, (x0, v0)
        assert rel_err(v, vr) < 2e-14, (x0, v0)


@pytest.mark.parametrize("offset", [1e-12, 1e-8, 1e-4])
def test_free_response_is_continuous_across_critical_damping(offset):
    m, k = 1.0, 1.0
    t = np.linspace(0.0, 25.0, 251)
    x_crit = (1.0 + (0.5 + 1.0) * t) * np.exp(-t)  # x0 = 1, v0 = 0.5, wn = 1
    for d in (2.0 * (1 - offset), 2.0, 2.0 * (1 + offset)):
        x, v = an.free_response(t, m, k, d, 1.0, 0.5)
        xr, vr = ref_free(t, m, k, d, 1.0, 0.5)
        assert rel_err(x, xr) < 1e-14
        assert rel_err(v, vr) < 1e-14
        # The motion depends smoothly on zeta: |dx/dzeta| is O(1) here.
        assert np.max(np.abs(x - x_crit)) <= 10 * offset + 1e-15


def test_slow_creep_of_extreme_overdamping_is_exact():
    # m = 1, k = 1, d = 1e9: after t >> m/d the mass creeps as x0 e^{-k t / d}.
    m, k, d, x0 = 1.0, 1.0, 1e9, 1.0
    t = np.array([1e-6, 1.0, 1e3, 1e8, 1e9, 5e9, 3e10])
    x, v = an.free_response(t, m, k, d, x0, 0.0)
    slow = -k / d  # exact to 1e-18 relative
    rtol = exp_rtol(slow * t[-1])  # exponents up to 30
    np.testing.assert_allclose(x, x0 * np.exp(slow * t), rtol=rtol, atol=0)
    np.testing.assert_allclose(v, slow * x0 * np.exp(slow * t), rtol=rtol, atol=0)
    xr, vr = ref_free(t, m, k, d, x0, 0.0)
    np.testing.assert_allclose(x, xr, rtol=rtol, atol=0)


def test_extreme_overdamping_initial_transient_matches_reference():
    # A kick v0 decays on the fast time scale m/d = 1e-9 s.
    m, k, d = 1.0, 1.0, 1e9
    t = np.concatenate([[0.0], np.geomspace(1e-13, 1e-6, 50)])
    x, v = an.free_response(t, m, k, d, 0.0, 1.0)
    xr, vr = ref_free(t, m, k, d, 0.0, 1.0)
    np.testing.assert_allclose(x[1:], xr[1:], rtol=1e-13, atol=0)
    assert rel_err(v, vr) < 1e-14


def test_free_mass_coasts_uniformly_or_to_rest():
    t = np.linspace(0.0, 50.0, 501)
    x, v = an.free_response(t, 2.0, 0.0, 0.0, 1.5, -0.25)
    np.testing.assert_allclose(x, 1.5 - 0.25 * t, rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(v, -0.25, rtol=0, atol=0)
    m, d = 2.0, 0.5
    x, v = an.free_response(t, m, 0.0, d, 1.5, -0.25)
    np.testing.assert_allclose(x, 1.5 - 0.25 * (m / d) * (1 - np.exp(-d * t / m)), rtol=1e-14)
    np.testing.assert_allclose(v, -0.25 * np.exp(-d * t / m), rtol=1e-14)


@pytest.mark.parametrize("name", list(REGIMES))
def test_free_response_satisfies_equation_of_motion(name):
    m, k, d = REGIMES[name]
    rate = max(math.sqrt(k / m), d / (2 * m), 0.1)
    t = np.linspace(1.0 / rate, 10.0 / rate, 50)
    res = eom_residual(lambda s: an.free_response(s, m, k, d, 0.7, -0.4), t, m, k, d, lambda s: 0.0 * s, h=1e-4 / rate)
    assert res < 1e-8


def test_free_response_survives_huge_times():
    t = np.array([0.0, 1e3, 1e12, 1e100, 1e300])
    for m, k, d in [(1, 1, 0), (1, 1, 1e-9), (1, 1, 1), (1, 1, 2), (1, 1, 2 + 1e-12), (1, 1, 1e9), (1, 0, 1)]:
        x, v = an.free_response(t, m, k, d, 1.0, -0.5)
        assert np.all(np.isfinite(x)) and np.all(np.isfinite(v)), (m, k, d)
        assert np.all(np.abs(x) <= 1.2) and np.all(np.abs(v) <= 1.2)
        if d > 0 and k > 0:
            assert x[-1] == 0.0 and v[-1] == 0.0


def test_free_response_returns_arrays_shaped_like_t():
    x, v = an.free_response(0.3, 1.0, 4.0, 0.1, 1.0, 0.0)
    assert isinstance(x, np.ndarray) and x.shape == () and v.shape == ()
    x, v = an.free_response(np.zeros((3, 4)), 1.0, 4.0, 0.1, 1.0, 0.0)
    assert x.shape == (3, 4) and np.all(x == 1.0) and np.all(v == 0.0)


# ---------------------------------------------------------------------------
# step response
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", [n for n in REGIMES if REGIMES[n][1] > 0])
def test_step_response_matches_static_offset_plus_free_vibration(name):
    m, k, d = REGIMES[name]
    rate = max(math.sqrt(k / m), d / (2 * m))
    t = np.concatenate([[0.0], np.geomspace(1e-6 / rate, 30.0 / rate, 80)])
    x, v = an.step_response(t, m, k, d, -9.81 * m, x0=0.1, v0=0.2)
    xr, vr = ref_step(t, m, k, d, -9.81 * m, 0.1, 0.2)
    assert rel_err(x, xr) < 2e-14
    assert rel_err(v, vr) < 2e-14


def test_step_response_settles_at_static_deflection():
    m, k, d, force = 2.0, 500.0, 20.0, 12.0
    x, v = an.step_response(np.array([50.0]), m, k, d, force)
    assert x[0] == pytest.approx(force / k, rel=1e-15)
    assert abs(v[0]) < 1e-15


def test_step_response_of_free_mass_is_uniform_acceleration():
    m, force = 3.0, 1.2
    t = np.linspace(0.0, 10.0, 101)
    x, v = an.step_response(t, m, 0.0, 0.0, force, x0=1.0, v0=-2.0)
    # x crosses zero twice: the bound is absolute, on the size of the terms
    assert_within(x, 1.0 - 2.0 * t + force * t**2 / (2 * m), poly_atol(t, [1.0, 2.0, 0.2]))
    assert_within(v, -2.0 + force * t / m, poly_atol(t, [2.0, 0.4]))


def test_step_response_of_damped_free_mass_reaches_terminal_velocity():
    m, d, force, x0, v0 = 3.0, 0.6, 1.2, 1.0, -2.0
    t = np.linspace(0.0, 300.0, 601)  # 60 time constants m/d
    x, v = an.step_response(t, m, 0.0, d, force, x0=x0, v0=v0)
    vt = force / d
    exact_v = vt + (v0 - vt) * np.exp(-d * t / m)
    exact_x = x0 + vt * t + (v0 - vt) * (m / d) * (1 - np.exp(-d * t / m))
    np.testing.assert_allclose(v, exact_v, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(x, exact_x, rtol=1e-14, atol=1e-14)
    assert v[-1] == pytest.approx(vt, rel=1e-12)


def test_step_response_with_tiny_stiffness_has_no_cancellation():
    # With k = 1e-20 the spring is irrelevant for t <= 100 s; F/k = 1e20 would
    # wipe out the answer in the textbook form F/k + free(x0 - F/k, v0).
    m, k, d, force = 1.0, 1e-20, 1.0, 1.0
    t = np.linspace(0.0, 100.0, 101)
    x, v = an.step_response(t, m, k, d, force)
    creep = force / d * (t - (m / d) * (1 - np.exp(-d * t / m)))
    np.testing.assert_allclose(x, creep, rtol=1e-13, atol=1e-300)
    np.testing.assert_allclose(v, force / d * (1 - np.exp(-d * t / m)), rtol=1e-13, atol=1e-300)


def test_step_response_starts_quadratically_from_rest():
    # x ~ F t^2 / (2 m) for t -> 0 in every regime: checks relative accuracy
    # where 1 - e^{-sigma t}(...) would cancel.
    t = np.array([1e-9, 1e-7, 1e-5])
    for m, k, d in [(1.0, 4.0, 0.0), (1.0, 4.0, 4.0), (1.0, 4.0, 1e3), (1.0, 0.0, 2.0)]:
        x, _ = an.step_response(t, m, k, d, 2.0)
        rate = max(d / m, math.sqrt(k / m))
        # x / (F t^2 / 2m) = 1 - (d/m) t / 3 + O(t^2)
        assert np.all(np.abs(x / (2.0 * t**2 / (2 * m)) - 1.0) <= rate * t)
        if k > 0:
            xr, _ = ref_step(t, m, k, d, 2.0, 0.0, 0.0)
        else:
            with localcontext() as ctx:
                ctx.prec = _PREC
                dm = Decimal(d) / Decimal(m)
                xr = [
                    float(Decimal(2.0) / Decimal(d) * (Decimal(float(s)) - (1 - (-dm * Decimal(float(s))).exp()) / dm))
                    for s in t
                ]
        np.testing.assert_allclose(x, xr, rtol=1e-13)


@pytest.mark.parametrize("name", list(REGIMES))
def test_step_response_satisfies_equation_of_motion(name):
    m, k, d = REGIMES[name]
    rate = max(math.sqrt(k / m), d / (2 * m), 0.1)
    t = np.linspace(1.0 / rate, 10.0 / rate, 50)
    res = eom_residual(
        lambda s: an.step_response(s, m, k, d, 3.0, 0.2, -0.1), t, m, k, d, lambda s: 3.0 + 0.0 * s, h=1e-4 / rate
    )
    assert res < 1e-8


# ---------------------------------------------------------------------------
# harmonic forcing
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", [n for n in REGIMES if n != "very-overdamped"])  # too stiff for DOP853
@pytest.mark.parametrize("ratio", [0.37, 1.0, 2.6])
def test_harmonic_response_matches_solve_ivp(name, ratio):
    m, k, d = REGIMES[name]
    wref = math.sqrt(k / m) if k > 0 else 1.7
    freq = ratio * wref / (2 * math.pi)
    omega = 2 * math.pi * freq
    f0 = 2.5
    t = np.linspace(0.0, 12.0 * 2 * math.pi / wref, 300)

    def rhs(s, z):
        return [z[1], (f0 * math.sin(omega * s) - d * z[1] - k * z[0]) / m]

    sol = solve_ivp(rhs, (0.0, t[-1]), [0.1, -0.2], method="DOP853", t_eval=t, rtol=1e-12, atol=1e-14)
    x, v = an.harmonic_response(t, m, k, d, f0, freq, x0=0.1, v0=-0.2)
    assert rel_err(x, sol.y[0]) < 1e-9
    assert rel_err(v, sol.y[1]) < 1e-9


@pytest.mark.parametrize("name", list(REGIMES))
def test_harmonic_response_matches_60_digit_reference(name):
    m, k, d = REGIMES[name]
    rate = max(math.sqrt(k / m), d / (2 * m), 0.5)
    for ratio in (0.37, 1.0, 2.6):
        freq = ratio * rate / (2 * math.pi)
        t = np.concatenate([[0.0], np.geomspace(1e-4 / rate, 30.0 / rate, 40)])
        x, v = an.harmonic_response(t, m, k, d, 0.8, freq, 0.2, -0.1)
        xr, vr = ref_harmonic(t, m, k, d, 0.8, freq, 0.2, -0.1)
        assert rel_err(x, xr) < 1e-13, ratio
        assert rel_err(v, vr) < 1e-13, ratio


def test_undamped_resonance_grows_secularly():
    # From rest, F0 sin(wn t): x = F0/(2k) sin(wn t) - F0/(2 m wn) t cos(wn t).
    m, k, f0 = 2.0, 2.0 * (2 * math.pi * 1.5) ** 2, 4.0
    freq = 1.5
    wn = 2 * math.pi * freq
    t = np.linspace(0.0, 20.0, 4001)
    x, v = an.harmonic_response(t, m, k, 0.0, f0, freq)
    exact_x = f0 / (2 * k) * np.sin(wn * t) - f0 / (2 * m * wn) * t * np.cos(wn * t)
    exact_v = f0 / (2 * m) * t * np.sin(wn * t)
    assert rel_err(x, exact_x) < 1e-13
    assert rel_err(v, exact_v) < 1e-13
    # The envelope grows linearly: amplitude F0 t / (2 m wn) after many cycles.
    late = t > 15.0
    assert np.max(np.abs(x[late])) == pytest.approx(f0 * 20.0 / (2 * m * wn), rel=2e-3)


@pytest.mark.parametrize("detuning", [-1e-9, 1e-9, -1e-12, 1e-12])
def test_near_resonance_is_continuous_with_secular_solution(detuning):
    m, k, f0 = 1.0, 9.0, 1.0
    wn = 3.0
    freq = wn * (1 + detuning) / (2 * math.pi)
    t = np.linspace(0.0, 5 * 2 * math.pi / wn, 1001)
    x, v = an.harmonic_response(t, m, k, 0.0, f0, freq, x0=0.01)
    secular = 0.01 * np.cos(wn * t) + f0 / (2 * k) * np.sin(wn * t) - f0 / (2 * m * wn) * t * np.cos(wn * t)
    assert rel_err(x, secular) < 1e-6
    xr, vr = ref_harmonic(t[::20], m, k, 0.0, f0, freq, 0.01, 0.0)
    assert rel_err(x[::20], xr) < 1e-13
    assert rel_err(v[::20], vr) < 1e-13


@pytest.mark.parametrize("zeta", [1e-9, 1e-4, 0.05])
def test_lightly_damped_near_resonance_matches_60_digit_reference(zeta):
    m, k = M0, K0
    d = d_for(zeta)
    for ratio in (1 - 1e-9, 1.0, 1 + 1e-7):
        freq = ratio * WN0 / (2 * math.pi)
        t = np.linspace(0.0, 40.0 / WN0, 61)
        x, v = an.harmonic_response(t, m, k, d, 0.8, freq, 0.2, -0.1)
        xr, vr = ref_harmonic(t, m, k, d, 0.8, freq, 0.2, -0.1)
        assert rel_err(x, xr) < 1e-13
        assert rel_err(v, vr) < 1e-13


def test_harmonic_response_settles_to_steady_state_amplitude_and_phase():
    m, k, d, f0, freq = 1.2, 300.0, 6.0, 5.0, 2.1
    amp, phase = an.steady_state_amplitude(m, k, d, f0, freq)
    omega = 2 * math.pi * freq
    assert amp == pytest.approx(f0 / math.sqrt((k - m * omega**2) ** 2 + (d * omega) ** 2), rel=1e-15)
    assert phase == pytest.approx(math.atan2(d * omega, k - m * omega**2), rel=1e-15)
    t = np.linspace(30.0, 32.0, 401)  # transient decays as e^{-2.5 t}
    x, _ = an.harmonic_response(t, m, k, d, f0, freq, x0=0.3, v0=1.0)
    np.testing.assert_allclose(x, amp * np.sin(omega * t - phase), rtol=0, atol=1e-13 * amp)


def test_steady_state_amplitude_limits():
    m, k, d, f0 = 2.0, 200.0, 4.0, 3.0
    wn = 10.0
    amp, phase = an.steady_state_amplitude(m, k, d, f0, wn / (2 * math.pi))
    assert amp == pytest.approx(f0 / (d * wn), rel=1e-14)  # resonance: X = F0 / (d wn)
    assert phase == pytest.approx(math.pi / 2, rel=1e-14)
    amp, phase = an.steady_state_amplitude(m, k, d, f0, 0.0)
    assert (amp, phase) == (f0 / k, 0.0)  # static deflection
    amp, phase = an.steady_state_amplitude(m, k, 0.0, f0, 3 * wn / (2 * math.pi))
    assert amp == pytest.approx(-f0 / (k - m * 9 * wn**2), rel=1e-14) and phase == pytest.approx(math.pi)


def test_steady_state_amplitude_is_infinite_at_undamped_resonance():
    freq = 0.5
    k = (2 * math.pi * freq) ** 2
    amp, phase = an.steady_state_amplitude(1.0, k, 0.0, 2.0, freq)
    assert amp == math.inf and phase == pytest.approx(math.pi / 2)
    amp, _ = an.steady_state_amplitude(1.0, k * (1 + 1e-14), 0.0, 2.0, freq)
    assert amp == math.inf


def test_zero_frequency_force_is_no_force():
    t = np.linspace(0.0, 5.0, 51)
    x, v = an.harmonic_response(t, 1.0, 4.0, 0.3, 7.0, 0.0, x0=0.5, v0=0.1)
    xf, vf = an.free_response(t, 1.0, 4.0, 0.3, 0.5, 0.1)
    np.testing.assert_array_equal(x, xf)
    np.testing.assert_array_equal(v, vf)


@pytest.mark.parametrize("name", list(REGIMES))
def test_harmonic_response_satisfies_equation_of_motion(name):
    m, k, d = REGIMES[name]
    rate = max(math.sqrt(k / m), d / (2 * m), 0.5)
    omega = 1.3 * rate
    t = np.linspace(1.0 / rate, 10.0 / rate, 50)
    res = eom_residual(
        lambda s: an.harmonic_response(s, m, k, d, 2.0, omega / (2 * math.pi), 0.1, 0.0),
        t,
        m,
        k,
        d,
        lambda s: 2.0 * np.sin(omega * s),
        h=1e-4 / rate,
    )
    assert res < 1e-8


def test_harmonic_response_survives_huge_times():
    t = np.array([0.0, 1e6, 1e15, 1e300])
    for m, k, d in [(1, 1, 0), (1, 1, 1e-9), (1, 1, 2), (1, 1, 1e9), (1, 0, 0.5)]:
        x, v = an.harmonic_response(t, m, k, d, 1.0, 0.3, 0.1, 0.1)
        assert np.all(np.isfinite(x)) and np.all(np.isfinite(v)), (m, k, d)


# ---------------------------------------------------------------------------
# invalid input
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "m, k, d, message",
    [
        (0.0, 1.0, 0.0, "mass"),
        (-1.0, 1.0, 0.0, "mass"),
        (1.0, -1.0, 0.0, "stiffness"),
        (1.0, 1.0, -0.1, "damping"),
        (float("nan"), 1.0, 0.0, "mass"),
        (1.0, float("inf"), 0.0, "stiffness"),
        (1.0, 1.0, float("nan"), "damping"),
    ],
)
def test_non_physical_oscillators_are_rejected(m, k, d, message):
    for call in (
        lambda: an.damping_ratio(m, k, d),
        lambda: an.damped_frequency(m, k, d),
        lambda: an.regime(m, k, d),
        lambda: an.characteristic_roots(m, k, d),
        lambda: an.free_response(1.0, m, k, d, 1.0, 0.0),
        lambda: an.step_response(1.0, m, k, d, 1.0),
        lambda: an.harmonic_response(1.0, m, k, d, 1.0, 1.0),
        lambda: an.steady_state_amplitude(m, k, d, 1.0, 1.0),
    ):
        with pytest.raises(ValueError, match=message):
            call()
    if message != "damping":
        with pytest.raises(ValueError, match=message):
            an.natural_frequency(m, k)


def test_bad_times_and_initial_conditions_are_rejected():
    with pytest.raises(ValueError, match=">= 0"):
        an.free_response([-1.0, 1.0], 1.0, 1.0, 0.0, 1.0, 0.0)
    with pytest.raises(ValueError, match="finite"):
        an.step_response([np.nan], 1.0, 1.0, 0.0, 1.0)
    with pytest.raises(ValueError, match="x0"):
        an.free_response(1.0, 1.0, 1.0, 0.0, np.inf, 0.0)
    with pytest.raises(ValueError, match="force_frequency"):
        an.harmonic_response(1.0, 1.0, 1.0, 0.0, 1.0, -2.0)


# ---------------------------------------------------------------------------
# kinematics
# ---------------------------------------------------------------------------


def test_polynomial_motion_differentiates_exactly():
    t = np.linspace(-2.0, 3.0, 11)
    x, v, a = an.polynomial_motion(t, [1.0, 2.0, 3.0, -0.5])
    np.testing.assert_allclose(x, 1 + 2 * t + 3 * t**2 - 0.5 * t**3, rtol=1e-15, atol=1e-14)
    np.testing.assert_allclose(v, 2 + 6 * t - 1.5 * t**2, rtol=1e-15, atol=1e-14)
    np.testing.assert_allclose(a, 6 - 3 * t, rtol=1e-15, atol=1e-14)
    x, v, a = an.polynomial_motion(2.0, [4.0])
    assert (float(x), float(v), float(a)) == (4.0, 0.0, 0.0)


def test_integrate_acceleration_reproduces_chapter_example():
    # a(t) = 1.2 t + 3.0, v(0) = 15 m/s, x(0) = 150 m:
    # v = 15 + 3 t + 0.6 t^2, x = 150 + 15 t + 1.5 t^2 + 0.2 t^3.
    x, v, a = an.integrate_acceleration(10.0, [3.0, 1.2], x0=150.0, v0=15.0)
    assert float(a) == pytest.approx(15.0, rel=1e-15)
    assert float(v) == pytest.approx(105.0, rel=1e-15)
    assert float(x) == pytest.approx(650.0, rel=1e-15)
    t = np.linspace(0.0, 10.0, 101)
    x, v, a = an.integrate_acceleration(t, [3.0, 1.2], x0=150.0, v0=15.0)
    assert_within(v, 15 + 3 * t + 0.6 * t**2, poly_atol(t, [15, 3, 0.6]))
    assert_within(x, 150 + 15 * t + 1.5 * t**2 + 0.2 * t**3, poly_atol(t, [150, 15, 1.5, 0.2]))


def test_constant_acceleration_gives_eq_5_5():
    # x = x0 + v0 t + a t^2 / 2 for constant a (free fall).
    t = np.linspace(0.0, 3.0, 31)
    x, v, a = an.integrate_acceleration(t, [-9.81], x0=45.0, v0=2.0)
    np.testing.assert_allclose(x, 45.0 + 2.0 * t - 9.81 * t**2 / 2, rtol=1e-14)
    np.testing.assert_allclose(v, 2.0 - 9.81 * t, rtol=1e-15, atol=1e-15)
    np.testing.assert_array_equal(a, -9.81)


def test_piecewise_linear_velocity_gives_area_under_the_tachograph():
    knots = [0.0, 10.0, 30.0, 40.0]
    speeds = [0.0, 20.0, 20.0, 0.0]
    x, v, a = an.piecewise_linear_velocity([0.0, 5.0, 10.0, 20.0, 35.0, 40.0], knots, speeds, x0=3.0)
    np.testing.assert_allclose(x, 3.0 + np.array([0.0, 25.0, 100.0, 300.0, 575.0, 600.0]), rtol=1e-15)
    np.testing.assert_allclose(v, [0.0, 10.0, 20.0, 20.0, 10.0, 0.0], rtol=1e-15)
    # Slope of the segment to the right at a knot; last segment at the end.
    np.testing.assert_array_equal(a, [2.0, 2.0, 0.0, 0.0, -2.0, -2.0])
    # Independent check: fine trapezoid integration is exact for linear v.
    t = np.linspace(0.0, 40.0, 4001)
    xs, vs, _ = an.piecewise_linear_velocity(t, knots, speeds)
    area = np.concatenate([[0.0], np.cumsum(0.5 * (vs[1:] + vs[:-1]) * np.diff(t))])
    np.testing.assert_allclose(xs, area, rtol=1e-13, atol=1e-11)


def test_piecewise_linear_velocity_rejects_times_outside_the_record():
    with pytest.raises(ValueError, match="within"):
        an.piecewise_linear_velocity([41.0], [0.0, 40.0], [0.0, 1.0])
    with pytest.raises(ValueError, match="within"):
        an.piecewise_linear_velocity([-0.1], [0.0, 40.0], [0.0, 1.0])
    with pytest.raises(ValueError, match="strictly increasing"):
        an.piecewise_linear_velocity([1.0], [0.0, 2.0, 2.0], [0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match="finite"):
        an.polynomial_motion(1.0, [1.0, np.nan])
