"""Section 5.2 as a MuJoCo scene: position, velocity and acceleration by differentiation and
integration, checked against hand-derived answers of the chapter's examples."""

import mujoco
import numpy as np
import pytest

import springlab
from springlab import scenes
from springlab.errors import BadInputError, ParameterError
from springlab.scenes.kinematics.scene import polynomial_expression
from springlab.sim import model_files
from springlab.sim.simulate import quiet_mujoco

EPS = np.finfo(float).eps


def test_polynomial_position_gives_the_textbook_velocity_and_acceleration():
    # x = 0.03 t^3 + 0.2 t^2 + 1.2 t + 3.0  =>  v = 0.09 t^2 + 0.4 t + 1.2,  a = 0.18 t + 0.4 (by hand)
    result = springlab.run("kinematics", "polynomial_position")
    q = result.to_dict()["quantities"]
    assert q["position_expression"] == "x(t) = 0.03 t^3 + 0.2 t^2 + 1.2 t + 3 m"
    assert q["velocity_expression"] == "v(t) = 0.09 t^2 + 0.4 t + 1.2 m/s"
    assert q["acceleration_expression"] == "a(t) = 0.18 t + 0.4 m/s^2"
    # at t = 10 s: x = 30 + 20 + 12 + 3, v = 9 + 4 + 1.2, a = 1.8 + 0.4
    assert q["end_time_s"] == pytest.approx(10.0, abs=1e-9)
    assert q["x_end_m"] == pytest.approx(65.0, rel=1e-12)
    assert q["v_end_m_s"] == pytest.approx(14.2, rel=1e-12)
    assert q["a_end_m_s2"] == pytest.approx(2.2, rel=1e-12)
    t = result.time
    np.testing.assert_allclose(result.pos["vehicle"], 0.03 * t**3 + 0.2 * t**2 + 1.2 * t + 3.0, rtol=1e-13)
    np.testing.assert_allclose(result.vel["vehicle"], 0.09 * t**2 + 0.4 * t + 1.2, rtol=1e-13)
    # the exact reference written beside it (analytic.integrate_acceleration) is the hand polynomial too,
    # to the rounding of two evaluations of a degree-n sum with positive terms: 2 x 2n eps (Higham 2002, 5.1)
    np.testing.assert_allclose(result.ref_pos["vehicle"], 0.03 * t**3 + 0.2 * t**2 + 1.2 * t + 3.0, rtol=12 * EPS)
    np.testing.assert_allclose(result.ref_vel["vehicle"], 0.09 * t**2 + 0.4 * t + 1.2, rtol=8 * EPS)
    # MuJoCo's own force divided by the mass is the textbook acceleration
    np.testing.assert_allclose(result.trajectory.act[:, 0] / 1000.0, 0.18 * t + 0.4, rtol=1e-13)


def test_linear_acceleration_integrates_to_the_textbook_velocity_and_position():
    # a = 1.2 t + 3.0, v(0) = 15, x(0) = 150  =>  v = 0.6 t^2 + 3 t + 15,  x = 0.2 t^3 + 1.5 t^2 + 15 t + 150
    result = springlab.run("kinematics", "linear_acceleration")
    q = result.to_dict()["quantities"]
    assert q["velocity_expression"] == "v(t) = 0.6 t^2 + 3 t + 15 m/s"
    assert q["position_expression"] == "x(t) = 0.2 t^3 + 1.5 t^2 + 15 t + 150 m"
    assert q["v_end_m_s"] == pytest.approx(0.6 * 25 + 15 + 15, rel=1e-12)  # 45 m/s at 5 s
    assert q["x_end_m"] == pytest.approx(0.2 * 125 + 1.5 * 25 + 75 + 150, rel=1e-12)  # 287.5 m
    t = result.time
    np.testing.assert_allclose(result.pos["vehicle"], 0.2 * t**3 + 1.5 * t**2 + 15 * t + 150, rtol=1e-13)
    assert result.to_dict()["passed"] is True


