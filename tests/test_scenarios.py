"""Every script in scenarios/ runs headless through the public API and prints its answer."""

import pathlib
import subprocess
import sys

import pytest

SCRIPTS = sorted((pathlib.Path(__file__).parents[1] / "scenarios").glob("*.py"))
#: scripts that take more than ~5 s on one core (the design study's 7^4 grid, a chaotic run)
SLOW = {"printer_which_properties", "nonlinear_forced_duffing"}


@pytest.mark.parametrize(
    "script",
    [pytest.param(p, marks=pytest.mark.slow) if p.stem in SLOW else p for p in SCRIPTS],
    ids=lambda p: p.stem,
)
def test_scenario_script_runs_headless(script, tmp_path):
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300)
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
