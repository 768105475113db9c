"""benchmarks/check.py, the gate on `make bench`'s table, on made-up tables (no timings in tests)."""

from __future__ import annotations

import json
import pathlib
import subprocess
import sys

from helpers.paths import ROOT

CHECK = ROOT / "benchmarks" / "check.py"


def _table(tmp_path: pathlib.Path, rows: list[tuple[str, float, float]]) -> pathlib.Path:
    path = tmp_path / "results.json"
    made_up = [{"name": n, "ratio": r, "budget": b, "floor": "rollout"} for n, r, b in rows]
    path.write_text(json.dumps({"machine": {}, "rows": made_up}))
    return path


def _check(path: pathlib.Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(CHECK), str(path)], capture_output=True, text=True, check=False)


def test_a_table_within_its_budgets_passes_and_a_ratio_equal_to_its_budget_is_within(tmp_path):
    done = _check(_table(tmp_path, [("run slider", 1.12, 1.3), ("validate", 1.2, 1.2)]))
    assert done.returncode == 0, done.stdout + done.stderr
    assert "2 of 2 rows within budget" in done.stdout


def test_lowering_a_budget_below_its_measured_ratio_fails_and_names_the_row(tmp_path):
    done = _check(_table(tmp_path, [("run slider", 1.12, 1.1), ("validate", 1.05, 1.2)]))
    assert done.returncode == 1
    assert "run slider: ratio 1.12 over its budget 1.1" in done.stdout
    assert "validate" not in done.stdout.split("\n")[0]


def test_a_ratio_that_is_no_number_is_over_any_budget(tmp_path):
    path = tmp_path / "results.json"
    path.write_text('{"rows": [{"name": "sweep", "ratio": NaN, "budget": 3}]}')
    assert _check(path).returncode == 1


def test_an_unreadable_table_is_exit_2_in_one_line(tmp_path):
    done = _check(tmp_path / "missing.json")
    assert done.returncode == 2 and done.stderr.count("\n") == 1
