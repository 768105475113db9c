"""The printer-head design study: every configuration obeys the physics, the ranking and its signs
are physical, the analytic estimate agrees, and `springlab design` keeps its contract; the study is
read from the scene's declaration (`Scene.design`), and its result is an immutable object whose
`to_dict()` is what `design --json` prints.

Independent references: the bang-bang minimum 2 sqrt(D M / F) by hand, and for the default
configuration the exact 2-DOF trajectory (scipy expm, on the study's own step grid) from which the
settling time is read off in the test.
"""

import dataclasses
import json
import math

import numpy as np
import pytest
import scipy.linalg

from helpers.cli import run_cli
from springlab import scenes
from springlab.errors import UnknownNameError
from springlab.scenes.capabilities.design import DesignSpec
from springlab.studies.design import study as design

#: the printer head's swept properties, in grid order
PROPERTIES = ("belt_stiffness", "carriage_mass", "damping_ratio", "drive_force")


@pytest.fixture(scope="module")
def small_study(small_design_study):
    """3^4 = 81 configurations: the grid's corners and centre, and a 9 x 9 plane (tests/conftest.py)."""
    return small_design_study


@pytest.fixture(scope="module")
def design_command(small_study, tmp_path_factory):
    """`springlab design printer_head --levels 3 --plane 9 --sobol 8 --json --output DIR` as a user types it, the
    study it asks for the session's small one (tests/conftest.py: the same call, computed once): run once and read
    by every test of what the command prints and writes (each write draws design.png and sobol.png, 0.7-1 s of
    CPU). Returns (CliResult, DIR, the options the command passed to the study); the files are read-only, so no
    reader can change what the next one reads."""
    asked = {}

    def recorded(model, **options):
        asked.update(options, model=model)
        return small_study

    out = tmp_path_factory.mktemp("design") / "d"
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(design, "run_study", recorded)
        printed = run_cli(
            "design", "printer_head", "--levels", "3", "--plane", "9", "--sobol", "8", "--json", "--output", out
        )
    for path in out.iterdir() if out.is_dir() else ():
        path.chmod(0o444)
    return printed, out, asked


@pytest.fixture(scope="module")
def default_study(default_design_study):
    """The default grid's 7^4 = 2401 configurations (tests/conftest.py, shared with the settling test)."""
    return default_design_study


def test_default_sweep_has_at_least_1000_configurations():
    grids = design.make_grids("printer_head", design.base_parameters("printer_head"), design.DEFAULT_LEVELS)
    values = design.configurations(grids)
    assert tuple(grids) == PROPERTIES
    assert len(values["belt_stiffness"]) == design.DEFAULT_LEVELS ** len(PROPERTIES) >= 1000
    # a full factorial: every combination once
    assert len({tuple(values[p][i] for p in PROPERTIES) for i in range(len(values["drive_force"]))}) == len(
        values["drive_force"]
    )


def test_the_scenes_that_declare_a_design_question_are_the_design_studies():
    declared = [name for name, scene in scenes.SCENES.items() if isinstance(scene.design, DesignSpec)]
    assert design.design_scenes() == declared == ["printer_head"]
    spec = scenes.get("printer_head").design
    assert spec.names == PROPERTIES and spec.scenario in scenes.get("printer_head").scenarios
    assert set(spec.sobol) <= {p.name for p in (*spec.properties, *spec.extra)}
    with pytest.raises(UnknownNameError, match="valid: printer_head"):
        design.run_study("slider")


@pytest.mark.slow
def test_every_configuration_settles_for_good(default_study):
    assert default_study.size == design.DEFAULT_LEVELS**4 == 2401
    assert np.all(np.isfinite(default_study.positioning_time_s))


@pytest.mark.slow
def test_no_configuration_beats_its_bang_bang_minimum(default_study):
    s = default_study
    total = s.values["carriage_mass"] + s.base["motor_mass"]
    minimum = 2 * np.sqrt(s.base["move_distance"] * total / s.values["drive_force"])
    # each simulation's dt divides the half-move: the move is the minimum itself
    np.testing.assert_allclose(s.move_time_s, minimum, rtol=1e-12)
    assert np.all(s.positioning_time_s >= minimum * (1 - 1e-12))


@pytest.mark.slow
def test_ranking_is_sorted_by_absolute_elasticity(default_study):
    elasticity = default_study.elasticities
    magnitudes = [abs(elasticity[name]) for name in default_study.ranking]
    assert magnitudes == sorted(magnitudes, reverse=True)
    assert set(default_study.ranking) == set(PROPERTIES)


