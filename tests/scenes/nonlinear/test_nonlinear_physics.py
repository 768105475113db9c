"""Section 5.5 as a MuJoCo scene: a non-linear spring's equilibria, separatrices, periods, escape
and chaos, checked against closed forms (elliptic integrals), scipy's ODE solvers and hand algebra."""

import math

import mujoco
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk, ellipkm1

import springlab
from springlab import scenes
from springlab.scenes.nonlinear import scene as nonlinear
from springlab.sim.simulate import quiet_mujoco

SCENE = scenes.get("nonlinear")
# models/nonlinear.xml: m = 1 kg, k1 = 100 N/m, k3 = -1e4 N/m^3 (softening); double well k1 = -100, k3 = 1e4
M, K1, K3 = 1.0, 100.0, -1e4
EPS = np.finfo(float).eps


def _built(scenario_name, **overrides):
    case = SCENE.case(scenario_name, overrides)
    return case.model, case.params, case


def _energy(x, v, k1, k3, m=M):
    return 0.5 * m * v**2 + 0.5 * k1 * x**2 + 0.25 * k3 * x**4


def _duffing_ode(k1, k3, damping=0.0, amplitude=0.0, omega=0.0, m=M):
    def rhs(t, s):
        return [s[1], (-k1 * s[0] - k3 * s[0] ** 3 - damping * s[1] + amplitude * np.sin(omega * t)) / m]

    return rhs


# -- the spring itself -----------------------------------------------------------------


def test_polynomial_joint_stiffness_gives_minus_k1_x_minus_k3_x_cubed():
    model, params, _ = _built("softening")
    assert (params["mass"], params["k1"], params["k3"]) == (M, K1, K3)  # read back from the MJCF
    data = mujoco.MjData(model)
    for x in (-0.25, -0.05, 0.0, 0.03, 0.1, 0.2):
        data.qpos[0] = x
        mujoco.mj_forward(model, data)
        # at the saddle (x = 0.1 m) the two terms cancel: each carries a rounding of eps times its size,
        # which MuJoCo (compiled with or without FMA) and this line need not share
        terms = abs(K1 * x) + abs(K3 * x**3)
        assert data.qfrc_passive[0] == pytest.approx(-(K1 * x + K3 * x**3), rel=0, abs=4 * EPS * terms)


def test_softening_spring_force_peaks_at_sqrt_k1_over_3_abs_k3():
    model, params, case = _built("softening")
    result = springlab.run("nonlinear", "softening", duration=0.01)
    q = result.to_dict()["quantities"]
    x_peak = math.sqrt(K1 / (3 * -K3))  # d/dx (k1 x + k3 x^3) = 0
    assert q["peak_force_stretch_m"] == pytest.approx(x_peak, rel=1e-15)
    assert q["peak_spring_force_N"] == pytest.approx(K1 * x_peak + K3 * x_peak**3, rel=1e-14)


# -- equilibria and their stability ----------------------------------------------------


def _transition_jacobian(model, x_e):
    """Continuous Jacobian [[0, 1], [da/dx, da/dv]] from MuJoCo's own discrete linearization
    (mjd_transitionFD, an independent route). With the semi-implicit euler step and no damping,
    v' = v + h a(x, v), x' = x + h v', so da/dx = A[1, 0] / h and da/dv = (A[1, 1] - 1) / h."""
    integrator = model.opt.integrator
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    data = mujoco.MjData(model)
    data.qpos[0] = x_e
    mujoco.mj_forward(model, data)
    nx = 2 * model.nv + model.na
    a = np.zeros((nx, nx))
    mujoco.mjd_transitionFD(model, data, 1e-8, True, a, None, None, None)
    model.opt.integrator = integrator
    h = model.opt.timestep
    return np.array([[0.0, 1.0], [a[model.nv, 0] / h, (a[model.nv, model.nv] - 1) / h]])


