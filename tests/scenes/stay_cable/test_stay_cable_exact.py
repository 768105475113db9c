"""The stay cable's exact layer (springlab.exact.cable, springlab.exact.random_vibration) against references built here.

* The N-element model's frequencies against its closed form (scipy's symmetric eigensolver on K, M built here),
  and against the continuum at the expected O(N^-2), with the leading coefficient -(k pi)^2 / 24 derived in the
  docs.
* The continuum with a damper: the roots of the transcendental equation as roots (residual at round-off), against
  closed forms at mid-span (tan(x / 2) = 2 i / eta) and in the pinned limit (eta -> inf: n pi / (1 - a / L)),
  against scipy's MINPACK on a different function (the tan form), and as the limit of the N-element model's
  complex eigenvalues (observed order 2 in N).
* The universal curve: its first-order correction (derived in the docs) leaves a remainder of second order in
  a / L; the optimum damper and the largest damping ratio against the curve within its stated error.
* Rain-wind: the stabilising damper as the root of the growth rate, bracketed by eigenvalues computed here.
* Random vibration: the Lyapunov covariances against the integral of e^{At} Q e^{A^T t} (Van Loan's exponential
  and doubling), the held covariance against the long exact recursion, the hold's effect of second order in dt,
  the scatter of a record's variance against the double sum of the autocovariance.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from springlab.errors import BadInputError, ParameterError
from springlab.exact import cable as cb
from springlab.exact import random_vibration as rv

EPS = float(np.finfo(float).eps)
#: a long stay (docs/scenes/stay_cable.md: 300 m, 55 strands at 40 % of their breaking load, 70 kg/m)
CABLE = cb.TautCable(300.0, 6.1e6, 70.0)


def _lumped_omega_by_eigh(n):
    mass, stiffness = CABLE.lumped_matrices(n)
    # built here from the definition, not from lumped_matrices: N masses m dx, springs T / dx to each neighbour
    dx = CABLE.length / (n + 1)
    k = CABLE.tension / dx
    reference = np.diag(np.full(n, 2 * k)) - np.diag(np.full(n - 1, k), 1) - np.diag(np.full(n - 1, k), -1)
    assert np.array_equal(stiffness, reference) and np.allclose(mass, CABLE.mass_per_length * dx, rtol=4 * EPS)
    return np.sqrt(scipy.linalg.eigh(reference, np.diag(np.full(n, CABLE.mass_per_length * dx)), eigvals_only=True))


# -- modes -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [2, 9, 49])
def test_the_n_element_frequencies_are_their_closed_form(n):
    by_eigh = _lumped_omega_by_eigh(n)
    closed = CABLE.lumped_omega(n)
    # a symmetric eigensolver errs by a few N eps |K| in lambda = omega^2: relative 4 N eps |K| / lambda_k in
    # lambda, half that in omega; |K| / lambda_k = 1 / sin^2(k pi / (2 (N + 1))) (Gershgorin: |K| <= 4 T / dx)
    k = np.arange(1, n + 1)
    bound = 2 * n * EPS / np.sin(k * math.pi / (2 * (n + 1))) ** 2
    assert np.all(np.abs(by_eigh / closed - 1) <= bound)
    assert np.max(bound) <= 1e-10  # the 1e-10, met by the bound itself at these N


@pytest.mark.parametrize("n", [2, 9, 49])
def test_the_discrete_sines_are_the_modes(n):
    mass, stiffness = CABLE.lumped_matrices(n)
    omega = CABLE.lumped_omega(n)
    for k in (1, 2, n):
        shape = cb.mode_shape(n, k)
        residual = stiffness @ shape - omega[k - 1] ** 2 * mass * shape
        # sin(j k pi / (N + 1)) carries its argument's rounding, eps j k pi / (N + 1) <= eps k pi, times a row of K
        row = 4 * CABLE.segment_stiffness(n)
        assert np.max(np.abs(residual)) <= 4 * EPS * row * (1 + k * math.pi)


def test_the_discretization_error_is_second_order_with_the_derived_coefficient():
    sizes = [9, 19, 39, 79, 159]
    continuum = CABLE.omega(3)
    errors = np.array([CABLE.lumped_omega(n, 3) / continuum - 1 for n in sizes])
    # doubling N + 1 divides the error by 4: observed order 2 (next term theta^4 / 120 relative: 1e-3 at N = 9)
    orders = np.log2(errors[:-1] / errors[1:])
    # e = -theta^2 / 6 + theta^4 / 120: halving theta gives the order 2 + log2(1 - 3 theta^2 / 80), 2 - 0.055 theta^2
    theta = np.arange(1, 4) * math.pi / (2 * (np.array(sizes[:-1])[:, None] + 1))
    assert np.all(np.abs(orders - 2) <= 0.06 * theta**2)
    for n, row in zip(sizes, errors, strict=True):
        leading = np.array([cb.lumped_relative_error_leading(n, k) for k in (1, 2, 3)])
        theta = np.arange(1, 4) * math.pi / (2 * (n + 1))
        assert np.all(np.abs(row - leading) <= theta**4 / 120 * 1.01)
        assert np.allclose(row, [cb.lumped_relative_error(n, k) for k in (1, 2, 3)], rtol=1e-9, atol=0)


def test_the_continuum_frequency_is_the_textbook_one():
    f1 = 1 / (2 * CABLE.length) * math.sqrt(CABLE.tension / CABLE.mass_per_length)
    assert CABLE.frequencies_hz(1)[0] == pytest.approx(f1, rel=4 * EPS)
    assert CABLE.impedance == pytest.approx(math.sqrt(6.1e6 * 70.0), rel=4 * EPS)


# -- the continuum with a damper ------------------------------------------------------------------------------


@pytest.mark.parametrize(("ratio", "eta"), [(0.02, 5.0), (0.02, 1 / (math.pi * 0.02)), (0.05, 40.0), (0.1, 0.3)])
def test_the_damped_roots_are_roots_to_round_off(ratio, eta):
    for mode in (1, 2, 3):
        x = cb.damped_wavenumber(mode, ratio, eta)
        residual = abs(np.sin(x) + 1j * eta * np.sin(ratio * x) * np.sin((1 - ratio) * x))
        # the residual of a root found to 2 eps |x|, evaluated with round-off eps (1 + eta) |terms|
        slope = abs(cb._slope(x, ratio, eta))
        terms = abs(np.sin(x)) + eta * abs(np.sin(ratio * x) * np.sin((1 - ratio) * x)) + 1
        assert residual <= slope * 4 * EPS * abs(x) + 8 * EPS * terms
        assert x.imag > 0  # a damper damps
        assert abs(x.real - mode * math.pi) < math.pi / 2  # still mode n


@pytest.mark.parametrize("eta", [0.05, 0.5, 1.5])
def test_a_damper_at_mid_span_is_a_closed_form(eta):
    # a = L / 2: sin x + i eta sin^2(x / 2) = 0 -> sin(x/2) = 0 (even modes, untouched) or tan(x/2) = 2 i / eta
    for mode in (1, 3, 5):
        closed = 2 * np.arctan(2j / eta) + (mode - 1) * math.pi
        closed = complex(closed.real % (2 * math.pi) if closed.real < 0 else closed.real, closed.imag)
        found = cb.damped_wavenumber(mode, 0.5, eta)
        assert abs(found - closed) <= 16 * EPS * abs(closed), (mode, found, closed)
    assert cb.damped_wavenumber(2, 0.5, eta) == pytest.approx(2 * math.pi, abs=16 * EPS * 2 * math.pi)


def test_a_stiff_damper_pins_the_cable_there():
    ratio = 0.05
    for mode in (1, 2):
        pinned = mode * math.pi / (1 - ratio)
        # tan(delta) = i eta sin^2 eps / (1 + i eta sin eps cos eps) -> tan(eps) as eta -> inf, to within O(1 / eta)
        for eta in (1e6, 1e8):
            found = cb.damped_wavenumber(mode, ratio, eta)
            assert abs(found - pinned) <= 4 / (eta * math.sin(ratio * pinned) ** 2)


def test_the_damped_roots_agree_with_minpack_on_the_tan_form():
    for ratio, eta in [(0.02, 8.0), (0.02, 20.0), (0.05, 3.0)]:
        for mode in (1, 2, 3):
            found = cb.damped_wavenumber(mode, ratio, eta)

            def tan_form(v, mode=mode, ratio=ratio, eta=eta):
                delta = complex(v[0], v[1])
                eps = ratio * (mode * math.pi + delta)
                value = np.tan(delta) * (1 + 1j * eta * np.sin(eps) * np.cos(eps)) - 1j * eta * np.sin(eps) ** 2
                return [value.real, value.imag]

            start = cb.universal_start(mode, ratio, eta) - mode * math.pi
            solution = scipy.optimize.root(tan_form, [start.real, start.imag], method="hybr", options={"xtol": 1e-12})
            other = mode * math.pi + complex(*solution.x)
            assert solution.success
            assert abs(found - other) <= 64 * EPS * abs(found)


def test_the_n_element_complex_modes_converge_to_the_continuum_at_second_order():
    ratio, eta = 0.02, 1 / (math.pi * 0.02)
    coefficient = eta * CABLE.impedance
    continuum = [cb.damped_eigenvalue(CABLE, mode, ratio * CABLE.length, coefficient) for mode in (1, 2, 3)]
    errors = []
    for n in (49, 99, 199):  # the damper on a node: a = 0.02 L is node (N + 1) / 50
        model = cb.LumpedCable.build(CABLE, n, damper_position=ratio * CABLE.length, damper_coefficient=coefficient)
        assert CABLE.damper_node(n, ratio * CABLE.length) * CABLE.spacing(n) == pytest.approx(ratio * CABLE.length)
        modes = model.complex_modes().oscillatory[:3]
        errors.append(np.abs(modes / np.array(continuum) - 1))
    errors = np.array(errors)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2) <= 0.05), orders
    assert np.all(errors[-1] <= 2e-3)


@pytest.mark.parametrize("factor", [1e-2, 0.1, 0.5, 1.0, 2.0, 10.0, 100.0])
def test_newton_on_the_determinant_is_the_dense_eigenvalue(factor):
    # the damper from a hundredth to a hundred times the universal optimum, modes 1-3 from the continuum's roots
    n, position = 99, 6.0
    coefficient = factor * CABLE.impedance / (math.pi * position / CABLE.length)
    model = cb.LumpedCable.build(
        CABLE, n, structural_ratio=0.001, damper_position=position, damper_coefficient=coefficient
    )
    assert model.is_tridiagonal()
    values = scipy.linalg.eigvals(model.state_matrix())  # LAPACK's QR algorithm on the 2N x 2N state matrix
    largest = float(np.max(np.abs(values)))
    oscillatory = values[values.imag > 64 * EPS * largest]
    oscillatory = oscillatory[np.argsort(oscillatory.imag)]
    for mode in (1, 2, 3):
        found = model.eigenvalue_near(cb.damped_eigenvalue(CABLE, mode, position, coefficient))
        dense = oscillatory[mode - 1]
        # the dense value's backward error is a few eps |A| (about N eps |lambda_max| on a well separated mode);
        # the determinant's terms cancel to (|lambda| / |lambda_max|)^2 of their size, so Newton's own round-off is
        # about (|lambda_max| / |lambda|)^2 eps |lambda|
        tolerance = n * EPS * largest + (largest / abs(dense)) ** 2 * EPS * abs(dense)
        assert abs(found - dense) <= tolerance, (mode, found, dense, tolerance)


@pytest.mark.parametrize("factor", [0.0, 0.1, 1.0, 10.0])
def test_newton_on_the_determinant_with_rain_winds_tendons_is_the_dense_eigenvalue(factor):
    # C = D + sum_k w_k u_k u_k^T: the damper on its node and two modal tendons of negative damping (modes 1, 2 grow)
    n, position, ratio = 49, 6.0, -0.005
    coefficient = factor * CABLE.impedance / (math.pi * position / CABLE.length)
    model = cb.LumpedCable.build(
        CABLE,
        n,
        structural_ratio=0.001,
        damper_position=position,
        damper_coefficient=coefficient,
        aero_ratio=ratio,
        aero_modes=2,
    )
    tendons = [(cb.mode_shape(n, k), CABLE.aero_mode_damping(n, ratio, k)) for k in (1, 2)]
    assert model.is_tridiagonal(tendons) and not model.is_tridiagonal()
    values = scipy.linalg.eigvals(model.state_matrix())
    largest = float(np.max(np.abs(values)))
    oscillatory = values[values.imag > 64 * EPS * largest]
    oscillatory = oscillatory[np.argsort(oscillatory.imag)]
    for mode in (1, 2, 3):
        found = model.eigenvalue_near(cb.damped_eigenvalue(CABLE, mode, position, coefficient), tendons)
        dense = oscillatory[mode - 1]
        # as above; the tendons' rank-2 correction adds a 2 x 2 solve, its round-off no larger than the pivots'
        tolerance = n * EPS * largest + (largest / abs(dense)) ** 2 * EPS * abs(dense)
        assert abs(found - dense) <= tolerance, (mode, found, dense, tolerance)


def test_the_stabilising_damper_by_newton_is_the_dense_eigenvalues_root(monkeypatch):
    n, ratio = 49, -0.005
    model = cb.LumpedCable.build(CABLE, n, structural_ratio=0.001, aero_ratio=ratio, aero_modes=3)
    tendons = [(cb.mode_shape(n, k), CABLE.aero_mode_damping(n, ratio, k)) for k in (1, 2, 3)]
    node = CABLE.damper_node(n, 6.0)
    confirmed = []
    confirm = cb._FollowedGrowth.confirm

    def spied(self, log_c):
        confirm(self, log_c)
        confirmed.append(log_c)  # reached only when the followed root is the dense eigenvalues' fastest mode

    monkeypatch.setattr(cb._FollowedGrowth, "confirm", spied)
    by_newton = cb.stabilising_damper(model, node, guess=math.nan, tendons=tendons)
    assert confirmed == [math.log(by_newton)]
    by_eigenvalues = cb.stabilising_damper(model, node, guess=math.nan)

    # both are Brent's roots of g(ln c), within 1e-14 + 1e-12 |ln c| of a root each, and each g is good to its
    # eigenvalues' error: N eps |lambda_max| for the dense ones (Newton's is smaller), over the slope dg / d ln c
    def growth(c):
        return float(np.max(scipy.linalg.eigvals(model.with_damper(node, c).state_matrix()).real))

    slope = abs(growth(by_eigenvalues * 1.001) - growth(by_eigenvalues / 1.001)) / (2 * math.log(1.001))
    largest = float(np.max(np.abs(scipy.linalg.eigvals(model.with_damper(node, by_eigenvalues).state_matrix()))))
    agree = 2 * (1e-14 + 1e-12 * abs(math.log(by_eigenvalues))) + 2 * n * EPS * largest / slope
    assert abs(math.log(by_newton / by_eigenvalues)) <= agree

    # where Newton fails, the dense eigenvalues decide, as for a model with no tendons given
    def fails(self, start, tendons=()):
        raise ArithmeticError("no")

    monkeypatch.setattr(cb.LumpedCable, "eigenvalue_near", fails)
    assert cb.stabilising_damper(model, node, guess=math.nan, tendons=tendons) == by_eigenvalues


def test_newton_on_the_determinant_refuses_a_model_that_is_not_tridiagonal():
    model = cb.LumpedCable.build(CABLE, 19, structural_ratio=0.001, aero_ratio=-0.005, aero_modes=2)
    assert not model.is_tridiagonal()
    with pytest.raises(ArithmeticError, match="tridiagonal"):
        model.eigenvalue_near(1j * float(CABLE.omega(1)[0]))


def test_the_model_finds_an_overdamped_motion_beside_a_stiff_damper():
    # eta > 2: the continuum has a real root x = i y (sinh y = eta sinh(r y) sinh((1 - r) y)); the model too
    model = cb.LumpedCable.build(CABLE, 99, damper_position=6.0, damper_coefficient=15.9 * CABLE.impedance)
    modes = model.complex_modes()
    assert len(modes.overdamped) >= 1 and np.all(modes.overdamped < 0)
    assert len(modes.oscillatory) + len(modes.overdamped) / 2 == pytest.approx(99, abs=0.5)


# -- the universal curve ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kappa", [0.3, 1.0, 3.0])
@pytest.mark.parametrize("mode", [1, 2])
def test_the_universal_curve_with_its_first_correction_leaves_a_second_order_remainder(mode, kappa):
    remainders = []
    for ratio in (0.004, 0.002, 0.001):
        eta = kappa / (mode * math.pi * ratio)
        exact = cb.damping_ratio_of(cb.damped_wavenumber(mode, ratio, eta))
        curve = cb.universal_damping_ratio(mode, ratio, eta)
        corrected = curve + cb.universal_correction(mode, ratio, eta)
        assert abs(exact - corrected) < abs(exact - curve)
        remainders.append((exact - corrected) / curve)
    # relative remainder O(ratio^2): halving a / L quarters it
    orders = np.log2(np.array(remainders[:-1]) / np.array(remainders[1:]))
    assert np.all(np.abs(orders - 2) <= 0.1), orders


@pytest.mark.parametrize("mode", [1, 2, 3])
def test_the_optimum_damper_and_the_largest_damping_against_the_universal_curve(mode):
    # the stated range (docs): zeta_max = (a / 2L)(1 + a / L + O((n pi a / L)^2)), eta_opt = eta_u (1 + O((n pi a / L)^2))
    remainders = []
    for ratio in (0.02, 0.01, 0.005, 0.0025):
        eta_opt, zeta_max = cb.exact_optimum(mode, ratio)
        eta_u, zeta_u = cb.universal_optimum(mode, ratio)
        second = (mode * math.pi * ratio) ** 2
        assert abs(zeta_max / zeta_u - 1) <= ratio + second
        assert abs(eta_opt / eta_u - 1) <= second
        remainders.append(zeta_max / zeta_u - 1 - ratio)
        # and the optimum is a maximum: 1 % either side of it damps less
        for factor in (0.99, 1.01):
            assert cb.damping_ratio_of(cb.damped_wavenumber(mode, ratio, eta_opt * factor)) < zeta_max
    # the first-order term is exactly a / L: what is left is second order
    orders = np.log2(np.array(remainders[:-1]) / np.array(remainders[1:]))
    assert np.all(np.abs(orders - 2) <= 0.15), orders


# -- rain-wind: the damper that stops the growth --------------------------------------------------------------------


def test_the_stabilising_damper_is_where_the_growth_rate_crosses_zero():
    model = cb.LumpedCable.build(CABLE, 49, structural_ratio=0.001, aero_ratio=-0.005, aero_modes=3)
    growing = model.complex_modes()
    # no damper: modes 1-3 grow at zeta_a omega_k less the structural decay (eigenvalues of A computed here)
    assert growing.growth_rate > 0
    node = CABLE.damper_node(49, 6.0)
    ratio = 6.0 / CABLE.length
    c_stop = cb.stabilising_damper(model, node, guess=math.nan)
    assert c_stop > 0
    # the same root from any start of the bracketing walk: far below, far above (past the root already), none;
    # Brent stops within 1e-14 + 1e-12 |ln c| of the root in ln c, so two answers differ by twice that
    agree = 2 * (1e-14 + 1e-12 * abs(math.log(c_stop)))
    for guess in (c_stop / 100.0, c_stop * 3.0, CABLE.impedance / (math.pi * ratio)):
        assert cb.stabilising_damper(model, node, guess=guess) == pytest.approx(c_stop, rel=agree)
    eigenvalues = scipy.linalg.eigvals(model.with_damper(node, c_stop).state_matrix())
    assert abs(float(np.max(eigenvalues.real))) <= 1e-9 * float(np.max(np.abs(eigenvalues)))
    for factor, sign in ((1 - 1e-3, 1), (1 + 1e-3, -1)):
        rate = float(np.max(scipy.linalg.eigvals(model.with_damper(node, c_stop * factor).state_matrix()).real))
        assert sign * rate > 0
    # the universal curve's estimate: mode 1 needs zeta_d = 0.005 - 0.001 from the damper, kappa / (1 + kappa^2) =
    # zeta_d / (a / L), the lower root; good to O(a / L) and the model's O(N^-2)
    target = (0.005 - 0.001) / ratio
    kappa = (1 - math.sqrt(1 - 4 * target**2)) / (2 * target)
    estimate = kappa / (math.pi * ratio) * CABLE.impedance
    assert c_stop == pytest.approx(estimate, rel=0.05)


def test_a_model_that_decays_needs_no_damper():
    model = cb.LumpedCable.build(CABLE, 9, structural_ratio=0.001, aero_ratio=-0.0005, aero_modes=1)
    assert cb.stabilising_damper(model, 1, guess=math.nan) == 0.0


# -- random vibration ----------------------------------------------------------------------------------------------


def _windy(n, damper=3e5, ratio=0.005):
    model = cb.LumpedCable.build(CABLE, n, structural_ratio=ratio, damper_position=30.0, damper_coefficient=damper)
    b = np.zeros((2 * n, 1))
    b[n:, 0] = CABLE.spacing(n) / model.mass  # p [N/m] on every node as p dx
    return model, b, np.array([[30.0]])


def _integral_by_doubling(a, noise, h, horizon):
    """int_0^horizon e^{At} Q e^{A^T t} dt: Van Loan's exponential over h, then P(2t) = P(t) + Phi(t) P(t) Phi(t)^T."""
    n = a.shape[0]
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n], block[:n, n:], block[n:, n:] = -a * h, noise * h, a.T * h
    e = scipy.linalg.expm(block)
    phi = e[n:, n:].T
    p = phi @ e[:n, n:]
    t = h
    while t < horizon:
        p, phi, t = p + phi @ p @ phi.T, phi @ phi, 2 * t
    return 0.5 * (p + p.T)


