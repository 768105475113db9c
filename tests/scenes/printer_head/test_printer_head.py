"""The printer head in MuJoCo agrees with the exact 2-DOF solution of M q'' + C q' + K q = f(t).

The references here are built in the test from the parameters alone: M, C, K in
(q_c, q_m) by hand, the exact solution by scipy.linalg.expm of the augmented
system (q, v, F) piecewise over the force segments, the belt mode from the 2x2
generalized eigenproblem, the linearization from mujoco.mjd_transitionFD. None of
them calls the package's own reference, analytic module or settling helpers.
"""

import math

import mujoco
import numpy as np
import pytest
import scipy.linalg

import springlab
import springlab.sim.model_files

BELT = np.array([[1.0, -1.0], [-1.0, 1.0]])  # the belt stretches by q_m - q_c


def _matrices(p):
    """M [kg], C [N s/m], K [N/m] in (q_c, q_m) from the run's parameters."""
    return (np.diag([p["carriage_mass"], p["motor_mass"]]), p["belt_damping"] * BELT, p["belt_stiffness"] * BELT)


def _segments(p, scenario, dt):
    """(start times [s], motor force [N]) of the scenario's input, derived from its definition."""
    if scenario == "step_force":
        return [0.0], [p["drive_force"]]
    if scenario == "move":
        total = p["carriage_mass"] + p["motor_mass"]
        # the half-move time sqrt(D M / F) rounded up to whole steps, force lowered to stop at D
        n = math.ceil(math.sqrt(p["move_distance"] * total / p["drive_force"]) / dt - 1e-9)
        force = total * p["move_distance"] / (n * dt) ** 2
        return [0.0, n * dt, 2 * n * dt], [force, -force, 0.0]
    return [0.0], [0.0]


def _initial(p):
    """(q0, v0): belt stretched by `deflection`, centre of mass at rest at 0."""
    m_c, m_m, s0 = p["carriage_mass"], p["motor_mass"], p["deflection"]
    return np.array([-m_m * s0, m_c * s0]) / (m_c + m_m), np.zeros(2)


def _augmented(p):
    """A [1/s] of z = (q_c, q_m, v_c, v_m, F), z' = A z: the force a constant generator state."""
    mass, damping, stiffness = _matrices(p)
    inverse = np.linalg.inv(mass)
    a = np.zeros((5, 5))
    a[0:2, 2:4] = np.eye(2)
    a[2:4, 0:2] = -inverse @ stiffness
    a[2:4, 2:4] = -inverse @ damping
    a[2:4, 4] = inverse @ np.array([0.0, 1.0])  # the force acts on the motor joint
    return a


def _exact(p, scenario, dt, time):
    """Exact (q, v) at `time` [s], each (len(time), 2): expm of the augmented 5x5 system per segment."""
    a = _augmented(p)
    starts, forces = _segments(p, scenario, dt)
    q0, v0 = _initial(p)
    state = np.concatenate([q0, v0, [forces[0]]])
    out = np.empty((len(time), 5))
    bounds = list(starts[1:]) + [math.inf]
    for i, (start, end) in enumerate(zip(starts, bounds)):
        state[4] = forces[i]
        inside = (time >= start - 1e-12) & (time < end - 1e-12)
        for j in np.flatnonzero(inside):
            out[j] = scipy.linalg.expm(a * (time[j] - start)) @ state
        if math.isfinite(end):
            state = scipy.linalg.expm(a * (end - start)) @ state
    return out[:, 0:2], out[:, 2:4]


def _belt_mode(p):
    """(omega_n [rad/s], zeta [-]) of the flexible mode from the 2x2 M, C, K.

    K v = omega^2 M v has omega = 0 (rigid body) and the belt mode; C is
    proportional to K, so the mode's damping ratio is c_modal / (2 omega m_modal).
    """
    mass, damping, stiffness = _matrices(p)
    omega_sq, vectors = scipy.linalg.eigh(stiffness, mass)
    shape = vectors[:, np.argmax(omega_sq)]
    omega = math.sqrt(max(omega_sq))
    zeta = (shape @ damping @ shape) / (2 * omega * (shape @ mass @ shape))
    return omega, zeta