@pytest.mark.slow
def test_elasticity_signs_are_physical(default_study):
    # stiffer belt (faster, smaller residual), more force (shorter move), more damping (faster decay)
    # all shorten the positioning; a heavier carriage lengthens it
    elasticity = default_study.elasticities
    assert elasticity["belt_stiffness"] < 0
    assert elasticity["drive_force"] < 0
    assert elasticity["damping_ratio"] < 0
    assert elasticity["carriage_mass"] > 0


@pytest.mark.slow
def test_analytic_estimate_agrees_with_simulation(default_study):
    # the estimate uses the residual vibration's exact envelope, so it can only overshoot by where
    # the last band exit lies under the envelope: at most one vibration period
    s = default_study
    period = 1 / s.natural_frequency_hz
    assert np.all(s.estimate_s >= s.positioning_time_s - 2 * s.dt_s)
    assert np.all(s.estimate_s <= s.positioning_time_s + period + 2 * s.dt_s)
    i = s.default_index
    assert s.estimate_s[i] / s.positioning_time_s[i] == pytest.approx(1.0, abs=0.05)


@pytest.mark.slow
def test_default_configuration_settles_as_the_exact_trajectory_says(small_study):
    # one configuration (the default) through the batch, vs expm on its own step grid
    study = small_study
    i = study.default_index
    base = study.base
    m_c, m_m = study.values["carriage_mass"][i], base["motor_mass"]
    k, zeta, limit = (study.values[name][i] for name in ("belt_stiffness", "damping_ratio", "drive_force"))
    total, reduced = m_c + m_m, m_c * m_m / (m_c + m_m)
    c = 2 * zeta * math.sqrt(k * reduced)
    dt = study.dt_s[i]
    # the largest step <= 0.1 / omega_n that divides the minimum half-move time sqrt(D M / F)
    half = math.sqrt(base["move_distance"] * total / limit)
    n = math.ceil(half / (design.OMEGA_DT / math.sqrt(k / reduced)))
    assert dt == pytest.approx(half / n, rel=1e-12)
    force = limit  # the switch falls on the grid: the full force, the true minimum time
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


def test_design_json_has_the_documented_shape(design_command):
    # the command line's arguments reach the study (levels, plane, Sobol samples, the library's defaults for the
    # rest), and the study they ask for is the session's small one (tests/conftest.py: the same call, computed
    # once; it cost this test 6 s to run it again)
    (code, out, err), folder, asked = design_command
    assert code == 0, err
    asked = dict(asked)
    executor = asked.pop("executor")
    assert executor is not None and not executor.distributed  # where the chunks run: here
    assert asked == {
        "model": "printer_head",
        "levels": 3,
        "plane_levels": 9,
        "sobol": 8,
        "sobol_seed": 0,
        "omega_dt": design.OMEGA_DT,
    }  # conftest's run_study("printer_head", levels=3, plane_levels=9, sobol=8): the rest its defaults
    summary = json.loads(out)
    for key in (
        "scene",
        "configurations",
        "levels",
        "properties",
        "fixed",
        "default",
        "fastest",
        "positioning_time_s",
        "elasticities",
        "local_elasticities",
        "ranking",
        "estimate_over_simulation",
        "wall_time_s",
        "configurations_per_s",
        "plane",
        "sobol",
    ):
        assert key in summary
    assert summary["configurations"] == 81 and summary["levels"] == 3 and summary["plane"]["levels"] == 9
    assert set(summary["elasticities"]) == set(PROPERTIES)
    assert summary["sobol"]["runs"] == 8 * 7
    default = summary["default"]
    assert default["positioning_time_s"] == pytest.approx(default["move_time_s"] + default["settling_time_s"])
    assert sorted(p.name for p in folder.iterdir()) == [
        "configurations.csv",
        "design.json",
        "design.png",
        "sobol.png",
    ]
    assert all((folder / name).stat().st_size > 0 for name in ("design.png", "sobol.png"))
    assert json.loads((folder / "design.json").read_text())["configurations"] == 81


def _cli_with(study, monkeypatch, cli, *argv):
    """`springlab design printer_head ARGV` with the study it computes replaced by `study`: (code, out)."""
    monkeypatch.setattr(design, "run_study", lambda *args, **kwargs: study)
    code, out, err = cli("design", "printer_head", *argv)
    assert code == 0, err
    return code, out


def test_to_dict_is_what_design_json_prints_and_design_json_holds(small_study, design_command):
    (code, out, err), folder, _ = design_command
    assert code == 0, err
    assert json.loads(out) == small_study.to_dict()
    assert json.loads((folder / "design.json").read_text()) == small_study.to_dict()
    # JSON-ready already: a round trip through json changes nothing, the sobol entry included
    assert json.loads(json.dumps(small_study.to_dict())) == small_study.to_dict()
    assert small_study.to_dict()["sobol"] == small_study.sobol.to_dict()