@pytest.mark.parametrize("n", [5, 30])
def test_the_stationary_covariance_is_the_integral_of_the_impulse_responses(n):
    model, b, w = _windy(n)
    a = model.state_matrix()
    noise = b @ w @ b.T
    slowest = -float(np.max(scipy.linalg.eigvals(a).real))
    brute = _integral_by_doubling(a, noise, 1e-3, 60 / slowest)  # the tail e^{-120} of the slowest decay left out
    scale = np.sqrt(np.outer(np.diag(brute), np.diag(brute)))
    # the Lyapunov operator's condition: |A| over its smallest |lambda_p + lambda_q| (the background decay alpha)
    alpha = CABLE.structural_node_damping(n, 0.005) / model.mass[0]
    condition = float(np.max(np.abs(scipy.linalg.eigvals(a)))) / alpha
    tolerance = 4 * n * EPS * condition
    damper = np.eye(n)[:, [CABLE.damper_node(n, 30.0) - 1]]
    structured = rv.second_order_covariance(model.mass, model.stiffness, alpha, damper, np.array([3e5]), b, w)
    assert np.max(np.abs(structured - brute) / scale) <= tolerance
    if n <= 5:  # Bartels-Stewart loses more than this bound at larger N (3e-8 at N = 99, the structured 8e-11)
        assert np.max(np.abs(rv.continuous_covariance(a, noise) - brute) / scale) <= tolerance


