"""`springlab fit` recovers the parameters behind a record, with honest intervals, from tidy and untidy data.

References are independent of the code under test: the records are generated
by the closed-form free response written out below (not springlab.analytic,
not MuJoCo), and the polynomial by numpy.polynomial.

Exact-data tolerance, 1e-6 relative (the issue's requirement), with margin:
the fit's RK4 grid has omega dt <= 0.05, whose frequency bias is
(omega dt)^4 / 120 = 5e-8 relative and whose damping bias is
(omega dt)^5 / 144 / zeta ~ 5e-8 at zeta = 0.05; cubic Hermite reading of
the grid adds (omega dt)^4 / 384 ~ 2e-8 of the amplitude.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from springlab import scenes
from springlab.errors import BadInputError
from springlab.studies.fit.fit import fit

EXACT = 1e-6


def free_decay(t, omega, zeta, x0, v0):
    """Independent closed form of x'' + 2 zeta omega x' + omega^2 x = 0: (x [m], v [m/s], a [m/s^2])."""
    t = np.asarray(t, float)
    if zeta < 1:
        wd = omega * math.sqrt(1 - zeta * zeta)
        c, s = np.cos(wd * t), np.sin(wd * t)
        envelope = np.exp(-zeta * omega * t)
        b = (v0 + zeta * omega * x0) / wd
        x = envelope * (x0 * c + b * s)
        v = envelope * ((b * wd - zeta * omega * x0) * c - (x0 * wd + zeta * omega * b) * s)
    else:
        r = omega * math.sqrt(zeta * zeta - 1)
        l1, l2 = -zeta * omega + r, -zeta * omega - r
        a1 = (v0 - l2 * x0) / (l1 - l2)
        a2 = x0 - a1
        x = a1 * np.exp(l1 * t) + a2 * np.exp(l2 * t)
        v = a1 * l1 * np.exp(l1 * t) + a2 * l2 * np.exp(l2 * t)
    a = -(omega**2) * x - 2 * zeta * omega * v
    return x, v, a


def write(path, columns: dict) -> str:
    names = list(columns)
    table = np.column_stack([np.asarray(columns[n], float) for n in names])
    np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
    return str(path)


def rel(value, truth):
    return abs(value / truth - 1)


# -- exact data -> parameters to 1e-6 -------------------------------------------------


def test_slider_omega_and_zeta_come_back_from_an_exact_decay(tmp_path):
    omega, zeta = 20.0, 0.05
    t = np.arange(0, 3, 2e-3)
    x, _, _ = free_decay(t, omega, zeta, 0.05, 0.1)
    result = fit("slider", write(tmp_path / "d.csv", {"time": t, "slider_pos": x + 0.002}), mass=2.0, run_scene=False)
    e = result.estimates
    assert rel(e["omega_n"]["value"], omega) < EXACT
    assert rel(e["zeta"]["value"], zeta) < EXACT
    assert rel(e["x0"]["value"], 0.05) < EXACT and rel(e["v0"]["value"], 0.1) < EXACT
    assert abs(e["offset"]["value"] - 0.002) < EXACT * 0.05
    # k and d given m, derived
    assert rel(result.derived["stiffness"]["value"], 2.0 * omega**2) < 3 * EXACT
    assert rel(result.derived["damping"]["value"], 2 * zeta * 2.0 * omega) < 3 * EXACT
    assert result.converged and result.cross_check["max_relative_difference"] < EXACT


def test_slider_stiffness_and_damping_given_the_mass(tmp_path):
    m, k, d = 2.0, 800.0, 4.0
    omega, zeta = math.sqrt(k / m), d / (2 * math.sqrt(k * m))
    t = np.arange(0, 3, 2e-3)
    x, _, _ = free_decay(t, omega, zeta, 0.05, 0.0)
    data = write(tmp_path / "d.csv", {"time": t, "slider_pos": x})
    result = fit("slider", data, free=["stiffness", "damping", "x0", "v0", "offset"], mass=m, run_scene=False)
    assert rel(result.estimates["stiffness"]["value"], k) < EXACT
    assert rel(result.estimates["damping"]["value"], d) < EXACT
    assert rel(result.derived["omega_n_rad_s"]["value"], omega) < EXACT


