"""Tests for springlab.exact.linear: exact responses of linear time-invariant systems.

The matrix exponential itself is scipy's; what is tested here is springlab's use of it: that
exp(X) - I keeps its own relative accuracy (small steps, creep and rigid-body modes), and that the
propagated responses match references that share no code with it: closed forms worked by hand,
springlab.analytic's single-DOF formulas (validated in test_analytic.py against 60-digit
references), scipy's DOP853 at tight tolerance, and momentum balance.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp

from springlab.exact import analytic as an
from springlab.exact import linear

EPS = np.finfo(float).eps


def rel_err(a, b):
    """Max error relative to the largest magnitude of the reference (absolute if it is 0)."""
    b = np.asarray(b)
    err = float(np.max(np.abs(np.asarray(a) - b)))
    scale = float(np.max(np.abs(b)))
    return err / scale if scale > 0 else err


# (mass, stiffness, damping) for the single-DOF reductions
REGIMES = {
    "undamped": (1.3, 2.7, 0.0),
    "light": (1.3, 2.7, 0.02 * 2.0 * math.sqrt(2.7 * 1.3)),
    "critical": (1.0, 1.0, 2.0),
    "overdamped": (1.3, 2.7, 3.0 * 2.0 * math.sqrt(2.7 * 1.3)),
    "free-mass-damped": (1.3, 0.0, 0.9),
}


# ---------------------------------------------------------------------------
# exp(X) - I
# ---------------------------------------------------------------------------


def _taylor_minus_identity(x, terms=12):
    """sum_{j=1}^{terms} X^j / j!: exact to roundoff for ||X|| <= 1e-3 (next term < 1e-39 relative)."""
    out = np.zeros_like(x)
    power = np.eye(x.shape[0])
    for j in range(1, terms + 1):
        power = power @ x / j
        out = out + power
    return out


@pytest.mark.parametrize("n", [1, 2, 3, 5, 8])
@pytest.mark.parametrize("scale", [1e-12, 1e-8, 1e-3])
def test_exp_minus_identity_of_small_matrices_is_relatively_exact(n, scale):
    # exp(X) - I of size ~||X||: subtracting I from exp(X) would leave only eps / ||X|| of it.
    rng = np.random.default_rng(n * 100 + round(-math.log10(scale)))
    for _ in range(4):
        x = rng.standard_normal((n, n)) * scale / math.sqrt(n)
        # a few roundings of size eps on each term of the series, a dozen terms
        assert rel_err(linear.expm_minus_identity(x), _taylor_minus_identity(x)) < 50 * EPS


@pytest.mark.parametrize("scale", [0.5, 2.0, 5.0, 20.0])
def test_exp_minus_identity_of_rotation_scaling_blocks_is_exact(scale):
    # A = Q blockdiag([[a, -b], [b, a]]) Q^T has exp(A) - I = Q blockdiag(e^a R(b) - I) Q^T.
    rng = np.random.default_rng(int(scale * 10))
    q, _ = np.linalg.qr(rng.standard_normal((6, 6)))
    a_re = rng.uniform(-1.0, 0.3, 3) * scale
    a_im = rng.uniform(-1.0, 1.0, 3) * scale
    blocks = np.zeros((6, 6))
    exact_blocks = np.zeros((6, 6))
    for i in range(3):
        j = 2 * i
        blocks[j : j + 2, j : j + 2] = [[a_re[i], -a_im[i]], [a_im[i], a_re[i]]]
        c, s = math.cos(a_im[i]), math.sin(a_im[i])
        exact_blocks[j : j + 2, j : j + 2] = math.exp(a_re[i]) * np.array([[c, -s], [s, c]]) - np.eye(2)
    a = q @ blocks @ q.T
    exact = q @ exact_blocks @ q.T
    # A itself carries rounding ~eps ||A||, which exp amplifies by ~e^||A|| relative to
    # exp(A) - I (>= 1 - e^-||A||), and Q's own rounding adds a few eps: 100 eps (1 + ||A||) e^||A||/(e^||A||-1)
    norm = float(np.linalg.norm(a, 2))
    bound = 100 * EPS * (1 + norm) * math.exp(norm) / math.expm1(norm)
    assert rel_err(linear.expm_minus_identity(a), exact) < bound


def test_exp_minus_identity_of_rotation_generator():
    for theta in (1e-9, 1e-5, 0.3, 2.3):
        d = linear.expm_minus_identity(np.array([[0.0, -theta], [theta, 0.0]]))
        # cos - 1 = -2 sin^2(theta / 2) without cancellation
        exact = np.array(
            [[-2 * math.sin(theta / 2) ** 2, -math.sin(theta)], [math.sin(theta), -2 * math.sin(theta / 2) ** 2]]
        )
        assert rel_err(d, exact) < 10 * EPS, theta


def test_exp_minus_identity_of_nilpotent_matrix_is_its_finite_taylor_series():
    n = np.diag([3.0, -2.0, 5.0], k=1)
    exact = n + n @ n / 2 + n @ n @ n / 6
    np.testing.assert_allclose(linear.expm_minus_identity(n), exact, rtol=10 * EPS, atol=10 * EPS)
    np.testing.assert_array_equal(linear.expm_minus_identity(np.zeros((3, 3))), np.zeros((3, 3)))


def test_exp_minus_identity_agrees_with_scipy_where_subtracting_identity_is_harmless():
    # For ||X|| ~ 1 exp(X) - I has no cancellation, so scipy.linalg.expm(X) - I is a reference to
    # ~eps relative; a non-normal matrix's exponential has condition ~||X|| (Higham 2008, ch. 10).
    rng = np.random.default_rng(7)
    for x in (
        rng.standard_normal((6, 6)),
        rng.standard_normal((6, 6)) * 8.0,
        np.array([[-1.0, 1e4, 0.0], [0.0, -2.0, 1e4], [0.0, 0.0, -3.0]]),
    ):
        reference = scipy.linalg.expm(x) - np.eye(x.shape[0])
        norm = float(np.abs(x).sum(axis=0).max())
        assert rel_err(linear.expm_minus_identity(x), reference) < 100 * EPS * norm


# ---------------------------------------------------------------------------
# state space and multi-DOF responses
# ---------------------------------------------------------------------------


def test_state_matrix_has_first_order_layout():
    mm = np.diag([2.0, 4.0])
    cc = np.array([[1.0, -1.0], [-1.0, 1.0]])
    kk = np.array([[6.0, -2.0], [-2.0, 2.0]])
    a = linear.state_matrix(mm, cc, kk)
    expected = np.array(
        [
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
            [-3.0, 1.0, -0.5, 0.5],
            [0.5, -0.5, 0.25, -0.25],
        ]
    )
    np.testing.assert_allclose(a, expected, rtol=0, atol=1e-16)


def test_state_matrix_rejects_non_physical_mass_matrix():
    kk = np.eye(2)
    with pytest.raises(ValueError, match="positive definite"):
        linear.state_matrix(np.diag([1.0, -1.0]), kk, kk)
    with pytest.raises(ValueError, match="symmetric"):
        linear.state_matrix(np.array([[1.0, 0.5], [0.0, 1.0]]), kk, kk)
    with pytest.raises(ValueError, match="2x2"):
        linear.state_matrix(np.eye(2), np.eye(3), kk)


def _two_body_chain():
    # Two masses joined by a spring and damper, nothing to ground: K and C are
    # singular (free rigid-body translation).
    mm = np.diag([2.0, 1.0])
    kk = np.array([[3.0, -3.0], [-3.0, 3.0]])
    cc = np.array([[0.1, -0.1], [-0.1, 0.1]])
    return mm, cc, kk


def test_linear_response_with_rigid_body_mode_and_switching_force_matches_solve_ivp():
    mm, cc, kk = _two_body_chain()
    breakpoints = np.array([0.0, 0.37, 2.0, 5.5])
    values = np.array([[1.0, 0.0], [0.0, -2.0], [0.5, 0.5], [0.0, 0.0]])
    q0, v0 = np.array([0.1, -0.2]), np.array([0.0, 0.3])
    t = np.linspace(0.0, 10.0, 100_001)

    q, v = linear.linear_response(t, mm, cc, kk, q0, v0, (breakpoints, values))

    minv = np.linalg.inv(mm)
    ref = np.empty((t.size, 4))
    z = np.concatenate([q0, v0])
    edges = list(breakpoints[1:]) + [t[-1]]
    lo = 0.0
    for i, hi in enumerate(edges):
        f = values[i]

        def rhs(_s, y, f=f):
            return np.concatenate([y[2:], minv @ (f - cc @ y[2:] - kk @ y[:2])])

        sel = (t >= lo) & (t < hi)
        sol = solve_ivp(
            rhs, (lo, hi), z, method="DOP853", rtol=1e-12, atol=1e-15, t_eval=np.concatenate([t[sel], [hi]])
        )
        ref[sel] = sol.y[:, :-1].T
        z = sol.y[:, -1]
        lo = hi
    ref[-1] = z
    assert rel_err(q, ref[:, :2]) < 1e-10
    assert rel_err(v, ref[:, 2:]) < 1e-10
    # Momentum balance of the free chain: total momentum = impulse of the force.
    p = v @ np.diag(mm)
    impulse = np.where(t < 0.37, t * 1.0, 0.37 - 2.0 * (np.minimum(t, 2.0) - 0.37))
    impulse = impulse + np.clip(t - 2.0, 0.0, 3.5) * 1.0
    np.testing.assert_allclose(p, mm[0, 0] * v0[0] + mm[1, 1] * v0[1] + impulse, rtol=0, atol=1e-12)


def test_uniform_grid_roundoff_does_not_accumulate():
    # 1e5 steps of an undamped oscillator over ~160 periods against cos/sin.
    t = np.linspace(0.0, 1000.0, 100_001)
    z = linear.lti_response(t, np.array([[0.0, 1.0], [-1.0, 0.0]]), [1.0, 0.0])
    assert np.max(np.abs(z[:, 0] - np.cos(t))) < 1e-12
    assert np.max(np.abs(z[:, 1] + np.sin(t))) < 1e-12
    # Same through a grid built by cumulative sums (steps differ by ulps).
    t2 = np.cumsum(np.full(100_001, 0.01)) - 0.01
    z2 = linear.lti_response(t2, np.array([[0.0, 1.0], [-1.0, 0.0]]), [1.0, 0.0])
    assert np.max(np.abs(z2[:, 0] - np.cos(t2))) < 1e-12


@pytest.mark.parametrize("name", ["undamped", "light", "critical", "overdamped", "free-mass-damped"])
def test_linear_response_reduces_to_single_dof_closed_forms(name):
    m, k, d = REGIMES[name]
    t = np.linspace(0.0, 20.0, 2001)
    q, v = linear.linear_response(t, [[m]], [[d]], [[k]], [0.4], [-0.3])
    x, xv = an.free_response(t, m, k, d, 0.4, -0.3)
    assert rel_err(q[:, 0], x) < 1e-13 and rel_err(v[:, 0], xv) < 1e-13
    q, v = linear.linear_response(t, [[m]], [[d]], [[k]], [0.4], [-0.3], force=[1.5])
    x, xv = an.step_response(t, m, k, d, 1.5, 0.4, -0.3)
    assert rel_err(q[:, 0], x) < 1e-13 and rel_err(v[:, 0], xv) < 1e-13


def test_stiff_damper_creep_is_exact_in_state_space():
    # m = 1, k = 1, d = 1e9: the slow mode e^{-1e-9 t} must survive the
    # matrix exponential (plain scaling and squaring loses ~1e-9 here).
    t = np.linspace(0.0, 5e9, 10_001)
    q, v = linear.linear_response(t, [[1.0]], [[1e9]], [[1.0]], [1.0], [0.0])
    np.testing.assert_allclose(q[:, 0], np.exp(-1e-9 * t), rtol=1e-13, atol=0)
    np.testing.assert_allclose(v[1:, 0], -1e-9 * np.exp(-1e-9 * t[1:]), rtol=1e-6)


def test_strong_decay_keeps_relative_accuracy():
    # Overdamped decay to ~1e-18 of the initial state over the run.
    m, k, d = 1.0, 4.0, 30.0
    for n in (301, 30_001):
        t = np.linspace(0.0, 300.0, n)
        q, v = linear.linear_response(t, [[m]], [[d]], [[k]], [1.0], [0.7])
        x, xv = an.free_response(t, m, k, d, 1.0, 0.7)
        np.testing.assert_allclose(q[:, 0], x, rtol=1e-12, atol=0)
        np.testing.assert_allclose(v[:, 0], xv, rtol=1e-12, atol=0)


def test_lti_response_with_harmonic_generator_reproduces_forced_vibration():
    # Augment the oscillator with y1' = W y2, y2' = -W y1 (y1 = sin W t) and
    # drive it with F0 y1: exact forcing without any time-dependent input.
    m, k, f0 = 1.0, 9.0, 2.0
    for d, omega in [(0.0, 3.0), (0.0, 2.2), (0.4, 3.0), (7.0, 1.1)]:
        a = np.array(
            [
                [0.0, 1.0, 0.0, 0.0],
                [-k / m, -d / m, f0 / m, 0.0],
                [0.0, 0.0, 0.0, omega],
                [0.0, 0.0, -omega, 0.0],
            ]
        )
        t = np.linspace(0.0, 30.0, 3001)
        z = linear.lti_response(t, a, [0.1, 0.0, 0.0, 1.0])
        x, v = an.harmonic_response(t, m, k, d, f0, omega / (2 * math.pi), x0=0.1)
        assert rel_err(z[:, 0], x) < 1e-12, (d, omega)
        assert rel_err(z[:, 1], v) < 1e-12, (d, omega)


def test_lti_response_handles_irregular_times_and_off_grid_breakpoints():
    # Force F1 on [0, 1.234), F2 after: superpose step responses from rest.
    m, k, d = 1.0, 16.0, 0.8
    a = linear.state_matrix([[m]], [[d]], [[k]])
    b = np.array([[0.0], [1.0 / m]])
    rng = np.random.default_rng(3)
    t = np.sort(np.concatenate([rng.uniform(0.0, 6.0, 150), [0.0, 1.234, 1.234, 6.0]]))
    z = linear.lti_response(t, a, [0.2, 0.0], b, (np.array([0.0, 1.234]), np.array([[2.0], [-1.0]])))
    x = an.free_response(t, m, k, d, 0.2, 0.0)[0] + an.step_response(t, m, k, d, 2.0)[0]
    late = t >= 1.234
    x[late] += an.step_response(t[late] - 1.234, m, k, d, -3.0)[0]
    assert rel_err(z[:, 0], x) < 1e-13


def test_lti_response_output_shapes_and_start_time():
    a = np.array([[0.0, 1.0], [-4.0, -0.2]])
    z = linear.lti_response(np.array([]), a, [1.0, 0.0])
    assert z.shape == (0, 2)
    t = np.array([0.5, 0.5, 2.0])
    z = linear.lti_response(t, a, [1.0, 0.0])
    x, v = an.free_response(t, 1.0, 4.0, 0.2, 1.0, 0.0)
    assert z.shape == (3, 2)
    np.testing.assert_allclose(z[:, 0], x, rtol=1e-14, atol=1e-15)
    np.testing.assert_array_equal(z[0], z[1])


def test_lti_response_rejects_bad_input():
    a = np.array([[0.0, 1.0], [-1.0, 0.0]])
    b = np.array([[0.0], [1.0]])
    with pytest.raises(ValueError, match="non-decreasing"):
        linear.lti_response([0.0, 2.0, 1.0], a, [1.0, 0.0])
    with pytest.raises(ValueError, match="t\\[0\\] >= 0"):
        linear.lti_response([-1.0, 2.0], a, [1.0, 0.0])
    with pytest.raises(ValueError, match="first breakpoint"):
        linear.lti_response([0.0, 1.0], a, [1.0, 0.0], b, (np.array([0.5, 1.0]), np.ones((2, 1))))
    with pytest.raises(ValueError, match="sorted"):
        linear.lti_response([0.0, 1.0], a, [1.0, 0.0], b, (np.array([0.0, 2.0, 1.0]), np.ones((3, 1))))
    with pytest.raises(ValueError, match="shape"):
        linear.lti_response([0.0, 1.0], a, [1.0, 0.0], b, (np.array([0.0, 1.0]), np.ones((3, 1))))
    with pytest.raises(ValueError, match="input matrix"):
        linear.lti_response([0.0, 1.0], a, [1.0, 0.0], None, [1.0])
    with pytest.raises(ValueError, match="z0"):
        linear.lti_response([0.0, 1.0], a, [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="q0"):
        linear.linear_response([0.0, 1.0], np.eye(2), np.zeros((2, 2)), np.eye(2), [1.0], [0.0, 0.0])


def test_generator_system_is_the_mechanics_with_its_inputs_as_states():
    # m x'' + d x' + k x = F0 sin(w t), written out by hand with g = (F0 sin, F0 cos), g' = w (g2, -g1)
    m, d, k, w = 2.0, 0.3, 50.0, 4.0
    a = linear.generator_system([[m]], [[d]], [[k]], forcing=[[1.0, 0.0]], generator=[[0.0, w], [-w, 0.0]])
    by_hand = np.array([[0, 1, 0, 0], [-k / m, -d / m, 1 / m, 0], [0, 0, 0, w], [0, 0, -w, 0]])
    np.testing.assert_array_equal(a, by_hand)
