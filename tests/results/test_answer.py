"""The answer type (springlab.answer): a sentence in the units a reader expects, the SI numbers it quotes kept."""

from __future__ import annotations

import json
import math

import pytest

from springlab.answer import Answer, compose, quantity


def test_a_creep_of_1_8_mm_per_s_reads_in_mm_per_s_and_stays_si_in_the_numbers():
    answer = compose("How fast?", "It creeps at {creep_velocity_m_s:.2g ~m/s}.", {"creep_velocity_m_s": 0.0018})
    assert answer.answer == "It creeps at 1.8 mm/s."
    assert answer.numbers == {"creep_velocity_m_s": 0.0018}


def test_units_convert_by_their_definitions():
    # 1 rpm is one turn (2 pi rad) a minute; 1 µm is 1e-6 m; 1° is pi/180 rad
    assert quantity(2.0 * math.pi * 119.0 / 60.0, "rpm", ".4g") == "119 rpm"
    assert quantity(12.5e-6, "µm") == "12.5 µm"
    assert quantity(math.pi / 4.0, "°", ".3g") == "45°"
    assert quantity(0.02661, "~s") == "26.6 ms"
    assert quantity(2.6963, "~s", ".5g") == "2.6963 s"
    assert quantity(0.25, "%", ".3g") == "25%"


def test_a_family_picks_the_unit_that_puts_the_number_between_1_and_1000():
    assert quantity(1.0, "~m") == "1 m"
    assert quantity(0.999, "~m") == "999 mm"
    assert quantity(3e-10, "~m") == "0.3 nm"  # below the smallest unit: the smallest
    assert quantity(0.0, "~m/s") == "0 m/s"


def test_every_quoted_field_is_recorded_and_words_are_not():
    answer = compose(
        "Q?",
        "{motion} between {turning_points_m[0]:.3g ~m} and {turning_points_m[1]:.3g ~m}, {n:.0f} cycles",
        {"motion": "bounded", "turning_points_m": [-0.05, 0.05], "n": 3, "unused_s": 1.0},
    )
    assert answer.answer == "bounded between -50 mm and 50 mm, 3 cycles"
    assert answer.numbers == {"turning_points_m": (-0.05, 0.05), "n": 3}


def test_an_unknown_unit_or_a_missing_value_is_an_error_not_an_empty_sentence():
    with pytest.raises(ValueError, match="unknown unit 'furlong'"):
        compose("Q?", "{x:.3g furlong}", {"x": 1.0})
    with pytest.raises(ValueError, match="no unit family"):
        compose("Q?", "{x:.3g ~furlong}", {"x": 1.0})
    with pytest.raises(KeyError):
        compose("Q?", "{x:.3g m}", {})


def test_the_json_fields_round_trip():
    answer = compose("Where?", "At {x_m:.3g ~m} ({p_m[0]:.2g m}).", {"x_m": 0.01234, "p_m": (1.0, 2.0)})
    data = json.loads(json.dumps(answer.to_dict()))
    assert set(data) == {"question", "answer", "answer_numbers"}
    assert data["answer_numbers"] == {"x_m": 0.01234, "p_m": [1.0, 2.0]}
    assert Answer.from_dict(data) == answer
    assert Answer.from_dict({}) is None
    assert answer.text() == "Question: Where?\nAnswer: At 12.3 mm (1 m)."


def test_a_damper_of_329_kn_s_per_m_reads_in_kn_s_per_m():
    assert quantity(329107.2, "~N s/m", ".4g") == "329.1 kN s/m"
    assert quantity(68.5, "~N s/m", ".3g") == "68.5 N s/m"
    assert quantity(0.01021, "%", ".4g") == "1.021%"
