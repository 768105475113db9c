"""The car on its suspension: the textbook's push-and-release (section 5.3) and the damped release.

Independent references: the textbook's own numbers (m = 1000 kg, k = 1e6 N/m,
250 kg of passers-by, clearance 0.10 m, g = 9.81 m/s^2) worked by hand, and the
closed forms of the free vibration written out here.
"""

import math

import mujoco
import numpy as np
import pytest

import springlab
from springlab import scenes
from springlab.sim import model_files
from springlab.sim.simulate import quiet_mujoco

G = 9.81
M, K, CLEARANCE, PUSH = 1000.0, 1e6, 0.10, 250.0
OMEGA = math.sqrt(K / M)  # 31.6227766 rad/s
SAG = PUSH * G / K  # 2.4525 mm


@pytest.fixture(scope="module")
def textbook():
    return springlab.run("car", "push_release")


def test_textbook_values_are_the_model_defaults(textbook):
    p = textbook.parameters
    assert (p["mass"], p["stiffness"], p["damping"], p["clearance"], p["push_mass"]) == (M, K, 0.0, CLEARANCE, PUSH)
    model = mujoco.MjModel.from_xml_path(str(model_files.path("car")))
    assert tuple(model.opt.gravity) == (0.0, 0.0, -G)


def test_static_sag_is_push_weight_over_k_and_the_height_before_release_follows(textbook):
    q = textbook.to_dict()["quantities"]
    assert q["static_sag_m"] == pytest.approx(0.0024525, rel=1e-12)  # 250 * 9.81 / 1e6
    assert q["height_before_release_m"] == pytest.approx(0.0975475, rel=1e-12)
    assert textbook.pos["heave"][0] == pytest.approx(0.0975475, rel=1e-12)


def test_equilibrium_amplitude_and_omega_are_the_textbook_answers(textbook):
    q = textbook.to_dict()["quantities"]
    assert q["equilibrium_height_m"] == pytest.approx(0.10, rel=1e-12)
    assert q["amplitude_m"] == pytest.approx(-0.0024525, rel=1e-12)  # starts below x_s
    assert q["omega_rad_s"] == pytest.approx(31.6227766017, rel=1e-10)  # sqrt(1000)
    assert q["period_s"] == pytest.approx(2 * math.pi / math.sqrt(1000.0), rel=1e-12)
    assert q["sag_under_own_weight_m"] == pytest.approx(0.00981, rel=1e-12)


def test_heave_follows_xs_plus_a_cos_omega_t(textbook):
    t = textbook.time
    expected = CLEARANCE - SAG * np.cos(OMEGA * t)
    # RK4's phase error: omega t (omega dt)^4 / 120 = 2.6e-7 of the amplitude after 1 s at 1 ms
    rk4 = OMEGA * t[-1] * (OMEGA * textbook.to_dict()["dt"]) ** 4 / 120
    assert rk4 < 1e-6
    assert np.max(np.abs(textbook.pos["heave"] - expected)) < 1.5 * rk4 * SAG
    assert np.max(np.abs(textbook.vel["heave"] - SAG * OMEGA * np.sin(OMEGA * t))) < 1.5 * rk4 * SAG * OMEGA
    assert textbook.to_dict()["passed"] is True


def test_phase_plane_is_an_ellipse_centred_at_the_equilibrium(textbook):
    q = textbook.to_dict()["quantities"]
    x, v = textbook.pos["heave"], textbook.vel["heave"]
    radius = ((x - 0.10) / SAG) ** 2 + (v / (OMEGA * SAG)) ** 2
    assert np.max(np.abs(radius - 1.0)) < 1e-6  # RK4 drifts mostly in phase, which keeps the ellipse
    assert q["phase_ellipse_height_semi_axis_m"] == pytest.approx(SAG, rel=1e-12)
    assert q["phase_ellipse_velocity_semi_axis_m_s"] == pytest.approx(SAG * OMEGA, rel=1e-12)
    # sampled maxima: a peak can fall half a step from a sample, 1 - cos(omega dt / 2) = (omega dt)^2 / 8
    sampling = (OMEGA * textbook.to_dict()["dt"]) ** 2 / 8
    assert q["max_height_m"] == pytest.approx(CLEARANCE + SAG, abs=SAG * sampling)
    assert q["max_speed_m_s"] == pytest.approx(SAG * OMEGA, rel=sampling)


def test_heave_is_the_height_of_the_car_bottom_above_the_ground(textbook):
    model, data = textbook.model, mujoco.MjData(textbook.model)
    for height in (0.0975475, 0.1, 0.1024525):
        data.qpos[model.joint("heave").qposadr[0]] = height
        mujoco.mj_kinematics(model, data)
        assert data.body("car").xpos[2] == pytest.approx(height, abs=1e-15)  # body frame = car bottom


def test_shipped_model_rests_at_the_clearance_in_static_equilibrium():
    with quiet_mujoco() as messages:
        model = mujoco.MjModel.from_xml_path(str(model_files.path("car")))
        data = mujoco.MjData(model)
        for _ in range(2000):
            mujoco.mj_step(model, data)
    assert messages == []
    assert model.nv == 1
    assert data.qpos[0] == pytest.approx(0.10, abs=1e-13)
    assert model.qpos_spring[0] == pytest.approx(0.10 + 1000 * 9.81 / 1e6, rel=1e-12)  # springref