@pytest.mark.parametrize(
    "scenario_name, expected",
    [
        ("softening", [(-0.1, False, "saddle"), (0.0, True, "center"), (0.1, False, "saddle")]),
        ("double_well", [(-0.1, True, "center"), (0.0, False, "saddle"), (0.1, True, "center")]),
    ],
)
def test_equilibria_are_where_the_spring_force_vanishes_with_stability_from_the_jacobian(scenario_name, expected):
    model, params, case = _built(scenario_name)
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    model.opt.timestep = 1e-3
    found = case.equilibria()
    field = case.phase_field()
    assert [(e["x"], e["stable"], e["kind"]) for e in found] == [
        (pytest.approx(x, rel=1e-15, abs=0), s, k) for x, s, k in expected
    ]
    for e in found:
        dx, dv = field(np.array([e["x"]]), np.array([0.0]))
        assert dx[0] == 0.0 and abs(dv[0]) < 1e-13
        # stability from MuJoCo's own linearization: centres have imaginary, saddles real +- eigenvalues
        eigenvalues = np.linalg.eigvals(_transition_jacobian(model, e["x"]))
        stiffness = params["k1"] + 3 * params["k3"] * e["x"] ** 2  # V''(x_e) by hand
        if e["kind"] == "center":
            assert np.max(np.abs(eigenvalues.real)) < 1e-6 * math.sqrt(stiffness / M)
            np.testing.assert_allclose(np.sort(np.abs(eigenvalues.imag)), math.sqrt(stiffness / M), rtol=1e-6)
        else:
            np.testing.assert_allclose(
                np.sort(eigenvalues.real), [-math.sqrt(-stiffness / M), math.sqrt(-stiffness / M)], rtol=1e-6
            )


def test_scene_linearization_agrees_with_mujocos_transition_derivatives():
    model, params, case = _built("double_well")
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    model.opt.timestep = 1e-3
    for x_e in (-0.1, 0.0, 0.1):
        np.testing.assert_allclose(
            SCENE.mujoco_jacobian(model, x_e, 1e-5), _transition_jacobian(model, x_e), rtol=1e-6, atol=1e-6
        )


def test_double_well_small_oscillation_frequency_is_sqrt_minus_2_k1_over_m():
    omega = math.sqrt(-2 * -100.0 / M)  # V''(+-sqrt(-k1/k3)) = k1 + 3 k3 (-k1/k3) = -2 k1
    result = springlab.run("nonlinear", "double_well", x0=0.1 + 1e-5, duration=2.0)
    q = result.to_dict()["quantities"]
    assert q["equilibria_m"] == [pytest.approx(-0.1, rel=1e-15), 0.0, pytest.approx(0.1, rel=1e-15)]
    assert q["stable_equilibria_m"] == [pytest.approx(-0.1, rel=1e-15), pytest.approx(0.1, rel=1e-15)]
    assert q["omega_at_+0.1_m_rad_s"] == pytest.approx(omega, rel=1e-15)
    assert q["omega_at_-0.1_m_rad_s"] == pytest.approx(omega, rel=1e-15)
    # a 10-micrometre oscillation about the well: anharmonic shift ~ (A / x_e)^2 = 1e-8
    assert q["period_simulated_s"] == pytest.approx(2 * math.pi / omega, rel=1e-6)


def test_damped_equilibria_are_stable_foci_or_nodes():
    model, params, case = _built("double_well", damping=2.0)
    kinds = [e["kind"] for e in case.equilibria()]
    assert kinds == ["stable focus", "saddle", "stable focus"]  # d^2 = 4 < 4 m V'' = 800
    model, params, case = _built("double_well", damping=40.0)
    found = case.equilibria()
    assert [e["kind"] for e in found] == ["stable node", "saddle", "stable node"]
    # the reported eigenvalues are those of MuJoCo's own Jacobian (damping included)
    for e in found:
        reported = np.sort_complex([complex(re, im) for re, im in e["eigenvalues_per_s"]])
        mujocos = np.sort_complex(np.linalg.eigvals(SCENE.mujoco_jacobian(model, e["x"], 1e-5)).astype(complex))
        np.testing.assert_allclose(reported, mujocos, rtol=1e-9)


