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
from scipy.optimize import brentq, minimize_scalar

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
    assert result.to_dict()["quantities"]["static_tire_force_n"] == pytest.approx((MS + MU) * G, rel=1e-12)


def test_body_and_wheel_follow_the_exact_response_to_the_half_sine_bump(bump):
    result, exact = bump
    heave, wheel = result.pos["heave"] - 0.10, result.pos["wheel"] - WHEEL_REST
    # validated to 1e-6 at its default 1 ms (RK4, predicted bound 5.9e-7; the wheel hop, 72 rad/s, dominates)
    assert np.max(np.abs(heave - exact[:, 0])) < 1e-6 * np.max(np.abs(exact[:, 0]))
    assert np.max(np.abs(wheel - exact[:, 1])) < 1e-6 * np.max(np.abs(exact[:, 1]))
    assert np.max(np.abs(result.vel["wheel"] - exact[:, 3])) < 1e-6 * np.max(np.abs(exact[:, 3]))
    assert result.to_dict()["passed"] is True


def continuous_peak(signal, start=0.0, stop=3.0, points=30001) -> float:
    """max |signal(t)| over [start, stop] [s]: a grid, then a bounded scalar search around its best point."""
    grid = np.linspace(start, stop, points)
    values = signal(grid)
    i = int(np.argmax(np.abs(values)))
    if i in (0, points - 1):
        return float(abs(values[i]))
    sign = np.sign(values[i])
    best = minimize_scalar(
        lambda t: -sign * signal(t)[0], bounds=(grid[i - 1], grid[i + 1]), method="bounded", options={"xatol": 1e-12}
    )
    return float(max(abs(signal(best.x)[0]), abs(values[i])))


def test_ride_quantities_agree_with_the_exact_response(bump):
    result, _ = bump
    q = result.to_dict()["quantities"]
    state, road, _ = continuous_quarter_car()

    def body_acceleration(t):
        xs, xw, vs, vw = state(t)
        return (-KS * (xs - xw) - CS * (vs - vw)) / MS

    # peaks between the samples (springlab.exact.events), to the run's tolerance
    tolerance = 2 * result.to_dict()["tolerance"]
    assert q["peak_body_acceleration_m_s2"] == pytest.approx(continuous_peak(body_acceleration), rel=tolerance)
    assert q["peak_suspension_travel_m"] == pytest.approx(
        continuous_peak(lambda t: state(t)[0] - state(t)[1]), rel=tolerance
    )
    assert q["peak_tire_deflection_m"] == pytest.approx(continuous_peak(lambda t: road(t) - state(t)[1]), rel=tolerance)
    lowest_tire = -continuous_peak(lambda t: np.maximum(state(t)[1] - road(t), 0.0))
    assert q["min_tire_force_n"] == pytest.approx((MS + MU) * G + KT * lowest_tire, rel=tolerance)
    assert q["tire_leaves_road"] is False
    assert q["bump_duration_s"] == 0.5


def test_modes_are_the_quarter_cars_body_bounce_and_wheel_hop(bump):
    q = bump[0].to_dict()["quantities"]
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


def continuous_quarter_car(height=H, length=L, speed=V, duration=3.0):
    """The exact (rtol 1e-13) solution as functions of time: (state(t) -> (xs, xw, vs, vw), road(t), road'(t))."""
    omega, end = math.pi * speed / length, length / speed

    def rhs(t, z, on_bump):
        xs, xw, vs, vw = z
        road = height * math.sin(omega * t) if on_bump else 0.0
        suspension = -KS * (xs - xw) - CS * (vs - vw)
        return [vs, vw, suspension / MS, (-suspension - KT * (xw - road)) / MU]

    options = dict(rtol=1e-13, atol=1e-16, method="DOP853", dense_output=True)
    on = solve_ivp(rhs, (0, end), [0, 0, 0, 0], args=(True,), **options)
    off = solve_ivp(rhs, (end, duration), on.y[:, -1], args=(False,), **options)

    def state(t):
        t = np.atleast_1d(np.asarray(t, float))
        return np.where(t <= end, on.sol(np.minimum(t, end)), off.sol(np.maximum(t, end)))

    def road(t):
        return np.where(t <= end, height * np.sin(omega * t), 0.0)

    def road_rate(t):
        return np.where(t <= end, height * omega * np.cos(omega * t), 0.0)

    return state, road, road_rate


