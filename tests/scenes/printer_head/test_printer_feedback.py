"""Sampled-data feedback on the printer head: the exact discrete closed loop against references built here,
and MuJoCo running the loop (raw mujoco: mj_forward, sensordata, mj_step with nstep; no scene API).

References: the zero-order-hold map by scipy.linalg.expm and scipy.integrate.quad_vec; the controller's
difference equation and the loop transfer written out here; the closed loop's poles checked as roots of
1 + L(z) with that L. The MuJoCo loop is held to a bound derived from RK4's order (the module docstring of
tests/scenes/printer_head/test_printer_shaping.py): each sample adds at most N |R(z) - e^z| |eta_k - eta_eq| to the belt
mode's coordinate eta (N steps of dt per sample, z = lambda dt, eta_eq the equilibrium under the held force), and
that error reaches the encoder through the exact closed loop's powers, sum_j |C A_cl^(k-1-j) W| delta_j.
"""

import math

import mujoco
import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

import springlab.sim.model_files
from helpers.printer_head import PERIOD, REFERENCE, SUBSTEPS, feedback_plant, reference_loop, rk4_loop_bound
from springlab.exact import sampled_loop
from springlab.scenes.printer_head import control
from springlab.sim.sampled import run_sampled, steps_per_sample

EPS = np.finfo(float).eps
#: PD gains [N/m], [N s/m], [N/(m s)]: the motor loop's and a PID variant; the carriage loop's, stable
MOTOR_GAINS = (2000.0, 30.0, 0.0)
PID_GAINS = (2000.0, 30.0, 20000.0)
CARRIAGE_GAINS = (500.0, 15.0, 0.0)


def _model(force_limit=False):
    spec = mujoco.MjSpec.from_file(str(springlab.sim.model_files.path("printer_head")))
    control.add_instruments(spec, force_limit=force_limit)
    model = spec.compile()
    model.opt.timestep = PERIOD / SUBSTEPS
    return model


def _loop_value(phi, gamma, row, gains, z):
    """L(z) = K(z) P(z) at a complex z, written out."""
    kp, kd, ki = gains
    plant = np.linalg.solve(z * np.eye(4) - phi, gamma.astype(complex))[row]
    law = kp + kd * (z - 1) / (PERIOD * z) + (ki * PERIOD * z / (z - 1) if ki else 0.0)
    return law * plant


# -- the exact sampled-data loop ------------------------------------------------------------------------------


def test_zero_order_hold_map_is_the_exponential_and_its_integral():
    a, b = feedback_plant()
    phi, gamma = sampled_loop.zoh(*control.belt_plant(_model()), PERIOD)
    assert np.allclose(phi, scipy.linalg.expm(a * PERIOD), rtol=0, atol=64 * EPS)
    quadrature = scipy.integrate.quad_vec(lambda t: scipy.linalg.expm(a * t) @ b[:, 0], 0.0, PERIOD, epsrel=1e-14)[0]
    assert gamma[:, 0] == pytest.approx(quadrature, rel=1e-12, abs=1e-12 * np.abs(quadrature).max())


def test_the_open_loop_held_run_is_the_held_run_bit_for_bit():
    # a chirp-like force held over each step from a deflected start: the open-loop path (no call per step) makes
    # the same steps as the general one, and its error propagation without a law the same as the general loop's
    a, b = control.belt_plant(_model())
    dt, steps = PERIOD / SUBSTEPS, 3000
    k = np.arange(steps)
    force = 3.0 * np.sin(2e-5 * k * k) * np.cos(0.01 * k)
    start = np.array([1e-3, -2e-3, 0.05, -0.01])
    states, forces = sampled_loop.held_run(a, b, dt, steps, start, lambda j, x: float(force[j]))
    open_states, open_forces = sampled_loop.held_open_run(a, b, dt, start, force)
    assert np.array_equal(open_states, states) and np.array_equal(open_forces, forces)
    error = sampled_loop.held_run_error(a, b, dt, 4, 1 / 120, states, forces)
    general = sampled_loop.held_run_error(a, b, dt, 4, 1 / 120, states, forces, response=lambda j, e: 0.0)
    assert np.array_equal(error, general)


