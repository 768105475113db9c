"""Results are objects: facts as attributes, immutable once returned, `to_dict()` is exactly what `--json`
prints, `to_pandas()` is exactly the CSV the command writes.

The JSON checks capture the object the command line computed (by wrapping the library function it calls)
and compare its `to_dict()` with the printed JSON; an independent API call must agree on everything but
wall times. Each `to_pandas()` is compared, number for number, with the CSV read back by pandas.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pandas
import pytest

import springlab
from helpers.contract import SUMMARY_KEYS
from springlab.cli.main import main
from springlab.runs.compare import ColumnError, Verdict
from springlab.runs.run import Result, ValidationRow, run_scenario
from springlab.studies import auto, families
from springlab.studies.auto import NO_SWEEP_NOTE


def _capture(monkeypatch, module, name: str) -> list:
    """Wrap module.name so every object it returns is kept (the object a command computed)."""
    seen: list = []
    original = getattr(module, name)

    def wrapper(*args, **kwargs):
        seen.append(original(*args, **kwargs))
        return seen[-1]

    monkeypatch.setattr(module, name, wrapper)
    return seen


def _without(data, keys=("wall_time_s",)):
    """`data` with the wall-time keys removed at every depth (two runs never take the same time)."""
    if isinstance(data, dict):
        return {k: _without(v, keys) for k, v in data.items() if k not in keys}
    if isinstance(data, list):
        return [_without(v, keys) for v in data]
    return data


# -- a run ------------------------------------------------------------------------------------------


def test_run_json_and_summary_json_are_the_results_to_dict(tmp_path, capsys, monkeypatch):
    seen = _capture(monkeypatch, auto, "run")
    code = main(["run", "slider", "free", "--set", "damping=2", "--json", "--output", str(tmp_path)])
    printed = json.loads(capsys.readouterr().out)
    assert code == 0 and len(seen) == 1
    result = seen[0]
    assert printed == result.to_dict() == json.loads((tmp_path / "summary.json").read_text())
    assert list(printed) == SUMMARY_KEYS
    # the same run through the API: the same facts, to the bit, but for its wall time
    again = springlab.run("slider", "free", damping=2.0)
    assert _without(again.to_dict()) == _without(printed)


def test_the_attributes_are_the_facts_summary_json_holds():
    result = springlab.run("slider", "underdamped", integrator="euler", dt=1e-3)
    data = result.to_dict()
    assert result.passed is data["passed"] is True
    assert result.verdict is Verdict.PASS and data["verdict"] == "PASS" and result.verdict.validated
    assert (result.scene, result.scenario, result.integrator, result.dt) == ("slider", "underdamped", "euler", 1e-3)
    assert result.steps == data["steps"] == round(data["duration"] / 1e-3)
    assert result.tolerance == data["tolerance"] == max(result.column_tolerances.values())
    assert {c: e.to_dict() for c, e in result.errors.items()} == data["errors"]
    assert all(isinstance(e, ColumnError) for e in result.errors.values())
    assert result.max_rel_error == max(e["max_rel"] for e in data["errors"].values())
    assert result.quantities == data["quantities"] and result.parameters == data["parameters"]
    assert result.estimate_range is not None and result.estimate_range.to_dict() == data["estimate_range"]
    assert result.checks == () and result.model_limits == ()
    # `summary` is kept as the same dict, in Python values, and warns that to_dict() is its new name
    with pytest.warns(DeprecationWarning, match=r"Result\.to_dict\(\)"):
        assert result.summary == data
    assert result.message.startswith("every compared column within its tolerance")


def test_to_dict_is_plain_json_where_python_has_inf_and_summary_keeps_it():
    result = springlab.run("printer_head", "settle", belt_damping=0.0)  # a carriage that never settles
    assert math.isinf(result.quantities["settling_time_s"])
    with pytest.warns(DeprecationWarning, match="deprecated"):
        assert math.isinf(result.summary["quantities"]["settling_time_s"])
    assert result.to_dict()["quantities"]["settling_time_s"] is None
    assert json.loads(json.dumps(result.to_dict(), allow_nan=False)) == result.to_dict()


@pytest.mark.parametrize(("scene", "scenario"), [("slider", "free"), ("car", "pitch_heave")])
def test_to_pandas_is_trajectory_csv(tmp_path, scene, scenario):
    result = run_scenario(scene, scenario, duration=0.5)
    assert main(["run", scene, scenario, "--duration", "0.5", "--output", str(tmp_path)]) in (0, 1)
    frame = result.to_pandas()
    written = pandas.read_csv(tmp_path / "trajectory.csv")
    assert list(frame.columns) == list(written.columns)
    assert len(frame) == result.steps + 1
    pandas.testing.assert_frame_equal(frame, written, check_exact=True)


def test_a_result_is_immutable_once_returned():
    result = springlab.run("slider", "free", duration=0.5)
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.passed = False  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.verdict = Verdict.FAIL  # type: ignore[misc]
    for series in (result.time, result.pos["slider"], result.vel["slider"], result.ref_pos["slider"]):
        with pytest.raises(ValueError, match="read-only"):
            series[0] = 1.0
    # the dicts handed out are copies: changing them changes nothing the result says
    with pytest.warns(DeprecationWarning):
        result.summary["passed"] = False
    result.to_dict()["errors"].clear()
    assert result.passed is True and result.to_dict()["passed"] is True and result.to_dict()["errors"]


def test_the_verdict_values_are_summary_jsons_strings():
    assert [v.value for v in Verdict] == [
        "PASS",
        "FAIL",
        "not validated: outside the range of the error estimate",
        "not validated: outside the scene's model",
    ]
    assert json.dumps(Verdict.NOT_VALIDATED) == '"not validated: outside the range of the error estimate"'
    assert f"{Verdict.PASS}" == str(Verdict.PASS) == "PASS" == Verdict.PASS
    assert springlab.Verdict is Verdict


def test_a_run_outside_its_scenes_model_says_so_whatever_its_errors():
    # the linear tire would pull on the road: matching the reference proves nothing from then on
    result = springlab.run("car", "road_bump", bump_height=0.03, bump_length=0.3, speed=10.0)
    assert result.passed is False and result.verdict is Verdict.OUTSIDE_MODEL and not result.verdict.validated
    assert result.model_limits and result.model_limits[0].startswith("the tire leaves the road at t = 0.0273274 s")
    assert result.message == "outside the scene's model: " + "; ".join(result.model_limits)
    assert result.to_dict()["verdict"] == "not validated: outside the scene's model"
    assert ValidationRow.of(result).note == f"{Verdict.OUTSIDE_MODEL.value}: " + "; ".join(result.model_limits)


# -- validate -----------------------------------------------------------------------------------------


def test_validate_json_is_its_rows_to_dict_and_each_row_is_its_run(capsys, monkeypatch):
    seen = _capture(monkeypatch, auto, "validate")
    assert main(["validate", "slider", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    rows = seen[0]
    assert all(isinstance(row, ValidationRow) for row in rows)
    assert printed == [row.to_dict() for row in rows]
    for row, data in zip(rows, printed):
        assert list(data)[:13] == [f.name for f in dataclasses.fields(ValidationRow)][:13]
        single = springlab.run("slider", row.scenario)
        assert _without(ValidationRow.of(single).to_dict()) == _without(data)
        assert (row.passed, row.verdict, row.max_rel_error) == (single.passed, single.verdict, single.max_rel_error)
        assert "note" not in data and row.note is None


def test_validate_auto_notes_the_scenarios_it_cannot_sweep(monkeypatch):
    # two of the non-linear scenarios (held to scalar checks: no trajectory for 'auto' to sweep); the
    # forced Duffing's self-convergence runs take seconds and add nothing here
    scene = springlab.SCENES["nonlinear"]
    chosen = [(scene, scene.scenarios[name]) for name in ("softening", "softening_escape")]
    monkeypatch.setattr(auto, "exact_scenarios", lambda names: chosen if names == ["nonlinear"] else [])
    rows = springlab.validate(["nonlinear"], integrator="auto", tol=1e-6)
    assert [row.scenario for row in rows] == ["softening", "softening_escape"]
    for row in rows:
        assert row.note == row.to_dict()["note"] == NO_SWEEP_NOTE
        # at the scene's validated setting, as `springlab run` without --integrator
        assert _without(dataclasses.replace(row, note=None).to_dict()) == _without(
            ValidationRow.of(springlab.run("nonlinear", row.scenario)).to_dict()
        )
    with pytest.raises(dataclasses.FrozenInstanceError):
        rows[0].passed = False  # type: ignore[misc]


def test_the_explicit_setting_run_refuses_auto_and_names_the_public_one():
    with pytest.raises(springlab.BadInputError, match="springlab.run"):
        run_scenario("slider", "free", integrator="auto", tol=1e-6)
    assert springlab.run is auto.run and springlab.validate is auto.validate
    assert isinstance(springlab.run("slider", "free", duration=0.1), Result)


# -- families ------------------------------------------------------------------------------------------


def test_a_zeta_family_serialises_its_runs_and_tabulates_their_trajectories():
    family = families.run_zeta_family("slider", "free", zetas=(0.0, 0.5), duration=0.5)
    data = family.to_dict()
    assert [entry["zeta"] for entry in data["runs"]] == [0.0, 0.5]
    assert [entry["run"] for entry in data["runs"]] == [run.to_dict() for _, run in family.runs]
    frame = family.to_pandas()
    for zeta, run in family.runs:
        part = frame[frame["zeta"] == zeta].drop(columns="zeta").reset_index(drop=True)
        pandas.testing.assert_frame_equal(part, run.to_pandas(), check_exact=True)


def test_a_phase_family_is_frozen_with_read_only_members():
    family = families.run_phase_family(run_scenario("slider", "undamped", duration=1.0))
    data = family.to_dict()
    assert [m["start"] for m in data["members"]] == [m.start for m in family.members]
    frame = family.to_pandas()
    kept = [m for m in family.members if m.x is not None]
    assert len(frame) == sum(len(m.x) for m in kept)
    first = kept[0]
    np.testing.assert_array_equal(frame[frame["member"] == 0]["x"].to_numpy(), first.x)
    with pytest.raises(ValueError, match="read-only"):
        first.x[0] = 0.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        family.center = 0.0  # type: ignore[misc]