def test_the_peak_body_acceleration_is_the_continuous_one_not_the_largest_sample():
    # 16 m/s: the continuous peak (8.3423 m/s^2) falls between steps; the largest sample of the exact
    # solution misses it by O(dt^2), the Hermite interpolant of the run by RK4's own accuracy
    state, _, _ = continuous_quarter_car(speed=16.0)

    def acceleration(t):
        xs, xw, vs, vw = state(t)
        return (-KS * (xs - xw) - CS * (vs - vw)) / MS

    grid = np.linspace(0.0, 3.0, 30001)
    i = int(np.argmax(np.abs(acceleration(grid))))
    sign = np.sign(acceleration(grid[i])[0])
    best = minimize_scalar(
        lambda t: -sign * acceleration(t)[0],
        bounds=(grid[i - 1], grid[i + 1]),
        method="bounded",
        options={"xatol": 1e-12},
    )
    peak = abs(acceleration(best.x)[0])
    for dt in (1e-3, 2e-3):
        result = springlab.run("car", "road_bump", speed=16.0, dt=dt)
        measured = result.to_dict()["quantities"]["peak_body_acceleration_m_s2"]
        sampled = np.max(np.abs(acceleration(result.time)))
        # the run is validated to its tolerance (relative to each column's peak); the acceleration is a
        # combination of positions and velocities weighted (ks |x| + cs |v|) / ms, and the Hermite
        # interpolation adds (omega dt)^4 / 384 of the wheel hop (72 rad/s), below 1e-6 at 2 ms
        tolerance = 2 * (result.to_dict()["tolerance"] + (72.0 * dt) ** 4 / 384)
        assert measured == pytest.approx(peak, rel=tolerance)
        assert abs(sampled - peak) > 10 * tolerance * peak  # reading the samples is not good enough


def test_a_short_sharp_bump_lifts_the_tire_off_the_road_and_the_run_says_it_is_not_validated():
    height, length, speed = 0.03, 0.3, 10.0
    state, road, road_rate = continuous_quarter_car(height, length, speed, duration=1.0)

    def tire(t):
        return (MS + MU) * G + KT * (road(t) - state(t)[1])

    grid = np.linspace(0.0, 1.0, 100001)
    first = int(np.argmax(tire(grid) < 0))
    root = brentq(lambda t: tire(t)[0], grid[first - 1], grid[first], xtol=1e-15)  # 0.0273274 s
    slope = KT * abs(float(road_rate(root)) - state(root)[3][0])  # |dF/dt| at the root [N/s]
    for dt in (1e-3, 5e-4, 2.5e-4):
        result = springlab.run("car", "road_bump", bump_height=height, bump_length=length, speed=speed, dt=dt)
        q = result.to_dict()["quantities"]
        assert q["tire_leaves_road"] is True
        # a force error kt * (the run's tolerance x the wheel's largest excursion) moves the root by that / slope
        wheel_scale = np.max(np.abs(state(grid)[1]))
        tolerance = 2 * KT * result.to_dict()["tolerance"] * wheel_scale / slope
        assert q["tire_lift_off_time_s"] == pytest.approx(root, abs=tolerance)
        assert q["min_tire_force_n"] == pytest.approx(np.min(tire(grid)), rel=1e-4)
        # the linear tire pulls after lift-off: matching the exact linear solution certifies nothing
        assert result.to_dict()["passed"] is False
        assert result.to_dict()["errors"]["wheel_pos"]["max_rel"] <= result.to_dict()["tolerance"]
        (limit,) = result.to_dict()["model_limits"]
        assert "tire leaves the road at t = 0.0273274 s" in limit


def test_a_bump_the_tire_follows_has_no_model_limits(bump):
    assert bump[0].to_dict()["model_limits"] == [] and bump[0].to_dict()["passed"] is True


def test_a_bump_ending_between_steps_is_covered_by_its_exact_input_error():
    # 0.5 s is not a whole number of 0.7 ms steps: the tire leaves the bump at 0.4998 s
    result = springlab.run("car", "road_bump", dt=7e-4, duration=1.5)
    exact = quarter_car(result.time)
    wheel_error = np.max(np.abs(result.vel["wheel"] - exact[:, 3])) / np.max(np.abs(exact[:, 3]))
    aligned = springlab.run("car", "road_bump", dt=5e-4, duration=1.5)
    assert wheel_error > 10 * aligned.to_dict()["errors"]["wheel_vel"]["max_rel"]  # the input error is real
    assert result.to_dict()["errors"]["wheel_vel"]["max_rel"] == pytest.approx(wheel_error, rel=1e-3)
    assert result.to_dict()["passed"] is True
    assert "step grid at 0.4998 s" in result.to_dict()["tolerance_basis"]


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