@pytest.mark.parametrize(
    ("encoder", "gains"), [("motor", MOTOR_GAINS), ("motor", PID_GAINS), ("carriage", CARRIAGE_GAINS)]
)
def test_exact_step_response_is_the_difference_equation(encoder, gains):
    row = control.ENCODERS[encoder][1]
    expected_y, expected_u, phi, gamma = reference_loop(gains, row, 2000)
    pid = sampled_loop.Pid(*gains, PERIOD)
    a, b = control.belt_plant(_model())
    y, u, _ = sampled_loop.step_response(
        *sampled_loop.zoh(a, b, PERIOD), control.output_row(encoder), pid, REFERENCE, 2000
    )
    # 2000 samples of a stable loop: round-off grows at most linearly, from entries of size REFERENCE
    assert np.max(np.abs(y - expected_y)) <= 1e4 * EPS * REFERENCE
    assert np.max(np.abs(u - expected_u)) <= 1e4 * EPS * max(gains) * REFERENCE
    # its fixed point is the set point: no steady-state error (the plant integrates, PD or PID alike)
    a_cl, b_cl, _, _ = sampled_loop.closed_loop(phi, gamma[:, None], control.output_row(encoder), pid)
    fixed = np.linalg.solve(np.eye(len(a_cl)) - a_cl, b_cl * REFERENCE)
    assert fixed[row] == pytest.approx(REFERENCE, rel=1e6 * EPS)


@pytest.mark.parametrize(
    ("encoder", "gains"), [("motor", MOTOR_GAINS), ("motor", PID_GAINS), ("carriage", CARRIAGE_GAINS)]
)
def test_closed_loop_poles_are_the_roots_of_one_plus_the_loop_transfer(encoder, gains):
    a, b = control.belt_plant(_model())
    phi, gamma = sampled_loop.zoh(a, b, PERIOD)
    row = control.ENCODERS[encoder][1]
    pid = sampled_loop.Pid(*gains, PERIOD)
    poles = np.linalg.eigvals(sampled_loop.closed_loop(phi, gamma, control.output_row(encoder), pid)[0])
    assert len(poles) == 4 + 1 + (gains[2] > 0)
    for pole in poles:
        value = _loop_value(phi, gamma[:, 0], row, gains, pole)
        # relative to the size of the terms that cancel (|L| ~ 1 at a root); clustered poles near z = 1 (the
        # rigid body's slow pair) are known to sqrt(eps) only
        assert abs(1 + value) <= 1e-6 * max(1.0, abs(value))
    assert np.max(np.abs(poles)) < 1


@pytest.mark.parametrize(
    ("encoder", "gains"), [("motor", MOTOR_GAINS), ("motor", PID_GAINS), ("carriage", CARRIAGE_GAINS)]
)
def test_the_margins_grid_brackets_by_the_batched_solves_signs(encoder, gains):
    # margins read their grid only for the signs of Im L, Re L and |L| - 1: the triangular form's grid gives the
    # batched solves' signs everywhere, and its values are within the solves' conditioning (the belt's rigid-body
    # double pole at z = 1: cond(z I - Phi) ~ 1 / |z - 1|^2 on the lowest frequency) of theirs
    a, b = control.belt_plant(_model())
    phi, gamma = sampled_loop.zoh(a, b, PERIOD)
    pid = sampled_loop.Pid(*gains, PERIOD)
    row = control.output_row(encoder)
    grid = np.geomspace(0.01, 0.5 / PERIOD * (1 - 1e-9), 40001)
    solved = sampled_loop.loop_response(phi, gamma, row, pid, grid)
    bracketing = sampled_loop._bracketing_response(phi, gamma, row, pid, grid)
    for part in (np.imag, np.real, lambda v: np.abs(v) - 1):
        assert np.array_equal(np.sign(part(bracketing)), np.sign(part(solved)))
    lowest = abs(np.exp(2j * math.pi * grid[0] * PERIOD) - 1)
    assert np.max(np.abs(bracketing - solved) / np.abs(solved)) <= 64 * EPS / lowest**2


