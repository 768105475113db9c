"""Every study states its question and answers it in words with units, from the numbers its JSON holds
(issue 34 item 1).

Each study's result has `question_answer` (a springlab.answer.Answer); its `to_dict()` (what `--json` prints
and the study's .json file holds) starts with `question`, `answer` and `answer_numbers` (the numbers the answer
quotes, SI), and the command prints the same two lines first. The answer's numbers are read back out of the
words here, each with its unit (mm, µm, ms, mm/s, rpm, ...) converted to SI and the precision it was printed
with: each must be a number of the JSON, each of `answer_numbers` must be in the words, and the numbers the
answer is about (the pick's timestep and error, the sweep's range, the boundaries) must be the JSON's fields.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from helpers.cli import computed_once
from helpers.timing import constant_time_run
from springlab.scenes import get
from springlab.studies import answers, tradeoff
from springlab.studies.friction_settings import friction_settings

#: a unit a sentence may write after a number -> its factor to SI (rpm: to rad/s; %: to a fraction)
UNITS = {
    "kHz": 1e3,
    "mHz": 1e-3,
    "Hz": 1.0,
    "rpm": 2.0 * math.pi / 60.0,
    "rad/s": 1.0,
    "µs": 1e-6,
    "ms": 1e-3,
    "s": 1.0,
    "nm/s": 1e-9,
    "µm/s": 1e-6,
    "mm/s": 1e-3,
    "m/s": 1.0,
    "µm/s²": 1e-6,
    "mm/s²": 1e-3,
    "m/s²": 1.0,
    "nm": 1e-9,
    "µm": 1e-6,
    "mm": 1e-3,
    "m": 1.0,
    "%": 1e-2,
}
_UNIT = "|".join(re.escape(u) for u in sorted(UNITS, key=len, reverse=True))
# a number not inside a name (rk4, S1, R^2) and not an interval's half-width (18.40 ± 0.05), then its unit
_NUMBER = re.compile(
    r"(?<![\w.^])(?<!± )(?P<number>[-+]?\d+(?:\.(?P<decimals>\d+))?(?:e(?P<exponent>[-+]?\d+))?)"
    rf"(?:\s?(?P<unit>{_UNIT})(?![\w/²]))?"
)


def quoted(text: str) -> list[tuple[float, float, str]]:
    """Every number of `text` as (value [SI], half its printed quantum [SI], the words): '5.34 mm' is
    (0.00534, 5e-6, '5.34 mm')."""
    out = []
    for match in _NUMBER.finditer(text):
        factor = UNITS.get(match["unit"] or "", 1.0)
        exponent = int(match["exponent"] or 0) - len(match["decimals"] or "")
        out.append((float(match["number"]) * factor, 0.5 * 10.0**exponent * factor, match[0]))
    return out


def numbers_of(data) -> list[float]:
    """Every number (not a bool) in a JSON value."""
    if isinstance(data, dict):
        return [x for value in data.values() for x in numbers_of(value)]
    if isinstance(data, list):
        return [x for value in data for x in numbers_of(value)]
    if isinstance(data, (int, float)) and not isinstance(data, bool):
        return [float(data)]
    return []


def _matches(value: float, half: float, number: float) -> bool:
    return abs(number - value) <= half * (1 + 1e-9) + 1e-15 * abs(number)


def assert_answer_from_json(data: dict, **fields: float) -> None:
    """`data` has a question and an answer; every number of the answer is a number of the JSON as printed,
    every one of `answer_numbers` is in the words, and each of `fields` (an answer number's name -> the JSON
    field it must equal) is that field."""
    question, answer, named = data["question"], data["answer"], data["answer_numbers"]
    assert question.strip().endswith("?") and answer.strip(), (question, answer)
    numbers = numbers_of(data)
    tokens = quoted(answer)
    for value, half, words in tokens:
        assert any(_matches(value, half, n) for n in numbers), f"{words!r} of the answer is no number of the JSON"
    for name, number in named.items():
        for one in number if isinstance(number, list) else [number]:
            assert any(_matches(v, h, one) for v, h, _ in tokens), f"{name} = {one!r} is not in: {answer}"
    for name, field in fields.items():
        assert named[name] == field, (name, named[name], field)


#: the study each command computes, where the command looks it up ("module:name")
STUDY_OF = {
    "tradeoff": "springlab.studies.tradeoff:tradeoff",
    "sweep": "springlab.studies.sweeps:sweep",
    "fit": "springlab.studies.fit.fit:fit",
    "refine": "springlab.studies.refine:refine",
    "frequency": "springlab.cli.commands.frequency:run_frequency",
    "rms": "springlab.studies.random_load:ensemble",
}


def assert_prints_its_json_first(cli, monkeypatch, argv: list[str]) -> dict:
    """The command's first two lines are its --json's question and answer (one source of the words). Its study is
    computed once, by the --json run, and the text run prints that same result: the two printers are held to one
    answer, and the study's cost is paid once."""
    made = computed_once(monkeypatch, STUDY_OF[argv[0]])
    data = json.loads(cli(*argv, "--json").out)
    lines = cli(*argv).out.splitlines()
    assert len(made) == 1
    assert lines[:2] == [f"Question: {data['question']}", f"Answer: {data['answer']}"]
    return data


