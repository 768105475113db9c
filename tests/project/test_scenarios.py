"""Every script in scenarios/ runs headless through the public API and prints its answer."""

import pytest

from helpers.paths import ROOT
from helpers.scripts import run_scripts

SCRIPTS = sorted((ROOT / "scenarios").glob("*.py"))
#: the scripts over ~1.5 s on one core (a chaotic run; the stay cable's four runs of 49 elements, the drill
#: string's breakaway, the printer's answer table): 10 s together, the quick loop runs the other 17 (3 s)
SLOW = {"nonlinear_forced_duffing", "stay_cable_damper", "drill_string_bit_friction", "printer_positioning_table"}
#: arguments that keep a script's run short where its default is a whole study: the design study's 3^4
#: grid instead of 7^4 (the same code path; its physics is tested in tests/studies/design/test_design.py), one
#: carriage's answer table instead of two (tests/scenes/printer_head/test_printer_control_scene.py runs both)
ARGS = {"printer_which_properties": ["--levels", "3"], "printer_positioning_table": ["--preset", "inkjet"]}


@pytest.fixture(scope="module")
def ran(tmp_path_factory):
    """Every script but the slow ones, each in a process and an empty folder of its own (helpers/scripts.py)."""
    quick = [p for p in SCRIPTS if p.stem not in SLOW]
    return run_scripts(quick, ARGS, tmp_path_factory.mktemp("scenarios"))


def _assert_answered(code, out, err):
    assert code == 0, err
    assert out.strip()
    assert "Traceback" not in err


@pytest.mark.parametrize("script", [p for p in SCRIPTS if p.stem not in SLOW], ids=lambda p: p.stem)
def test_scenario_script_runs_headless(script, ran):
    _assert_answered(*ran[script.stem])


#: the runs a script makes at a scenario's own settings that the session has made already (tests/conftest.py:
#: `scenario_run`): the script's `springlab.run(scene, scenario)` is handed that Result (helpers/scripts.py), so
#: the forced Duffing's chaos (4 s of CPU: its twin runs refined three times, 110 s of Lyapunov pairs) is
#: computed once per session, not again for its script; the script's own lines still run and print
SERVED = {"nonlinear_forced_duffing": [("nonlinear", "forced_duffing")]}


@pytest.fixture(scope="module")
def ran_slow(tmp_path_factory, scenario_run):
    """The slow scripts, as `ran` runs the others (one interpreter, a fork each), with the session's SERVED runs."""
    slow = [p for p in SCRIPTS if p.stem in SLOW]
    served = {stem: {key: scenario_run(*key) for key in keys} for stem, keys in SERVED.items()}
    return run_scripts(slow, ARGS, tmp_path_factory.mktemp("slow_scenarios"), served=served)


@pytest.mark.slow
@pytest.mark.parametrize("script", [p for p in SCRIPTS if p.stem in SLOW], ids=lambda p: p.stem)
def test_slow_scenario_script_runs_headless(script, ran_slow):
    _assert_answered(*ran_slow[script.stem])


def test_exercise_script_prints_the_textbook_answer(ran):
    out = ran["under_or_overdamped"].out
    assert "overdamped" in out
    assert "x(t) = 10 e^(-1 t) + -5 e^(-2 t)" in out


def test_the_car_script_prints_the_three_answers(ran):
    # Chapter 5.3's car on its springs: the static sag, the release's amplitude and frequency, the phase ellipse
    out = ran["car_push_release"].out
    assert "= 2.4525 mm" in out and "97.5475 mm above the ground" in out
    assert "x_s = 100.0000 mm, A = -2.4525 mm" in out and "omega = sqrt(k/m) = 31.6228 rad/s" in out
    assert "an ellipse centred at (x_s, 0)" in out and "omega |A| = 0.07755 m/s" in out
