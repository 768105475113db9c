"""The slider in MuJoCo agrees with the exact solution of m x'' + d x' + k x = F(t)."""

import math

import numpy as np
import pytest
import scipy.linalg

import springlab
from springlab.sim.simulate import ORDERS


@pytest.mark.parametrize(
    "scenario",
    ["free", "undamped", "underdamped", "critical", "overdamped", "step", "harmonic", "resonance", "exercise"],
)
def test_default_setting_reaches_1e6_relative_accuracy(scenario):
    result = springlab.run("slider", scenario)
    worst = max(e["max_rel"] for e in result.to_dict()["errors"].values())
    assert worst <= 1e-6
    assert result.to_dict()["passed"] is True


@pytest.mark.parametrize("integrator", list(ORDERS))
@pytest.mark.parametrize("scenario", ["undamped", "underdamped", "critical", "overdamped", "step", "harmonic"])
def test_the_predicted_tolerance_bounds_the_measured_error(integrator, scenario):
    # What this checks, plainly: springlab.runs.compare's predicted bound (the code's own formula) is an upper
    # bound of the error the run reports, and the verdict follows the 1e-2 cap. It is not an independent
    # check of that error; test_unforced_error_is_the_exact_error_of_the_integrators_one_step_map is.
    result = springlab.run("slider", scenario, integrator=integrator, dt=1e-3, duration=2.0)
    summary = result.to_dict()
    assert summary["estimate_range"]["inside"] is True  # omega dt = 0.01: the prediction holds
    reference = result.case.reference(result.time, dt=1e-3)
    predicted = springlab.runs.compare.tolerances(reference, integrator, 1e-3, result.time)
    for column, error in summary["errors"].items():
        assert error["max_rel"] <= predicted[column], column
    # a PASS certifies at most 1e-2 (discrete's dissipation costs it more over 2 s)
    worst = max(e["max_rel"] for e in summary["errors"].values())
    assert summary["passed"] is (worst <= springlab.runs.compare.CERTIFIED_CAP)


def _one_step_map(integrator, m, k, d, h):
    """The integrator's exact one-step map of (x, v) on m x'' + d x' + k x = 0, derived by hand.

    euler / implicit / implicitfast: damping implicit, spring explicit, (m + h d) v' = m v - h k x,
    x' = x + h v'; rk4: R(hA), R(s) = 1 + s + s^2/2 + s^3/6 + s^4/24; discrete: backward Euler.
    """
    a = np.array([[0.0, 1.0], [-k / m, -d / m]])
    if integrator in ("euler", "implicit", "implicitfast"):
        c = m + h * d
        velocity = np.array([-h * k / c, m / c])
        return np.array([np.array([1.0, 0.0]) + h * velocity, velocity])
    if integrator == "rk4":
        s = h * a
        return np.eye(2) + s + s @ s / 2 + s @ s @ s / 6 + s @ s @ s @ s / 24
    return np.linalg.inv(np.eye(2) - h * a)


@pytest.mark.parametrize("integrator", list(ORDERS))
@pytest.mark.parametrize("scenario", ["undamped", "underdamped", "critical", "overdamped"])
def test_unforced_error_is_the_exact_error_of_the_integrators_one_step_map(integrator, scenario):
    # independent of springlab's reference and tolerance: the run must equal the hand-derived map's powers,
    # and its reported error must equal that map's exact global error against scipy's expm
    dt, duration = 1e-3, 2.0
    result = springlab.run("slider", scenario, integrator=integrator, dt=dt, duration=duration)
    p = result.parameters
    m, k, d = p["mass"], p["stiffness"], p["damping"]
    step = _one_step_map(integrator, m, k, d, dt)
    # the exact flow over one step, applied n times (its round-off is covered like the map's)
    flow = scipy.linalg.expm(np.array([[0.0, 1.0], [-k / m, -d / m]]) * dt)
    z = exact_z = np.array([p["x0"], p["v0"]])
    discrete, exact = np.empty((len(result.time), 2)), np.empty((len(result.time), 2))
    for i in range(len(result.time)):
        discrete[i], exact[i] = z, exact_z
        z, exact_z = step @ z, flow @ exact_z
    steps = len(result.time) - 1
    # round-off of n products of a map with norm ~1 (and of MuJoCo's own steps): 100 eps per step
    roundoff = 100 * np.finfo(float).eps * steps
    for column, j in (("slider_pos", 0), ("slider_vel", 1)):
        simulated = result.pos["slider"] if j == 0 else result.vel["slider"]
        scale = np.max(np.abs(exact[:, j]))
        assert np.max(np.abs(simulated - discrete[:, j])) <= roundoff * scale, column
        map_error = np.max(np.abs(discrete[:, j] - exact[:, j])) / scale
        assert result.to_dict()["errors"][column]["max_rel"] == pytest.approx(map_error, rel=1e-6, abs=2 * roundoff)


def test_rk4_tolerance_is_a_tight_prediction_not_a_blanket():
    # the leading-order prediction of RK4's error must be within a factor 2..4 of the real error
    result = springlab.run("slider", "undamped", integrator="rk4", dt=5e-3, duration=5.0)
    error = result.to_dict()["errors"]["slider_pos"]["max_rel"]
    assert result.to_dict()["tolerance"] / 4 <= error <= result.to_dict()["tolerance"]