def test_the_reader_reads_units_and_precision_back():
    assert quoted("creep velocity 1.8 mm/s after 1.61 s at 5.34e-05 (relative), 119 rpm, -5.34 mm") == [
        (pytest.approx(1.8e-3), pytest.approx(0.05e-3), "1.8 mm/s"),
        (1.61, pytest.approx(0.005), "1.61 s"),
        (5.34e-05, pytest.approx(0.005e-5), "5.34e-05"),
        (pytest.approx(119 * 2 * math.pi / 60), pytest.approx(0.5 * 2 * math.pi / 60), "119 rpm"),
        (pytest.approx(-5.34e-3), pytest.approx(0.005e-3), "-5.34 mm"),
    ]
    assert quoted("rk4 at 22 steps, R^2 = 0.98, 18.40 ± 0.05") == [
        (22.0, 0.5, "22"),
        (0.98, pytest.approx(0.005), "0.98"),
        (18.4, pytest.approx(0.005), "18.40"),
    ]
    assert answers.written(0.0018, "~m/s") == "1.8 mm/s" and answers.written(-0.00534, "~m") == "-5.34 mm"
    assert answers.written(1.61, "~s") == "1.61 s" and answers.written(0.0225, "~s") == "22.5 ms"
    assert answers.unit_of("creep_velocity_m_s") == "~m/s" and answers.unit_of("damping_ratio") == ""
    say = answers.Quoter()
    assert say.dt("dt_s", 0.002) == "dt = 2 ms" and say.named("creep_velocity_m_s", 5.21e-4) == "521 µm/s"
    assert say.answer("Q?", "A.").numbers == {"dt_s": 0.002, "creep_velocity_m_s": 5.21e-4}


def test_tradeoff_answers_with_the_verified_pick_and_the_orders_and_prints_them_first(cli, monkeypatch):
    # the answer's numbers are the pick's (counted work ranks it) and the orders: the trade-off's timer, which times
    # every setting again alone, is the constant of helpers/timing.py (tests/studies/test_tradeoff.py holds the real)
    monkeypatch.setattr(tradeoff, "time_run", constant_time_run)
    data = assert_prints_its_json_first(
        cli, monkeypatch, ["tradeoff", "slider", "free", "--tol", "1e-4", "--duration", "0.5"]
    )
    pick = data["recommendation"]
    assert_answer_from_json(
        data, dt_s=pick["dt"], max_rel_error=pick["max_rel_error"], order_rk4=data["orders"]["rk4"], cost=pick["cost"]
    )
    assert " ms" in data["answer"] and pick["integrator"] in data["answer"]


