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


def test_a_row_a_script_emits_reads_back_as_the_same_row_nan_included(bench, capsys):
    module, _ = bench
    row = _row(module, name="render car road_bump, end to end", cpu_s=float("nan"), on_wall=True, note="n")
    module.emit(row)
    (line,) = capsys.readouterr().out.splitlines()
    assert line.startswith(module.ROW_PREFIX)
    (back,) = module.script_rows(line)
    assert back.to_dict().keys() == row.to_dict().keys()
    assert back.name == row.name and back.on_wall and back.ratio == row.ratio and back.cpu_s != back.cpu_s


def test_the_table_pastes_a_scripts_output_without_its_row_lines_and_counts_them(bench):
    module, _ = bench
    row = _row(module, name="fit reader")
    text = f"1. a line of its own\n{module.ROW_PREFIX}{json.dumps(row.to_dict())}\n2. another\n"
    where = {"platform": "p", "cpus": 2, "python": "3", "mujoco": "4", "date_utc": "d", "load_average_1_5_15": [0] * 3}
    page = module.markdown(module.script_rows(text), where, [("bench_fit_bigfile.py --readers-only", 12.0, text)])
    pasted = page.split("### bench_fit_bigfile.py --readers-only (12.0 s; its 1 row in the table)")[1]
    assert "1. a line of its own\n2. another" in pasted and module.ROW_PREFIX not in pasted
    assert "| fit reader |" in page.split("###")[0]


def test_the_per_run_comparison_sums_every_run_and_prints_a_line_each(bench, capsys):
    """bench_creep's and bench_friction's shared loop, on stand-in callables: what it adds up, not how fast."""
    module, _ = bench
    import measure

    calls = []
    runs = [
        measure.PerRun(f"run{k} ", 10 * (k + 1), *(lambda k=k, w=w: calls.append((k, w)) for w in "slr"))
        for k in range(3)
    ]
    found = measure.per_run_comparison(runs, steps_width=5, repeat=2)
    assert found["runs"] == 3 and found["steps"] == 60
    assert sorted(calls) == sorted((k, w) for k in range(3) for w in "slr" for _ in range(2))
    assert all(found[key] >= 0 for key in ("study_cpu", "loop_cpu", "rollout_cpu"))
    printed = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in printed[:3]] == ["run0", "run1", "run2"]
    assert printed[-1].lstrip().startswith("mean ratio study/plain loop")


def _fixture_rows(module) -> dict[str, list]:
    """tests/data/bench_rows.txt: what each script of the default run printed at make bench's size (recorded on a
    shared machine: its numbers are no reference), its rows grouped by the script named in each row's note."""
    text = (ROOT / "tests" / "data" / "bench_rows.txt").read_text()
    rows: dict[str, list] = {}
    for row in module.script_rows(text):
        rows.setdefault(row.note.split(".py:")[0], []).append(row)
    return rows


def test_every_script_of_the_default_run_emits_rows_each_with_a_floor_and_a_budget(bench):
    module, _ = bench
    rows = _fixture_rows(module)
    for name in module.default_scripts():
        assert rows.get(name), f"{name} printed no row"
        source = (BENCH / f"{name}.py").read_text()
        assert "emit(" in source, name
        for row in rows[name]:
            assert row.floor and row.budget_basis, row.name
            assert 0 < row.budget < float("inf"), row.name
            floor = row.floor_wall_s if row.on_wall else row.floor_cpu_s
            assert floor > 0, row.name
    assert set(rows) <= set(module.SCRIPTS), set(rows) - set(module.SCRIPTS)


def test_a_script_left_out_of_the_default_run_says_which_table_row_measures_the_same(bench):
    module, _ = bench
    skipped = [name for name, script in module.SCRIPTS.items() if script.skipped]
    assert skipped and set(skipped).isdisjoint(module.default_scripts())
    for name in skipped:
        text = " ".join((BENCH / f"{name}.py").read_text().split())
        assert "Not in `make bench`'s default run" in text, name
        assert "emit(" in text, name  # alone, it still adds its rows


def test_every_script_is_in_the_list_of_scripts_and_the_default_run_is_estimated_at_25_minutes_at_most():
    env = {"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin"}
    listed = subprocess.run(
        [sys.executable, str(BENCH / "bench.py"), "--list"], capture_output=True, text=True, env=env, check=True
    ).stdout
    minutes = int(listed.rsplit("chosen: about ", 1)[1].split()[0])
    assert minutes <= 25
    sys.path.insert(0, str(BENCH))
    try:
        import bench as module
    finally:
        sys.path.remove(str(BENCH))
    assert set(module.SCRIPTS) == {p.stem for p in BENCH.glob("bench_*.py")}
