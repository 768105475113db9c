"""Written data is exactly what it says: last state kept, exact times, one JSON type per key, labelled checks."""

import csv
import json
import math

import pytest

import springlab
from springlab import files, scenes
from springlab.cli.main import main


def _rows(path):
    with open(path) as handle:
        return list(csv.reader(handle))


@pytest.mark.parametrize("every", [1, 7, 10, 1000, 5000])
def test_record_every_keeps_the_first_and_the_final_state(tmp_path, capsys, every):
    # 5 s at 10 ms: steps 0..500; every 7th is 0, 7, ..., 497, and the final state t = 5 s must follow
    code = main(
        ["run", "slider", "--dt", "0.01", "--duration", "5", "--record-every", str(every), "--output", str(tmp_path)]
    )
    capsys.readouterr()
    assert code == 0
    rows = _rows(tmp_path / "trajectory.csv")[1:]
    steps = list(range(0, 501, every))
    if steps[-1] != 500:
        steps.append(500)
    assert [float(r[0]) for r in rows] == [k * 0.01 for k in steps]
    assert float(rows[-1][0]) == 5.0


def test_csv_time_is_k_dt_exactly_not_an_accumulated_sum(tmp_path, capsys):
    # 0.005 is not a binary fraction: summing it 987 times drifts (4.934999999999917); k * dt does not
    main(["run", "slider", "--dt", "0.005", "--duration", "5", "--output", str(tmp_path)])
    capsys.readouterr()
    times = [r[0] for r in _rows(tmp_path / "trajectory.csv")[1:]]
    assert times == [repr(k * 0.005) if k else "0" for k in range(1001)] or all(
        float(t) == k * 0.005 for k, t in enumerate(times)
    )
    assert times[987] == "4.9350000000000005" or float(times[987]) == 987 * 0.005


def _json_type(value):
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, (int, float)):
        return "number"
    return type(value).__name__


#: runs that reach the non-finite corners: a carriage that never settles (no belt damping), a Duffing pair
#: that does not separate in 2 s, a slider with no spring (frequency ratio undefined)
EDGE_CASES = [
    ("printer_head", "settle", {"belt_damping": 0.0}),
    ("printer_head", "move", {"belt_damping": 0.0}),
    ("nonlinear", "forced_duffing", {"duration": 2.0}),
    ("slider", "harmonic", {"stiffness": 0.0, "duration": 1.0}),
]


def _summaries(scenario_run):
    out = []
    for scene in scenes.SCENES.values():
        for scenario in scene.scenarios:
            out.append(scenario_run(scene.name, scenario).to_dict())  # the scenario's own settings, run once
    for scene, scenario, settings in EDGE_CASES:
        settings = dict(settings)
        duration = settings.pop("duration", None)
        out.append(springlab.run(scene, scenario, duration=duration, **settings).to_dict())
    return out


def _reject_constant(name):
    raise AssertionError(f"non-standard JSON constant {name}")


@pytest.mark.slow
def test_every_quantity_of_every_scene_keeps_one_json_type_and_null_comes_with_a_flag(scenario_run):
    types: dict[tuple[str, str], set[str]] = {}
    for summary in _summaries(scenario_run):
        text = files.dumps(summary)
        data = json.loads(text, parse_constant=_reject_constant)
        assert '"inf"' not in text and '"nan"' not in text and '"-inf"' not in text
        quantities = data["quantities"]
        flags = [k for k, v in quantities.items() if isinstance(v, bool)]
        for key, value in quantities.items():
            types.setdefault((data["scene"], key), set()).add(_json_type(value))
            if value is None:
                # a null says "infinite or undefined"; a boolean beside it says which case this is
                assert flags, f"{data['scene']}/{data['scenario']}: {key} is null with no flag beside it"
    for (scene, key), seen in types.items():
        assert len(seen - {"null"}) <= 1, f"{scene}.{key} mixes JSON types {seen}"


def test_a_carriage_that_never_settles_writes_null_and_a_false_flag(tmp_path, capsys):
    code = main(["run", "printer_head", "settle", "--set", "belt_damping=0", "--output", str(tmp_path)])
    capsys.readouterr()
    assert code in (0, 1)
    quantities = json.loads((tmp_path / "summary.json").read_text(), parse_constant=_reject_constant)["quantities"]
    assert quantities["settled_for_good"] is False
    assert quantities["settling_time_s"] is None
    assert math.isinf(springlab.run("printer_head", "settle", belt_damping=0.0).quantities["settling_time_s"])


@pytest.mark.slow  # the forced Duffing's shared run (4 s of CPU) is its first reader's
def test_the_validation_table_names_what_each_error_measures(cli, monkeypatch, scenario_run):
    from springlab.studies import auto

    # the claim is the table's words: its runs at the scenarios' own settings are the session's shared ones
    # (tests/conftest.py; run_scene without a setting is run_scenario), the forced Duffing's alone costs 4 s
    def shared(scene, scenario, **setting):
        assert not any(setting.values()), setting
        return scenario_run(scene, scenario)

    monkeypatch.setattr(auto, "run_scene", shared)
    code, out, _ = cli("validate", "nonlinear", "slider")
    assert code == 0
    header, *lines = out.splitlines()
    assert "error of" in header and "max rel err" not in header
    rows = {line.split()[1]: line for line in lines if line.startswith(("slider ", "nonlinear "))}
    assert "trajectory max_rel" in rows["free"]
    # the forced Duffing has no closed form: its row is the observed order's error, and says so
    assert "observed_order rel" in rows["forced_duffing"] and "trajectory" not in rows["forced_duffing"]
    assert "period_s rel" in rows["softening"]