def test_the_structured_covariance_takes_several_low_rank_terms():
    n = 12
    model = cb.LumpedCable.build(CABLE, n, structural_ratio=0.02, aero_ratio=-0.004, aero_modes=2)
    model = model.with_damper(2, 2e5)
    alpha = CABLE.structural_node_damping(n, 0.02) / model.mass[0]
    factors = np.column_stack([np.eye(n)[:, 1], cb.mode_shape(n, 1), cb.mode_shape(n, 2)])
    weights = np.array([2e5, CABLE.aero_mode_damping(n, -0.004, 1), CABLE.aero_mode_damping(n, -0.004, 2)])
    _, b, w = _windy(n)
    structured = rv.second_order_covariance(model.mass, model.stiffness, alpha, factors, weights, b, w)
    brute = _integral_by_doubling(model.state_matrix(), b @ w @ b.T, 1e-3, 1e5)
    scale = np.sqrt(np.outer(np.diag(brute), np.diag(brute)))
    assert np.max(np.abs(structured - brute) / scale) <= 1e-10


@pytest.mark.parametrize("aero", [-0.005, 0.0])
def test_a_one_step_maps_decay_is_read_off_its_bilinear_schur_form(aero):
    # the cable's exact step maps, growing with rain-wind's negative damping or decaying without it, and maps
    # pushed onto and past the unit circle: the Schur form's verdict is the eigenvalues' |mu| < 1
    n = 19
    model = cb.LumpedCable.build(CABLE, n, structural_ratio=0.001, aero_ratio=aero, aero_modes=1)
    step = scipy.linalg.expm(model.state_matrix() * 0.05)
    radius = float(np.max(np.abs(scipy.linalg.eigvals(step))))
    for scale in (1.0, 0.999, 1.001 / radius, 1.0 / radius - 1e-6):
        transition = step * scale
        decays = float(np.max(np.abs(scipy.linalg.eigvals(transition)))) < 1.0
        assert rv._decays_by_schur(transition) == decays, (aero, scale)
    assert not rv._decays_by_schur(step[:9, :9])  # under 10 states scipy solves directly: the eigenvalues decide