def _last_exit(time, deviation, band):
    """Time [s] of the last sample of |deviation| above `band`, 0 if none."""
    outside = np.flatnonzero(np.abs(deviation) > band)
    return 0.0 if outside.size == 0 else float(time[outside[-1]])


@pytest.mark.parametrize("scenario", ["step_force", "move", "settle"])
def test_trajectories_match_the_exact_two_dof_solution(scenario):
    result = springlab.run("printer_head", scenario)
    p, dt = result.parameters, result.to_dict()["dt"]
    every = 10  # expm per sample is the cost; every 10th step covers every phase of the 195 Hz mode
    time = result.time[::every]
    q, v = _exact(p, scenario, dt, time)
    omega, _ = _belt_mode(p)
    # RK4 is exact on the rigid-body motion (piecewise cubic) and switches on step boundaries are
    # exact: the error is the belt mode's, (omega t)(omega dt)^4 / 120 of its carriage amplitude
    vibration = np.max(np.abs(q[:, 1] - q[:, 0])) * p["motor_mass"] / (p["carriage_mass"] + p["motor_mass"])
    predicted = 2 * omega * time[-1] * (omega * dt) ** 4 / 120 * vibration
    scale = max(np.max(np.abs(q)), 1e-12)
    for column, joint in enumerate(("carriage", "motor")):
        position_error = np.max(np.abs(result.pos[joint][::every] - q[:, column]))
        velocity_error = np.max(np.abs(result.vel[joint][::every] - v[:, column]))
        assert position_error <= predicted + 1e-12 * scale, joint
        assert velocity_error <= omega * predicted + 1e-12 * scale * omega, joint
    assert result.to_dict()["passed"] is True


def test_move_stops_the_centre_of_mass_exactly_at_the_distance():
    result = springlab.run("printer_head", "move")
    p = result.parameters
    total = p["carriage_mass"] + p["motor_mass"]
    centre = (p["carriage_mass"] * result.pos["carriage"] + p["motor_mass"] * result.pos["motor"]) / total
    q = result.to_dict()["quantities"]
    after = result.time >= q["move_time_s"] - 1e-12
    np.testing.assert_allclose(centre[after], p["move_distance"], rtol=0, atol=1e-12)


def test_belt_mode_frequency_and_damping_ratio_match_the_two_by_two_eigenproblem():
    result = springlab.run("printer_head", "settle", duration=0.001)
    q = result.to_dict()["quantities"]
    omega, zeta = _belt_mode(result.parameters)
    assert q["natural_frequency_hz"] == pytest.approx(omega / (2 * math.pi), rel=1e-12)
    assert q["damping_ratio"] == pytest.approx(zeta, rel=1e-12)
    # the XML's comment: 195 Hz at zeta = 0.030 (k = 5e4 N/m, mu = 0.2 * 0.04 / 0.24 kg)
    assert q["natural_frequency_hz"] == pytest.approx(math.sqrt(5e4 / (0.2 * 0.04 / 0.24)) / (2 * math.pi))
    assert q["damping_ratio"] == pytest.approx(0.030, abs=1e-4)
    # the scene's own linearization of RK4's step map: off by RK4's (omega dt)^4 / 120 per radian
    omega_dt = omega * result.to_dict()["dt"]
    rk4 = 2 * omega_dt**4 / 120
    assert q["linearized_natural_frequency_hz"] == pytest.approx(omega / (2 * math.pi), rel=rk4)
    assert q["linearized_damping_ratio"] == pytest.approx(zeta, rel=rk4 / zeta)


def _transition_mode(model, integrator, dt):
    """(omega_n [rad/s], zeta [-]) of the belt from mjd_transitionFD's eigenvalues, s = ln(lambda) / dt."""
    model.opt.integrator = integrator
    model.opt.timestep = dt
    data = mujoco.MjData(model)
    a = np.zeros((2 * model.nv, 2 * model.nv))
    mujoco.mjd_transitionFD(model, data, 1e-8, True, a, None, None, None)
    roots = np.log(np.linalg.eigvals(a).astype(complex)) / dt
    belt = roots[np.argsort(-np.abs(roots))[:2]]  # the rigid-body roots are 0
    omega = math.sqrt(float(np.real(belt[0] * belt[1])))
    return omega, -float(np.real(belt[0] + belt[1])) / (2 * omega)