def test_tradeoff_without_tol_answers_with_the_orders(monkeypatch):
    monkeypatch.setattr(tradeoff, "time_run", constant_time_run)  # orders and errors: no wall time read
    data = tradeoff.sweep("slider", "free", duration=0.5, integrators=("euler", "rk4")).to_dict()
    best = min(
        (r for r in data["runs"] if not r["diverged"] and not r["beyond_limit"]), key=lambda r: r["max_rel_error"]
    )
    assert_answer_from_json(
        data, order_euler=data["orders"]["euler"], best_dt_s=best["dt"], best_max_rel_error=best["max_rel_error"]
    )


def test_stability_answers_with_the_undamped_limits(stability_report):
    data = stability_report.to_dict()
    undamped = {
        f"{b['integrator']}_omega_dt": b["measured_omega_dt"]
        for b in data["boundaries"]
        if b["zeta"] == 0.0 and b["measured_omega_dt"] is not None and math.isfinite(b["measured_omega_dt"])
    }
    worst = max(b["relative_difference"] for b in data["boundaries"])
    assert undamped and "rk4_omega_dt" in undamped
    assert_answer_from_json(data, **undamped, largest_relative_difference=worst, boundaries=len(data["boundaries"]))


def test_sweep_answers_with_its_counts_and_the_headlines_range(cli, monkeypatch):
    data = assert_prints_its_json_first(
        cli,
        monkeypatch,
        ["sweep", "slider", "free", "--vary", "x0=0.01:0.1:3", "--vary", "damping=0.5:40:2:log", "--duration", "0.5"],
    )
    assert data["answer_numbers"]["max_displacement_m_min"] < data["answer_numbers"]["max_displacement_m_max"]
    peaks = [row["quantities"]["max_displacement_m"] for row in data["rows"] if row["passed"]]
    smallest = min(range(len(data["rows"])), key=lambda i: data["rows"][i]["quantities"]["max_displacement_m"])
    assert_answer_from_json(
        data,
        passed=data["passed"],
        configurations=data["configurations"],
        max_displacement_m_min=min(peaks),
        max_displacement_m_max=max(peaks),
        x0_at_min=data["rows"][smallest]["values"]["x0"],
    )
    assert " mm" in data["answer"]


def test_the_design_study_and_its_sobol_indices_answer_from_their_json(small_design_study):
    data = small_design_study.to_dict()
    assert data["question"] == small_design_study.design.question
    assert_answer_from_json(
        data,
        default_positioning_time_s=data["default"]["positioning_time_s"],
        positioning_time_s_max=data["positioning_time_s"]["max"],
    )
    assert "µm" in data["answer"] and " um" not in data["answer"]
    sobol = small_design_study.sobol.to_dict()
    assert_answer_from_json(
        sobol, **{f"S1_{n}": v for n, v in sobol["S1"].items()}, first_order_sum=sobol["first_order_sum"]
    )


