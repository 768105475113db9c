"""pitch_heave: the car as a 2-DOF body (heave + pitch) on front and rear axle spring-dampers.

Independent references: the 2x2 matrices written out by hand from the model's
geometry (a = 1.2 m, b = 1.5 m, m = 1000 kg, I = 1500 kg m^2, kf = 0.45e6 N/m,
kr = 0.55e6 N/m, dampers at zeta = 0.3 of each axle's static load), with
scipy's eigh/eig and expm (test-only) for the eigenproblem and the exact motion.
"""

import math

import mujoco
import numpy as np
import pytest
import scipy.linalg

import springlab
from springlab import scenes
from springlab.scenes.car import scene as car_scene

G = 9.81
M, J, A, B = 1000.0, 1500.0, 1.2, 1.5
KF, KR = 0.45e6, 0.55e6
CF = 2 * 0.3 * math.sqrt(KF * M * B / (A + B))
CR = 2 * 0.3 * math.sqrt(KR * M * A / (A + B))
MASS = np.diag([M, J])
# q = (heave [m], pitch [rad], + nose down): front height x - a theta, rear x + b theta
STIFFNESS = np.array([[KF + KR, KR * B - KF * A], [KR * B - KF * A, KF * A**2 + KR * B**2]])
DAMPING = np.array([[CF + CR, CR * B - CF * A], [CR * B - CF * A, CF * A**2 + CR * B**2]])
STATE = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(MASS, STIFFNESS), -np.linalg.solve(MASS, DAMPING)]])


@pytest.fixture(scope="module")
def result():
    return springlab.run("car", "pitch_heave")


def test_parameters_are_the_models_geometry_and_the_stated_split(result):
    p = result.parameters
    assert (p["front_axle_distance"], p["rear_axle_distance"], p["pitch_inertia"]) == (A, B, J)
    assert p["front_stiffness"] == pytest.approx(KF, rel=1e-14)
    assert p["rear_stiffness"] == pytest.approx(KR, rel=1e-14)
    assert p["front_damping"] == pytest.approx(CF, rel=1e-14)
    assert p["rear_damping"] == pytest.approx(CR, rel=1e-14)
    assert p["push_position"] == A  # pushed down over the front axle


def test_mujoco_linearization_gives_exactly_the_textbook_m_c_k(result):
    linear = car_scene.linearize(result.model, np.array([0.10, 0.0]))
    np.testing.assert_allclose(linear["M"], MASS, rtol=1e-9, atol=1e-9 * J)
    np.testing.assert_allclose(linear["K"], STIFFNESS, rtol=1e-8, atol=1e-8 * KF)
    np.testing.assert_allclose(linear["C"], DAMPING, rtol=1e-8, atol=1e-8 * CF)
    assert result.to_dict()["quantities"]["linearization_max_rel_diff"] < 1e-8


def test_natural_frequencies_and_mode_shapes_agree_with_the_2x2_eigenproblem(result):
    q = result.to_dict()["quantities"]
    omega2, shapes = scipy.linalg.eigh(STIFFNESS, MASS)
    for i in (0, 1):
        assert q[f"omega_{i + 1}_rad_s"] == pytest.approx(math.sqrt(omega2[i]), rel=1e-9)
        assert q[f"omega_{i + 1}_analytic_rad_s"] == pytest.approx(math.sqrt(omega2[i]), rel=1e-12)
        ratio = shapes[1, i] / shapes[0, i]
        assert q[f"mode_{i + 1}_pitch_per_heave_rad_m"] == pytest.approx(ratio, rel=1e-8)
        assert q[f"mode_{i + 1}_node_m"] == pytest.approx(1 / ratio, rel=1e-8)
    # bounce mode's node lies outside the wheelbase, pitch mode's inside it
    assert q["mode_1_node_m"] < -B and -B < q["mode_2_node_m"] < A


def test_modal_damping_ratios_agree_with_the_damped_eigenvalues(result):
    q = result.to_dict()["quantities"]
    state = STATE
    roots = sorted((r for r in np.linalg.eigvals(state) if r.imag > 0), key=abs)
    for i, root in enumerate(roots, start=1):
        assert q[f"mode_{i}_damping_ratio"] == pytest.approx(-root.real / abs(root), rel=1e-8)
        assert q[f"omega_d_{i}_rad_s"] == pytest.approx(root.imag, rel=1e-8)
        # the damping ratio's own natural frequency |lambda| (python-control's damp: 4.678 / 5.939 Hz),
        # not the undamped frequency_i_hz (4.6746 / 5.9429 Hz) beside it
        assert q[f"mode_{i}_natural_frequency_hz"] == pytest.approx(abs(root) / (2 * math.pi), rel=1e-8)
    assert q["mode_1_natural_frequency_hz"] == pytest.approx(4.678, abs=5e-4)
    assert q["mode_2_natural_frequency_hz"] == pytest.approx(5.939, abs=5e-4)
    assert abs(q["mode_1_natural_frequency_hz"] - q["frequency_1_hz"]) > 1e-3