# -- periods and the energy integral ---------------------------------------------------------


def test_softening_period_matches_the_jacobi_sn_closed_form():
    # x'' + w^2 x - b x^3 = 0, x = A sn(p t, k): p^2 = w^2 - b A^2 / 2, k^2 = b A^2 / (2 p^2), T = 4 K(k) / p
    for amplitude in (0.02, 0.09, 0.0999):
        p2 = K1 / M - (-K3 / M) * amplitude**2 / 2
        m1 = (K1 / M - (-K3 / M) * amplitude**2) / p2  # 1 - k^2 without cancellation
        period, error = nonlinear.oscillation_period(M, K1, K3, amplitude, 0.0)
        assert period == pytest.approx(4 * ellipkm1(m1) / math.sqrt(p2), rel=1e-11)
        assert error < 1e-12 * period


def test_double_well_periods_match_the_jacobi_dn_and_cn_closed_forms():
    # X'' = X - X^3 (X = x sqrt(k3 / -k1), tau = sqrt(-k1 / m) t); inside a well X = B dn(B tau / sqrt2, k),
    # k^2 = 2 (B^2 - 1) / B^2, T = 2 sqrt2 K / B; across both wells X = B cn(sqrt(B^2 - 1) tau, k),
    # k^2 = B^2 / (2 (B^2 - 1)), T = 4 K / sqrt(B^2 - 1)
    k1, k3 = -100.0, 1e4
    scale, rate = math.sqrt(-k1 / k3), math.sqrt(-k1 / M)
    b = 0.13 / scale
    inner = 2 * math.sqrt(2) * ellipk(2 * (b * b - 1) / (b * b)) / (b * rate)
    assert nonlinear.oscillation_period(M, k1, k3, 0.13, 0.0)[0] == pytest.approx(inner, rel=1e-12)
    b = 0.15 / scale
    outer = 4 * ellipk(b * b / (2 * (b * b - 1))) / (math.sqrt(b * b - 1) * rate)
    assert nonlinear.oscillation_period(M, k1, k3, 0.15, 0.0)[0] == pytest.approx(outer, rel=1e-12)
    # launched from the bottom of the well with a velocity: the same orbit as from its turning point
    a, top = nonlinear.turning_points(0.1, 0.3, M, k1, k3)
    assert nonlinear.oscillation_period(M, k1, k3, 0.1, 0.3)[0] == pytest.approx(
        nonlinear.oscillation_period(M, k1, k3, top, 0.0)[0], rel=1e-10
    )


def test_linear_spring_period_and_quarter_period_transit():
    assert nonlinear.oscillation_period(2.0, 50.0, 0.0, 0.3, 0.1)[0] == pytest.approx(
        2 * math.pi * math.sqrt(2 / 50), rel=1e-14
    )
    assert nonlinear.transit_time(1.0, 100.0, 0.0, 0.2, 0.0, 0.0)[0] == pytest.approx(math.pi / 20, rel=1e-14)


def test_simulated_period_matches_scipy_event_detection():
    result = springlab.run("nonlinear", "softening")
    event = lambda t, s: s[1]  # noqa: E731 - v = 0
    event.direction = -1
    sol = solve_ivp(_duffing_ode(K1, K3), (0, 5), [0.09, 0.0], events=event, rtol=1e-12, atol=1e-15, method="DOP853")
    maxima = sol.t_events[0]
    independent = (maxima[-1] - maxima[0]) / (len(maxima) - 1)
    q = result.to_dict()["quantities"]
    assert q["period_simulated_s"] == pytest.approx(independent, rel=1e-9)
    assert q["period_quadrature_s"] == pytest.approx(independent, rel=1e-9)