def test_gain_margin_is_where_the_carriage_loop_loses_stability():
    a, b = control.belt_plant(_model())
    phi, gamma = sampled_loop.zoh(a, b, PERIOD)
    output = control.output_row("carriage")
    pid = sampled_loop.Pid(*CARRIAGE_GAINS, PERIOD)
    critical = sampled_loop.critical_gain(phi, gamma, output, pid)
    margins = sampled_loop.margins(phi, gamma, output, pid)
    # the two routes agree: the poles (bisection on the spectral radius) and the frequency response
    assert 20 * math.log10(critical) == pytest.approx(margins["gain_margin_db"], abs=1e-9)
    # at the critical gain a pole pair sits on the unit circle at the phase crossover
    poles = np.linalg.eigvals(sampled_loop.closed_loop(phi, gamma, output, pid.scaled(critical))[0])
    top = poles[np.argmax(np.abs(poles))]
    assert abs(abs(top) - 1) <= 1e-9
    assert abs(np.angle(top)) / (2 * math.pi * PERIOD) == pytest.approx(margins["phase_crossover_hz"], rel=1e-6)
    # L there is real, negative, -1 / critical (the test's own L)
    value = _loop_value(
        phi, gamma[:, 0], 0, CARRIAGE_GAINS, np.exp(2j * math.pi * margins["phase_crossover_hz"] * PERIOD)
    )
    assert value.real * critical == pytest.approx(-1.0, abs=1e-9) and abs(value.imag) <= 1e-9 * abs(value)
    # the phase crossover is the belt: across the belt the loop sees its resonance with the belt's phase lag
    assert margins["phase_crossover_hz"] == pytest.approx(194.9, rel=0.01)
    # phase margin at the gain crossover, 180 deg - |arg L| with |L| = 1
    crossover = _loop_value(
        phi, gamma[:, 0], 0, CARRIAGE_GAINS, np.exp(2j * math.pi * margins["gain_crossover_hz"] * PERIOD)
    )
    assert abs(crossover) == pytest.approx(1.0, abs=1e-9)
    assert margins["phase_margin_deg"] == pytest.approx(180 - abs(math.degrees(np.angle(crossover))), abs=1e-9)
    # the motor loop's gains drive the carriage loop unstable; the boundary lies below 1
    motor_gains_on_carriage = sampled_loop.Pid(*MOTOR_GAINS, PERIOD)
    assert sampled_loop.spectral_radius(phi, gamma, output, motor_gains_on_carriage) > 1
    assert sampled_loop.critical_gain(phi, gamma, output, motor_gains_on_carriage) < 1


# -- MuJoCo runs the loop -------------------------------------------------------------------------------------


def _mujoco_loop(model, encoder, pid, samples):
    """Raw MuJoCo: the controller reads the encoder each sample (mj_forward first), holds u for SUBSTEPS steps."""
    law = sampled_loop.PidLaw(pid)
    address = model.sensor(control.ENCODERS[encoder][0]).adr[0]
    data = mujoco.MjData(model)
    return run_sampled(
        model,
        data,
        lambda k, readings: np.array([law.update(readings[address], REFERENCE)]),
        steps_per_sample=SUBSTEPS,
        samples=samples,
    ), address


@pytest.mark.parametrize(
    ("encoder", "gains"), [("motor", MOTOR_GAINS), ("motor", PID_GAINS), ("carriage", CARRIAGE_GAINS)]
)
def test_mujoco_loop_matches_the_exact_sampled_loop(encoder, gains):
    model = _model()
    samples = 1500
    pid = sampled_loop.Pid(*gains, PERIOD)
    output = control.output_row(encoder)
    phi, gamma = sampled_loop.zoh(*control.belt_plant(model), PERIOD)
    y, u, states = sampled_loop.step_response(phi, gamma, output, pid, REFERENCE, samples)
    run, address = _mujoco_loop(model, encoder, pid, samples)
    assert run.diverged_at is None
    measured = run.readings[:, address]
    bound = rk4_loop_bound(phi, gamma, output, pid, states, u) + 64 * EPS * REFERENCE * SUBSTEPS * np.arange(
        samples + 1
    )
    assert np.all(np.abs(measured - y) <= bound)
    # the law passes the encoder's error on: kp e_k + kd (e_k + e_(k-1)) / T + ki T sum e_j
    kp, kd, ki = gains
    law_bound = kp * bound[:-1] + kd * (bound[:-1] + np.concatenate([[0.0], bound[:-2]])) / PERIOD
    law_bound += ki * PERIOD * np.cumsum(bound[:-1]) + 64 * EPS * np.max(np.abs(u))
    assert np.all(np.abs(run.control[:, 0] - u) <= law_bound)
    # the sensor is read at the sample, not one step stale (as sensordata is after mj_step): a stale read would
    # differ from the exact loop by the encoder's motion over one step, far beyond the bound
    phi_short, gamma_short = sampled_loop.zoh(*control.belt_plant(model), PERIOD - PERIOD / SUBSTEPS)
    stale = (states[:-1] @ phi_short.T + np.outer(u, gamma_short[:, 0])) @ output[0]
    assert np.max(np.abs(stale - y[1:])) > 100 * np.max(bound)


def _oscillation(readings, start, stop):
    """Largest |y - reference| [m] over samples [start, stop)."""
    return float(np.max(np.abs(readings[start:stop] - REFERENCE)))