def test_a_growing_model_has_no_held_or_continuous_covariance():
    # rain-wind's negative damping without a damper: mode 1 grows, so no stationary covariance (the model's words,
    # whether the decay was read off a Schur form or the eigenvalues)
    model = cb.LumpedCable.build(CABLE, 19, structural_ratio=0.001, aero_ratio=-0.005, aero_modes=1)
    b = np.zeros((38, 1))
    b[19:, 0] = 1.0 / model.mass
    with pytest.raises(BadInputError, match="the model has no stationary covariance: a mode does not decay"):
        rv.held_covariance(model.state_matrix(), b, np.array([[1.0]]), 0.01)
    with pytest.raises(BadInputError, match="the model has no stationary covariance: a mode does not decay"):
        rv.continuous_covariance(model.state_matrix(), b @ b.T)


def test_the_held_covariance_is_the_long_exact_recursion():
    n = 5
    model, b, w = _windy(n)
    a, dt = model.state_matrix(), 0.02
    phi, gamma = rv.zero_order_hold(a, b, dt)
    # the hold by Van Loan, independently: Gamma = int_0^dt e^{As} ds B
    assert np.allclose(
        gamma, scipy.linalg.solve(a, (phi - np.eye(2 * n)) @ b), rtol=0, atol=1e-12 * np.abs(gamma).max()
    )
    held = rv.held_covariance(a, b, w, dt)
    step = gamma @ (w / dt) @ gamma.T
    recursion, power = step.copy(), phi.copy()
    for _ in range(40):  # P_{2k} = P_k + Phi^k P_k Phi^k^T: 2^40 steps, the slowest mode's tail long gone
        recursion, power = recursion + power @ recursion @ power.T, power @ power
    scale = np.sqrt(np.outer(np.diag(recursion), np.diag(recursion)))
    assert np.max(np.abs(held - recursion) / scale) <= 1e-9