def test_to_dict_carries_the_attributes(small_study):
    s, summary = small_study, small_study.to_dict()
    i = s.default_index
    assert summary["scene"] == s.scene == "printer_head"
    assert summary["configurations"] == s.size == 81 and summary["levels"] == s.levels == 3
    assert summary["ranking"] == list(s.ranking) and summary["elasticities"] == dict(s.elasticities)
    assert summary["regression_r2"] == s.regression_r2
    assert summary["local_elasticities"] == dict(s.local_elasticities)
    assert summary["default"]["positioning_time_s"] == s.positioning_time_s[i]
    assert summary["default"]["properties"] == {name: s.values[name][i] for name in PROPERTIES}
    assert summary["fixed"] == {name: s.base[name] for name in ("motor_mass", "move_distance", "positioning_band")}
    assert summary["plane"]["configurations"] == s.plane.positioning_time_s.size == 81


def test_to_pandas_has_a_row_per_configuration_as_configurations_csv(small_study, design_command):
    frame = small_study.to_pandas()
    _, folder, _ = design_command  # the command's folder, written by the one writer (springlab.outputs.write)
    lines = (folder / "configurations.csv").read_text().splitlines()
    assert lines[0].split(",") == list(frame.columns)
    assert len(frame) == small_study.size == len(lines) - 1
    np.testing.assert_array_equal(frame["positioning_time_s"].to_numpy(), small_study.positioning_time_s)
    np.testing.assert_array_equal(frame["belt_stiffness"].to_numpy(), small_study.values["belt_stiffness"])
    # the CSV's last row is the to_pandas last row, at full precision
    assert [float(v) for v in lines[-1].split(",")] == frame.iloc[-1].tolist()


def test_a_study_cannot_be_changed_once_returned(small_study):
    with pytest.raises(dataclasses.FrozenInstanceError):
        small_study.steps = 0
    with pytest.raises(ValueError, match="read-only"):
        small_study.positioning_time_s[0] = 0.0
    with pytest.raises(ValueError, match="read-only"):
        small_study.values["drive_force"][0] = 0.0
    with pytest.raises(TypeError):
        small_study.base["drive_force"] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        small_study.plane.positioning_time_s[0, 0] = 0.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        small_study.sobol.runs = 0


def test_design_text_answers_both_questions(small_study, monkeypatch, cli):
    _, out = _cli_with(small_study, monkeypatch, cli, "--plane", "0")
    assert "How fast?" in out and "Which properties?" in out
    assert small_study.answer in out and small_study.sobol.answer in out
    # the design table lists every property once, in the ranking's order (the Sobol table follows it)
    table = out.split("log-log fit")[0]
    rows = [words[0] for words in map(str.split, table.splitlines()) if words and words[0] in PROPERTIES]
    assert rows == list(small_study.ranking)


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["design", "slider"], "printer_head"),
        (["design", "printer_head", "--levels", "4"], "odd"),
        (["design", "printer_head", "--levels", "3", "--plane", "4"], "plane"),
        (["design", "printer_head", "--levels", "3", "--set", "drive_force=-5"], "drive_force"),
        (["design", "printer_head", "--levels", "3", "--set", "belt_damping=0"], "belt_damping"),
    ],
)
def test_design_bad_input_exits_2_with_one_line(argv, needle, cli):
    code, out, err = cli(*argv)
    assert code == 2
    assert out == ""
    assert len(err.strip().splitlines()) == 1
    assert needle in err


@pytest.mark.slow
def test_plane_spans_the_two_most_influential_properties_around_the_default(small_study):
    plane = small_study.plane
    assert (plane.y_name, plane.x_name) == small_study.ranking[:2]
    assert plane.positioning_time_s.shape == (9, 9) == plane.estimate_s.shape
    # its axes cover the study's grid ranges, with the default in the middle
    np.testing.assert_allclose(plane.y[[0, 4, 8]], small_study.grids[plane.y_name], rtol=1e-12)
    np.testing.assert_allclose(plane.x[[0, 4, 8]], small_study.grids[plane.x_name], rtol=1e-12)
    # the same configurations as the grid's corners and centre, on the same step grids: the same times
    axes = list(small_study.grids)
    shape = (3,) * len(axes)
    index = [1] * len(shape)
    index[axes.index(plane.y_name)] = slice(None)
    index[axes.index(plane.x_name)] = slice(None)
    coarse = small_study.positioning_time_s.reshape(shape)[tuple(index)]
    if axes.index(plane.y_name) > axes.index(plane.x_name):
        coarse = coarse.T
    np.testing.assert_allclose(plane.positioning_time_s[::4, ::4], coarse, rtol=1e-12)
    assert np.all(np.isfinite(plane.positioning_time_s))