def test_slider_mass_and_damping_given_the_stiffness(tmp_path):
    m, k, d = 2.0, 800.0, 4.0
    t = np.arange(0, 3, 2e-3)
    x, _, _ = free_decay(t, math.sqrt(k / m), d / (2 * math.sqrt(k * m)), 0.05, 0.0)
    data = write(tmp_path / "d.csv", {"time": t, "slider_pos": x})
    result = fit("slider", data, free=["mass", "damping", "x0", "v0", "offset"], stiffness=k, run_scene=False)
    assert rel(result.estimates["mass"]["value"], m) < EXACT
    assert rel(result.estimates["damping"]["value"], d) < EXACT


def test_slider_overdamped_decay(tmp_path):
    omega, zeta = 10.0, 2.0
    t = np.arange(0, 2, 1e-3)
    x, _, _ = free_decay(t, omega, zeta, 0.1, -0.5)
    result = fit("slider", write(tmp_path / "d.csv", {"time": t, "slider_pos": x}), run_scene=False)
    assert rel(result.estimates["omega_n"]["value"], omega) < EXACT
    assert rel(result.estimates["zeta"]["value"], zeta) < EXACT
    assert "overdamped" in result.verdict


def test_slider_mass_stiffness_and_damping_from_a_known_step_force(tmp_path):
    # a known force makes the static deflection F/k visible: all three are identifiable (no free offset)
    m, k, d, force = 1.0, 100.0, 2.0, 10.0
    omega, zeta = math.sqrt(k / m), d / (2 * math.sqrt(k * m))
    t = np.arange(0, 3, 2e-3)
    x, _, _ = free_decay(t, omega, zeta, -force / k, 0.0)  # about the new equilibrium F/k, from rest at 0
    data = write(tmp_path / "d.csv", {"time": t, "slider_pos": x + force / k})
    result = fit(
        "slider",
        data,
        "step",
        free=["mass", "stiffness", "damping", "x0", "v0"],
        force_amplitude=force,
        run_scene=False,
    )
    for name, truth in (("mass", m), ("stiffness", k), ("damping", d)):
        assert rel(result.estimates[name]["value"], truth) < EXACT


def test_car_stiffness_and_damping_from_a_recorded_heave(tmp_path):
    car = scenes.get("car")
    p = car.resolve(car.scenario("damped_release"), {})
    m, k, d = p["mass"], p["stiffness"], p["damping"]
    t = np.arange(0, 1.0, 1e-3)
    x, _, _ = free_decay(t, math.sqrt(k / m), d / (2 * math.sqrt(k * m)), -0.004, 0.0)
    data = write(tmp_path / "d.csv", {"time": t, "heave_pos": x + p["clearance"]})
    result = fit("car", data, "damped_release", run_scene=False)
    assert result.free[:2] == ("stiffness", "damping")
    assert rel(result.estimates["stiffness"]["value"], k) < EXACT
    assert rel(result.estimates["damping"]["value"], d) < EXACT
    assert rel(result.derived["damping_ratio"]["value"], p["damping_ratio"]) < EXACT


def test_car_mass_given_the_stiffness(tmp_path):
    car = scenes.get("car")
    p = car.resolve(car.scenario("damped_release"), {})
    m, k, d = p["mass"], p["stiffness"], p["damping"]
    t = np.arange(0, 1.0, 1e-3)
    x, _, _ = free_decay(t, math.sqrt(k / m), d / (2 * math.sqrt(k * m)), -0.004, 0.0)
    data = write(tmp_path / "d.csv", {"time": t, "heave_pos": x + p["clearance"]})
    result = fit(
        "car", data, "damped_release", free=["mass", "damping", "x0", "v0", "offset"], stiffness=k, run_scene=False
    )
    assert rel(result.estimates["mass"]["value"], m) < EXACT