@pytest.mark.parametrize("integrator", [mujoco.mjtIntegrator.mjINT_EULER, mujoco.mjtIntegrator.mjINT_IMPLICIT])
def test_mujoco_linearization_converges_to_the_analytic_belt_mode_at_first_order(integrator):
    # mjd_transitionFD refuses RK4; euler and implicit are first order, so the roots they realize
    # are off by O(zeta omega dt): measured at two timesteps, the error must shrink ~10x per 10x dt
    result = springlab.run("printer_head", "settle", duration=0.001)
    omega, zeta = _belt_mode(result.parameters)
    errors = []
    for dt in (1e-5, 1e-6):
        lin_omega, lin_zeta = _transition_mode(result.model, integrator, dt)
        bound = zeta * omega * dt + (omega * dt) ** 2  # leading first-order term x2, plus second order
        assert abs(lin_omega / omega - 1) <= bound
        assert abs(lin_zeta / zeta - 1) <= bound
        errors.append(abs(lin_zeta / zeta - 1))
    assert 5 <= errors[0] / errors[1] <= 20


@pytest.mark.parametrize(
    "scenario, overrides",
    [
        ("move", {}),
        ("settle", {}),
        ("move", {"belt_stiffness": 2e4, "belt_damping": 3.0}),
    ],
)
def test_settling_time_matches_the_exact_trajectory_within_one_step(scenario, overrides):
    result = springlab.run("printer_head", scenario, **overrides)
    p, dt = result.parameters, result.to_dict()["dt"]
    q = result.to_dict()["quantities"]
    band = q["settling_band_m"]
    start = q.get("move_time_s", 0.0)
    target = p["move_distance"] if scenario == "move" else 0.0
    # the exact carriage position sampled 20x finer than the simulation from the move's end (force
    # off from there): the exact state there, then the exact one-sample transition expm(A h) repeated
    (q0,), (v0,) = _exact(p, scenario, dt, np.array([start]))
    fine = np.arange(0.0, result.time[-1] - start, dt / 20)
    transition = scipy.linalg.expm(_augmented(p) * (dt / 20))
    state = np.concatenate([q0, v0, [0.0]])
    carriage = np.empty(len(fine))
    for i in range(len(fine)):
        carriage[i] = state[0]
        state = transition @ state
    exact = _last_exit(fine, carriage - target, band)
    assert exact > 0  # the case does leave the band, so the comparison means something
    assert q["settled_for_good"] is True
    assert abs(q["settling_time_s"] - exact) <= dt


def test_bang_bang_move_takes_the_minimum_time_2_sqrt_dm_over_f():
    result = springlab.run("printer_head", "move")
    p, dt = result.parameters, result.to_dict()["dt"]
    q = result.to_dict()["quantities"]
    minimum = 2 * math.sqrt(p["move_distance"] * (p["carriage_mass"] + p["motor_mass"]) / p["drive_force"])
    assert q["minimum_move_time_s"] == pytest.approx(minimum, rel=1e-14)
    # rounded up to the step grid: at most one step more per half
    assert minimum <= q["move_time_s"] <= minimum + 2 * dt
    assert q["move_force_n"] <= p["drive_force"]
    assert q["positioning_time_s"] == pytest.approx(q["move_time_s"] + q["settling_time_s"])