def test_transition_fd_of_a_fine_euler_step_converges_to_the_same_eigenvalues(result):
    # mjd_transitionFD gives the discrete-time A of one step; log(eig)/dt -> continuous roots as dt -> 0
    model = result.model
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    model.opt.timestep = 1e-5
    data = mujoco.MjData(model)
    data.qpos[:] = [0.10, 0.0]
    mujoco.mj_forward(model, data)
    a = np.zeros((2 * model.nv, 2 * model.nv))
    mujoco.mjd_transitionFD(model, data, 1e-7, True, a, None, None, None)
    discrete = np.log(np.linalg.eigvals(a).astype(complex)) / model.opt.timestep
    state = STATE
    exact = np.linalg.eigvals(state)
    for root in exact:
        # first order: |error| ~ |lambda|^2 dt / 2 = 0.7 % of |lambda| ... here 1e-5 s: < 1e-3 relative
        assert np.min(np.abs(discrete - root)) < 1e-3 * abs(root)


def test_release_after_a_push_over_the_front_axle_is_the_exact_linear_motion(result):
    force = 250 * G
    q0 = np.array([0.10, 0.0]) + np.linalg.solve(STIFFNESS, [-force, force * A])
    state = STATE
    # deviation from the equilibrium (0.10 m, 0 rad) moves as exp(A t) z0
    z0 = np.concatenate([q0 - [0.10, 0.0], [0.0, 0.0]])
    t = result.time
    step = scipy.linalg.expm(state * (t[1] - t[0]))
    z = np.empty((len(t), 4))
    z[0] = z0
    for n in range(1, len(t)):
        z[n] = step @ z[n - 1]
    heave, pitch = result.pos["heave"] - 0.10, result.pos["pitch"]
    # validated to 1e-6 at its default 2 ms (RK4, predicted bound 5.4e-7)
    assert np.max(np.abs(heave - z[:, 0])) < 1e-6 * np.max(np.abs(z[:, 0]))
    assert np.max(np.abs(pitch - z[:, 1])) < 1e-6 * np.max(np.abs(z[:, 1]))
    assert np.max(np.abs(result.vel["pitch"] - z[:, 3])) < 1e-6 * np.max(np.abs(z[:, 3]))
    assert result.to_dict()["passed"] is True
    q = result.to_dict()["quantities"]
    assert q["initial_heave_offset_m"] == pytest.approx(z0[0], rel=1e-12)
    assert q["initial_pitch_rad"] == pytest.approx(z0[1], rel=1e-12) and z0[1] > 0  # nose down


def test_heave_stays_the_bottom_height_below_the_centre_of_mass_at_any_pitch(result):
    # the hinge passes through the centre of mass, 0.45 m above the car bottom
    model, data = result.model, mujoco.MjData(result.model)
    for heave, pitch in ((0.1, 0.0), (0.09, 0.05), (0.12, -0.1)):
        data.qpos[:] = [heave, pitch]
        mujoco.mj_kinematics(model, data)
        assert data.body("car").xipos[2] == pytest.approx(heave + 0.45, abs=1e-14)
        # a positive pitch lowers the front axle station: rigid rotation, -a sin(theta) to first order
        front = data.site("front_axle").xpos[2] - data.body("car").xipos[2]
        assert front == pytest.approx(-A * math.sin(pitch) + (0.6 - 0.45) * math.cos(pitch), abs=1e-14)


def test_axle_springs_are_fixed_tendons_linear_in_the_joint_coordinates(result):
    model, data = result.model, mujoco.MjData(result.model)
    data.qpos[:] = [0.093, 0.02]
    mujoco.mj_forward(model, data)
    assert data.ten_length[model.tendon("front_suspension").id] == pytest.approx(0.093 - A * 0.02, abs=1e-15)
    assert data.ten_length[model.tendon("rear_suspension").id] == pytest.approx(0.093 + B * 0.02, abs=1e-15)


def test_static_equilibrium_is_at_the_clearance_with_the_load_split_by_the_lever_rule(result):
    model = scenes.get("car").build(result.parameters, scenes.get("car").scenario("pitch_heave"))
    data = mujoco.MjData(model)
    data.qpos[:] = [0.10, 0.0]
    mujoco.mj_forward(model, data)
    np.testing.assert_allclose(data.qacc, 0.0, atol=1e-9)
    forces = -model.tendon_stiffness * (data.ten_length - model.tendon_lengthspring[:, 0])
    assert forces[model.tendon("front_suspension").id] == pytest.approx(M * G * B / (A + B), rel=1e-12)
    assert forces[model.tendon("rear_suspension").id] == pytest.approx(M * G * A / (A + B), rel=1e-12)


@pytest.mark.parametrize(
    "overrides, message",
    [
        ({"push_mass": 5000.0}, "through the ground"),
        ({"push_mass": 2000.0}, "off its front springs"),
        ({"pitch_inertia": 0.0}, "pitch_inertia must be"),
        ({"front_damping": 100.0, "damping_ratio": 0.2}, "not both"),
        ({"stiffness": 2e6}, "does not apply"),
    ],
)
def test_bad_pitch_heave_input_is_rejected(overrides, message):
    with pytest.raises(springlab.BadInputError, match=message):
        springlab.run("car", "pitch_heave", **overrides)
