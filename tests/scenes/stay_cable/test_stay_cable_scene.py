"""The stay-cable scene's claims, each against a reference built here from the parameters (never the scene's own).

* The shipped model is the generator's, and the matrices the scene reads back are the N-element model.
* `modes`: the N-element frequencies against their closed form (to 1e-10), the continuum's at O(N^-2) with the
  derived coefficient; the run's f1 within RK4's bound of the closed form.
* `damper`: the run's complex eigenvalue against the quadratic eigenproblem solved here (to 1e-8); the
  continuum's from the transcendental equation (a root, near n pi); the N-element values converging to it at
  second order; the best damper and its ratio within the universal curve's stated range.
* `wind`: the scene's continuous and held covariances against Lyapunov solutions of a model built here; the
  integrator's variance bias falling at implicitfast's order; 40 seeded records inside their 99 % interval in at
  least 38 (a test that can fail, 0.8 % of the time for a correct simulation); a seed's record the same in the
  study's batches as in `springlab run`, and on a dask cluster as locally.
* `rain_wind`: the growth rate within 1e-6 of Re(lambda); the stabilising damper to 1e-3 (runs 0.1 % either side
  grow and decay).
* Bad input: one line, exit 2, nothing written.
"""

from __future__ import annotations

import json
import math

import mujoco
import numpy as np
import pytest
import scipy.linalg

import springlab
from helpers.stay_cable import WINDY
from springlab.cli.main import main
from springlab.exact import cable as cb
from springlab.exact.linearize import linearize
from springlab.runs.run import run_scenario
from springlab.scenes import get
from springlab.scenes.stay_cable import answers, build, stationary
from springlab.scenes.stay_cable.readback import CableModel
from springlab.sim import model_files
from springlab.studies import random_load, rms_settings

EPS = float(np.finfo(float).eps)
SCENE = get("stay_cable")
L, T, MU = 300.0, 6.1e6, 70.0
C = math.sqrt(T / MU)


def _model_here(n, damper_node=0, damper=0.0, structural=0.0, aero=0.0, aero_modes=0):
    """(M diag, C, K) of the N-element model from its definition: masses m dx, springs T / dx, the damper on a node,
    mass-proportional intrinsic damping 2 zeta_s omega_1 m dx, modal aero terms (springlab docs' formulas)."""
    dx = L / (n + 1)
    mass = np.full(n, MU * dx)
    k = T / dx
    stiffness = 2 * k * np.eye(n) - k * np.eye(n, k=1) - k * np.eye(n, k=-1)
    damping = np.eye(n) * 2 * structural * MU * (math.pi * C / L) * dx
    if damper_node:
        damping[damper_node - 1, damper_node - 1] += damper
    for mode in range(1, aero_modes + 1):
        shape = np.sin(np.arange(1, n + 1) * mode * math.pi / (n + 1))
        omega = 2 * C / dx * math.sin(mode * math.pi / (2 * (n + 1)))
        damping += 4 * aero * omega * MU * dx / (n + 1) * np.outer(shape, shape)
    return mass, damping, stiffness


def _state_matrix(mass, damping, stiffness):
    n = len(mass)
    return np.block([[np.zeros((n, n)), np.eye(n)], [-stiffness / mass[:, None], -damping / mass[:, None]]])


# -- the model ---------------------------------------------------------------------------------------------


def test_the_shipped_model_is_the_generators_at_the_defaults():
    assert model_files.path("stay_cable").read_text() == build.model_xml()
    shipped = mujoco.MjModel.from_xml_path(str(model_files.path("stay_cable")))
    case = SCENE.case("wind", {})
    for field in ("body_mass", "dof_damping", "tendon_stiffness", "wrap_prm", "actuator_gear"):
        assert np.array_equal(getattr(shipped, field), getattr(case.model, field)), field
    assert case.params["n_elements"] == 99 and case.params["damper_position"] == 6.0


