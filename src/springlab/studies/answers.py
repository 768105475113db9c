"""How a study writes its answer: the sentence and the SI numbers it quotes, as one `springlab.answer.Answer`.

Every study's result has `question_answer` (an Answer: its question, the answer in one or two sentences, and
the numbers the sentence quotes, name -> SI value); `question` and `answer` are its two strings, the command
prints `Answer.text()` first and `to_dict()` starts with `Answer.to_dict()` (`question`, `answer`,
`answer_numbers`), so the terminal and the JSON cannot disagree. A study's sentence has parts that depend on
its data (a pick or none, one resonance or three), so it is written with a `Quoter` rather than one template:
each number goes through the quoter, which writes it in the unit a reader expects (springlab.answer's units:
`~s` gives 2 ms, `~m/s` 1.8 mm/s, `rpm` from rad/s) and records it under its name.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from springlab.answer import FAMILIES, UNITS, Answer, Quoted, quantity

#: a quantity's name ends in its SI unit (DESIGN: `omega_rad_s`, `static_sag_m`): suffix -> the unit (or
#: family) a sentence writes it in
SUFFIXES = (
    ("_m_s2", "m/s²"),
    ("_m_s", "~m/s"),
    ("_rad_s", "rpm"),
    ("_hz", "Hz"),
    ("_m", "~m"),
    ("_s", "~s"),
)


def unit_of(name: str) -> str:
    """The unit a quantity called `name` is written in ('' if its name ends in none: a ratio or a count).

    Parameters
    ----------
    name
        e.g. 'stop_position_m' ('~m': m, mm, µm or nm), 'creep_velocity_m_s' ('~m/s'), 'damping_ratio' ('').
    """
    return next((unit for suffix, unit in SUFFIXES if name.endswith(suffix)), "")


class Quoter:
    """Writes the numbers of one answer and records each (name -> SI value) for `Answer.numbers`."""

    def __init__(self) -> None:
        self.numbers: dict[str, Quoted] = {}

    def __call__(self, name: str, value: float, unit: str = "", spec: str = ".3g") -> str:
        """`value` [SI] in words, recorded as `name`: with a unit of springlab.answer ('~s', 'mm/s', 'rpm', ...)
        or without one (a ratio, an error, a count).

        Parameters
        ----------
        name
            the number's name in `answer_numbers` (ending in its SI unit where it has one).
        value
            the value [SI].
        unit
            the unit or '~family' to write it in ('': the bare number).
        spec
            the number format.
        """
        value = float(value) if not isinstance(value, int) else value
        self.numbers[name] = value
        return written(value, unit, spec)

    def dt(self, name: str, value: float) -> str:
        """A timestep [s] in words, recorded as `name`: 'dt = 2 ms'."""
        return f"dt = {self(name, value, '~s')}"

    def named(self, name: str, value: float, spec: str = ".3g") -> str:
        """A named quantity's value in the unit its name ends in (`unit_of`), recorded under its name."""
        return self(name, value, unit_of(name), spec)

    def answer(self, question: str, text: str) -> Answer:
        """The Answer: `question`, `text` and the numbers quoted."""
        return Answer(question, text, dict(self.numbers))


def written(value: float, unit: str = "", spec: str = ".3g") -> str:
    """`value` [SI] in words in `unit` (springlab.answer's units and '~families'; '': the bare number)."""
    if unit and math.isfinite(value):
        return quantity(value, unit, spec)
    return format(value, spec)


def unit_words(unit: str) -> tuple[str, str]:
    """(the unit springlab.answer writes a value of SI `unit` in, words after a bare number): 'm' -> ('~m', ''),
    'N s/m' (not converted) -> ('', ' N s/m'), '-' -> ('', '')."""
    if unit in FAMILIES:
        return f"~{unit}", ""
    if unit in UNITS:
        return unit, ""
    return "", "" if unit in ("-", "") else f" {unit}"


def of_words(question: str, text: str, numbers: Mapping[str, Quoted]) -> Answer:
    """An Answer whose sentence an older part of the study writes itself (e.g. the fit's verdict), with the
    numbers it quotes named by the caller."""
    return Answer(question, text, dict(numbers))


def capital(text: str) -> str:
    """`text` with its first letter in upper case (a clause that starts a sentence)."""
    return text[:1].upper() + text[1:]