def test_exercise_gives_the_textbook_answer():
    # chapter 5.4 'Under or overdamped?': d/m = 3, k/m = 2, x0 = 5 m -> x = 10 e^-t - 5 e^-2t
    result = springlab.run("slider", "exercise")
    q = result.to_dict()["quantities"]
    assert q["regime"] == "overdamped"
    assert q["damping_ratio"] == pytest.approx(3 / (2 * math.sqrt(2)), rel=1e-14)
    assert q["lambda_1_per_s"] == pytest.approx(-1.0, rel=1e-14)
    assert q["lambda_2_per_s"] == pytest.approx(-2.0, rel=1e-14)
    assert q["coefficient_A_m"] == pytest.approx(10.0, rel=1e-14)
    assert q["coefficient_B_m"] == pytest.approx(-5.0, rel=1e-14)
    t = result.time
    textbook = 10 * np.exp(-t) - 5 * np.exp(-2 * t)
    assert np.max(np.abs(result.pos["slider"] - textbook)) / 5.0 < 1e-8


def test_undamped_motion_is_x0_cos_omega_t():
    # eq. 5.9 with the model's own m and k read back from MuJoCo
    result = springlab.run("slider", "undamped", x0=0.2)
    m, k = result.parameters["mass"], result.parameters["stiffness"]
    expected = 0.2 * np.cos(math.sqrt(k / m) * result.time)
    assert np.max(np.abs(result.pos["slider"] - expected)) < 0.2 * 1e-6


def test_step_force_settles_at_static_deflection_f_over_k():
    result = springlab.run("slider", "step", duration=20.0, damping=5.0)
    q = result.to_dict()["quantities"]
    assert q["static_deflection_m"] == pytest.approx(10.0 / result.parameters["stiffness"])
    assert result.pos["slider"][-1] == pytest.approx(q["static_deflection_m"], rel=1e-6)


def test_resonance_grows_linearly_like_t_cos():
    # undamped at omega = omega_n from rest: x = F0/(2 m w^2) (sin wt - wt cos wt)
    result = springlab.run("slider", "resonance")
    m, k, f0 = result.parameters["mass"], result.parameters["stiffness"], result.parameters["force_amplitude"]
    w = math.sqrt(k / m)
    t = result.time
    expected = f0 / (2 * m * w**2) * (np.sin(w * t) - w * t * np.cos(w * t))
    assert np.max(np.abs(result.pos["slider"] - expected)) / np.max(np.abs(expected)) < 1e-6


def test_harmonic_response_approaches_the_steady_state_amplitude():
    result = springlab.run("slider", "harmonic", damping=4.0, duration=20.0)
    q = result.to_dict()["quantities"]
    m, k, d = (result.parameters[n] for n in ("mass", "stiffness", "damping"))
    w = 2 * math.pi * result.parameters["force_frequency"]
    expected = result.parameters["force_amplitude"] / math.hypot(k - m * w * w, d * w)
    assert q["steady_state_amplitude_m"] == pytest.approx(expected, rel=1e-12)
    tail = result.pos["slider"][result.time > 15.0]
    assert np.max(np.abs(tail)) == pytest.approx(expected, rel=1e-3)


def _observed_order(integrator, scenario):
    errors = []
    dts = (2e-3, 1e-3, 5e-4)
    for dt in dts:
        r = springlab.run("slider", scenario, integrator=integrator, dt=dt, duration=2.0)
        errors.append(r.to_dict()["errors"]["slider_pos"]["max_rel"])
    return np.polyfit(np.log(dts), np.log(errors), 1)[0]


@pytest.mark.parametrize(
    "integrator,order", [("euler", 1), ("implicit", 1), ("implicitfast", 1), ("discrete", 1), ("rk4", 4)]
)
def test_observed_convergence_order_matches_the_integrator(integrator, order):
    # underdamped free response; the harmonic case checks that forcing keeps the order too
    assert _observed_order(integrator, "underdamped") == pytest.approx(order, abs=0.3)


def test_rk4_keeps_fourth_order_under_harmonic_forcing():
    assert _observed_order("rk4", "harmonic") == pytest.approx(4, abs=0.3)


def test_model_values_are_read_back_from_the_mjcf():
    # the defaults come from models/slider.xml, not from a Python copy
    import mujoco

    from springlab.sim import model_files

    model = mujoco.MjModel.from_xml_path(str(model_files.path("slider")))
    result = springlab.run("slider", "free", duration=0.1)
    assert result.parameters["mass"] == model.body("block").mass[0]
    assert result.parameters["stiffness"] == model.jnt_stiffness[0]
    assert result.parameters["damping"] == model.dof_damping[0]


def test_overrides_reach_the_compiled_model():
    result = springlab.run("slider", "free", duration=0.1, mass=2.0, stiffness=800.0, damping=4.0)
    assert result.model.body("block").mass[0] == 2.0
    assert result.model.jnt_stiffness[0] == 800.0
    assert result.model.dof_damping[0] == 4.0
    assert result.to_dict()["quantities"]["omega_n_rad_s"] == pytest.approx(20.0)


@pytest.mark.parametrize("scenario", list(springlab.SCENES["slider"].scenarios))
def test_default_setting_is_predicted_to_meet_1e6(scenario):
    # the per-scenario dt is chosen so that the order-based bound itself is <= 1e-6
    assert springlab.run("slider", scenario).to_dict()["tolerance"] <= 1e-6