def test_positioning_time_estimate_is_the_runs_move_time_plus_the_estimated_settling():
    # definition (docs/scenes/printer_head.md): the move this run makes is known exactly, so only the
    # settling is estimated: realized move time 2 n dt + ln(A / band) / (zeta omega_n), A the envelope of
    # the exact residual vibration after the move (not the minimum move time 2 sqrt(D M / F))
    result = springlab.run("printer_head", "move")
    p, dt = result.parameters, result.to_dict()["dt"]
    q = result.to_dict()["quantities"]
    starts, _ = _segments(p, "move", dt)
    move_time = starts[2]
    q_exact, v_exact = _exact(p, "move", dt, np.array([move_time]))
    q_end, v_end = q_exact[0], v_exact[0]
    omega, zeta = _belt_mode(p)
    omega_d = omega * math.sqrt(1 - zeta**2)
    stretch, rate = q_end[1] - q_end[0], v_end[1] - v_end[0]
    total = p["carriage_mass"] + p["motor_mass"]
    envelope = p["motor_mass"] / total * math.hypot(stretch, (rate + zeta * omega * stretch) / omega_d)
    settling = math.log(envelope / p["positioning_band"]) / (zeta * omega)
    # expm of the 5x5 system: relative error ~ eps x its condition (exp of omega t ~ 1e3 rad), far below 1e-9
    assert q["move_time_s"] == pytest.approx(move_time, rel=1e-12)
    assert q["positioning_time_estimate_s"] == pytest.approx(move_time + settling, rel=1e-9)
    minimum = 2 * math.sqrt(p["move_distance"] * total / p["drive_force"])
    assert abs(q["positioning_time_estimate_s"] - (minimum + settling)) > 0.5 * (move_time - minimum)


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["run", "printer_head", "move", "--set", "carriage_mass=-0.2"], "carriage_mass"),
        (["run", "printer_head", "move", "--set", "belt_stiffness=0"], "belt_stiffness"),
        (["run", "printer_head", "move", "--set", "belt_damping=-1"], "belt_damping"),
        (["run", "printer_head", "move", "--set", "drive_force=nan"], "drive_force"),
        (["run", "printer_head", "jump"], "move"),
    ],
)
def test_non_physical_values_exit_2_with_one_line(argv, needle, cli):
    code, out, err = cli(*argv)
    assert code == 2
    assert out == ""
    assert len(err.strip().splitlines()) == 1
    assert needle in err


def test_model_is_lean_the_belt_is_the_only_tendon():
    model = mujoco.MjModel.from_xml_path(str(springlab.sim.model_files.path("printer_head")))
    assert np.all(model.opt.gravity == 0)
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONSTRAINT  # nothing is limited
    assert np.all(model.dof_armature == 0) and np.all(model.dof_frictionloss == 0)
    assert model.ntendon == 1  # the belt; its picture is drawn by the renderer, not computed every step
    assert model.tendon("belt").id == 0


@pytest.mark.parametrize("periods", [6.5, 7.0, 7.25])
def test_undamped_residual_vibration_is_4_sin_squared_of_omega_t_over_4_times_the_static_stretch(periods):
    # superposed force steps +F', -2F', +F' at 0, T/2, T leave an undamped belt oscillating with
    # amplitude |1 - exp(i omega T / 2)|^2 = 4 sin^2(omega T / 4) times the static stretch F' m_c/(M k);
    # the carriage sees m_m / M of it. The stiffness is chosen so each half-move lasts `periods` belt
    # periods (whole numbers cancel the vibration: input shaping by the move time alone).
    default = springlab.run("printer_head", "move", duration=0.001).parameters
    m_c, m_m = default["carriage_mass"], default["motor_mass"]
    total, reduced = m_c + m_m, m_c * m_m / (m_c + m_m)
    half = math.sqrt(default["move_distance"] * total / default["drive_force"])
    stiffness = reduced * (2 * math.pi * periods / half) ** 2
    result = springlab.run("printer_head", "move", belt_stiffness=stiffness, belt_damping=0.0, duration=0.1)
    q, dt = result.to_dict()["quantities"], result.to_dict()["dt"]
    omega = math.sqrt(stiffness / reduced)
    assert q["half_move_belt_periods"] == pytest.approx(q["move_time_s"] / 2 * omega / (2 * math.pi), rel=1e-12)
    assert q["half_move_belt_periods"] == pytest.approx(periods, abs=omega * dt / (2 * math.pi))  # grid rounding
    static = q["move_force_n"] * m_c / (total * stiffness)
    amplitude = (m_m / total) * 4 * static * math.sin(omega * q["move_time_s"] / 4) ** 2
    # sampled peaks fall short of the amplitude by at most a factor cos(omega dt / 2)
    rk4 = 2 * omega * 0.1 * (omega * dt) ** 4 / 120 * 4 * static
    assert amplitude * math.cos(omega * dt / 2) - rk4 <= q["residual_amplitude_m"] <= amplitude + rk4
    if periods == 7.0:
        assert q["residual_amplitude_m"] < 0.01 * (m_m / total) * 4 * static