def test_the_kept_bilinear_solve_is_scipys_to_the_bit():
    # a held covariance and its record's two sums solve with one map: the transform and Schur form are kept
    # (rv._bilinear), and every solve must still be scipy.linalg.solve_discrete_lyapunov's, bit for bit
    n = 6
    model, b, w = _windy(n)
    phi, gamma = rv.zero_order_hold(model.state_matrix(), b, 0.02)
    first, second = gamma @ (w / 0.02) @ gamma.T, np.outer(phi[:, 1], phi[:, 1])
    for noise in (first, second, first):  # the third from the kept form
        solved = rv.solve_discrete_lyapunov(phi, noise)
        assert np.array_equal(solved, scipy.linalg.solve_discrete_lyapunov(phi, noise))
        residual = phi @ solved @ phi.T - solved + noise
        assert np.max(np.abs(residual)) <= 1e-12 * np.max(np.abs(solved))
    small = phi[:4, :4] * 0.5  # below 10 states: scipy's direct method
    assert np.array_equal(
        rv.solve_discrete_lyapunov(small, first[:4, :4]), scipy.linalg.solve_discrete_lyapunov(small, first[:4, :4])
    )
    held = rv.held_covariance(model.state_matrix(), b, w, 0.02, (phi, gamma))
    assert np.array_equal(held, rv.held_covariance(model.state_matrix(), b, w, 0.02))


