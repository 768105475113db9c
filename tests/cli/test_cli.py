"""The command line keeps its contract: outputs, exit codes, one-line errors, nothing partial."""

import csv
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from helpers.contract import SUMMARY_KEYS

#: euler at omega dt = 3 on the slider: past euler's stability limit, so the run diverges (exit 3)
DIVERGING_RUN = ("run", "slider", "--integrator", "euler", "--dt", "0.3", "--duration", "60")


def test_run_exercise_writes_the_csv_and_json_contract(tmp_path, cli):
    code, out, err = cli("run", "slider", "exercise", "--output", str(tmp_path / "d"))
    assert code == 0, err
    with open(tmp_path / "d" / "trajectory.csv") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == ["time", "slider_pos", "slider_vel", "slider_pos_ref", "slider_vel_ref"]
    summary = json.loads((tmp_path / "d" / "summary.json").read_text())
    assert len(rows) - 1 == summary["steps"] + 1  # t = 0 included
    assert list(summary) == SUMMARY_KEYS
    assert summary["quantities"]["regime"] == "overdamped"
    # full double precision: the CSV reproduces the textbook answer to 1e-12 where the physics allows
    table = np.array(rows[1:], dtype=float)
    t, x_ref = table[:, 0], table[:, 3]
    np.testing.assert_allclose(x_ref, 10 * np.exp(-t) - 5 * np.exp(-2 * t), rtol=0, atol=5e-14)
    assert set(summary["errors"]) == {"slider_pos", "slider_vel"}


def test_run_json_prints_the_summary(cli):
    code, out, _ = cli("run", "slider", "--json", "--duration", "0.5")
    assert code == 0
    assert json.loads(out)["scenario"] == "free"


def test_record_every_thins_the_csv(tmp_path, cli):
    code, _, _ = cli(
        "run", "slider", "--duration", "1", "--dt", "0.001", "--record-every", "10", "--output", str(tmp_path)
    )
    assert code == 0
    lines = (tmp_path / "trajectory.csv").read_text().splitlines()
    assert len(lines) == 1 + 101


def test_an_inaccurate_run_is_written_flagged_and_exits_1(tmp_path, cli):
    # first-order euler at 10 ms cannot meet a 1e-6 demand: a result, clearly flagged
    code, out, _ = cli(
        "run",
        "slider",
        "undamped",
        "--integrator",
        "euler",
        "--dt",
        "0.01",
        "--tol",
        "1e-6",
        "--output",
        str(tmp_path),
        "--json",
    )
    summary = json.loads(out)
    assert code == 1
    assert summary["passed"] is False and summary["tolerance"] == 1e-6
    assert summary["errors"]["slider_pos"]["max_rel"] > 1e-6
    assert (tmp_path / "trajectory.csv").exists() and (tmp_path / "summary.json").exists()


@pytest.mark.parametrize(
    "argv,needle",
    [
        (["run", "slider", "--set", "mass=-1"], "mass must be a finite number >= 1e-15 kg"),
        (["run", "slider", "--set", "mass=0"], "mass must be a finite number >= 1e-15 kg"),
        (["run", "slider", "--set", "stiffness=-5"], "stiffness must be a finite number >= 0 N/m"),
        (["run", "slider", "--set", "damping=-1"], "damping must be a finite number >= 0 N s/m"),
        (["run", "slider", "--set", "x0=nan"], "x0 must be a finite number"),
        (["run", "slider", "--set", "v0=inf"], "v0 must be a finite number"),
        (["run", "slider", "--set", "mass=heavy"], "mass must be a number"),
        (["run", "slider", "--set", "colour=3"], "unknown parameter of slider 'colour'; valid: damping"),
        (["run", "slider", "--set", "mass"], "--set takes NAME=VALUE"),
        (["run", "slidr"], "unknown scene 'slidr'; valid:"),
        (["run", "slider", "bounce"], "unknown scenario of slider 'bounce'; valid: critical"),
        (["run", "slider", "--integrator", "leapfrog"], "unknown integrator 'leapfrog'; valid: discrete, euler"),
        (["run", "slider", "--dt", "0"], "dt must be a finite number > 0 s"),
        (["run", "slider", "--dt=-1e-3"], "dt must be a finite number > 0 s"),
        (["run", "slider", "--dt", "fast"], "invalid float value"),
        (["run", "slider", "--duration", "0"], "duration must be a finite number > 0 s"),
        (["run", "slider", "--record-every", "0"], "--record-every must be an integer >= 1"),
        (["run", "slider", "--tol", "-1"], "tol must be a finite number > 0"),
        (["fly"], "invalid choice"),
        (["plot", "slider", "--kind", "pie", "--output", "p.png"], "invalid choice: 'pie'"),
    ],
)
def test_bad_input_exits_2_with_one_line_naming_what_is_valid(argv, needle, cli):
    code, out, err = cli(*argv)
    assert code == 2
    assert needle in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err


def test_unwritable_output_is_a_clear_error_and_leaves_nothing(tmp_path, cli):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, _, err = cli("run", "slider", "--duration", "0.1", "--output", str(blocker / "sub"))
    assert code == 2
    assert "cannot create output directory" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_divergence_exits_3_names_the_limit_and_writes_nothing(tmp_path, cli):
    code, _, err = cli(*DIVERGING_RUN, "--output", str(tmp_path / "d"))
    assert code == 3
    assert "omega*dt = 3 exceeds the euler stability limit" in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "d").exists()


def test_console_script_prints_no_traceback_and_leaves_no_mujoco_log(tmp_path):
    env = dict(os.environ)
    proc = subprocess.run(
        [sys.executable, "-m", "springlab.cli.main", *DIVERGING_RUN],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert proc.returncode == 3
    assert proc.stderr.startswith("springlab: error: simulation diverged")
    assert "Traceback" not in proc.stderr and "WARNING" not in proc.stderr + proc.stdout
    assert list(tmp_path.iterdir()) == []


def test_validate_is_green_and_json_lists_every_exact_scenario(cli):
    code, out, _ = cli("validate", "slider", "--json")
    rows = json.loads(out)
    assert code == 0
    assert {r["scenario"] for r in rows} >= {"free", "step", "harmonic", "exercise", "critical"}
    assert all(r["passed"] and r["max_rel_error"] <= r["tolerance"] for r in rows)


def test_list_json_names_scenes_scenarios_and_units(cli):
    code, out, _ = cli("list", "--json")
    catalogue = json.loads(out)
    slider = next(s for s in catalogue if s["scene"] == "slider")
    assert slider["parameters"]["mass"]["unit"] == "kg"
    assert "exercise" in slider["scenarios"]


def test_outputs_get_ordinary_file_permissions(tmp_path, cli):
    # written through a temporary file and renamed: the result must not inherit mkstemp's 0600
    code, _, _ = cli("run", "slider", "--duration", "0.1", "--output", str(tmp_path))
    assert code == 0
    umask = os.umask(0)
    os.umask(umask)
    for name in ("trajectory.csv", "summary.json"):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o666 & ~umask


def test_a_closed_pipe_ends_quietly_without_a_traceback():
    # `springlab list | head -1`: the reader leaves early
    proc = subprocess.Popen(
        [sys.executable, "-m", "springlab.cli.main", "list"], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    proc.stdout.close()  # before the child writes: its first write hits a closed pipe
    err = proc.stderr.read().decode()
    proc.wait(timeout=60)
    assert "Traceback" not in err and "BrokenPipe" not in err
