"""road_bump: the quarter car over a half-sine bump, driven by an MJCF-native road input.

Independent reference: the quarter-car equations written out by hand, in
deviations from the static equilibrium,

    ms xs'' = -ks (xs - xw) - cs (xs' - xw')
    mu xw'' =  ks (xs - xw) + cs (xs' - xw') - kt (xw - r(t)),
    r(t) = H sin(pi v t / L) for 0 <= t <= L / v, 0 after,

integrated by scipy's solve_ivp at rtol 1e-12 in two pieces split at the
bump's end (test-only), with the textbook car's corner: ms = 1000/4 kg, the
comfort springs 6e4/4 N/m, dampers at zeta = 0.3, a 40 kg wheel on a
2e5 N/m tire.
"""

import math

import mujoco
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import springlab

G = 9.81
MS, MU, KS, KT = 250.0, 40.0, 15000.0, 2.0e5
CS = 2 * 0.3 * math.sqrt(6e4 * 1000.0) / 4
H, L, V = 0.08, 4.0, 8.0
WHEEL_REST = 0.3 - (MS + MU) * G / KT  # unloaded radius 0.3 m, compressed by the static load


def quarter_car(time, height=H, length=L, speed=V):
    """Exact (rtol 1e-12) deviations (xs, xw, vs, vw) from rest [m, m/s] at `time`."""
    omega, end = math.pi * speed / length, length / speed

    def rhs(t, z, on_bump):
        xs, xw, vs, vw = z
        road = height * math.sin(omega * t) if on_bump else 0.0
        suspension = -KS * (xs - xw) - CS * (vs - vw)
        return [vs, vw, suspension / MS, (-suspension - KT * (xw - road)) / MU]

    options = dict(rtol=1e-12, atol=1e-15, method="DOP853")
    on = solve_ivp(rhs, (0, end), [0, 0, 0, 0], args=(True,), t_eval=time[time <= end], **options)
    at_end = solve_ivp(rhs, (0, end), [0, 0, 0, 0], args=(True,), **options).y[:, -1]
    off = solve_ivp(rhs, (end, time[-1]), at_end, args=(False,), t_eval=time[time > end], **options)
    return np.hstack([on.y, off.y]).T


@pytest.fixture(scope="module")
def bump():
    result = springlab.run("car", "road_bump")
    return result, quarter_car(result.time)


def test_the_quarter_car_is_one_corner_of_the_car(bump):
    result, _ = bump
    model = result.model
    assert model.body("car").mass[0] == pytest.approx(MS)
    assert model.body("wheels").mass[0] == pytest.approx(MU)
    assert result.parameters["stiffness"] == 6e4 and result.parameters["damping_ratio"] == 0.3
    assert sorted(result.pos) == ["heave", "wheel"]  # the exciter is internal, not reported


def test_the_car_rests_in_static_equilibrium_before_the_bump(bump):
    result, _ = bump
    assert result.pos["heave"][0] == pytest.approx(0.10, abs=1e-15)
    assert result.pos["wheel"][0] == pytest.approx(WHEEL_REST, abs=1e-15)
    assert result.summary["quantities"]["static_tire_force_n"] == pytest.approx((MS + MU) * G, rel=1e-12)


def test_body_and_wheel_follow_the_exact_response_to_the_half_sine_bump(bump):
    result, exact = bump
    heave, wheel = result.pos["heave"] - 0.10, result.pos["wheel"] - WHEEL_REST
    # validated to 1e-6 at its default 1 ms (RK4, predicted bound 5.9e-7; the wheel hop, 72 rad/s, dominates)
    assert np.max(np.abs(heave - exact[:, 0])) < 1e-6 * np.max(np.abs(exact[:, 0]))
    assert np.max(np.abs(wheel - exact[:, 1])) < 1e-6 * np.max(np.abs(exact[:, 1]))
    assert np.max(np.abs(result.vel["wheel"] - exact[:, 3])) < 1e-6 * np.max(np.abs(exact[:, 3]))
    assert result.summary["passed"] is True