def test_the_holds_effect_on_the_variance_is_second_order_in_dt():
    n = 5
    model, b, w = _windy(n)
    a = model.state_matrix()
    continuous = rv.continuous_covariance(a, b @ w @ b.T)
    effects = [rv.held_covariance(a, b, w, dt)[2, 2] / continuous[2, 2] - 1 for dt in (0.04, 0.02, 0.01)]
    orders = np.log2(np.array(effects[:-1]) / np.array(effects[1:]))
    assert np.all(np.abs(orders - 2) <= 0.05), orders
    assert all(effect < 0 for effect in effects)  # the hold's sinc^2 removes power near the modes


def test_the_scatter_of_a_records_variance_is_the_double_sum_of_the_autocovariance():
    n = 3
    model, b, w = _windy(n, damper=5e4, ratio=0.05)
    a, dt, samples = model.state_matrix(), 0.05, 1500
    phi, gamma = rv.zero_order_hold(a, b, dt)
    p = rv.held_covariance(a, b, w, dt)
    c = np.zeros(2 * n)
    c[1] = 1.0
    lags = np.empty(samples)
    power, v = np.eye(2 * n), p @ c
    for k in range(samples):
        lags[k] = c @ power @ v
        power = power @ phi
    weights = samples - np.arange(samples)
    brute = 2.0 / samples**2 * (samples * lags[0] ** 2 + 2 * np.sum(weights[1:] * lags[1:] ** 2))
    assert rv.record_variance(p, phi, c, samples) == pytest.approx(brute, rel=1e-8)
    # the continuous record of the same length: the sampled sum tends to the integral as dt -> 0 (first order)
    continuous = rv.record_variance_continuous(rv.continuous_covariance(a, b @ w @ b.T), a, c, samples * dt)
    assert continuous == pytest.approx(brute, rel=0.05)