@pytest.mark.parametrize("a, v0, x0", [(2.0, 10.0, 0.0), (-3.0, 20.0, 5.0)])
def test_constant_acceleration_follows_eq_5_5(a, v0, x0):
    result = springlab.run("kinematics", "constant_acceleration", a0=a, v0=v0, x0=x0)
    t = result.time
    np.testing.assert_allclose(result.vel["vehicle"], v0 + a * t, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(result.pos["vehicle"], x0 + v0 * t + 0.5 * a * t**2, rtol=1e-13, atol=1e-11)
    assert result.to_dict()["quantities"]["a_end_m_s2"] == a


def test_tachograph_displacement_is_the_area_under_v_and_acceleration_its_slope():
    result = springlab.run("kinematics", "tachograph")
    q = result.to_dict()["quantities"]
    # 0-4 s: 0 -> 6 m/s, 4-8 s: 6 m/s, 8-12 s: 6 -> 0 m/s; areas 12, 24, 12 m (triangles and a rectangle)
    assert q["segment_accelerations_m_s2"] == [1.5, 0.0, -1.5]
    assert q["segment_displacements_m"] == [12.0, 24.0, 12.0]
    assert q["displacement_m"] == 48.0
    t, x, v = result.time, result.pos["vehicle"], result.vel["vehicle"]
    for when, position, velocity in ((4.0, 12.0, 6.0), (8.0, 36.0, 6.0), (12.0, 48.0, 0.0)):
        i = int(np.argmin(np.abs(t - when)))
        assert x[i] == pytest.approx(position, abs=1e-11)
        assert v[i] == pytest.approx(velocity, abs=1e-11)
    # the exact reference (analytic.piecewise_linear_velocity) against the hand-integrated record
    hand_x = np.where(t < 4, 0.75 * t**2, np.where(t < 8, 12 + 6 * (t - 4), 36 + 6 * (t - 8) - 0.75 * (t - 8) ** 2))
    np.testing.assert_allclose(result.ref_pos["vehicle"], hand_x, rtol=0, atol=1e-12)
    hand_v = np.where(t < 4, 1.5 * t, np.where(t < 8, 6.0, 6.0 - 1.5 * (t - 8)))
    np.testing.assert_allclose(result.ref_vel["vehicle"], hand_v, rtol=0, atol=1e-12)
    # the displacement read off the simulated v(t) by the trapezoid rule (exact for piecewise-linear v)
    assert np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(t)) == pytest.approx(48.0, abs=1e-9)
    assert q["x_end_simulated_m"] == pytest.approx(48.0, abs=1e-11)


@pytest.mark.parametrize("scenario", ["polynomial_position", "linear_acceleration", "tachograph"])
def test_rk4_is_exact_for_cubic_motion_even_at_coarse_steps(scenario):
    # the motion is a polynomial of degree <= 3 on every step, which RK4 integrates exactly:
    # only round-off remains, even with a step of half a second
    result = springlab.run("kinematics", scenario, dt=0.5 if scenario != "tachograph" else 1.0)
    worst = max(e["max_rel"] for e in result.to_dict()["errors"].values())
    assert worst < 1e-13
    assert result.to_dict()["passed"] is True


def test_first_order_integrators_converge_at_first_order_within_their_tolerance():
    errors = []
    for dt in (0.01, 0.005):
        result = springlab.run("kinematics", "polynomial_position", integrator="euler", dt=dt)
        assert result.to_dict()["passed"] is True
        errors.append(result.to_dict()["errors"]["vehicle_pos"]["max_abs"])
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.01)


def test_semi_implicit_euler_errors_match_the_hand_derivation():
    # MuJoCo's euler: act_{k+1} = act_k + h ctrl, v_{k+1} = v_k + h a_k, x_{k+1} = x_k + h v_{k+1},
    # with a_k = a0 + j t_k. Summing the series by hand:
    #   v_k - v(t_k) = -j h t / 2,   x_k - x(t_k) = a0 h t / 2 - j h^2 t / 6   (exactly)
    h, a0, j = 0.01, 0.4, 0.18
    result = springlab.run("kinematics", "polynomial_position", integrator="euler", dt=h)
    t = np.arange(len(result.time)) * h
    np.testing.assert_allclose(result.vel["vehicle"] - (0.09 * t**2 + 0.4 * t + 1.2), -j * h * t / 2, atol=1e-11)
    np.testing.assert_allclose(
        result.pos["vehicle"] - (0.03 * t**3 + 0.2 * t**2 + 1.2 * t + 3.0),
        a0 * h * t / 2 - j * h**2 * t / 6,
        atol=1e-11,
    )