def test_ride_quantities_agree_with_the_exact_response(bump):
    result, exact = bump
    q = result.summary["quantities"]
    xs, xw, vs, vw = exact.T
    t = result.time
    road = np.where(t <= L / V, H * np.sin(math.pi * V / L * t), 0.0)
    body_acceleration = (-KS * (xs - xw) - CS * (vs - vw)) / MS
    assert q["peak_body_acceleration_m_s2"] == pytest.approx(np.max(np.abs(body_acceleration)), rel=1e-6)
    assert q["peak_suspension_travel_m"] == pytest.approx(np.max(np.abs(xs - xw)), rel=1e-6)
    assert q["peak_tire_deflection_m"] == pytest.approx(np.max(np.abs(road - xw)), rel=1e-6)
    assert q["min_tire_force_n"] == pytest.approx((MS + MU) * G + KT * np.min(road - xw), rel=1e-6)
    assert q["tire_leaves_road"] is False
    assert q["bump_duration_s"] == 0.5


def test_modes_are_the_quarter_cars_body_bounce_and_wheel_hop(bump):
    q = bump[0].summary["quantities"]
    mass = np.diag([MS, MU])
    stiffness = np.array([[KS, -KS], [-KS, KS + KT]])
    damping = np.array([[CS, -CS], [-CS, CS]])
    state = np.block(
        [[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(mass, stiffness), -np.linalg.solve(mass, damping)]]
    )
    roots = sorted((r for r in np.linalg.eigvals(state) if r.imag > 0), key=abs)
    assert q["body_frequency_hz"] == pytest.approx(abs(roots[0]) / (2 * math.pi), rel=1e-10)
    assert q["wheel_hop_frequency_hz"] == pytest.approx(abs(roots[1]) / (2 * math.pi), rel=1e-10)
    assert 1.0 < q["body_frequency_hz"] < 1.5  # a comfort suspension (Gillespie: 1-1.5 Hz)


def test_a_short_sharp_bump_makes_the_tire_leave_the_road():
    result = springlab.run("car", "road_bump", bump_height=0.03, bump_length=0.3, speed=10.0, duration=1.0)
    exact = quarter_car(result.time, 0.03, 0.3, 10.0)
    t = result.time
    road = np.where(t <= 0.03, 0.03 * np.sin(math.pi * 10.0 / 0.3 * t), 0.0)
    tire = (MS + MU) * G + KT * (road - exact[:, 1])
    q = result.summary["quantities"]
    assert q["tire_leaves_road"] is True and np.min(tire) < 0
    assert q["min_tire_force_n"] == pytest.approx(np.min(tire), rel=1e-5)
    assert q["tire_lift_off_time_s"] == pytest.approx(t[np.argmax(tire < 0)])


def test_a_bump_ending_between_steps_is_covered_by_its_exact_input_error():
    # 0.5 s is not a whole number of 0.7 ms steps: the tire leaves the bump at 0.4998 s
    result = springlab.run("car", "road_bump", dt=7e-4, duration=1.5)
    exact = quarter_car(result.time)
    wheel_error = np.max(np.abs(result.vel["wheel"] - exact[:, 3])) / np.max(np.abs(exact[:, 3]))
    aligned = springlab.run("car", "road_bump", dt=5e-4, duration=1.5)
    assert wheel_error > 10 * aligned.summary["errors"]["wheel_vel"]["max_rel"]  # the input error is real
    assert result.summary["errors"]["wheel_vel"]["max_rel"] == pytest.approx(wheel_error, rel=1e-3)
    assert result.summary["passed"] is True
    assert "step grid at 0.4998 s" in result.summary["tolerance_basis"]


def test_the_input_needs_no_python_callback():
    # open-loop controls and MJCF elements only: the model runs in mujoco.rollout as it is
    result = springlab.run("car", "road_bump", duration=0.6)
    assert mujoco.get_mjcb_control() is None
    model = result.model
    assert model.nu == 2 and model.actuator("tire_on_bump").trntype == mujoco.mjtTrn.mjTRN_TENDON


@pytest.mark.parametrize(
    "overrides, message",
    [
        ({"speed": 0.0}, "speed must be"),
        ({"speed": -8.0}, "speed must be"),
        ({"bump_height": 0.2}, "through the ground"),
        ({"bump_height": 0.12, "bump_length": 0.5}, "off its suspension springs"),
        ({"tire_stiffness": 0.0}, "tire_stiffness must be"),
        ({"unsprung_mass": -1.0}, "unsprung_mass must be"),
        ({"push_mass": 100.0}, "does not apply"),
    ],
)
def test_bad_road_bump_input_is_rejected(overrides, message):
    with pytest.raises(springlab.BadInputError, match=message):
        springlab.run("car", "road_bump", **overrides)
