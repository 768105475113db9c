"""One output writer (springlab.outputs.write): every file a result declares, into its folder, all or nothing.

Read with `ast` where the claim is about the source (which modules write, which functions are gone), so the
check needs no study to run.
"""

from __future__ import annotations

import ast
import json

import numpy as np
import pytest

from helpers import source
from helpers.source import PACKAGE
from springlab import files, outputs
from springlab.errors import BadInputError
from springlab.runs.run import run_scenario
from springlab.studies import tradeoff

#: the writers the one writer replaced (issue 32): none may come back under its old name
OLD_WRITERS = {
    "runs/run.py": {"write_run"},
    "plots/charts.py": {"write_tradeoff", "write_stability"},
    "plots/sweep.py": {"write"},
    "plots/audit.py": {"write_audit"},
    "plots/frequency.py": {"write_frequency"},
    "plots/refine.py": {"write_refine"},
    "plots/friction_settings.py": {"write"},
    "plots/random_load.py": {"write_ensemble", "write_settings"},
    "studies/fit/fit.py": {"write"},
    "studies/design/study.py": {"write"},
    "runs/model_run.py": {"write_model_run"},
    "plots/model_tradeoff.py": {"write_model_tradeoff"},
}


@pytest.fixture(scope="module")
def small_run():
    return run_scenario("slider", "free", duration=0.2)


@pytest.fixture(scope="module")
def small_sweep():
    """A short slider trade-off sweep (a study the writer writes), once for the tests of its refusals and of a
    failed drawing, which read no timing: one timing repeat."""
    return tradeoff.sweep("slider", "free", duration=0.2, timing_repeats=1)


def test_a_run_writes_summary_json_as_to_dict_and_the_csv_at_k_dt(small_run, tmp_path):
    written = outputs.write(small_run, tmp_path / "run")
    assert [p.name for p in written] == ["trajectory.csv", "summary.json"]
    assert json.loads((tmp_path / "run" / "summary.json").read_text()) == small_run.to_dict()
    lines = (tmp_path / "run" / "trajectory.csv").read_text().splitlines()
    assert lines[0].split(",") == list(small_run.columns())
    time = np.array([float(line.split(",")[0]) for line in lines[1:]])
    # step k is at k dt exactly, not MuJoCo's accumulated clock
    np.testing.assert_array_equal(time, np.arange(small_run.steps + 1) * small_run.dt)


def test_every_thins_a_runs_csv_and_is_refused_elsewhere(small_run, small_sweep, tmp_path):
    outputs.write(small_run, tmp_path, every=7)
    rows = (tmp_path / "trajectory.csv").read_text().splitlines()[1:]
    assert len(rows) == len(files.recorded_rows(small_run.steps + 1, 7))
    study = small_sweep
    with pytest.raises(BadInputError, match="every="):
        outputs.write(study, tmp_path / "t", every=2)
    with pytest.raises(BadInputError, match="quantity="):
        outputs.write(study, tmp_path / "t", quantity="x")
    assert not (tmp_path / "t").exists()


def test_a_drawing_that_fails_leaves_no_file_and_no_temporary(tmp_path, monkeypatch, small_sweep):
    study = small_sweep

    def broken(result, path, options):
        path.write_bytes(b"half a png")
        raise RuntimeError("the drawing failed")

    monkeypatch.setitem(outputs.DRAWN, (type(study), "tradeoff.png"), broken)
    with pytest.raises(RuntimeError, match="the drawing failed"):
        outputs.write(study, tmp_path)
    assert list(tmp_path.iterdir()) == []  # tradeoff.json was written first, to a temporary: gone too


def test_a_rename_that_fails_removes_the_files_already_renamed(tmp_path):
    (tmp_path / "b.json").mkdir()  # os.replace of a file onto a directory fails
    writers = {"a.json": lambda p: p.write_text("{}"), "b.json": lambda p: p.write_text("{}")}
    with pytest.raises(OSError):
        files.write_all(tmp_path, writers)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.json"]


def test_a_result_declares_only_json_csv_png_and_mp4_files():
    assert files.Output("x.json", "{}").kind == "json"
    with pytest.raises(ValueError, match="writes"):
        files.Output("x.txt", "text")
    with pytest.raises(ValueError, match="carries its text"):
        files.Output("x.png", "text")
    with pytest.raises(ValueError, match="carries its text"):
        files.Output("x.csv")


def test_every_declared_figure_has_its_drawing():
    """Each `outputs()` names its drawn files as literals: each has an entry in outputs.DRAWN."""
    drawn = {name for _, name in outputs.DRAWN}
    declared = set()
    for path in source.source_files():
        for node in source.nodes(path):  # parsed once per test process (helpers/source.py)
            if isinstance(node, ast.FunctionDef) and node.name == "outputs":
                for call in ast.walk(node):
                    if (
                        isinstance(call, ast.Call)
                        and isinstance(call.func, ast.Name)
                        and call.func.id == "Output"
                        and len(call.args) == 1
                        and isinstance(call.args[0], ast.Constant)
                    ):
                        declared.add(call.args[0].value)
    assert declared, "no result declares a figure"
    assert declared <= drawn, f"declared without a drawing in outputs.DRAWN: {sorted(declared - drawn)}"


def test_the_old_writers_are_gone_and_the_commands_write_through_outputs():
    for module, names in OLD_WRITERS.items():
        tree = source.tree(PACKAGE / module)
        defined = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
        assert not names & defined, f"{module} still defines {sorted(names & defined)}: write with springlab.outputs"
    folders = {"run", "tradeoff", "stability", "sweep", "design", "audit", "fit", "frequency", "refine"}
    folders |= {"friction_settings", "rms"}
    for name in sorted(folders):
        text = (PACKAGE / "cli" / "commands" / f"{name}.py").read_text()
        assert "outputs.write(" in text, f"`springlab {name} --output DIR` does not write through springlab.outputs"