def test_actuator_force_is_the_integrated_control():
    # the documented actuator: dyntype integrator (act' = ctrl), force = gain x act
    with quiet_mujoco() as messages:
        model = mujoco.MjModel.from_xml_path(str(model_files.path("kinematics")))
    assert messages == []
    ramp = model.actuator("force_ramp").id
    assert model.actuator_dyntype[ramp] == mujoco.mjtDyn.mjDYN_INTEGRATOR
    assert model.na == 1
    data = mujoco.MjData(model)
    data.act[0] = 1234.0
    data.ctrl[:] = [77.0, 5.0]
    mujoco.mj_forward(model, data)
    assert data.actuator_force[ramp] == 1234.0
    assert data.act_dot[0] == 77.0
    assert data.qacc[0] * model.body("vehicle").mass[0] == pytest.approx(1234.0 + 5.0, rel=1e-15)


def test_mass_is_read_back_from_the_model_and_does_not_change_the_motion():
    heavy = springlab.run("kinematics", "polynomial_position", mass=12000.0)
    light = springlab.run("kinematics", "polynomial_position", mass=0.5)
    assert heavy.to_dict()["quantities"]["force_expression"] == "F(t) = 2160 t + 4800 N"
    np.testing.assert_allclose(heavy.pos["vehicle"], light.pos["vehicle"], rtol=1e-13)
    default = scenes.get("kinematics").resolve(scenes.get("kinematics").scenario(None), {})
    assert default["mass"] == 1000.0  # models/kinematics.xml


@pytest.mark.parametrize("dt", [0.002, 0.0005])
def test_tachograph_is_exact_on_any_step_grid_through_its_switch_times(dt):
    # MuJoCo's accumulated time overshoots 12 s by round-off at these steps; the run still compares
    result = springlab.run("kinematics", "tachograph", dt=dt)
    assert result.to_dict()["passed"] is True
    assert result.to_dict()["errors"]["vehicle_pos"]["max_rel"] < 1e-11


def test_tachograph_refuses_steps_that_straddle_its_switch_times():
    with pytest.raises(BadInputError, match="dt must divide"):
        springlab.run("kinematics", "tachograph", dt=0.003)


def test_tachograph_refuses_a_run_longer_than_its_record():
    with pytest.raises(BadInputError, match="duration must be <= 12 s"):
        springlab.run("kinematics", "tachograph", duration=13.0)


def test_tachograph_refuses_parameters_its_profile_fixes():
    with pytest.raises(ParameterError, match="valid for tachograph: mass, x0"):
        springlab.run("kinematics", "tachograph", v0=3.0)


def test_constant_acceleration_phase_field_is_tangent_to_its_parabola():
    scene = scenes.get("kinematics")
    case = scene.case("constant_acceleration")
    params = case.params
    field = case.phase_field()
    # orbit v^2 = v0^2 + 2 a (x - x0): its tangent (dx, dv) is parallel to (v, a)
    x = np.linspace(0, 50, 7)
    v = np.sqrt(params["v0"] ** 2 + 2 * params["a0"] * (x - params["x0"]))
    dx, dv = field(x, v)
    np.testing.assert_allclose(dv / dx, params["a0"] / v, rtol=1e-14)
    for name in ("polynomial_position", "tachograph"):
        assert scene.case(name).phase_field() is None  # not autonomous
    assert case.equilibria() == []


@pytest.mark.parametrize(
    "coefficients, text",
    [
        ([3.0, 1.2, 0.2, 0.03], "x(t) = 0.03 t^3 + 0.2 t^2 + 1.2 t + 3 m"),
        ([0.0, -1.0, 1.0], "x(t) = t^2 - t m"),
        ([-2.5], "x(t) = -2.5 m"),
        ([0.0, 0.0], "x(t) = 0 m"),
    ],
)
def test_polynomial_expressions_read_like_the_textbook(coefficients, text):
    assert polynomial_expression("x", coefficients, "m") == text