def test_carriage_loop_is_bounded_1_percent_below_the_critical_gain_and_grows_1_percent_above():
    model = _model()
    phi, gamma = sampled_loop.zoh(*control.belt_plant(model), PERIOD)
    output = control.output_row("carriage")
    pid = sampled_loop.Pid(*CARRIAGE_GAINS, PERIOD)
    critical = sampled_loop.critical_gain(phi, gamma, output, pid)
    samples, early, late = 20000, (2000, 4000), (18000, 20000)
    for factor in (0.99, 1.01):
        scaled = pid.scaled(critical * factor)
        radius = sampled_loop.spectral_radius(phi, gamma, output, scaled)
        run, address = _mujoco_loop(model, "carriage", scaled, samples)
        assert run.diverged_at is None
        ratio = _oscillation(run.readings[:, address], *late) / _oscillation(run.readings[:, address], *early)
        predicted = radius ** (late[0] - early[0])
        # the windows' peaks follow the dominant pair to within a period's sampling of the oscillation (the
        # pair turns by 2 pi f T = 0.24 rad per sample: a sampled peak reads low by at most 1 - cos(0.12) = 0.7 %)
        assert ratio == pytest.approx(predicted, rel=0.02)
        if factor < 1:
            assert radius < 1 and ratio < 1
        else:
            assert radius > 1 and ratio > 1


# -- MuJoCo's own position actuator, the continuous PD ---------------------------------------------------------