def test_printer_belt_from_a_carriage_ring_down(tmp_path):
    printer = scenes.get("printer_head")
    p = printer.resolve(printer.scenario("settle"), {})
    m_c, m_m, k, c = p["carriage_mass"], p["motor_mass"], p["belt_stiffness"], p["belt_damping"]
    mu = m_c * m_m / (m_c + m_m)
    t = np.arange(0, 0.05, 2e-5)
    # the carriage rings about the resting centre of mass (the move's target, 50 mm)
    x, _, _ = free_decay(t, math.sqrt(k / mu), c / (2 * math.sqrt(k * mu)), 1e-4, 0.0)
    result = fit("printer_head", write(tmp_path / "d.csv", {"time": t, "carriage_pos": x + 0.05}))
    assert rel(result.estimates["belt_stiffness"]["value"], k) < EXACT
    assert rel(result.estimates["belt_damping"]["value"], c) < EXACT
    assert result.run is not None  # the identified scene ran


# -- untidy data ------------------------------------------------------------------------


def test_uneven_sampling_is_read_at_each_sample(tmp_path):
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 3, 1500))
    x, _, _ = free_decay(t, 20.0, 0.05, 0.05, 0.0)
    result = fit("slider", write(tmp_path / "d.csv", {"time": t, "slider_pos": x}), run_scene=False)
    assert rel(result.estimates["omega_n"]["value"], 20.0) < EXACT
    assert any("uneven" in note for note in result.record.notes)


def test_accelerometer_record_fits_on_acceleration_with_its_bias(tmp_path):
    t = np.arange(0, 3, 2e-3)
    _, _, a = free_decay(t, 20.0, 0.05, 0.05, 0.0)
    result = fit("slider", write(tmp_path / "d.csv", {"time": t, "slider_acc": a + 0.3}), run_scene=False)
    assert result.record.signal == "acc"
    assert rel(result.estimates["omega_n"]["value"], 20.0) < EXACT
    assert rel(result.estimates["zeta"]["value"], 0.05) < EXACT
    assert abs(result.estimates["offset"]["value"] - 0.3) < EXACT * 0.3


def test_held_start_is_detected_and_dropped(tmp_path):
    t = np.arange(0, 3, 2e-3)
    x, _, _ = free_decay(np.clip(t - 0.5, 0, None), 20.0, 0.05, 0.05, 0.0)
    result = fit("slider", write(tmp_path / "d.csv", {"time": t, "slider_pos": x}), run_scene=False)
    assert result.record.release_detected
    assert 0.5 <= result.record.origin <= 0.5 + 0.02  # first sample that left the held level
    assert rel(result.estimates["omega_n"]["value"], 20.0) < EXACT


def test_start_drops_the_record_before_it(tmp_path):
    t = np.arange(0, 3, 2e-3)
    x, _, _ = free_decay(np.clip(t - 0.5, 0, None), 20.0, 0.05, 0.05, 0.0)
    result = fit("slider", write(tmp_path / "d.csv", {"time": t, "slider_pos": x}), start=0.7, run_scene=False)
    assert result.record.origin == 0.7 and not result.record.release_detected
    assert result.record.dropped_before_start == np.count_nonzero(t < 0.7)
    assert rel(result.estimates["omega_n"]["value"], 20.0) < EXACT


def test_release_time_from_rest_is_fitted_as_a_delay(tmp_path):
    t = np.arange(0, 3, 2e-3)
    x, _, _ = free_decay(np.clip(t - 0.4567, 0, None), 20.0, 0.05, 0.05, 0.0)
    data = write(tmp_path / "d.csv", {"time": t, "slider_pos": x})
    result = fit("slider", data, free=["omega_n", "zeta", "x0", "offset", "delay"], v0=0.0, run_scene=False)
    assert abs(result.estimates["delay"]["value"] - 0.4567) < 1e-6
    assert rel(result.estimates["omega_n"]["value"], 20.0) < EXACT


def test_millimetres_scale_and_a_mapped_column(tmp_path):
    t = np.arange(0, 3, 2e-3)
    x, _, _ = free_decay(t, 20.0, 0.05, 0.05, 0.0)
    data = write(tmp_path / "d.csv", {"t_s": t, "x_mm": 1e3 * x})
    result = fit("slider", data, map={"t_s": "time", "x_mm": "slider_pos"}, scale=1e-3, run_scene=False)
    assert rel(result.estimates["x0"]["value"], 0.05) < EXACT