@pytest.mark.parametrize("n", [2, 9, 49])
def test_the_read_back_model_is_mujocos_linearization_and_the_definition(n):
    case = SCENE.case("wind", {"n_elements": n, "damper_position": 30.0, "aero_modes": min(n, 2)})
    cable = CableModel.of(case.model)
    node = round(30.0 / (L / (n + 1)))
    mass, damping, stiffness = _model_here(n, max(node, 1), 3.3e5, 0.001, -0.005, min(n, 2))
    lin = linearize(case.model)
    for found, mujoco_says, here in (
        (np.diag(cable.lumped.mass), lin.M, np.diag(mass)),
        (cable.lumped.stiffness, lin.K, stiffness),
        (cable.lumped.damping, lin.C, damping),
    ):
        scale = np.max(np.abs(here))
        assert np.max(np.abs(found - here)) <= 64 * EPS * scale  # the same formulas, rounded differently
        assert np.max(np.abs(mujoco_says - found)) <= 1e-9 * scale  # centred differences of a linear model
    assert cable.load == pytest.approx(np.full(n, L / (n + 1)), rel=4 * EPS)


# -- modes ------------------------------------------------------------------------------------------------


def test_the_modes_run_measures_f1_and_reports_the_closed_forms():
    result = run_scenario("stay_cable", "modes")
    q = result.quantities
    n = 99
    dx = L / (n + 1)
    for k in (1, 2, 3):
        closed = C / (math.pi * dx) * math.sin(k * math.pi / (2 * (n + 1)))
        assert abs(q[f"mode_{k}_frequency_hz_exact"] / closed - 1) <= 1e-10
        assert q[f"mode_{k}_frequency_hz_continuum"] == pytest.approx(k * C / (2 * L), rel=4 * EPS)
    theta = math.pi / (2 * (n + 1))
    # sin(theta) / theta - 1 = -theta^2 / 6 + theta^4 / 120 - ...: the leading term within the next one
    assert abs(q["mode_1_discretization_error"] - theta**2 / 6) <= theta**4 / 120 * 1.01
    # RK4 at dt: the measured frequency within 2 (w dt)^4 / 120 of the closed form (+ round-off)
    omega = 2 * math.pi * q["mode_1_frequency_hz_exact"]
    bound = 2 * (omega * result.dt) ** 4 / 120 + 100 * EPS / (omega * result.dt)
    assert abs(q["mode_1_frequency_hz"] / q["mode_1_frequency_hz_exact"] - 1) <= bound
    assert result.passed


# -- the damper --------------------------------------------------------------------------------------------


def _damped_mode_1_here(n, node, damper):
    values = scipy.linalg.eigvals(_state_matrix(*_model_here(n, node, damper)))
    oscillatory = values[values.imag > 1e-9 * np.max(np.abs(values))]
    return oscillatory[np.argmin(oscillatory.imag)]


def test_the_damper_run_measures_the_complex_eigenvalue_to_1e_8():
    result = run_scenario("stay_cable", "damper", n_elements=49, duration=8.0)
    q = result.quantities
    exact = _damped_mode_1_here(49, 1, 3.3e5)  # dx = 6 m: the damper at 6 m is node 1
    assert abs(q["mode_1_frequency_hz"] / (abs(exact) / (2 * math.pi)) - 1) <= 1e-8
    assert abs(q["mode_1_damping_ratio"] / (-exact.real / abs(exact)) - 1) <= 1e-8
    assert result.passed


def test_the_n_element_damping_converges_to_the_continuums_at_second_order():
    ratios = []
    for n in (49, 99, 199):  # the damper at 6 m is on a node in each (dx = 6, 3, 1.5 m)
        exact = _damped_mode_1_here(n, 6 * (n + 1) // 300, 3.3e5)
        ratios.append(-exact.real / abs(exact))
    continuum_lambda = answers.continuum_mode_1(CableModel.of(SCENE.case("damper", {"n_elements": 199}).model))
    continuum = -continuum_lambda.real / abs(continuum_lambda)
    # the continuum's root: sin x + i eta sin(x a / L) sin(x (1 - a / L)) = 0 at x = beta L near pi
    zeta, eta, ratio = continuum, 3.3e5 / math.sqrt(T * MU), 6.0 / L
    errors = np.abs(np.array(ratios) / zeta - 1)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2) <= 0.1), (ratios, zeta, orders)
    x = math.pi + 0j
    for _ in range(60):  # Newton here on the same equation, from the undamped root
        f = np.sin(x) + 1j * eta * np.sin(ratio * x) * np.sin((1 - ratio) * x)
        df = np.cos(x) + 1j * eta * (
            ratio * np.cos(ratio * x) * np.sin((1 - ratio) * x)
            + (1 - ratio) * np.sin(ratio * x) * np.cos((1 - ratio) * x)
        )
        x -= f / df
    assert abs(x.imag / abs(x) - zeta) <= 64 * EPS * zeta


