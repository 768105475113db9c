"""`springlab sweep`: every row is the run `springlab run` makes at the same parameters, diverged runs
are rows (not a failed sweep), and bad ranges are one-line errors (exit 2) that write nothing."""

from __future__ import annotations

import csv
import dataclasses
import json
import math

import numpy as np
import pandas
import pytest

import springlab
from springlab import outputs
from springlab.cli.main import main
from springlab.errors import BadInputError, DivergedError
from springlab.exact.limits import stability_limit
from springlab.studies import sweeps
from springlab.studies.sweeps import configurations, make_axis

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def test_grid_is_the_full_factorial_with_the_last_axis_fastest():
    axes = [make_axis("mass", 1.0, 4.0, 4, log=True), make_axis("damping", 0.0, 2.0, 3)]
    values = configurations(axes)
    # log spacing: equal ratios (4^(1/3)); linear: equal steps
    assert np.allclose(values["mass"][::3], [1.0, 4 ** (1 / 3), 4 ** (2 / 3), 4.0], rtol=1e-15)
    assert list(values["damping"][:3]) == [0.0, 1.0, 2.0]
    assert len(values["mass"]) == 12


def test_random_samples_stay_in_the_box_and_repeat_with_the_seed():
    axes = [make_axis("mass", 0.5, 2.0, None, log=True), make_axis("damping", 1.0, 3.0, None)]
    first = configurations(axes, samples=200, sample_seed=7)
    again = configurations(axes, samples=200, sample_seed=7)
    assert all(np.array_equal(first[n], again[n]) for n in first)
    assert first["mass"].min() >= 0.5 and first["mass"].max() <= 2.0
    assert first["damping"].min() >= 1.0 and first["damping"].max() <= 3.0


@pytest.mark.parametrize(
    "scene, scenario, vary",
    [
        ("slider", "free", {"damping": (0.5, 40.0, 3, "log"), "stiffness": (200.0, 800.0, 2)}),
        ("slider", "step", {"force_amplitude": (0.5, 2.0, 2)}),  # an actuator: per-step controls
        ("car", "road_bump", {"speed": (3.0, 9.0, 2)}),
    ],
)
def test_every_row_equals_a_single_run_at_its_parameters(scene, scenario, vary):
    # a chunk is one threaded rollout, the function springlab.run steps with; evaluation is shared
    result = springlab.sweep(scene, scenario, vary=vary)
    assert result.size == math.prod(spec[2] for spec in vary.values())
    for i, row in enumerate(result.rows):
        values = {name: float(result.values[name][i]) for name in result.values}
        assert row.values == values
        single = springlab.run(scene, scenario, **values)
        assert row.quantities == {k: v for k, v in single.quantities.items() if not isinstance(v, list)}
        assert row.errors == {c: e.max_rel for c, e in single.errors.items()}
        assert row.passed == single.passed and not row.diverged


def test_a_diverged_configuration_is_a_marked_row_and_run_refuses_it():
    # rk4 at omega*dt = sqrt(k/m)*dt = 0.16, 1.6 and 16: the last is past its stability limit (2.83 at zeta ~ 0)
    result = springlab.sweep(
        "slider",
        "free",
        vary={"stiffness": (10.0, 100000.0, 3, "log")},
        integrator="rk4",
        dt=0.05,
        duration=2.0,
        mass=1.0,
    )
    for row in result.rows:
        params = row.parameters
        omega = math.sqrt(params["stiffness"] / params["mass"])
        zeta = params["damping"] / (2 * math.sqrt(params["stiffness"] * params["mass"]))
        assert row.diverged == (omega * 0.05 > stability_limit("rk4", zeta))
        if row.diverged:
            assert row.passed is False and "diverged" in row.detail
            with pytest.raises(DivergedError):
                springlab.run("slider", "free", integrator="rk4", dt=0.05, duration=2.0, **params)
    assert [row.diverged for row in result.rows] == [False, False, True]
    assert result.diverged == 1 and result.passed + result.failed == result.size == 3


@pytest.mark.parametrize(
    "vary, message",
    [
        ("mass=1:2", "needs N"),
        ("mass=1:2:x", "NAME=LOW:HIGH:N"),
        ("mass=-1:2:3:log", "log range needs LOW > 0"),
        ("weight=1:2:3", "unknown parameter of slider 'weight'"),
        ("mass=0:1:3", "configuration 0 (mass=0): mass must be a finite number"),
    ],
)
def test_bad_ranges_are_one_line_errors_and_write_nothing(tmp_path, cli, vary, message):
    code, _, err = cli("sweep", "slider", "free", "--vary", vary, "--output", str(tmp_path / "out"))
    assert code == 2
    assert message in err and err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_varied_and_fixed_at_once_is_refused():
    with pytest.raises(BadInputError, match="both varied"):
        springlab.sweep("slider", vary={"mass": (1.0, 2.0, 2)}, mass=3.0)


def test_cli_writes_the_csv_and_the_plot_and_json_is_silent_on_stderr(tmp_path, capsys, monkeypatch):
    computed = []
    original = sweeps.sweep
    monkeypatch.setattr(sweeps, "sweep", lambda *a, **k: computed.append(original(*a, **k)) or computed[-1])
    out = tmp_path / "sweep"
    code = main(
        [
            "sweep",
            "slider",
            "free",
            "--vary",
            "damping=1:30:3:log",
            "--vary",
            "mass=1:2:2",
            "--output",
            str(out),
            "--json",
        ]
    )
    captured = capsys.readouterr()
    assert code == 0 and captured.err == ""  # no progress bar under --json
    data = json.loads(captured.out)
    assert data["configurations"] == 6 and data["diverged"] == 0
    with open(out / "sweep.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 6
    assert {"damping", "mass", "max_displacement_m", "slider_pos_max_rel", "passed", "diverged"} <= set(rows[0])
    # numbers at full precision: the CSV reproduces the JSON's errors exactly
    for row, record in zip(rows, data["rows"]):
        assert float(row["slider_pos_max_rel"]) == record["errors"]["slider_pos"]
        assert math.isclose(float(row["damping"]), record["values"]["damping"], rel_tol=0, abs_tol=0)
    assert (out / "sweep.png").read_bytes()[:8] == PNG_SIGNATURE
    # the JSON is the sweep's to_dict(), sweep.csv its to_pandas()
    (result,) = computed
    assert data == result.to_dict()
    assert (result.size, result.diverged, result.passed + result.failed) == (6, 0, 6)
    assert [row.to_dict() for row in result.rows] == data["rows"]
    frame = result.to_pandas()
    written = pandas.read_csv(out / "sweep.csv")  # empty cells (overdamped rows have no period_s) read as NaN
    assert list(frame.columns) == list(written.columns)
    pandas.testing.assert_frame_equal(frame.drop(columns="detail"), written.drop(columns="detail"), check_exact=True)
    assert list(frame["detail"]) == [""] * 6 and written["detail"].isna().all()  # nothing diverged
    np.testing.assert_array_equal(frame["damping"], result.values["damping"])
    # immutable: frozen rows, read-only value columns
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.rows[0].passed = False
    with pytest.raises(ValueError, match="read-only"):
        result.values["mass"][0] = 3.0


def test_plot_rejects_an_unknown_quantity_and_leaves_no_file(tmp_path):
    result = springlab.sweep("slider", "free", vary={"damping": (1.0, 2.0, 2)})
    with pytest.raises(BadInputError, match="unknown quantity"):
        outputs.write(result, tmp_path, quantity="nonsense")
    assert list(tmp_path.iterdir()) == []