def test_nan_and_empty_rows_are_skipped_and_counted(tmp_path):
    t = np.arange(0, 3, 2e-3)
    x, _, _ = free_decay(t, 20.0, 0.05, 0.05, 0.0)
    lines = ["time,slider_pos"] + [f"{a:.17g},{b:.17g}" for a, b in zip(t, x)]
    lines[100] = f"{t[99]:.17g},"  # missing value
    lines[200] = f"{t[199]:.17g},nan"
    lines[300] = f",{x[299]:.17g}"  # missing time
    (tmp_path / "d.csv").write_text("\n".join(lines) + "\n")
    result = fit("slider", str(tmp_path / "d.csv"), run_scene=False)
    assert result.record.skipped_nan == 3
    assert result.record.time.size == t.size - 3
    assert rel(result.estimates["omega_n"]["value"], 20.0) < EXACT


def test_too_few_rows_after_skipping_is_bad_input(tmp_path):
    (tmp_path / "d.csv").write_text("time,slider_pos\n" + "".join(f"{i},nan\n" for i in range(50)) + "1,2\n")
    with pytest.raises(BadInputError, match="usable sample"):
        fit("slider", str(tmp_path / "d.csv"))


# -- what cannot be identified -----------------------------------------------------------


@pytest.mark.parametrize(
    ("free", "match"),
    [
        (["mass", "stiffness", "damping"], "cannot all be fitted"),
        (["omega_n", "stiffness"], "not both"),
        (["omega_n", "zeta", "x0", "v0", "delay"], "delay and v0"),
        (["viscosity"], "unknown fit parameter"),
    ],
)
def test_unidentifiable_requests_are_refused(tmp_path, free, match):
    t = np.arange(0, 1, 2e-3)
    x, _, _ = free_decay(t, 20.0, 0.05, 0.05, 0.0)
    with pytest.raises(BadInputError, match=match):
        fit("slider", write(tmp_path / "d.csv", {"time": t, "slider_pos": x}), free=free)


def test_mass_and_stiffness_need_damping(tmp_path):
    t = np.arange(0, 1, 2e-3)
    x, _, _ = free_decay(t, 20.0, 0.0, 0.05, 0.0)
    with pytest.raises(BadInputError, match="damping = 0"):
        fit("slider", write(tmp_path / "d.csv", {"time": t, "slider_pos": x}), free=["mass", "stiffness"], damping=0)


def test_printer_masses_are_refused(tmp_path):
    t = np.arange(0, 0.01, 2e-5)
    x, _, _ = free_decay(t, 1200.0, 0.03, 1e-4, 0.0)
    with pytest.raises(BadInputError, match="--set carriage_mass"):
        fit("printer_head", write(tmp_path / "d.csv", {"time": t, "carriage_pos": x}), free=["carriage_mass"])


# -- kinematics: the textbook polynomial ------------------------------------------------


def test_textbook_polynomial_back_from_noisy_samples_as_numpy_fits_it(tmp_path):
    rng = np.random.default_rng(5)
    t = np.linspace(0, 10, 201)
    truth = [3.0, 1.2, 0.2, 0.03]  # x(t) = 0.03 t^3 + 0.2 t^2 + 1.2 t + 3 (section 5.2)
    x = np.polynomial.polynomial.polyval(t, truth) + rng.normal(0, 0.05, t.size)
    result = fit("kinematics", write(tmp_path / "d.csv", {"time": t, "vehicle_pos": x}), run_scene=False)
    reference = np.polynomial.Polynomial.fit(t, x, 3).convert().coef
    names = ("constant_m", "linear_coefficient_m_s", "quadratic_coefficient_m_s2", "cubic_coefficient_m_s3")
    design = np.vander(t, 4, increasing=True)
    residual = x - design @ reference
    covariance = residual @ residual / (t.size - 4) * np.linalg.inv(design.T @ design)
    quantile = 1.9720  # Student t, 0.975, 197 degrees of freedom
    for i, name in enumerate(names):
        got = result.derived[name]
        half = got["ci95"][1] - got["value"]
        # the same least-squares problem: equal up to the conditioning of the cubic's normal equations
        assert abs(got["value"] - reference[i]) < 1e-6 * math.sqrt(covariance[i, i])
        assert abs(half / (quantile * math.sqrt(covariance[i, i])) - 1) < 1e-3
        assert abs(got["value"] - truth[i]) < half * 2  # the truth within the interval (with margin)
    # v(t) and a(t) carry their bands
    curves = result.curves
    assert len(curves["v_m_s"]) == len(curves["time_s"]) and min(curves["a_m_s2_ci95_halfwidth"]) > 0


