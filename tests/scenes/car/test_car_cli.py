"""The car on the command line: its columns, its validation, its one-line errors."""

import csv
import json

import pytest


@pytest.mark.parametrize(
    "scenario, joints",
    [
        ("push_release", ["heave"]),
        ("pitch_heave", ["heave", "pitch"]),
        ("road_bump", ["heave", "wheel"]),
    ],
)
def test_trajectory_has_the_scenarios_joints_and_their_references(tmp_path, cli, scenario, joints):
    code, _, err = cli("run", "car", scenario, "--duration", "0.6", "--output", str(tmp_path))
    assert code == 0, err
    with open(tmp_path / "trajectory.csv") as handle:
        header = next(csv.reader(handle))
    expected = ["time"] + [f"{j}_{k}" for j in joints for k in ("pos", "vel")]
    expected += [f"{j}_{k}_ref" for j in joints for k in ("pos", "vel")]
    assert header == expected
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["passed"] is True


def test_validate_car_passes_every_scenario(cli):
    code, out, _ = cli("validate", "car", "--json")
    rows = json.loads(out)
    assert code == 0
    assert [r["scenario"] for r in rows] == ["push_release", "damped_release", "pitch_heave", "road_bump"]
    assert all(r["passed"] for r in rows)
    # each scenario's default dt is the largest whose predicted bound meets 1e-6
    assert all(r["tolerance"] <= 1e-6 for r in rows)


def test_run_prints_the_textbook_answers(cli):
    code, out, _ = cli("run", "car", "push_release")
    assert code == 0
    assert "static_sag_m               0.0024525" in out
    assert "height_before_release_m    0.0975475" in out
    assert "omega_rad_s                31.6227766" in out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--set", "speed=0"], "speed must be a finite number > 0 m/s"),
        (["--set", "bump_height=0.2"], "through the ground"),
    ],
)
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, cli, argv, message):
    code, out, err = cli("run", "car", "road_bump", *argv, "--output", str(tmp_path / "d"))
    assert code == 2
    assert message in err and err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "d").exists()


def test_a_tire_that_leaves_the_road_is_written_but_not_validated(tmp_path, cli):
    # the linear tire would pull on the road after 0.0273 s: the outputs are a result, exit 1 says not to trust it
    argv = ["run", "car", "road_bump", "--set", "bump_height=0.03", "--set", "bump_length=0.3", "--set", "speed=10"]
    code, out, err = cli(*argv, "--output", str(tmp_path))
    assert code == 1
    assert "not validated: outside the scene's model" in out and "PASS" not in out
    (line,) = err.strip().splitlines()
    assert line.startswith("springlab: car road_bump is not validated: the tire leaves the road at t = 0.0273274 s")
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["passed"] is False and summary["quantities"]["tire_leaves_road"] is True
