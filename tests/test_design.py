"""The printer-head design study: every configuration obeys the physics, the ranking and its signs
are physical, the analytic estimate agrees, and `springlab design` keeps its contract.

Independent references: the bang-bang minimum 2 sqrt(D M / F) by hand, and for the default
configuration the exact 2-DOF trajectory (scipy expm, on the study's own step grid) from which the
settling time is read off in the test.
"""

import json
import math

import numpy as np
import pytest
import scipy.linalg

from springlab import design
from springlab.cli import main


@pytest.fixture(scope="module")
def small_study():
    """3^4 = 81 configurations: the grid's corners and centre."""
    return design.run_study(levels=3)


@pytest.fixture(scope="module")
def default_study():
    """5^4 = 625 configurations over the default spans (the default 7^4 takes 10-20 s on 2 shared
    cores: it runs in the demo and `springlab design`, not here)."""
    return design.run_study(levels=5)


def test_default_sweep_has_at_least_1000_configurations():
    grids = design.make_grids(design.base_parameters(), design.DEFAULT_LEVELS)
    values = design.configurations(grids)
    assert len(values["belt_stiffness"]) == design.DEFAULT_LEVELS ** len(design.PROPERTIES) >= 1000
    # a full factorial: every combination once
    assert len({tuple(values[p][i] for p in design.PROPERTIES) for i in range(len(values["drive_force"]))}) \
        == len(values["drive_force"])


def test_every_configuration_settles_for_good(default_study):
    assert default_study.size == 625
    assert np.all(np.isfinite(default_study.positioning_time_s))


def test_no_configuration_beats_its_bang_bang_minimum(default_study):
    s = default_study
    total = s.values["carriage_mass"] + s.base["motor_mass"]
    minimum = 2 * np.sqrt(s.base["move_distance"] * total / s.values["drive_force"])
    assert np.all(s.move_time_s >= minimum * (1 - 1e-12))
    assert np.all(s.move_time_s <= minimum + 2 * s.dt_s + 1e-15)  # rounded up to each grid by < 1 step/half
    assert np.all(s.positioning_time_s >= minimum)


def test_ranking_is_sorted_by_absolute_elasticity(default_study):
    elasticity = default_study.elasticities()
    magnitudes = [abs(elasticity[name]) for name in default_study.ranking()]
    assert magnitudes == sorted(magnitudes, reverse=True)
    assert set(default_study.ranking()) == set(design.PROPERTIES)


def test_elasticity_signs_are_physical(default_study):
    # stiffer belt (faster, smaller residual), more force (shorter move), more damping (faster decay)
    # all shorten the positioning; a heavier carriage lengthens it
    elasticity = default_study.elasticities()
    assert elasticity["belt_stiffness"] < 0
    assert elasticity["drive_force"] < 0
    assert elasticity["damping_ratio"] < 0
    assert elasticity["carriage_mass"] > 0


def test_analytic_estimate_agrees_with_simulation(default_study):
    # the estimate uses the residual vibration's exact envelope, so it can only overshoot by where
    # the last band exit lies under the envelope: at most one vibration period
    s = default_study
    period = 1 / s.natural_frequency_hz
    assert np.all(s.estimate_s >= s.positioning_time_s - 2 * s.dt_s)
    assert np.all(s.estimate_s <= s.positioning_time_s + period + 2 * s.dt_s)
    i = s.default_index()
    assert s.estimate_s[i] / s.positioning_time_s[i] == pytest.approx(1.0, abs=0.05)


def test_default_configuration_settles_as_the_exact_trajectory_says(small_study):
    # one configuration (the default) through the batch, vs expm on its own step grid
    study = small_study
    i = study.default_index()
    base = study.base
    m_c, m_m = study.values["carriage_mass"][i], base["motor_mass"]
    k, zeta, limit = (study.values[name][i] for name in ("belt_stiffness", "damping_ratio", "drive_force"))
    total, reduced = m_c + m_m, m_c * m_m / (m_c + m_m)
    c = 2 * zeta * math.sqrt(k * reduced)
    dt = study.dt_s[i]
    assert dt == pytest.approx(0.1 / math.sqrt(k / reduced), rel=1e-12)
    n = math.ceil(math.sqrt(base["move_distance"] * total / limit) / dt - 1e-9)
    force = total * base["move_distance"] / (n * dt) ** 2
    belt = np.array([[1.0, -1.0], [-1.0, 1.0]])
    a = np.zeros((5, 5))
    a[0:2, 2:4] = np.eye(2)
    a[2:4, 0:2] = -np.diag([1 / m_c, 1 / m_m]) @ (k * belt)
    a[2:4, 2:4] = -np.diag([1 / m_c, 1 / m_m]) @ (c * belt)
    a[3, 4] = 1 / m_m
    step = scipy.linalg.expm(a * dt)
    state = np.array([0.0, 0.0, 0.0, 0.0, force])
    carriage = [0.0]
    for j in range(int(0.2 / dt)):
        state[4] = force if j < n else (-force if j < 2 * n else 0.0)
        state = step @ state
        carriage.append(state[0])
    carriage = np.array(carriage)
    time = np.arange(len(carriage)) * dt
    outside = np.flatnonzero(np.abs(carriage - base["move_distance"]) > base["positioning_band"])
    last_exit = time[outside[-1]]  # the exit lies in the step after the last sample outside
    assert study.move_time_s[i] == pytest.approx(2 * n * dt, rel=1e-12)
    assert last_exit <= study.positioning_time_s[i] <= last_exit + dt


def test_design_json_has_the_documented_shape(capsys, tmp_path):
    code = main(["design", "printer_head", "--levels", "3", "--json", "--output", str(tmp_path / "d")])
    out, err = capsys.readouterr()
    assert code == 0, err
    summary = json.loads(out)
    for key in ("scene", "configurations", "levels", "properties", "fixed", "default", "fastest",
                "positioning_time_s", "elasticities", "local_elasticities", "ranking",
                "estimate_over_simulation", "wall_time_s", "configurations_per_s"):
        assert key in summary
    assert summary["configurations"] == 81 and summary["levels"] == 3
    assert set(summary["elasticities"]) == set(design.PROPERTIES)
    default = summary["default"]
    assert default["positioning_time_s"] == pytest.approx(default["move_time_s"] + default["settling_time_s"])
    assert sorted(p.name for p in (tmp_path / "d").iterdir()) == ["configurations.csv", "design.json",
                                                                  "design.png"]
    assert json.loads((tmp_path / "d" / "design.json").read_text())["configurations"] == 81


def test_design_text_answers_both_questions(capsys):
    code = main(["design", "printer_head", "--levels", "3"])
    out, _ = capsys.readouterr()
    assert code == 0
    assert "How fast?" in out and "Which properties?" in out


@pytest.mark.parametrize("argv, needle", [
    (["design", "slider"], "printer_head"),
    (["design", "printer_head", "--levels", "4"], "odd"),
    (["design", "printer_head", "--levels", "3", "--set", "drive_force=-5"], "drive_force"),
    (["design", "printer_head", "--levels", "3", "--set", "belt_damping=0"], "belt_damping"),
])
def test_design_bad_input_exits_2_with_one_line(argv, needle, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    assert len(err.strip().splitlines()) == 1
    assert needle in err