def test_the_variance_interval_is_a_scaled_chi_square():
    interval = rv.variance_interval(2.0, 0.02, 0.99)
    nu = 2 * 2.0**2 / 0.02**2
    assert interval.degrees_of_freedom == pytest.approx(nu)
    # nu = 20000: the normal interval 2 -+ 2.5758 x 0.02, moved by Cornish-Fisher's skew term
    # (z^2 - 1) / 6 x skew x spread, skew = 2 sqrt(2 / nu): 3.8e-4
    skew_shift = (2.5758**2 - 1) / 6 * 2 * math.sqrt(2 / nu) * 0.02
    assert interval.low == pytest.approx(2.0 - 2.5758 * 0.02 + skew_shift, abs=1e-4)
    assert interval.high == pytest.approx(2.0 + 2.5758 * 0.02 + skew_shift, abs=1e-4)
    low, high = interval.rms_interval()
    assert low == pytest.approx(math.sqrt(interval.low)) and high == pytest.approx(math.sqrt(interval.high))
    true_low, true_high = interval.true_variance_interval(2.0)
    assert true_low < 2.0 < true_high
    # a short record (nu = 50) is skewed: its interval is not symmetric about sigma^2
    short = rv.variance_interval(2.0, 0.4, 0.99)
    assert short.high - 2.0 > 2.0 - short.low