@pytest.mark.parametrize("scenario_name", ["softening", "softening_escape", "double_well"])
def test_undamped_runs_conserve_energy_to_1e_minus_6(scenario_name):
    result = springlab.run("nonlinear", scenario_name)
    p = result.parameters
    x, v = result.pos["block"], result.vel["block"]
    e = _energy(x, v, p["k1"], p["k3"])
    assert np.max(np.abs(e - e[0])) <= 1e-6 * np.max(0.5 * M * v**2)
    assert result.to_dict()["passed"] is True


# -- escape ------------------------------------------------------------------------------


def test_escape_outside_the_separatrix_stops_at_three_saddle_distances_not_as_divergence():
    # the finite-time blow-up of x'' = +|k3| x^3 lies well inside 100 s: the run must stop, not diverge
    result = springlab.run("nonlinear", "softening_escape", duration=100.0)
    x = result.pos["block"]
    assert result.trajectory.stopped
    assert abs(x[-1]) >= 0.3 > abs(x[-2])
    assert result.time[-1] < 1.0
    q = result.to_dict()["quantities"]
    assert q["escaped"] is True and q["escape_radius_m"] == pytest.approx(0.3, rel=1e-15)
    assert result.to_dict()["passed"] is True
    # the energy is above the saddle's: outside the separatrix
    assert q["energy_J"] == pytest.approx(0.5 * 0.75**2) and q["separatrix_energy_J"] == pytest.approx(0.25)


def test_escape_time_matches_scipy_event_detection():
    event = lambda t, s: s[0] - 0.3  # noqa: E731
    event.terminal = True
    sol = solve_ivp(_duffing_ode(K1, K3), (0, 5), [0.0, 0.75], events=event, rtol=1e-12, atol=1e-15, method="DOP853")
    independent = sol.t_events[0][0]
    q = springlab.run("nonlinear", "softening_escape").to_dict()["quantities"]
    assert q["escape_time_s"] == pytest.approx(independent, rel=1e-8)
    assert q["escape_time_quadrature_s"] == pytest.approx(independent, rel=1e-10)
    # from rest just beyond the saddle (a turning-point start)
    event2 = lambda t, s: s[0] - 0.25  # noqa: E731
    event2.terminal = True
    sol = solve_ivp(_duffing_ode(K1, K3), (0, 5), [0.11, 0.0], events=event2, rtol=1e-12, atol=1e-15, method="DOP853")
    assert nonlinear.transit_time(M, K1, K3, 0.11, 0.0, 0.25)[0] == pytest.approx(sol.t_events[0][0], rel=1e-9)


def test_a_numerical_blow_up_of_a_bounded_orbit_is_a_divergence_not_an_escape():
    # inside the separatrix the block cannot escape; an RK4 step far beyond its stability limit
    # throws it out anyway, and that must be reported as a divergence (exit 3), never as an escape
    with pytest.raises(springlab.DivergedError, match="stability limit"):
        springlab.run("nonlinear", "softening", dt=0.3)


def test_bounded_motion_inside_the_separatrix_never_escapes():
    result = springlab.run("nonlinear", "softening", x0=0.0999, duration=10.0)
    assert not result.trajectory.stopped
    assert np.max(np.abs(result.pos["block"])) <= 0.0999 + 1e-12
    assert result.to_dict()["quantities"]["motion"] == "bounded"


# -- separatrices and the phase field -------------------------------------------------------------


@pytest.mark.parametrize("scenario_name, k1, k3", [("softening", K1, K3), ("double_well", -100.0, 1e4)])
def test_separatrices_lie_on_the_saddle_energy_level(scenario_name, k1, k3):
    model, params, case = _built(scenario_name)
    curves = case.separatrices()
    saddle = 0.1 if k1 > 0 else 0.0
    level = 0.5 * k1 * saddle**2 + 0.25 * k3 * saddle**4  # 0.25 J and 0 J by hand
    assert curves
    for x, v in curves:
        assert len(x) == len(v) > 100
        np.testing.assert_allclose(_energy(x, v, k1, k3), level, atol=1e-13)
    xs = np.concatenate([c[0] for c in curves])
    vs = np.concatenate([c[1] for c in curves])
    if scenario_name == "double_well":
        # the figure eight: homoclinic loops through 0 reaching |x| = sqrt(-2 k1 / k3) at v = 0
        assert np.max(np.abs(xs)) == pytest.approx(math.sqrt(0.02), rel=1e-14)
        assert len(curves) == 4
    else:
        # heteroclinic arcs between the saddles cross x = 0 at v = +-sqrt(2 E_s / m)
        assert np.max(np.abs(vs[np.abs(xs) < 1e-3])) == pytest.approx(math.sqrt(0.5), rel=1e-6)


