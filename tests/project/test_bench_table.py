"""benchmarks/bench.py's table on made-up rows: ratios, rows a script prints, the choice of rows, the paths it shows.

No timing is asserted here (speed is measured by `make bench`, never in a test).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from helpers.paths import ROOT

BENCH = ROOT / "benchmarks"


@pytest.fixture(scope="module")
def bench():
    sys.path.insert(0, str(BENCH))
    try:
        import bench as module
        import paths

        yield module, paths
    finally:
        sys.path.remove(str(BENCH))


def _row(bench, **fields):
    base = dict(
        name="x", work="w", wall_s=4.0, cpu_s=3.0, floor="rollout", floor_wall_s=2.0, floor_cpu_s=1.5, budget=2.5
    )
    return bench.Row(**(base | {"budget_basis": "(set)"} | fields))


def test_a_ratio_is_cpu_over_the_floors_cpu_or_wall_over_wall_where_the_row_says(bench):
    module, _ = bench
    assert _row(module).ratio == 3.0 / 1.5
    assert _row(module, on_wall=True).ratio == 4.0 / 2.0
    assert _row(module, floor_cpu_s=0.0).ratio == float("inf")


def test_a_script_adds_rows_by_printing_them_and_its_other_lines_stay_text(bench):
    module, _ = bench
    fields = {"name": "fit 2M rows", "work": "2e6 rows", "wall_s": 9.0, "cpu_s": 8.0, "floor": "numpy.loadtxt"}
    fields |= {"floor_wall_s": 3.0, "floor_cpu_s": 2.0, "budget": 5.0, "budget_basis": "(set)", "ratio": 4.0}
    text = f"1. a line of its own\n{module.ROW_PREFIX}{json.dumps(fields)}\n2. another\n"
    (row,) = module.script_rows(text)
    assert row.name == "fit 2M rows" and row.ratio == 8.0 / 2.0 and row.budget == 5.0
    assert module.script_rows("no rows here\n") == []


def test_the_table_shows_paths_relative_to_the_checkout_and_no_temporary_folder(bench):
    import sysconfig
    import tempfile

    module, _ = bench
    installed = sysconfig.get_paths()["purelib"]
    text = (
        f"friction-settings {ROOT / 'tests' / 'data' / 'gripper.xml'} --output {tempfile.gettempdir()}/tmpab12/x;"
        f" audit {installed}/dm_control/suite/humanoid.xml"
    )
    shown = module.shown(text)
    assert str(ROOT) not in shown and tempfile.gettempdir() + "/" not in shown and installed not in shown
    assert "tests/data/gripper.xml" in shown and "site-packages/dm_control/suite/humanoid.xml" in shown


def test_every_row_group_and_script_is_listed_with_a_rough_time_and_unknown_names_are_refused():
    env = {"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin"}
    listed = subprocess.run(
        [sys.executable, str(BENCH / "bench.py"), "--list"], capture_output=True, text=True, env=env, check=True
    ).stdout
    for name in ("run", "validate", "demo", "render", "interactive", "view", "fit", "audit humanoid", "import"):
        assert any(line.startswith(f"{name} ") and line.rstrip().endswith("s") for line in listed.splitlines()), name
    scripts = sorted(p.stem for p in BENCH.glob("bench_*.py"))
    assert all(f"\n{name} " in listed for name in scripts)
    assert "chosen: about" in listed
    refused = subprocess.run(
        [sys.executable, str(BENCH / "bench.py"), "--skip", "nosuchrow"], capture_output=True, text=True, env=env
    )
    assert refused.returncode == 2 and "unknown row groups nosuchrow" in refused.stderr
