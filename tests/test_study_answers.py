"""Every study states its question and answers it in words with units, from the numbers its JSON holds
(issue 34 item 1).

Each study's `to_dict()` (what `--json` prints and the study's .json file holds) carries `question` and
`answer`; the command prints the same two first. The answer's numbers are read back out of the words here,
each with its unit (mm, µm, ms, mm/s, rpm, ...) converted to SI and the precision it was printed with, and
each must be a number of the JSON within that precision; the numbers a study's answer is about (the pick's
timestep and error, the range of a sweep, the boundaries) must be among them.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

import springlab
from springlab.cli.main import main
from springlab.scenes import get
from springlab.studies import answers, tradeoff
from springlab.studies.friction_settings import friction_settings
from springlab.studies.sweeps import sweep

#: a unit a sentence may write after a number -> its factor to SI (rpm: to rad/s; %: to a fraction)
UNITS = {
    "kHz": 1e3,
    "mHz": 1e-3,
    "Hz": 1.0,
    "rpm": 2.0 * math.pi / 60.0,
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
_NUMBER = re.compile(
    r"(?<![\w.^])(?P<number>[-+]?\d+(?:\.(?P<decimals>\d+))?(?:e(?P<exponent>[-+]?\d+))?)"
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


def assert_answer_from_json(data: dict, *about: float) -> None:
    """`data` has a question and an answer; every number of the answer is a number of `data` as printed, and
    each of `about` is quoted in it."""
    question, answer = data["question"], data["answer"]
    assert question.strip().endswith("?") and answer.strip(), (question, answer)
    numbers = numbers_of({k: v for k, v in data.items() if k not in ("question", "answer")})
    tokens = quoted(answer)
    for value, half, words in tokens:
        assert any(_matches(value, half, n) for n in numbers), f"{words!r} of the answer is no number of the JSON"
    for number in about:
        assert any(_matches(value, half, number) for value, half, _ in tokens), f"{number!r} is not quoted: {answer}"


def test_the_reader_reads_units_and_precision_back():
    assert quoted("creep velocity 1.8 mm/s after 1.61 s at 5.34e-05 (relative), 119 rpm, -5.34 mm") == [
        (pytest.approx(1.8e-3), pytest.approx(0.05e-3), "1.8 mm/s"),
        (1.61, pytest.approx(0.005), "1.61 s"),
        (5.34e-05, pytest.approx(0.005e-5), "5.34e-05"),
        (pytest.approx(119 * 2 * math.pi / 60), pytest.approx(0.5 * 2 * math.pi / 60), "119 rpm"),
        (pytest.approx(-5.34e-3), pytest.approx(0.005e-3), "-5.34 mm"),
    ]
    assert quoted("rk4 at 22 steps, R^2 = 0.98") == [(22.0, 0.5, "22"), (0.98, pytest.approx(0.005), "0.98")]
    assert answers.amount(0.0018, "m/s") == "1.8 mm/s" and answers.amount(-0.00534, "m") == "-5.34 mm"
    assert answers.amount(1.61, "s") == "1.61 s" and answers.amount(0.0225, "s") == "22.5 ms"
    assert answers.amount(0.0009996, "m") == "1 mm" and answers.amount(12.566371, "rad/s") == "120 rpm"
    assert answers.quantity("creep_velocity_m_s", 5.21e-4) == "521 µm/s"


def test_tradeoff_answers_with_the_verified_pick_and_the_orders_and_prints_them_first(capsys):
    result = tradeoff.tradeoff("slider", "free", tol=1e-4, duration=0.5)
    data = result.to_dict()
    pick = data["recommendation"]
    assert_answer_from_json(data, pick["dt"], pick["max_rel_error"], data["orders"]["rk4"], pick["tol"])
    assert "ms" in data["answer"] and pick["integrator"] in data["answer"]
    assert main(["tradeoff", "slider", "free", "--tol", "1e-4", "--duration", "0.5"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[:2] == [f"Question: {data['question']}", f"Answer: {data['answer']}"]


def test_tradeoff_without_tol_answers_with_the_orders():
    data = tradeoff.tradeoff("slider", "free", duration=0.5, integrators=("euler", "rk4")).to_dict()
    best = min(
        (r for r in data["runs"] if not r["diverged"] and not r["beyond_limit"]), key=lambda r: r["max_rel_error"]
    )
    assert_answer_from_json(data, data["orders"]["euler"], best["dt"], best["max_rel_error"])


def test_stability_answers_with_the_undamped_limits(stability_report):
    data = stability_report.to_dict()
    undamped = [b["measured_omega_dt"] for b in data["boundaries"] if b["zeta"] == 0.0]
    assert_answer_from_json(data, *undamped, max(b["relative_difference"] for b in data["boundaries"]))


def test_sweep_answers_with_its_counts_and_the_headlines_range(capsys):
    result = sweep("slider", "free", vary={"damping": (0.5, 40.0, 4, "log")}, duration=0.5)
    data = result.to_dict()
    zeta = [row["quantities"]["damping_ratio"] for row in data["rows"]]
    assert result.headline == "max_displacement_m"
    assert_answer_from_json(data, data["passed"], data["configurations"])
    by_ratio = sweep("slider", "free", vary={"damping": (0.5, 40.0, 4, "log")}, duration=0.5)
    assert min(zeta) < max(zeta) and by_ratio.answer == result.answer
    assert main(["sweep", "slider", "free", "--vary", "damping=0.5:40:4:log", "--duration", "0.5"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[:2] == [f"Question: {data['question']}", f"Answer: {data['answer']}"]


def test_the_design_study_and_its_sobol_indices_answer_from_their_json(small_design_study):
    data = small_design_study.to_dict()
    assert data["question"] == small_design_study.design.question
    assert_answer_from_json(data, data["default"]["positioning_time_s"])
    assert "µm" in data["answer"] and " um" not in data["answer"]
    sobol = small_design_study.sobol.to_dict()
    assert_answer_from_json(sobol, *sobol["S1"].values())


def test_fit_answers_with_its_estimates_and_prints_them_first(tmp_path, capsys):
    t = np.arange(0.0, 1.0, 0.01)
    decay = 0.05 * np.exp(-0.5 * t) * np.cos(20.0 * t)  # a damped oscillation [m]
    result = springlab.fit("slider", {"time": t, "slider_pos": decay}, mass=2.0)
    data = result.to_dict()
    assert data["answer"] == data["verdict"]
    # the ± half-widths and the share of the amplitude are derived from the JSON's numbers, not among them:
    # the answer's estimates and residual are
    tokens = quoted(data["answer"])
    omega = (data["derived"].get("omega_n_rad_s") or data["estimates"]["omega_n"])["value"]
    for number in (omega, data["residual_rms"]):
        assert any(_matches(value, half, number) for value, half, _ in tokens), data["answer"]
    assert data["question"].endswith("?") and all(name in data["question"] for name in data["free"])
    path = tmp_path / "decay.csv"
    path.write_text("time,slider_pos\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(t, decay)))
    assert_prints_its_json_first(capsys, ["fit", "slider", str(path), "--set", "mass=2"])


def assert_prints_its_json_first(capsys, argv: list[str]) -> dict:
    """The command's first two lines are its --json's question and answer (one source of the words)."""
    main([*argv, "--json"])
    data = json.loads(capsys.readouterr().out)
    main(argv)
    lines = capsys.readouterr().out.splitlines()
    assert lines[:2] == [f"Question: {data['question']}", f"Answer: {data['answer']}"]
    return data


def test_refine_answers_with_its_verified_size_integrator_and_timestep(capsys):
    data = assert_prints_its_json_first(
        capsys, ["refine", "drill_string", "--tol", "0.2", "--sizes", "4,8", "--integrators", "euler,rk4"]
    )
    pick = data["recommendation"]
    assert data["quantity"] == "mode_1_frequency_hz"
    assert_answer_from_json(data, pick["size"], pick["dt"], pick["error_bound"], pick["tol"])


def test_audit_answers_with_its_own_setting_and_the_pick(shipped_audit):
    data = shipped_audit("slider").to_dict()
    own, pick = data["own_setting"], data["recommendation"]
    assert_answer_from_json(data, own["error"], own["margin"], pick["dt"], pick["error"])


def test_frequency_answers_with_its_band_resonances_and_cheapest_setting(capsys):
    data = assert_prints_its_json_first(capsys, ["frequency", "car"])
    resonances = [r["frequency_hz"] for r in data["resonances"]]
    assert resonances and data["within_tol_hz"] is not None
    assert_answer_from_json(data, *resonances, data["within_tol_hz"][1], data["cheapest"]["max_dt_s"], data["tol"])


def test_friction_settings_answers_per_case_and_its_values_carry_units():
    ends = {s.name: (s.mujoco_default, s.values[-1]) for s in get("friction").dry_friction.settings}
    study = friction_settings(
        "friction", ["incline_hold"], tol=1e-2, integrators=("euler",), dts=(2e-3, 1e-3), values=ends
    )
    data = study.to_dict()
    (case,) = data["cases"]
    assert_answer_from_json(data, case["default"]["max_rel_error"], case["pick"]["dt"], case["pick"]["verified_error"])
    # the case's paragraph: the hold's creep velocity in mm/s or µm/s, the crept distance in mm or µm, as measured
    creep = case["default"]["values"]["creep_velocity_m_s"]
    assert answers.quantity("creep_velocity_m_s", creep) in case["answer"]
    assert re.search(r"creep velocity -?[\d.e+-]+ (mm|µm|nm)/s", case["answer"]), case["answer"]
    for value, half, words in quoted(case["answer"]):
        if " " not in words:  # a count (settings that tie) or a bare ratio: the values with units are checked
            continue
        assert any(_matches(value, half, n) for n in numbers_of(case)), f"{words!r} is no number of the case"


def test_the_random_load_studies_print_their_json_question_and_answer_first(capsys):
    cable = ["--set", "n_elements=9", "--set", "damper_position=30", "--set", "damper_coefficient=4e4"]
    data = assert_prints_its_json_first(capsys, ["rms", "stay_cable", "--seeds", "2", "--record", "20", *cable])
    assert data["answer"] and data["question"].endswith("?")