def test_separatrix_leaves_the_saddle_with_slope_of_its_rate():
    model, params, case = _built("softening")
    rate = math.sqrt(2 * K1 / M)  # sqrt(-V''(x_s) / m) with V'' = -2 k1
    for x, v in case.separatrices():
        near = (np.abs(np.abs(x) - 0.1) < 1e-4) & (np.abs(np.abs(x) - 0.1) > 1e-9)
        if near.any():
            np.testing.assert_allclose(np.abs(v[near]) / np.abs(np.abs(x[near]) - 0.1), rate, rtol=1e-3)


def test_phase_field_is_mujocos_acceleration():
    model, params, case = _built("double_well", damping=1.5)
    field = case.phase_field()
    data = mujoco.MjData(model)
    rng = np.random.default_rng(7)
    for x, v in rng.uniform(-0.2, 0.2, size=(20, 2)):
        data.qpos[0], data.qvel[0] = x, v
        mujoco.mj_forward(model, data)
        dx, dv = field(np.array([x]), np.array([v]))
        assert dx[0] == v
        assert dv[0] == pytest.approx(data.qacc[0], rel=1e-13, abs=1e-15)


# -- the forced, chaotic double well ---------------------------------------------------------------


@pytest.fixture(scope="module")
def forced(scenario_run):
    # springlab.run("nonlinear", "forced_duffing") validates the scenario's own settings (rk4, 1 ms): the
    # session's shared run of them (tests/conftest.py), whose chaos figures cost 5 s
    return scenario_run("nonlinear", "forced_duffing")


@pytest.mark.slow
def test_forced_duffing_agrees_with_an_independent_solver_until_its_accuracy_horizon(forced):
    p = forced.parameters
    omega = 2 * math.pi * p["force_frequency"]
    assert omega == pytest.approx(10.0)  # Holmes' Duffing in units of 0.1 m and 0.1 s: forcing at 1
    t = forced.time
    sol = solve_ivp(
        _duffing_ode(p["k1"], p["k3"], p["damping"], p["force_amplitude"], omega),
        (0, t[-1]),
        [p["x0"], p["v0"]],
        t_eval=t,
        rtol=1e-12,
        atol=1e-15,
        method="DOP853",
    )
    difference = np.abs(sol.y[0] - forced.pos["block"])
    # the exciter's sinusoidal force keeps RK4 at fourth order: a 1 s run is good to ~1e-10 m
    assert np.max(difference[t <= 1.0]) < 1e-9
    horizon = forced.to_dict()["quantities"]["accurate_until_s"]
    assert 5.0 < horizon < t[-1]
    # the trajectory is as good as its own Richardson estimate says (1 % of the 0.1 m wells)
    assert np.max(difference[t <= horizon]) < 1e-3