def test_the_best_damper_is_within_the_universal_curves_stated_range():
    result = run_scenario("stay_cable", "damper", duration=2.0)
    q = result.quantities
    ratio = 6.0 / L
    universal_c, universal_zeta = math.sqrt(T * MU) * L / (math.pi * 6.0), ratio / 2
    assert q["optimal_damper_n_s_m_universal"] == pytest.approx(universal_c, rel=4 * EPS)
    # docs/scenes/stay_cable.md: zeta_max within a / L + (pi a / L)^2 of a / 2L, c_opt within (pi a / L)^2
    assert abs(q["max_damping_ratio_continuum"] / universal_zeta - 1) <= ratio + (math.pi * ratio) ** 2
    assert abs(q["optimal_damper_n_s_m_continuum"] / universal_c - 1) <= (math.pi * ratio) ** 2
    # the N-element model's best damper gives its largest ratio: 1 % either side gives less
    best = q["optimal_damper_n_s_m_exact"]
    modes = [_damped_mode_1_here(99, 2, f * best) for f in (0.99, 1.0, 1.01)]
    zetas = [-m.real / abs(m) for m in modes]
    # the scene's ratio (Newton on the determinant) and this one (dense eigenvalues) at the same damper: the dense
    # one is good to N eps |lambda_max| / |lambda_1| (the state matrix's backward error; |lambda_max| is the damper's
    # overdamped root c / m dx or omega_N), Newton's to (omega_N / omega_1)^2 eps (its pivots' cancellation)
    omega_1, omega_n = math.pi * math.sqrt(T / MU) / L, 2 * math.sqrt(T / MU) * 100 / L
    dense = 99 * EPS * max(best / (MU * L / 100), omega_n) / omega_1
    assert zetas[1] >= max(zetas[0], zetas[2])
    assert abs(zetas[1] - q["max_damping_ratio_exact"]) <= dense + (omega_n / omega_1) ** 2 * EPS


def test_the_best_damper_by_newton_is_the_dense_searchs_and_falls_back_to_it(monkeypatch):
    cable = CableModel.of(SCENE.case("damper", {}).model)
    guess = math.log(math.sqrt(T * MU) * L / (math.pi * 6.0))
    bounds = (guess - math.log(answers.SEARCH_FACTOR), guess + math.log(answers.SEARCH_FACTOR))
    by_newton = answers._optimum_by_newton(cable, bounds)
    by_eigenvalues = answers._optimum_by_eigenvalues(cable, bounds)
    # each ratio of the dense search is good to N eps |lambda_max| / |lambda_1| (the state matrix's backward error;
    # |lambda_max| is the damper's overdamped root c / m dx at most 30 times the optimum, or omega_N)
    node_mass = MU * L / 100
    largest = max(30.0 * by_eigenvalues[0] / node_mass, 2 * math.sqrt(T / MU) * 100 / L)
    tolerance = 99 * EPS * largest / (math.pi * math.sqrt(T / MU) / L)
    assert abs(by_newton[1] - by_eigenvalues[1]) <= tolerance
    # the ratio is flat at the optimum: near it zeta = zeta_max / cosh(ln(c / c_opt)) (the universal curve), so two
    # searches whose ratios differ by up to 2 tolerance find ln c within sqrt(4 tolerance / zeta_max), plus xatol
    assert abs(math.log(by_newton[0] / by_eigenvalues[0])) <= math.sqrt(4 * tolerance / by_newton[1]) + 2e-9

    # where Newton fails (or the damping is not diagonal) the search runs on the dense eigenvalues, as before
    def fails(self, start, tendons=()):
        raise ArithmeticError("the determinant's recurrence needs K tridiagonal")

    monkeypatch.setattr(cb.LumpedCable, "eigenvalue_near", fails)
    fallback = answers.damper_optimum(cable)
    assert (fallback.coefficient_exact, fallback.ratio_exact) == by_eigenvalues


# -- the wind ---------------------------------------------------------------------------------------------------