@pytest.mark.parametrize("nu", [0.7, 3.0, 50.0, 20000.0])
def test_the_interval_quantiles_are_scipy_stats_chi_square_to_the_bit(nu):
    import scipy.stats  # the reference: springlab computes the quantile without importing scipy.stats

    spread = math.sqrt(2 * 2.0**2 / nu)
    interval = rv.variance_interval(2.0, spread, 0.99)
    reference_nu = 2 * 2.0**2 / spread**2
    assert interval.low == 2.0 * float(scipy.stats.chi2.ppf((1 - 0.99) / 2, reference_nu)) / reference_nu
    assert interval.high == 2.0 * float(scipy.stats.chi2.ppf((1 + 0.99) / 2, reference_nu)) / reference_nu


# -- bad input -------------------------------------------------------------------------------------------------


def test_bad_cables_and_dampers_are_refused_with_one_line():
    for values in [(300.0, -1.0, 70.0), (0.0, 6e6, 70.0), (300.0, 6e6, math.inf), (300.0, math.nan, 70.0)]:
        with pytest.raises(ParameterError, match="finite number > 0"):
            cb.TautCable(*values)
    with pytest.raises(ParameterError, match="n_elements must be a whole number >= 2"):
        CABLE.spacing(1)
    for position in (0.0, 300.0, -5.0, 301.0, math.nan):
        with pytest.raises(ParameterError, match="damper_position must lie inside the cable"):
            CABLE.damper_node(9, position)
    with pytest.raises(BadInputError, match="no stationary covariance"):
        model = cb.LumpedCable.build(CABLE, 5, structural_ratio=0.001, aero_ratio=-0.01, aero_modes=1)
        rv.continuous_covariance(model.state_matrix(), np.eye(10))