@pytest.mark.slow
def test_twin_runs_separate_like_the_variational_equation(forced):
    # d(dx)'' = -(k1 + 3 k3 x^2) dx / m - d dx' / m along the trajectory, integrated by scipy
    p = forced.parameters
    omega = 2 * math.pi * p["force_frequency"]
    base = _duffing_ode(p["k1"], p["k3"], p["damping"], p["force_amplitude"], omega)

    def with_tangent(t, s):
        dx = s[2:]
        return base(t, s[:2]) + [dx[1], (-(p["k1"] + 3 * p["k3"] * s[0] ** 2) * dx[0] - p["damping"] * dx[1]) / M]

    t_end = 8.0
    sol = solve_ivp(
        with_tangent,
        (0, t_end),
        [p["x0"], p["v0"], 1.0, 0.0],
        dense_output=True,
        rtol=1e-11,
        atol=1e-14,
        method="DOP853",
    )
    # the scene's own runs at the scenario's setting, without springlab.run's chaos figures (1.3 s a run)
    setting = forced.to_dict()
    integrator, dt = setting["integrator"], setting["dt"]
    twin = SCENE.case("forced_duffing", {"x0": p["x0"] + 1e-9}).simulate(integrator, dt, t_end)
    lead_case = SCENE.case("forced_duffing", {})
    lead = lead_case.simulate(integrator, dt, t_end)
    block = lead_case.model.joint("block").qposadr[0]
    for when in (4.0, 6.0, 8.0):
        i = int(round(when / dt))
        separation = twin.qpos[i, block] - lead.qpos[i, block]
        assert separation == pytest.approx(1e-9 * sol.sol(when)[2], rel=1e-3)


@pytest.mark.slow
def test_forced_duffing_is_chaotic(forced):
    q = forced.to_dict()["quantities"]
    assert q["perturbation_m"] == 1e-9 and q["well_size_m"] == pytest.approx(0.1)
    assert 5.0 < q["separation_time_s"] < forced.time[-1]
    # a positive exponent is chaos; 1e-9 m -> 0.1 m is ln(1e8) = 18.4 e-foldings
    assert q["lyapunov_exponent_per_s"] > 0.5
    assert q["ftle_per_s"] == pytest.approx(math.log(0.1 / 1e-9) / q["separation_time_s"], rel=0.5)
    assert forced.to_dict()["passed"] is True
    observed = next(c for c in forced.to_dict()["checks"] if c["name"] == "observed_order")
    assert observed["reference"] == 4 and abs(observed["value"] - 4) < 0.5


@pytest.mark.slow  # the session's forced run (`forced`, 4 s of CPU) is its first reader's: ~5 s with its own ODE
def test_forced_duffing_separation_time_is_the_converged_one_of_the_exact_system(forced):
    # the exact pair by scipy: x and the gap g = x_twin - x as states of their own (g starts at 1e-9 m, so
    # its absolute tolerance sits 15 orders below it), stopped where |g| first reaches the 0.1 m wells
    p = forced.parameters
    m, k1, k3, d = p["mass"], p["k1"], p["k3"], p["damping"]
    amplitude, omega = p["force_amplitude"], 2 * math.pi * p["force_frequency"]

    def pair(t, s):
        x, v, g, gv = s
        x2 = x + g
        force = amplitude * math.sin(omega * t)
        return [
            v,
            (-k1 * x - k3 * x**3 - d * v + force) / m,
            gv,
            (-k1 * g - k3 * g * (x2 * x2 + x2 * x + x * x) - d * gv) / m,
        ]

    def apart(t, s):
        return abs(s[2]) - 0.1

    apart.terminal = True
    sol = solve_ivp(
        pair,
        (0, 40.0),
        [p["x0"], p["v0"], 1e-9, 0.0],
        method="DOP853",
        rtol=1e-12,
        atol=[1e-15, 1e-14, 1e-24, 1e-23],
        events=apart,
    )
    exact = sol.t_events[0][0]  # 20.5934 s
    q = forced.to_dict()["quantities"]
    assert q["separation_time_converged"] is True
    # converged: the last two refinements agree within SEPARATION_RTOL, and so does the exact system
    last, before = q["separation_time_refinement_s"][-1], q["separation_time_refinement_s"][-2]
    assert abs(last - before) <= nonlinear.SEPARATION_RTOL * last
    assert q["separation_time_s"] == pytest.approx(exact, rel=nonlinear.SEPARATION_RTOL)
    assert q["ftle_per_s"] == pytest.approx(math.log(0.1 / 1e-9) / exact, rel=nonlinear.SEPARATION_RTOL)
    # the default 1 ms run alone is not converged for this question (its trajectory leaves the exact one first)
    assert abs(q["separation_time_at_run_dt_s"] - exact) > 10 * nonlinear.SEPARATION_RTOL * exact
    assert q["accurate_until_s"] < exact
    assert q["lyapunov_exponent_basis"].startswith("estimate")