def test_the_winds_exact_covariances_are_the_lyapunov_solutions_of_the_model_built_here():
    case = SCENE.case("wind", WINDY)
    exact = stationary.wind_exact(case, "implicitfast", 0.02)
    mass, damping, stiffness = _model_here(9, 1, 4e4, 0.01)
    a = _state_matrix(mass, damping, stiffness)
    b = np.zeros((18, 1))
    b[9:, 0] = (L / 10) / mass
    continuous = scipy.linalg.solve_continuous_lyapunov(a, -30.0 * b @ b.T)
    scale = np.sqrt(np.outer(np.diag(continuous), np.diag(continuous)))
    # both are backward stable: a few eps times the condition of the Lyapunov operator (|A| / decay ~ 1e4 here)
    assert np.max(np.abs(exact.continuous - continuous) / scale) <= 1e-9
    # held: the exact recursion P = Phi P Phi^T + Gamma (S / dt) Gamma^T with Phi, Gamma from expm, summed here
    block = scipy.linalg.expm(np.block([[a, b], [np.zeros((1, 19))]]) * 0.02)
    phi, gamma = block[:18, :18], block[:18, 18:]
    held, power = gamma @ gamma.T * 30.0 / 0.02, phi
    for _ in range(60):  # doubling: the sum over 2^60 steps, far beyond every mode's decay
        held, power = held + power @ held @ power.T, power @ power
    assert np.max(np.abs(exact.held - held) / scale) <= 1e-9


def test_the_integrators_variance_bias_falls_at_its_order():
    case = SCENE.case("wind", {})  # the default stay, N = 99
    biases = []
    for dt in (0.008, 0.004, 0.002):
        exact = stationary.wind_exact(case, "implicitfast", dt)
        mid = CableModel.of(case.model).midspan - 1
        biases.append(exact.bias[mid, mid] / exact.held[mid, mid])
    orders = np.log2(np.array(biases[:-1]) / np.array(biases[1:]))
    assert np.all(np.abs(orders - 1) <= 0.1), (biases, orders)


@pytest.mark.slow
def test_forty_seeded_records_fall_inside_their_own_99_percent_interval():
    """At 99 %, a correct simulation leaves more than 2 of 40 outside with probability 0.8 %."""
    result = random_load.ensemble("stay_cable", seeds=40, record=200.0, dt=0.01, **WINDY)
    assert result.level == 0.99 and random_load.allowed_outside(40, 0.99) == 2
    assert result.inside >= 38, result.answer
    # the integrator's own bias is far inside the scatter the records are judged against
    assert abs(result.integrated / result.held - 1) <= 0.1 * result.spread / result.held
    # pooled: 40 independent records within 3 standard errors of the held variance
    assert abs(result.mean_variance - result.held) <= 3 * result.spread / math.sqrt(40)
    # and the exact continuous value inside the reported biases (the hold's, the integrator's) and that scatter
    reported = abs(result.held / result.continuous - 1) + abs(result.integrated / result.held - 1)
    assert (
        abs(result.mean_variance / result.continuous - 1) <= reported + 3 * result.spread / math.sqrt(40) / result.held
    )


@pytest.mark.slow
def test_a_seeds_record_is_the_same_in_the_study_as_in_a_run_and_on_a_cluster(dask_cluster):
    study = random_load.ensemble("stay_cable", seeds=[3, 5], record=20.0, **WINDY)
    alone = springlab.run("stay_cable", "wind", duration=20.0, seed=5, **WINDY)
    assert study.variances[1] == pytest.approx(alone.quantities["rms_displacement_m"] ** 2, rel=1e-13)
    # the session's LocalCluster of 2 worker processes (tests/conftest.py), not a start of its own
    distributed = random_load.ensemble("stay_cable", seeds=[3, 5], record=20.0, executor=dask_cluster, **WINDY)
    assert distributed.variances == study.variances


def test_the_wind_runs_check_is_its_records_interval():
    result = run_scenario("stay_cable", "wind", duration=200.0, dt=0.01, **WINDY)
    (check,) = result.checks
    q = result.quantities
    low, high = q["rms_displacement_m_ci95"]
    held = q["rms_displacement_m_held"]
    assert check.reference == held and low < held < high
    # held to its 99 % interval on the side it falls, wider than the reported 95 % one
    assert check.tolerance > (high / held - 1 if check.value >= held else 1 - low / held)
    assert q["rms_reduction_factor"] == pytest.approx(q["rms_displacement_m_no_damper"] / q["rms_displacement_m_exact"])
    assert q["variance_hold_error"] == pytest.approx(
        q["rms_displacement_m_held"] ** 2 / q["rms_displacement_m_exact"] ** 2 - 1
    )


