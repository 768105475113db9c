"""Every scenario answers its question in words, once (issue 34 item 1): the terminal, summary.json and the demo
report's Q/A box show the same `Answer`, the exact value beside the measured one, in the units a reader expects.
"""

from __future__ import annotations

import contextlib
import html
import io
import json
import math
import pathlib
import re

import pytest

from springlab import scenes
from springlab.cli import text as cli_text
from springlab.cli.main import main
from springlab.demo.report import build_html
from springlab.demo.state import DemoState

SCENARIOS = [(scene.name, scenario) for scene in scenes.SCENES.values() for scenario in scene.scenarios]
#: an SI length, time or speed written in powers of ten: the unit a reader expects (mm, µm, ms, mm/s) was not chosen
RAW_SI = re.compile(r"\d[eE][-+]?\d+ (m|s|m/s)\b")


def _terminal(result) -> list[str]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        cli_text.print_run(result, None)
    return out.getvalue().splitlines()


def _report_box(result, tmp_path: pathlib.Path) -> tuple[str, str]:
    state = DemoState(out=tmp_path, results={(result.scene, result.scenario): result})
    page = build_html(state)
    box = re.search(r"<p class='question'><b>Question\.</b> (.*?)<br><b>Answer\.</b> (.*?)</p>", page)
    assert box, "the report shows the scenario's Q/A box"
    return html.unescape(box.group(1)), html.unescape(box.group(2))


@pytest.mark.slow
@pytest.mark.parametrize(("scene", "scenario"), SCENARIOS)
def test_the_terminal_the_json_and_the_report_show_one_answer(scene, scenario, scenario_run, tmp_path):
    result = scenario_run(scene, scenario)
    answer = result.answer
    assert answer is not None and answer.question and answer.answer
    # the terminal prints it first
    assert _terminal(result)[:2] == [f"Question: {answer.question}", f"Answer: {answer.answer}"]
    # summary.json carries the same text and the SI numbers it quotes, each the run's own value
    data = json.loads(json.dumps(result.to_dict()))
    assert (data["question"], data["answer"]) == (answer.question, answer.answer)
    values = {**result.parameters, **result.quantities}
    for name, number in data["answer_numbers"].items():
        if name in values:  # a quantity or parameter; the rest are the run's facts (dt_s, max_rel_error, ...)
            expected = values[name]
            expected = list(expected) if isinstance(expected, (list, tuple)) else expected
            assert number == pytest.approx(expected, rel=0, abs=0, nan_ok=True), name
    # the report's box is the same sentence
    assert _report_box(result, tmp_path) == (answer.question, answer.answer)
    assert not RAW_SI.search(answer.answer), answer.answer


@pytest.mark.slow
@pytest.mark.parametrize(("scene", "scenario"), SCENARIOS)
def test_an_answer_quoting_a_measured_value_quotes_its_exact_value_beside_it(scene, scenario, scenario_run):
    result = scenario_run(scene, scenario)
    quoted = set(result.answer.numbers)
    quantities = result.quantities
    for name in quoted:
        exact = f"{name}_exact"
        if exact in quantities and isinstance(quantities[exact], float) and math.isfinite(quantities[exact]):
            assert exact in quoted, f"{scene}/{scenario} quotes {name} without {exact}"
        if name.endswith("_exact") and name.removesuffix("_exact") in quantities:
            assert name.removesuffix("_exact") in quoted, f"{scene}/{scenario} quotes {name} without the measured"


@pytest.mark.slow
def test_the_drill_string_prints_the_readmes_sentence(scenario_run):
    # README: "winds up 1.70 turns, breaks free at 2.6963 s ..., whips round at 119 rpm, 2x the top drive"
    answer = scenario_run("drill_string", "breakaway").answer.answer
    for words in ("winds up 1.70 turns", "breaks free at 2.6963 s", "whips round at 119 rpm, 2x the top drive"):
        assert words in answer, answer


def test_springlab_run_prints_the_question_and_answer_first_and_json_has_them(capsys):
    assert main(["run", "slider", "exercise"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert main(["run", "slider", "exercise", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert lines[:2] == [f"Question: {data['question']}", f"Answer: {data['answer']}"]
    # the chapter's answer x(t) = 10 e^(-t) - 5 e^(-2t) m, worked by hand (m = 1, k = 2, c = 3, x0 = 5)
    assert "x(t) = 10 e^(-1 t) + (-5) e^(-2 t) m" in data["answer"]
    assert data["answer_numbers"]["coefficient_A_m"] == pytest.approx(10.0, rel=1e-12)


def test_validate_prints_one_answer_line_per_scenario_and_its_json_carries_them(capsys):
    assert main(["validate", "kinematics"]) == 0
    out = capsys.readouterr().out
    assert main(["validate", "kinematics", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert len(rows) == len(scenes.get("kinematics").scenarios)
    for row in rows:
        assert f"  kinematics {row['scenario']}: {row['answer']}" in out.splitlines()
        assert row["question"]


def test_a_step_grid_that_changes_the_ramp_is_said_in_the_verdict_line(capsys):
    # 2 s on a 12 ms grid: round(2 / 0.012) = 167 steps, 2.004 s
    main(["run", "drill_string", "spin_up", "--dt", "0.012", "--duration", "3", "--set", "n_elements=4"])
    lines = capsys.readouterr().out.splitlines()
    verdict = next(line for line in lines if line.startswith("  tolerance"))
    assert "lasts 2.004 s" in verdict and "0.01 s" in verdict
    main(["run", "drill_string", "spin_up", "--dt", "0.012", "--duration", "3", "--set", "n_elements=4", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert len(data["grid_notes"]) == 1 and "2.004 s" in data["grid_notes"][0]
    # a dt that divides the ramp changes nothing and says nothing
    main(["run", "drill_string", "spin_up", "--dt", "0.01", "--duration", "3", "--set", "n_elements=4", "--json"])
    assert json.loads(capsys.readouterr().out)["grid_notes"] == []