def test_kinematics_degree_two_and_velocity_data(tmp_path):
    t = np.linspace(0, 5, 51)
    v = 15.0 + 3.0 * t  # v(t) of uniformly accelerated motion
    result = fit("kinematics", write(tmp_path / "d.csv", {"time": t, "vehicle_vel": v}), degree=2, run_scene=False)
    assert result.free == ("v0", "a0")
    assert rel(result.estimates["a0"]["value"], 3.0) < 1e-9


def test_kinematics_chooses_the_degree_of_uniformly_accelerated_motion(tmp_path):
    rng = np.random.default_rng(8)
    t = np.linspace(0, 5, 101)
    x = 10.0 * t + t**2 + rng.normal(0, 0.01, t.size)  # eq. 5.5: a = 2 m/s^2 from 10 m/s, no jerk
    result = fit("kinematics", write(tmp_path / "d.csv", {"time": t, "vehicle_pos": x}), run_scene=False)
    assert result.free == ("x0", "v0", "a0")
    assert any("degree chosen" in note for note in result.record.notes)
    low, high = result.estimates["a0"]["ci95"]
    assert low <= 2.0 <= high


def test_kinematics_refuses_an_offset(tmp_path):
    t = np.linspace(0, 5, 51)
    with pytest.raises(BadInputError, match="indistinguishable"):
        fit("kinematics", write(tmp_path / "d.csv", {"time": t, "vehicle_pos": t**2}), free=["x0", "offset"])


# -- coverage of the 95 % intervals --------------------------------------------------------


def _coverage(tmp_path, scene, column, t, omega, zeta, amplitude, noise, truths, seeds=50, **fixed):
    inside = 0
    for seed in range(seeds):
        rng = np.random.default_rng(1000 + seed)
        x, _, _ = free_decay(t, omega, zeta, amplitude, 0.0)
        data = write(tmp_path / "d.csv", {"time": t, column: x + rng.normal(0, noise, t.size)})
        result = fit(scene, data, run_scene=False, **fixed)
        for name, truth in truths.items():
            low, high = result.estimates[name]["ci95"]
            inside += low <= truth <= high
    return inside / (seeds * len(truths))


@pytest.mark.slow
def test_slider_intervals_cover_the_truth_95_percent_of_the_time(tmp_path):
    t = np.arange(0, 1.5, 5e-3)
    share = _coverage(tmp_path, "slider", "slider_pos", t, 20.0, 0.05, 0.05, 2e-3, {"omega_n": 20.0, "zeta": 0.05})
    assert 0.88 <= share <= 0.99


@pytest.mark.slow
def test_car_intervals_cover_the_truth_95_percent_of_the_time(tmp_path):
    car = scenes.get("car")
    p = car.resolve(car.scenario("damped_release"), {})
    m, k, d = p["mass"], p["stiffness"], p["damping"]
    t = np.arange(0, 0.5, 2e-3)
    omega, zeta = math.sqrt(k / m), d / (2 * math.sqrt(k * m))
    share = _coverage(
        tmp_path, "car", "heave_pos", t, omega, zeta, -0.004, 1e-4, {"stiffness": k, "damping": d}, scenario=None
    )
    assert 0.88 <= share <= 0.99


def test_fit_json_has_the_contract_keys(tmp_path):
    from springlab import outputs

    t = np.arange(0, 1, 2e-3)
    x, _, _ = free_decay(t, 20.0, 0.05, 0.05, 0.0)
    result = fit("slider", write(tmp_path / "d.csv", {"time": t, "slider_pos": x}))
    outputs.write(result, tmp_path / "out")
    doc = json.loads((tmp_path / "out" / "fit.json").read_text())
    for key in ("scene", "scenario", "free", "estimates", "derived", "residual_rms", "samples", "time_span_s"):
        assert key in doc
    for key in ("cross_check", "optimizer", "correlation", "degrees_of_freedom"):
        assert key in doc
    assert set(doc["estimates"]["omega_n"]) == {"value", "ci95", "unit"}
    assert (tmp_path / "out" / "trajectory.csv").exists() and (tmp_path / "out" / "summary.json").exists()