# -- rain-wind ------------------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_rain_wind_grows_at_the_complex_eigenvalues_rate():
    result = run_scenario("stay_cable", "rain_wind", n_elements=49, duration=60.0)
    mass, damping, stiffness = _model_here(49, 1, 0.0, 0.001, -0.005, 1)
    rate = float(np.max(scipy.linalg.eigvals(_state_matrix(mass, damping, stiffness)).real))
    q = result.quantities
    assert rate > 0 and abs(q["growth_rate_1_s_exact"] / rate - 1) <= 1e-9
    assert abs(q["growth_rate_1_s"] / rate - 1) <= 1e-6
    assert result.passed


@pytest.mark.slow
def test_the_stabilising_damper_stops_the_growth_within_1e_3():
    result = run_scenario("stay_cable", "rain_wind", n_elements=19, duration=1.0)
    c_stop = result.quantities["stabilising_damper_n_s_m"]
    rates = []
    for factor in (1 - 1e-3, 1 + 1e-3):  # dx = 15 m: the damper at 6 m sits on node 1
        mass, damping, stiffness = _model_here(19, 1, c_stop * factor, 0.001, -0.005, 1)
        rates.append(float(np.max(scipy.linalg.eigvals(_state_matrix(mass, damping, stiffness)).real)))
    assert rates[0] > 0 > rates[1]
    # and MuJoCo agrees: runs 0.1 % either side grow and decay at those rates
    for factor, rate in zip((1 - 1e-3, 1 + 1e-3), rates):
        run = run_scenario("stay_cable", "rain_wind", n_elements=19, duration=60.0, damper_coefficient=c_stop * factor)
        assert math.copysign(1.0, run.quantities["growth_rate_1_s"]) == math.copysign(1.0, rate)
        assert abs(run.quantities["growth_rate_1_s"] - rate) <= 1e-6 * abs(rate) + run.checks[0].tolerance * abs(rate)


# -- bad input -----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("setting", "says"),
    [
        ("n_elements=1", "n_elements must be a finite number >= 2"),
        ("damper_position=300", "damper_position must lie inside the cable"),
        ("damper_position=-1", "damper_position must be a finite number > 0"),
        ("tension=-6e6", "tension must be a finite number > 0"),
        ("wind_intensity=nan", "wind_intensity must be a finite number >= 0"),
        ("wind_intensity=inf", "wind_intensity must be a finite number >= 0"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_nothing_written(tmp_path, capsys, setting, says):
    out = tmp_path / "out"
    assert main(["run", "stay_cable", "wind", "--set", setting, "--output", str(out)]) == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


@pytest.mark.slow
def test_the_rms_command_answers_in_words_and_json(tmp_path, capsys):
    code = main(
        ["rms", "stay_cable", "--seeds", "4", "--record", "20", "--json", "--output", str(tmp_path)]
        + [f"--set={k}={v}" for k, v in WINDY.items()]
    )
    printed = json.loads(capsys.readouterr().out)
    assert code == 0 and printed["question"].startswith("How large") and " m " in printed["answer"]
    assert {p.name for p in tmp_path.iterdir()} == {"rms.json", "rms.csv", "rms.png"}
    assert main(["rms", "slider"]) == 2 and "has no scenario under a random load" in capsys.readouterr().err


@pytest.mark.slow
def test_the_settings_study_extrapolates_the_continuum_and_verifies_its_pick():
    study = rms_settings.rms_settings(
        "stay_cable", tol=0.4, integrators=("implicitfast",), seed_counts=(1, 2), record=100.0, sizes=(49,)
    )
    # Richardson from the declared sizes' exact variances, computed here with scipy's Lyapunov solver
    variances = []
    for n in (199, 399):
        mass, damping, stiffness = _model_here(n, 6 * (n + 1) // 300, 3.3e5, 0.001)
        a = _state_matrix(mass, damping, stiffness)
        b = np.zeros((2 * n, 1))
        b[n:, 0] = (L / (n + 1)) / mass
        covariance = scipy.linalg.solve_continuous_lyapunov(a, -30.0 * b @ b.T)
        variances.append(covariance[(n + 1) // 2 - 1, (n + 1) // 2 - 1])
    limit = variances[1] + (variances[1] - variances[0]) / 3
    assert study.continuum == pytest.approx(limit, rel=1e-8)
    pick = study.recommendation
    assert pick.found and pick.error is not None and pick.error <= 0.4
    assert pick.row is not None and pick.row.error is not None and pick.row.error <= 0.4 - study.continuum_error
    assert "records of 100 s" in study.answer and study.to_dict()["question"].startswith("How many")