def _servo_model(integrator, kp, kv, dt):
    """The printer head with MuJoCo's position actuator on the motor (kp, kv) in place of the force motor."""
    spec = mujoco.MjSpec.from_file(str(springlab.sim.model_files.path("printer_head")))
    spec.delete(spec.actuator("drive"))
    servo = spec.add_actuator(name="servo", target="motor", trntype=mujoco.mjtTrn.mjTRN_JOINT)
    servo.set_to_position(kp=kp, kv=kv)
    model = spec.compile()
    model.opt.timestep = dt
    model.opt.integrator = {
        "rk4": mujoco.mjtIntegrator.mjINT_RK4,
        "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    }[integrator]
    return model


def _continuous_pd(kp, kd, time):
    """The continuous PD loop on the motor, u = kp (r - q_m) - kd v_m, at evenly spaced `time` from 0 [s]: exact by
    expm of its closed loop (round-off grows by a few ulps per reuse of the step)."""
    a, b = feedback_plant()
    closed = a - b @ np.array([[0.0, kp, 0.0, kd]])
    forcing = b[:, 0] * kp * REFERENCE
    augmented = np.zeros((5, 5))
    augmented[:4, :4], augmented[:4, 4] = closed, forcing
    step = scipy.linalg.expm(augmented * (time[1] - time[0]))  # evenly spaced times from 0: one step reused
    state, out = np.array([0, 0, 0, 0, 1.0]), []
    for _ in time:
        out.append(state[1])
        state = step @ state
    return np.array(out)


def test_position_actuator_is_the_continuous_pd_and_the_sampled_loop_differs_by_the_hold():
    kp, kd, _ = MOTOR_GAINS
    dt = PERIOD / SUBSTEPS
    steps = 3000
    time = np.arange(steps + 1) * dt
    exact = _continuous_pd(kp, kd, time)
    model = _servo_model("rk4", kp, kd, dt)
    data = mujoco.MjData(model)
    data.ctrl[0] = REFERENCE
    positions = [data.qpos[1]]
    for _ in range(steps):
        mujoco.mj_step(model, data)
        positions.append(data.qpos[1])
    # RK4 on the continuous loop: its fastest mode's |z|^5 / 120 per step, over the run (a generous x steps)
    a, b = feedback_plant()
    z = np.max(np.abs(np.linalg.eigvals(a - b @ np.array([[0.0, kp, 0.0, kd]])))) * dt
    assert np.max(np.abs(np.array(positions) - exact)) <= steps * z**5 / 120 / (1 - z / 6) * REFERENCE
    # the sampled loop at 5 kHz differs from the continuous one by the hold: about half a period of delay,
    # so by at most T/2 times the largest motor velocity, and by more than round-off
    sampled, _, _ = sampled_loop.step_response(
        *sampled_loop.zoh(a, b, PERIOD),
        control.output_row("motor"),
        sampled_loop.Pid(*MOTOR_GAINS, PERIOD),
        REFERENCE,
        steps // SUBSTEPS,
    )
    difference = np.max(np.abs(sampled - exact[::SUBSTEPS]))
    velocity = np.max(np.abs(np.diff(exact))) / dt
    assert 1e-9 < difference <= PERIOD * velocity
    # implicitfast treats kv implicitly: stable at a step where the explicit derivative of the sampled law is not
    big_kd = 10 * 2 * model.body("motor").mass[0] / PERIOD  # the backward difference is stable while kd T / m_m < 2
    servo = _servo_model("implicitfast", kp, big_kd, PERIOD)
    data = mujoco.MjData(servo)
    data.ctrl[0] = REFERENCE
    mujoco.mj_step(servo, data, nstep=2000)
    assert np.all(np.isfinite(data.qpos)) and abs(data.qpos[1] - REFERENCE) < REFERENCE
    explicit = sampled_loop.Pid(kp, big_kd, 0.0, PERIOD)
    assert sampled_loop.spectral_radius(*sampled_loop.zoh(a, b, PERIOD), control.output_row("motor"), explicit) > 1


# -- bad input ------------------------------------------------------------------------------------------------


def test_bad_controller_settings_say_what_is_valid():
    with pytest.raises(ValueError, match="kp must be a finite number >= 0"):
        sampled_loop.Pid(-1.0, 30.0, 0.0, PERIOD)
    with pytest.raises(ValueError, match="faster than MuJoCo's step"):
        steps_per_sample(20000.0, 1e-4)
    with pytest.raises(ValueError, match="not a whole number of MuJoCo steps"):
        steps_per_sample(3000.0, 1e-4)
    assert steps_per_sample(5000.0, 1e-4) == 2
    with pytest.raises(ValueError, match="unknown encoder 'belt'; valid: motor, carriage"):
        control.output_row("belt")


@pytest.mark.parametrize("encoder", ["motor", "carriage"])
def test_the_exact_overshoot_is_the_held_loops_continuous_maximum(encoder, scenario_run):
    # issue 34 item 3: overshoot_m_exact is the exact loop's largest excursion between its steps, not its
    # largest sample; here the held motion of each step around the peak is integrated by DOP853 (rtol 1e-12)
    result = scenario_run("printer_head", f"feedback_{encoder}")
    variant = result.case.scenario.variant
    exact = variant.exact(result.case, result.dt, result.steps)
    a, b = control.belt_plant(result.model)
    target = result.parameters["move_distance"]
    best = int(np.argmax(exact.states[:, 0]))
    peak = -math.inf
    for step in range(max(best - 2, 0), min(best + 2, len(exact.forces))):
        force = exact.forces[step]
        solved = scipy.integrate.solve_ivp(
            lambda _t, x, force=force: a @ x + b[:, 0] * force,
            (0.0, result.dt),
            exact.states[step],
            method="DOP853",
            rtol=1e-12,
            atol=1e-18,
            dense_output=True,
        )
        grid = np.linspace(0.0, result.dt, 2001)
        peak = max(peak, float(np.max(solved.sol(grid)[0])))
    # the grid of dt/2000 reads a smooth peak low by at most (w dt / 2000)^2 / 8 of the belt's swing: < 1e-12 m
    assert result.quantities["overshoot_m_exact"] == pytest.approx(peak - target, abs=1e-12)
    # the sampled maximum (the old value) is lower by more than that: the steps miss the peak
    assert np.max(exact.states[:, 0]) - target < result.quantities["overshoot_m_exact"] - 1e-10


@pytest.mark.parametrize("encoder", ["motor", "carriage"])
def test_the_exact_positioning_time_is_a_root_of_the_held_loops_motion(encoder, scenario_run):
    # issue 34 item 3: positioning_time_s_exact is where the exact held motion itself leaves the band for the last
    # time (Brent on the step's exact map), not a root of an interpolant of its steps; DOP853 integrates that step
    result = scenario_run("printer_head", f"feedback_{encoder}")
    exact = result.case.scenario.variant.exact(result.case, result.dt, result.steps)
    a, b = control.belt_plant(result.model)
    target, band = result.parameters["move_distance"], result.parameters["positioning_band"]
    exit_time = result.quantities["positioning_time_s_exact"]
    step = int(exit_time // result.dt)
    force = exact.forces[step]
    solved = scipy.integrate.solve_ivp(
        lambda _t, x: a @ x + b[:, 0] * force,
        (0.0, result.dt),
        exact.states[step],
        method="DOP853",
        rtol=1e-12,
        atol=1e-18,
        dense_output=True,
    )
    offset = exit_time - step * result.dt
    deviation = solved.sol(offset)[0] - target
    # at the root the deviation is the band; DOP853's error at rtol 1e-12 on a position of D: about 1e-12 D
    assert abs(abs(deviation) - band) <= 1e-12 * target
    # and the exact loop stays within the band at every later step of its record
    later = exact.states[step + 1 :, 0] - target
    assert np.all(np.abs(later) <= band)
