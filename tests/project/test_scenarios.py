"""Every script in scenarios/ runs headless through the public API and prints its answer."""

import subprocess
import sys

import pytest

from helpers.paths import ROOT

SCRIPTS = sorted((ROOT / "scenarios").glob("*.py"))
#: scripts that take more than ~5 s on one core (a chaotic run)
SLOW = {"nonlinear_forced_duffing"}
#: arguments that keep a script's run short where its default is a whole study: the design study's 3^4
#: grid instead of 7^4 (the same code path; its physics is tested in tests/studies/design/test_design.py), one carriage's
#: answer table instead of two (tests/scenes/printer_head/test_printer_control_scene.py runs both)
ARGS = {"printer_which_properties": ["--levels", "3"], "printer_positioning_table": ["--preset", "inkjet"]}


@pytest.mark.parametrize(
    "script",
    [pytest.param(p, marks=pytest.mark.slow) if p.stem in SLOW else p for p in SCRIPTS],
    ids=lambda p: p.stem,
)
def test_scenario_script_runs_headless(script, tmp_path):
    command = [sys.executable, str(script), *ARGS.get(script.stem, [])]
    proc = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip()
    assert "Traceback" not in proc.stderr


def test_exercise_script_prints_the_textbook_answer(tmp_path):
    script = next(s for s in SCRIPTS if s.stem == "under_or_overdamped")
    out = subprocess.run(
        [sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300
    ).stdout
    assert "overdamped" in out
    assert "x(t) = 10 e^(-1 t) + -5 e^(-2 t)" in out
