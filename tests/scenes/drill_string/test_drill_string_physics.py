"""The drill string against references built here: root finders, limits, MuJoCo's own linearization, closed forms.

* The continuum's (beta L) tan(beta L) = rho J_p L / J_b against scipy's TOMS 748 on the tangent form (a different
  function and method) and against its fixed-free (J_b -> 0) and fixed-fixed (J_b -> inf) limits.
* The continuum's two exact solutions of the start-up (the modal series with its stated truncation bound, the
  travelling waves) against each other.
* The N-element model's M, K and modes against springlab.exact.linearize (MuJoCo's mjd_inverseFD) to 1e-9, so
  the discretization error (N) and the integration error (dt) are measured apart; the chain encoding against the
  tendon encoding.
* Observed orders: the discretization error of f1 in N (2), the run's error in dt (RK4: 4).
* MuJoCo's frictionloss at the bit is Coulomb: the same torque at every slip speed (no velocity weakening).
* Bad input: exit 2, one line.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from springlab.cli.main import main
from springlab.exact.linearize import linearize
from springlab.runs.run import prepare, run_scenario
from springlab.scenes.drill_string import build, continuum
from springlab.scenes.drill_string.lumped import LumpedString

EPS = np.finfo(float).eps
#: the defaults, from the MJCF's sources (5 in drill pipe, steel, a 100 kg m^2 BHA, 1000 m)
L, G, RHO, J_B = 1000.0, 79.3e9, 7850.0, 100.0
J_P = math.pi * (0.127**4 - 0.10861**4) / 32


def _model(scenario: str = "modes", **overrides):
    scene, chosen, params = prepare("drill_string", scenario, overrides)
    return scene.build(params, chosen)


# -- the continuum -----------------------------------------------------------------------------


@pytest.mark.parametrize("mu", [1e-4, 0.05, 0.9325, 7.0, 1e4])
def test_continuum_roots_agree_with_toms748_on_the_tangent_form(mu):
    roots = continuum.roots(mu, 12)
    for n, x in enumerate(roots, start=1):
        low, high = (n - 1) * math.pi, (n - 0.5) * math.pi
        # x tan x - mu rises monotonically from -mu to +inf on the branch: a different function and method
        shrink = 1e-12 * max(high, 1.0)
        independent = scipy.optimize.toms748(
            lambda s: s * math.tan(s) - mu, low + shrink, high - shrink, xtol=1e-300, rtol=4 * EPS, maxiter=500
        )
        # both stop within a few ulp of their own floating-point root; the tangent form's root moves by its
        # round-off eps (|x tan x| + mu) over its slope |tan x + x sec^2 x|
        slope = abs(math.tan(x) + x / math.cos(x) ** 2)
        tolerance = 8 * EPS * x + 4 * EPS * (abs(x * math.tan(x)) + mu) / slope
        assert abs(x - independent) <= tolerance, (n, x, independent)
        assert low < x <= high


def test_the_residual_of_every_root_is_round_off():
    mu = 0.9325
    for x in continuum.roots(mu, 50):
        # a root within 4 ulp of the true one leaves |f'(x)| 4 eps x, plus the evaluation's own round-off
        slope = abs(math.sin(x) + x * math.cos(x) + mu * math.sin(x))
        assert abs(x * math.sin(x) - mu * math.cos(x)) <= slope * 4 * EPS * x + 4 * EPS * (x + mu)


def test_a_massless_bit_is_a_fixed_free_rod():
    rod = continuum.Rod(L, G, RHO, J_P, 0.0)
    c = math.sqrt(G / RHO)
    n = np.arange(1, 9)
    assert np.allclose(rod.frequencies(8), (2 * n - 1) * math.pi * c / (2 * L), rtol=4 * EPS, atol=0)
    # a light BHA: mu x_n tan x_n = mu moves x_n = (n - 1/2) pi down by about (n - 1/2) pi / mu
    light = continuum.Rod(L, G, RHO, J_P, 1e-6)
    shift = 1 - light.frequencies(8) / ((2 * n - 1) * math.pi * c / (2 * L))
    assert np.all(shift > 0) and np.all(shift <= 2 / light.mu)


def test_a_heavy_bit_is_a_mass_on_the_rod_spring_and_a_fixed_fixed_rod_above_it():
    heavy = continuum.Rod(L, G, RHO, J_P, 1e9)
    c, mu = math.sqrt(G / RHO), heavy.mu
    omega = heavy.frequencies(8)
    # mode 1: the bit on the rod's torsional spring G J_p / L, x^2 = mu - mu^2/3 + ...
    assert abs(omega[0] / math.sqrt(G * J_P / L / 1e9) - 1) <= mu / 3
    # the rest: the rod held at both ends, n pi c / L, moved up by mu / (n pi)^2
    n = np.arange(1, 8)
    fixed_fixed = n * math.pi * c / L
    assert np.all(np.abs(omega[1:] / fixed_fixed - 1) <= 2 * mu / (n * math.pi) ** 2)


def test_the_modal_start_up_and_the_travelling_waves_agree_within_the_stated_truncation_bound():
    rod = continuum.Rod(L, G, RHO, J_P, J_B)
    alpha, ramp, modes = 2 * math.pi / 2.0, 2.0, 2000
    time = np.linspace(0.0, 6.0, 301)
    _, speed = rod.modal_spin_up(time, L, alpha, ramp, modes)
    waves = continuum.WaveSolution(rod, 0.0, alpha, ramp)
    waves.solve(6.0)
    exact = np.array([waves.speed(t) for t in time])
    _, bound = rod.modal_tail_bound(modes, alpha)
    # the waves are integrated to rtol 1e-12: their own error is far below the bound
    assert np.max(np.abs(speed - exact)) <= bound + 1e-9 * alpha * ramp


def test_the_stuck_bit_breaks_free_when_the_travelling_waves_torque_reaches_the_friction():
    rod = continuum.Rod(L, G, RHO, J_P, J_B)
    alpha, ramp, friction = math.pi, 2.0, 1e4
    t_b = continuum.stuck_breakaway_time(rod, friction, alpha, ramp)
    # before the first wave returns (t < 3 L/c) the stuck bit feels 2 Z Omega(t - L/c): a closed form by hand
    tau = L / math.sqrt(G / RHO)
    z = RHO * math.sqrt(G / RHO) * J_P
    assert continuum.stuck_bit_torque(rod, 2 * tau, alpha, ramp)[0] == pytest.approx(2 * z * alpha * tau, rel=4 * EPS)
    assert abs(continuum.stuck_bit_torque(rod, t_b, alpha, ramp)[0] / friction - 1) <= 16 * EPS
    # and the stick-slip solver's first slip happens there too
    assert continuum.WaveSolution(rod, friction, alpha, ramp).solve(t_b + 0.5).first("slip") == pytest.approx(t_b)


# -- the N-element model against MuJoCo's linearization --------------------------------------------------


@pytest.mark.parametrize("n", [8, 64])
def test_the_n_element_model_is_mujocos_linearization_to_1e9(n):
    model = _model(n_elements=n)
    lumped = LumpedString.of(model)
    linear = linearize(model)
    dofs = [int(model.joint(name).dofadr[0]) for name in lumped.names]
    mass, stiffness = linear.M[np.ix_(dofs, dofs)], linear.K[np.ix_(dofs, dofs)]
    assert np.all(np.abs(mass - np.diag(lumped.mass)) <= 1e-9 * lumped.mass[:, None])
    assert np.max(np.abs(stiffness - lumped.stiffness)) <= 1e-9 * np.max(np.abs(lumped.stiffness))
    # the modes MuJoCo integrates are the model's own exact ones
    omega, _ = lumped.modes()
    theirs = np.sqrt(np.clip(scipy.linalg.eigh(stiffness, mass, eigvals_only=True), 0, None))[1:]
    assert np.max(np.abs(theirs / omega - 1)) <= 1e-9


def test_the_chain_encoding_has_the_tendon_encodings_modes():
    scene, chosen, params = prepare("drill_string", "modes", {"n_elements": 16})
    spec = scene.model_spec()
    build.generate(spec, params, encoding="chain")
    chain = linearize(spec.compile())
    omega_chain = np.sqrt(np.clip(scipy.linalg.eigh(chain.K, chain.M, eigvals_only=True), 0, None))[1:]
    omega, _ = LumpedString.of(_model(n_elements=16)).modes()
    assert np.max(np.abs(omega_chain / omega - 1)) <= 1e-9


def test_the_shipped_model_is_the_string_at_two_elements():
    shipped = mujoco.MjModel.from_xml_path(str(build_path()))
    generated = _model(n_elements=2)
    a, b = LumpedString.of(shipped), LumpedString.of(generated)
    assert np.allclose(a.mass, b.mass, rtol=1e-12) and np.allclose(a.stiffness, b.stiffness, rtol=1e-12)
    assert a.friction == 1e4 and b.friction == 0.0  # the modes scenario is friction-free


def build_path():
    from springlab.sim import model_files

    return model_files.path("drill_string")


# -- observed orders ----------------------------------------------------------------------------------


def test_the_discretization_error_of_f1_is_second_order_in_n():
    rod = continuum.Rod(L, G, RHO, J_P, J_B)
    exact = rod.frequencies(1)[0]
    errors = [abs(LumpedString.of(_model(n_elements=n)).modes()[0][0] / exact - 1) for n in (16, 32, 64)]
    orders = [math.log2(errors[i] / errors[i + 1]) for i in range(2)]
    # lumped masses: error = C (beta h)^2 + O(h^4); at these N the h^4 term moves the slope by < 0.01
    assert all(abs(p - 2) <= 0.02 for p in orders), orders


def test_the_runs_error_in_dt_is_fourth_order_for_rk4():
    errors = []
    for dt in (0.02, 0.01):  # omega_max dt = 1.0, 0.5 at N = 8
        result = run_scenario("drill_string", "spin_up", integrator="rk4", dt=dt, duration=4.0, n_elements=8)
        errors.append(max(e.max_rel for e in result.errors.values()))
    assert abs(math.log2(errors[0] / errors[1]) - 4) <= 0.3, errors


# -- runs against the exact N-element model and the continuum -------------------------------------------------


@pytest.mark.slow
def test_the_breakaway_run_meets_the_exact_stick_slip_and_the_continuum(scenario_run):
    result = scenario_run("drill_string", "breakaway")  # the session's run of the scenario (tests/conftest.py)
    q = result.quantities
    assert result.passed and {c.name for c in result.checks} == {
        "breakaway_time_s",
        "peak_bit_speed_rad_s",
        "restick_time_s",
    }
    # 32 elements: the rod's breakaway and peak speed to 1e-4 (measured 5.5e-5 and 4.6e-5: docs/scenes)
    assert abs(q["breakaway_time_s"] / q["breakaway_time_s_continuum"] - 1) <= 1e-4
    assert abs(q["peak_bit_speed_rad_s"] / q["peak_bit_speed_rad_s_continuum"] - 1) <= 1e-4
    # the quasi-static wind-up T_f / (G J_p / L) is within 1 % of the dynamic one at this slow a ramp
    assert abs(q["windup_turns"] / q["windup_turns_static"] - 1) <= 0.01
    assert q["peak_speed_ratio"] > 1.9 and q["sticks_again"] is True


@pytest.mark.slow
def test_the_spin_up_run_is_exact_and_the_continuum_within_its_discretization(scenario_run):
    result = scenario_run("drill_string", "spin_up")  # the session's run of the scenario (tests/conftest.py)
    q = result.quantities
    assert result.passed
    # the run's bit speed is the N-element model's to its tolerance; its gap to the continuum is the model's
    assert q["bit_speed_error_vs_exact_rad_s"] <= 1e-4
    assert q["bit_speed_error_vs_continuum_rad_s"] <= (
        q["bit_speed_discretization_error_rad_s"]
        + q["bit_speed_error_vs_exact_rad_s"]
        + q["continuum_truncation_bound_rad_s"]
    )


def test_mujocos_frictionloss_is_coulomb_the_same_torque_at_every_slip_speed():
    model = _model("breakaway")
    lumped = LumpedString.of(model)
    data = mujoco.MjData(model)
    model.opt.timestep = 1e-3
    bit = int(model.joint("bit").dofadr[0])
    control = lumped.drive_control(2 * math.pi / 2.0)
    forces, speeds = [], []
    for step in range(6000):
        data.ctrl[0] = control if step < 2000 else 0.0
        mujoco.mj_step(model, data)
        rows = [i for i in range(data.nefc) if data.efc_type[i] == mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF]
        if abs(data.qvel[bit]) > 0.5 and rows:
            forces.append(abs(data.efc_force[rows[0]]))
            speeds.append(abs(data.qvel[bit]))
    assert max(speeds) > 10 * min(speeds)  # slipping at speeds an order of magnitude apart
    # the friction torque is T_f whatever the speed: no velocity weakening (MuJoCo has no such model)
    assert np.max(np.abs(np.array(forces) / lumped.friction - 1)) <= 1e-9


# -- bad input -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "setting, words",
    [
        ("n_elements=0", "n_elements must be"),
        ("n_elements=5000", "<= 4096"),
        ("n_elements=2.5", "whole number"),
        ("shear_modulus=-1", "shear_modulus must be"),
        ("density=0", "density must be"),
        ("length=nan", "length must be"),
        ("inner_diameter=0.2", "inner_diameter must be smaller"),
        ("bit_inertia=0.5", "bit_inertia must be"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(setting, words, capsys):
    assert main(["run", "drill_string", "modes", "--set", setting]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and "Traceback" not in err


def test_a_generated_model_saved_as_mjcf_keeps_its_physics(tmp_path):
    # `springlab audit` reads any MJCF: the generated string, written out, must reload with the same M and K
    scene, chosen, params = prepare("drill_string", "modes", {"n_elements": 16})
    spec = scene.model_spec()
    scene.edit(spec, params, chosen)
    original = spec.compile()
    path = tmp_path / "drill_16.xml"
    path.write_text(spec.to_xml())
    reloaded = mujoco.MjModel.from_xml_path(str(path))
    a, b = LumpedString.of(original), LumpedString.of(reloaded)
    # MjSpec.to_xml writes 6 significant digits: half a unit in the 6th digit, relative
    assert np.allclose(a.mass, b.mass, rtol=5e-6, atol=0)
    assert np.allclose(a.stiffness, b.stiffness, rtol=5e-6, atol=1e-300)