def test_lyapunov_estimator_recovers_the_exact_exponent_of_a_damped_linear_oscillator():
    # linear, damped, forced: every perturbation decays like exp(-d t / 2m), so the exponent is -d / 2m
    case = SCENE.case("forced_duffing", {"k1": 100.0, "k3": 0.0, "damping": 2.0})
    exponent, _ = SCENE.lyapunov_exponent(case, "rk4", 1e-3, transient=1.0, total=20.0)
    assert exponent == pytest.approx(-1.0, abs=0.02)


def test_forced_runs_are_checked_at_the_integrators_own_order():
    result = springlab.run(
        "nonlinear", "forced_duffing", integrator="euler", dt=1e-3, duration=5.0, force_amplitude=3.0
    )
    observed = next(c for c in result.to_dict()["checks"] if c["name"] == "observed_order")
    assert observed["reference"] == 1
    assert abs(observed["value"] - 1) < 0.5


# -- the check mechanism ---------------------------------------------------------------------------


def test_a_failed_check_flags_the_run_and_the_cli_exits_1(cli):
    code, out, _ = cli("run", "nonlinear", "softening", "--integrator", "euler", "--duration", "2")
    assert code == 1
    assert "check energy_drift_relative" in out and "FAIL" in out


def test_a_plot_of_a_run_that_fails_its_checks_says_which_and_exits_1(tmp_path, cli):
    # held to its checks alone, the run has no tolerance of compared columns: the note names the failed checks
    # (this raised TypeError formatting the absent tolerance before results were objects)

    argv = ["plot", "nonlinear", "softening", "--integrator", "euler", "--duration", "2"]
    code, _, err = cli(*argv, "--output", str(tmp_path / "time.png"))
    assert code == 1 and (tmp_path / "time.png").is_file()
    (line,) = err.strip().splitlines()
    assert line.startswith("note: nonlinear/softening is outside its tolerance (check energy_drift_relative: error")
    assert line.endswith("; see 'springlab run'") and "Traceback" not in err


def test_validation_row_of_a_checked_scenario_shows_its_tightest_check():
    from springlab.runs.run import ValidationRow

    result = springlab.run("nonlinear", "double_well")
    row = ValidationRow.of(result)
    checks = result.checks
    assert {c.name for c in checks} >= {
        "energy_drift_relative",
        "period_s",
        "omega_at_+0.1_m_rad_s",
        "saddle_rate_at_0_m_per_s",
    }
    tightest = max(checks, key=lambda c: c.error / c.tolerance)
    assert (row.max_rel_error, row.tolerance) == (tightest.error, tightest.tolerance)
    assert row.measure == f"{tightest.name} rel"
    assert row.passed is True and row.checks == checks
    assert row.to_dict()["checks"] == result.to_dict()["checks"]


def test_a_stop_condition_cuts_a_run_at_its_event():
    from springlab.sim.simulate import simulate

    with quiet_mujoco():
        model = mujoco.MjModel.from_xml_path(str(springlab.sim.model_files.path("slider")))
    free = simulate(model, integrator="rk4", dt=1e-3, duration=1.0, qpos=[0.1])
    cut = simulate(model, integrator="rk4", dt=1e-3, duration=1.0, qpos=[0.1], stop=lambda q, v: q[:, 0] < 0)
    first = int(np.flatnonzero(free.qpos[:, 0] < 0)[0])
    assert cut.stopped and not free.stopped
    assert len(cut.time) == first + 1
    np.testing.assert_array_equal(cut.qpos, free.qpos[: first + 1])
