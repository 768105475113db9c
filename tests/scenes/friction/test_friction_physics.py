"""The friction scene's exact Coulomb answers against independent computations.

Each claim of springlab.scenes.friction.coulomb is checked against something built here: the ODE
m x'' + k x = f_c - F sgn(x') integrated slide by slide with scipy's DOP853 and its event location
(root finding of v = 0 to 1e-12), a second derivation by energy (every half cycle the friction's
work F |x_n - x_{n+1}| takes (k/2)(x_n^2 - x_{n+1}^2) out of the spring, so |x_n| - |x_{n+1}| = 2F/k
about the equilibrium), and textbook closed forms (a = g (sin theta - mu cos theta)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import springlab
from springlab.runs.run import prepare
from springlab.scenes.friction.coulomb import CoulombMotion

#: DOP853 at these tolerances: the event times and positions it locates agree to ~1e-13 over a few periods
RTOL, ATOL = 1e-13, 1e-16
#: what the comparisons allow [-, relative to the motion's period or amplitude]: the event location's own
#: accuracy (brentq in solve_ivp to ~4 eps of the time, plus DOP853's local error on the arc)
EVENT_TOL = 1e-12


def _slides_by_ivp(m, k, friction, force, x0, v0, horizon):
    """[(turning time [s], turning position [m])] from integrating each slide with DOP853 and an event at v = 0,
    and whether the block sticks at the end: independent of the closed forms."""
    t, x, v = 0.0, x0, v0
    turns = []
    while t < horizon:
        if v == 0.0:
            net = force - k * x
            if abs(net) <= friction:
                return turns, True
            direction = math.copysign(1.0, net)
        else:
            direction = math.copysign(1.0, v)

        def rhs(_, y, s=direction):
            return [y[1], (force - k * y[0] - s * friction) / m]

        def stopped(_, y, s=direction):
            return y[1] * s  # the slide in direction s ends where its velocity reaches 0

        stopped.terminal, stopped.direction = True, -1
        solution = solve_ivp(
            rhs, (t, horizon), [x, v], method="DOP853", rtol=RTOL, atol=ATOL, events=stopped, dense_output=False
        )
        if not solution.t_events[0].size:
            return turns, False
        t, x, v = float(solution.t_events[0][0]), float(solution.y_events[0][0][0]), 0.0
        turns.append((t, x))
    return turns, False


@pytest.mark.parametrize(
    "m, k, friction, force, x0, v0",
    [
        (1.0, 100.0, 1.0, 0.0, 0.105, 0.0),  # coulomb_decay
        (1.0, 100.0, 0.981, 0.0, 0.105, 0.0),  # contact_decay
        (2.0, 50.0, 1.5, 3.0, -0.2, 0.7),  # an incline's pull, released moving
        (0.5, 400.0, 0.3, -1.0, 0.01, -2.0),
    ],
)
def test_turning_times_and_points_match_event_location_on_the_ode(m, k, friction, force, x0, v0):
    motion = CoulombMotion(m, k, friction, force, x0, v0, horizon=20.0)
    turns, sticks = _slides_by_ivp(m, k, friction, force, x0, v0, 20.0)
    period = 2 * math.pi * math.sqrt(m / k)
    amplitude = max(abs(x0 - force / k), abs(v0) * math.sqrt(m / k))
    assert motion.half_cycles == len(turns) and motion.stops == sticks
    for (t_ivp, x_ivp), t, x in zip(turns, motion.turning_times, motion.turning_points):
        assert abs(t - t_ivp) <= EVENT_TOL * period
        assert abs(x - x_ivp) <= EVENT_TOL * amplitude
    # between the events the state is the ODE's too
    time = np.linspace(0.0, motion.stop_time if motion.stops else 20.0, 57)
    x, v = motion.state(time)
    reference = solve_ivp(
        lambda t, y: [y[1], (force - k * y[0] - friction * np.sign(y[1])) / m],
        (0.0, time[-1]),
        [x0, v0],
        method="DOP853",
        rtol=1e-10,
        atol=1e-14,
        t_eval=time,
        max_step=period / 200,
    )
    # sgn(v) is discontinuous at the turns: the plain integrator steps across them only to ~1e-7 here
    assert np.max(np.abs(x - reference.y[0])) <= 1e-6 * amplitude


def test_released_from_rest_the_amplitude_falls_by_2F_over_k_each_half_cycle_by_energy():
    # second derivation: x_n = (-1)^n (x0 - 2 n F / k) about the equilibrium, until |x_n| <= F / k
    m, k, friction, x0 = 1.0, 100.0, 1.0, 0.105
    expected, x, n = [], x0, 0
    while abs(x) > friction / k:
        x = -(x - math.copysign(2 * friction / k, x))
        expected.append(x)
        n += 1
    motion = CoulombMotion(m, k, friction, 0.0, x0, 0.0, horizon=10.0)
    assert motion.half_cycles == n == 5
    np.testing.assert_allclose(motion.turning_points, expected, rtol=0, atol=8 * np.finfo(float).eps * x0)
    # each half cycle lasts half a period: the stop is n pi / omega, at the last turning point
    assert motion.stop_time == pytest.approx(n * math.pi / math.sqrt(k / m), rel=4 * np.finfo(float).eps * n)
    assert motion.stop_position == expected[-1]
    assert abs(motion.stop_position) <= friction / k < abs(expected[-2])
    # the decrement is linear, 2F/k, not a constant ratio as under viscous damping
    amplitudes = np.abs([x0, *expected])
    np.testing.assert_allclose(-np.diff(amplitudes)[:-1], 2 * friction / k, rtol=1e-12)
    ratios = amplitudes[1:-1] / amplitudes[:-2]
    assert np.ptp(ratios) > 0.1  # far from a constant factor


def test_a_block_inside_the_stick_zone_never_moves_and_one_on_its_edge_sticks():
    motion = CoulombMotion(1.0, 100.0, 1.0, 0.5, 0.0149, 0.0, horizon=5.0)  # |f_c - k x| = 0.99 N < F
    x, v = motion.state(np.linspace(0, 5, 11))
    assert motion.stops and motion.stop_time == 0.0 and motion.half_cycles == 0
    assert np.all(x == 0.0149) and np.all(v == 0.0)
    assert CoulombMotion(1.0, 100.0, 1.0, 0.0, 0.01, 0.0, horizon=1.0).stop_time == 0.0  # |k x| = F exactly


def test_an_incline_holds_below_its_friction_angle_and_slides_above_it_at_g_sin_minus_mu_cos():
    g, m, mu = 9.81, 1.3, 0.5
    for degrees, holds in ((20.0, True), (26.5, True), (26.6, False), (60.0, False)):
        theta = math.radians(degrees)
        assert (math.tan(theta) <= mu) == holds
        motion = CoulombMotion(m, 0.0, mu * m * g * math.cos(theta), m * g * math.sin(theta), 0.0, 0.0, horizon=2.0)
        time = np.linspace(0.0, 2.0, 41)
        x, v = motion.state(time)
        if holds:
            assert motion.stops and np.all(x == 0.0) and np.all(v == 0.0)
        else:
            a = g * (math.sin(theta) - mu * math.cos(theta))
            # the difference of two forces: its relative round-off grows as they near each other
            condition = (math.sin(theta) + mu * math.cos(theta)) / (math.sin(theta) - mu * math.cos(theta))
            np.testing.assert_allclose(x, 0.5 * a * time**2, rtol=16 * np.finfo(float).eps * condition, atol=0)
            np.testing.assert_allclose(v, a * time, rtol=16 * np.finfo(float).eps * condition, atol=0)


def test_a_block_thrown_up_an_incline_brakes_then_slides_back_or_stays():
    # v0 up the slope (x positive down it): friction and gravity both brake, then it stays if tan theta <= mu
    g, m, mu, v0 = 9.81, 1.0, 0.3, -2.0
    for degrees in (10.0, 40.0):
        theta = math.radians(degrees)
        friction, slope = mu * m * g * math.cos(theta), m * g * math.sin(theta)
        motion = CoulombMotion(m, 0.0, friction, slope, 0.0, v0, horizon=3.0)
        braking = g * (math.sin(theta) + mu * math.cos(theta))
        assert motion.turning_times[0] == pytest.approx(-v0 / braking, rel=1e-14)
        assert motion.turning_points[0] == pytest.approx(-(v0**2) / (2 * braking), rel=1e-14)
        assert motion.stops == (math.tan(theta) <= mu)


def test_the_scene_reads_its_physics_back_from_the_compiled_model():
    cases = {
        "coulomb_decay": (1.0, 100.0, 1.0, 0.0),
        "contact_decay": (1.0, 100.0, 0.1 * 9.81, 0.0),
        "incline_hold": (1.0, 0.0, 0.5 * 9.81 * math.cos(math.radians(20)), 9.81 * math.sin(math.radians(20))),
        "incline_slide": (1.0, 0.0, 0.3 * 9.81 * math.cos(math.radians(30)), 9.81 * math.sin(math.radians(30))),
    }
    for scenario, expected in cases.items():
        scene, chosen, params = prepare("friction", scenario, {})
        model = scene.build(params, chosen)
        np.testing.assert_allclose(scene.physical(model), expected, rtol=1e-14, atol=1e-15)
    scene, chosen, params = prepare("friction", "contact_decay", {"mass": 2.0, "mu": 0.2, "incline_deg": 15.0})
    m, k, friction, slope = scene.physical(scene.build(params, chosen))
    theta = math.radians(15.0)
    assert friction == pytest.approx(0.2 * 2.0 * 9.81 * math.cos(theta), rel=1e-14)
    assert slope == pytest.approx(2.0 * 9.81 * math.sin(theta), rel=1e-14)


def test_the_default_scenarios_exact_quantities_are_the_textbook_numbers():
    decay = springlab.run("friction", "coulomb_decay").quantities
    assert decay["half_cycles_exact"] == 5
    assert decay["stop_time_s_exact"] == pytest.approx(5 * math.pi / 10, rel=1e-15)
    assert decay["stop_position_m_exact"] == pytest.approx(-0.005, abs=1e-16)
    assert decay["amplitude_drop_per_half_cycle_m"] == pytest.approx(0.02, rel=1e-15)
    contact = springlab.run("friction", "contact_decay").quantities
    assert contact["half_cycles_exact"] == 5
    assert contact["stop_position_m_exact"] == pytest.approx(-(0.105 - 5 * 2 * 0.981 / 100), rel=1e-13)
    slide = springlab.run("friction", "incline_slide").quantities
    a = 9.81 * (math.sin(math.radians(30)) - 0.3 * math.cos(math.radians(30)))
    assert slide["acceleration_m_s2_exact"] == pytest.approx(a, rel=1e-15)
    assert slide["distance_m_exact"] == pytest.approx(0.5 * a * 0.5**2, rel=1e-12)  # in the 0.5 s run


def test_a_run_cut_before_the_first_turn_counts_no_exact_half_cycle_and_passes():
    # 0.04 s of the coulomb decay: the block is still on its first slide (half a period is pi / omega = 0.314 s),
    # so neither MuJoCo's block nor the exact one has turned yet
    from springlab import run

    result = run("friction", "coulomb_decay", duration=0.04)
    assert result.quantities["half_cycles_exact"] == 0 == result.quantities["half_cycles"]
    assert result.quantities["half_period_s"] > 0.04
    assert result.passed