def test_springref_is_recomputed_so_rest_stays_at_the_clearance_for_any_mass():
    scene = scenes.get("car")
    scenario = scene.scenario("push_release")
    params = scene.resolve(scenario, {"mass": 1300.0, "clearance": 0.15})
    model = scene.build(params, scenario)
    assert model.qpos_spring[0] == pytest.approx(0.15 + 1300 * G / K, rel=1e-12)
    assert model.qpos0[0] == pytest.approx(0.15)


def test_model_is_lean():
    model = mujoco.MjModel.from_xml_path(str(model_files.path("car")))
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    assert model.nv == 1 and model.nu == 0
    assert model.dof_armature[0] == 0 and model.dof_frictionloss[0] == 0
    assert model.tendon_stiffness.sum() == 0 and model.tendon_damping.sum() == 0  # the springs drawn are pictures
    assert model.camera("side").id >= 0


# -- damped release ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def damped():
    return springlab.run("car", "damped_release")


def test_default_damping_ratio_is_a_typical_passenger_car_value(damped):
    # Gillespie, Fundamentals of Vehicle Dynamics, ch. 5: 0.2-0.4
    assert damped.parameters["damping_ratio"] == 0.3
    assert damped.parameters["damping"] == pytest.approx(2 * 0.3 * math.sqrt(K * M), rel=1e-14)
    assert damped.to_dict()["quantities"]["damping_ratio"] == pytest.approx(0.3, rel=1e-12)


def test_damped_release_matches_the_underdamped_closed_form(damped):
    zeta = 0.3
    omega_d = OMEGA * math.sqrt(1 - zeta**2)
    t = damped.time
    # x - x_s = e^(-zeta w t) (A cos wd t + zeta w A / wd sin wd t), A = -sag, released at rest
    expected = CLEARANCE - SAG * np.exp(-zeta * OMEGA * t) * (
        np.cos(omega_d * t) + zeta * OMEGA / omega_d * np.sin(omega_d * t)
    )
    # validated to 1e-6 at its default 2 ms (predicted bound 5.6e-7)
    assert np.max(np.abs(damped.pos["heave"] - expected)) < 1e-6 * SAG
    q = damped.to_dict()["quantities"]
    assert q["omega_d_rad_s"] == pytest.approx(omega_d, rel=1e-12)
    assert q["regime"] == "underdamped"


def test_logarithmic_decrement_measured_from_the_peaks_equals_2_pi_zeta_over_sqrt(damped):
    q = damped.to_dict()["quantities"]
    theory = 2 * math.pi * 0.3 / math.sqrt(1 - 0.09)
    assert q["logarithmic_decrement"] == pytest.approx(theory, rel=1e-12)
    # peaks from the velocity's zeros with a cubic Hermite interpolant: O(dt^4) accurate
    assert q["logarithmic_decrement_measured"] == pytest.approx(theory, rel=1e-6)
    assert q["measured_extrema"] >= 3


def test_setting_damping_directly_reports_its_damping_ratio():
    result = springlab.run("car", "damped_release", damping=2 * 0.25 * math.sqrt(K * M), duration=0.2)
    assert result.parameters["damping_ratio"] == pytest.approx(0.25, rel=1e-12)


@pytest.mark.parametrize(
    "overrides, message",
    [
        ({"push_mass": 20000.0}, "through the ground"),
        ({"push_mass": 1500.0}, "off its springs"),
        ({"mass": 0.0}, "mass must be"),
        ({"stiffness": -1.0}, "stiffness must be"),
        ({"damping": -5.0}, "damping must be"),
        ({"speed": 3.0}, "does not apply"),
    ],
)
def test_non_physical_or_irrelevant_input_is_rejected_with_one_line(overrides, message):
    with pytest.raises(springlab.BadInputError, match=message) as error:
        springlab.run("car", "push_release", **overrides)
    assert "\n" not in str(error.value)


def test_a_damped_car_may_take_a_push_that_would_lift_the_undamped_one():
    # undamped: rebound = sag > m g / k for push_mass > 1000 kg; with zeta = 0.3 the first
    # overshoot is exp(-pi zeta / sqrt(1 - zeta^2)) = 0.372 of it
    overshoot = math.exp(-math.pi * 0.3 / math.sqrt(1 - 0.09))
    result = springlab.run("car", "damped_release", push_mass=1500.0, duration=0.3)
    sampling = (OMEGA * result.to_dict()["dt"]) ** 2 / 8  # the sampled peak, as above
    assert np.max(result.pos["heave"]) - 0.1 == pytest.approx(1500 * G / K * overshoot, rel=sampling)
    with pytest.raises(springlab.BadInputError, match="off its springs"):
        springlab.run("car", "damped_release", push_mass=1.01 * M / overshoot)


def test_both_damping_and_damping_ratio_is_ambiguous():
    with pytest.raises(springlab.BadInputError, match="not both"):
        springlab.run("car", "damped_release", damping=100.0, damping_ratio=0.2)