def test_fit_answers_with_its_estimates_and_prints_them_first(tmp_path, cli, monkeypatch):
    t = np.arange(0.0, 1.0, 0.01)
    decay = 0.05 * np.exp(-0.5 * t) * np.cos(20.0 * t)  # a damped oscillation [m]
    path = tmp_path / "decay.csv"
    path.write_text("time,slider_pos\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(t, decay)))
    data = assert_prints_its_json_first(cli, monkeypatch, ["fit", "slider", str(path), "--set", "mass=2"])
    assert data["answer"] == data["verdict"]
    assert all(name in data["question"] for name in data["free"])
    omega = data["derived"].get("omega_n_rad_s") or data["estimates"]["omega_n"]
    key = "omega_n_rad_s" if "omega_n_rad_s" in data["derived"] else "omega_n"
    assert_answer_from_json(data, **{key: omega["value"]}, residual_rms=data["residual_rms"])


def test_refine_answers_with_its_verified_size_integrator_and_timestep(cli, monkeypatch):
    data = assert_prints_its_json_first(
        cli, monkeypatch, ["refine", "drill_string", "--tol", "0.2", "--sizes", "4,8", "--integrators", "euler,rk4"]
    )
    pick = data["recommendation"]
    assert data["quantity"] == "mode_1_frequency_hz"
    assert_answer_from_json(
        data,
        size=pick["size"],
        dt_s=pick["dt"],
        error_bound=pick["error_bound"],
        discretization_error=pick["discretization_error"],
        integration_error=pick["integration_error"],
    )


def test_audit_answers_with_its_own_setting_and_the_pick(shipped_audit):
    data = shipped_audit("slider").to_dict()
    own, pick = data["own_setting"], data["recommendation"]
    assert_answer_from_json(
        data, own_error=own["error"], own_margin=own["margin"], dt_s=pick["dt"], error=pick["error"]
    )


def test_frequency_answers_with_its_band_resonances_and_cheapest_setting(cli, monkeypatch):
    data = assert_prints_its_json_first(cli, monkeypatch, ["frequency", "car"])
    assert data["resonances"] and data["within_tol_hz"] is not None
    assert_answer_from_json(
        data,
        resonance_1_hz=data["resonances"][0]["frequency_hz"],
        within_tol_high_hz=data["within_tol_hz"][1],
        cheapest_dt_s=data["cheapest"]["max_dt_s"],
        dt_s=data["dt"],
    )


def test_friction_settings_answers_per_case_and_its_values_carry_units():
    ends = {s.name: (s.mujoco_default, s.values[-1]) for s in get("friction").dry_friction.settings}
    study = friction_settings(
        "friction", ["incline_hold"], tol=1e-2, integrators=("euler",), dts=(2e-3, 1e-3), values=ends
    )
    data = study.to_dict()
    (case,) = data["cases"]
    assert_answer_from_json(
        data,
        incline_hold_default_error=case["default"]["max_rel_error"],
        incline_hold_pick_dt_s=case["pick"]["dt"],
        incline_hold_pick_error=case["pick"]["verified_error"],
    )
    # the case's paragraph: the hold's creep velocity in mm/s or µm/s (it was "creep velocity 0.0018")
    creep = case["default"]["values"]["creep_velocity_m_s"]
    assert answers.written(creep, "~m/s") in case["answer"]
    assert re.search(r"creep velocity -?[\d.e+-]+ (mm|µm|nm)/s", case["answer"]), case["answer"]
    for value, half, words in quoted(case["answer"]):
        if " " not in words:  # a count (settings that tie) or a bare ratio: the values with units are checked
            continue
        assert any(_matches(value, half, n) for n in numbers_of(case)), f"{words!r} is no number of the case"


def test_the_random_load_studies_print_their_json_question_and_answer_first(cli, monkeypatch):
    cable = ["--set", "n_elements=9", "--set", "damper_position=30", "--set", "damper_coefficient=4e4"]
    data = assert_prints_its_json_first(
        cli, monkeypatch, ["rms", "stay_cable", "--seeds", "2", "--record", "20", *cable]
    )
    assert_answer_from_json(data, inside=data["inside"]) if "inside" in data else assert_answer_from_json(data)


def test_friction_settings_says_when_mujocos_defaults_were_not_swept():
    ends = {s.name: (s.mujoco_default,) for s in get("friction").dry_friction.settings}
    study = friction_settings("friction", ["coulomb_decay"], integrators=("rk4",), dts=(1e-3, 5e-4), values=ends)
    assert study.cases[0].default is None  # MuJoCo's default is euler at 2 ms
    assert "coulomb_decay: MuJoCo's defaults not in the sweep" in study.answer and "diverged" not in study.answer
