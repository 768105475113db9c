"""A question and its answer in words: the one source of the sentence a run or a study prints first, puts in its
JSON and the demo report shows in its Q/A box.

An `Answer` holds the question, the answer sentence and the numbers the sentence quotes (name -> SI value),
so the terminal, the JSON and the report cannot disagree: each shows the same object. `compose` writes the
sentence from a template over named SI values, in the units a reader expects::

    compose("How fast does it creep?", "It creeps at {creep_velocity_m_s:.2g ~m/s}.", {"creep_velocity_m_s": 1.8e-3})
    -> Answer(question="How fast does it creep?", answer="It creeps at 1.8 mm/s.",
              numbers={"creep_velocity_m_s": 0.0018})

A field's format spec is a Python number format, a space, and a unit: `{x:.3g mm}` converts the SI value to
millimetres and writes "12.3 mm"; `{x:.3g ~m}` picks the unit of the family (m, mm, µm, nm) that puts the
number between 1 and 1000; `{w:.4g rpm}` converts rad/s to rpm. Without a unit the value is formatted as it
is (for a count, a ratio or a word). The JSON keeps the SI values (`answer_numbers`), never the converted ones.
"""

from __future__ import annotations

import dataclasses
import math
import string
from collections.abc import Mapping, Sequence
from typing import Any

#: the JSON keys of an answer (`question` and `answer` as docs/json.md lists them, plus the numbers they quote)
QUESTION_KEY = "question"
ANSWER_KEY = "answer"
NUMBERS_KEY = "answer_numbers"

#: unit written in text -> factor from its SI unit (value in this unit = SI value x factor)
UNITS: dict[str, float] = {
    # length from m
    "km": 1e-3,
    "m": 1.0,
    "cm": 1e2,
    "mm": 1e3,
    "µm": 1e6,
    "nm": 1e9,
    # time from s
    "h": 1.0 / 3600.0,
    "min": 1.0 / 60.0,
    "s": 1.0,
    "ms": 1e3,
    "µs": 1e6,
    # speed from m/s
    "km/h": 3.6,
    "m/s": 1.0,
    "mm/s": 1e3,
    "µm/s": 1e6,
    "nm/s": 1e9,
    # acceleration from m/s^2
    "m/s²": 1.0,
    "mm/s²": 1e3,
    # angular speed from rad/s
    "rad/s": 1.0,
    "rpm": 60.0 / (2.0 * math.pi),
    # angle from rad
    "rad": 1.0,
    "mrad": 1e3,
    "°": 180.0 / math.pi,
    "turns": 1.0 / (2.0 * math.pi),
    # frequency from Hz
    "kHz": 1e-3,
    "Hz": 1.0,
    "mHz": 1e3,
    # rates from 1/s
    "1/s": 1.0,
    # force, torque, energy, damping, mass from SI
    "kN": 1e-3,
    "N": 1.0,
    "mN": 1e3,
    "N m": 1.0,
    "J": 1.0,
    "mJ": 1e3,
    "µJ": 1e6,
    "kN s/m": 1e-3,
    "N s/m": 1.0,
    "kg": 1.0,
    "g": 1e3,
    "kg m²": 1.0,
    "dB": 1.0,
    # a fraction written as a percentage
    "%": 100.0,
}
#: `~unit` picks from its family the unit that puts the number in [1, 1000) (largest first)
FAMILIES: dict[str, tuple[str, ...]] = {
    "m": ("m", "mm", "µm", "nm"),
    "s": ("s", "ms", "µs"),
    "m/s": ("m/s", "mm/s", "µm/s", "nm/s"),
    "N": ("kN", "N", "mN"),
    "Hz": ("kHz", "Hz", "mHz"),
    "J": ("J", "mJ", "µJ"),
    "N s/m": ("kN s/m", "N s/m"),
}
#: units written without a space after the number
_ATTACHED = ("°", "%")

#: an SI value an answer quotes: a number, or a list of them (e.g. turning points [m])
Quoted = float | int | tuple[float, ...]


def unit_for(value: float, unit: str) -> str:
    """The unit to write `value` [SI] in: `unit` itself, or for `~unit` the family member giving [1, 1000).

    Raises
    ------
    ValueError
        the unit is not in `UNITS`, or `~unit` names no family of `FAMILIES`.
    """
    if unit.startswith("~"):
        family = FAMILIES.get(unit[1:])
        if family is None:
            raise ValueError(f"no unit family {unit!r}: valid families are {', '.join('~' + f for f in FAMILIES)}")
        size = abs(value)
        if not math.isfinite(size) or size == 0.0:
            return unit[1:]
        for member in family:
            if size * UNITS[member] >= 1.0 - 5e-13:
                return member
        return family[-1]
    if unit not in UNITS:
        raise ValueError(f"unknown unit {unit!r}: valid units are {', '.join(UNITS)}")
    return unit


def quantity(value: float, unit: str, spec: str = ".3g") -> str:
    """`value` [SI] written in `unit` (or `~family`) with the number format `spec`: e.g. '1.8 mm/s'."""
    shown = unit_for(value, unit)
    number = format(value * UNITS[shown], spec)
    return f"{number}{shown}" if shown in _ATTACHED else f"{number} {shown}"


class _Quoting(string.Formatter):
    """str.format with units in the format spec, recording each field it quotes (name -> SI value)."""

    def __init__(self) -> None:
        super().__init__()
        self.quoted: dict[str, Any] = {}

    def get_field(self, field_name: str, args: Sequence[Any], kwargs: Mapping[str, Any]) -> Any:
        obj, first = super().get_field(field_name, args, kwargs)
        whole = kwargs[first] if isinstance(first, str) else args[first]
        if isinstance(whole, bool) or isinstance(whole, str):
            return obj, first
        if isinstance(whole, (int, float)):
            self.quoted[str(first)] = whole
        elif isinstance(whole, (list, tuple)) and all(isinstance(x, (int, float)) for x in whole):
            self.quoted[str(first)] = tuple(whole)
        return obj, first

    def format_field(self, value: Any, format_spec: str) -> str:
        spec, _, unit = format_spec.partition(" ")
        if not unit:
            return super().format_field(value, format_spec)
        return quantity(float(value), unit, spec)


@dataclasses.dataclass(frozen=True)
class Answer:
    """A question and its answer in one or two sentences, with the numbers the sentence quotes.

    Attributes
    ----------
    question
        the question in words.
    answer
        the answer in words, every number with its unit.
    numbers
        the quoted numbers by name, in SI (the name ends in its unit, as in a run's quantities).
    """

    question: str
    answer: str
    numbers: Mapping[str, Quoted] = dataclasses.field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The JSON fields: `question`, `answer` (text) and `answer_numbers` (name -> SI value)."""
        numbers = {name: list(v) if isinstance(v, tuple) else v for name, v in self.numbers.items()}
        return {QUESTION_KEY: self.question, ANSWER_KEY: self.answer, NUMBERS_KEY: numbers}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Answer | None:
        """The answer in a JSON dict written by `to_dict` (None where it has no question)."""
        if not data.get(QUESTION_KEY):
            return None
        numbers = {k: tuple(v) if isinstance(v, list) else v for k, v in (data.get(NUMBERS_KEY) or {}).items()}
        return cls(str(data[QUESTION_KEY]), str(data.get(ANSWER_KEY) or ""), numbers)

    def text(self) -> str:
        """The two lines the terminal prints first: 'Question: ...' and 'Answer: ...'."""
        return f"Question: {self.question}\nAnswer: {self.answer}"


def compose(question: str, template: str, values: Mapping[str, Any]) -> Answer:
    """The `Answer` whose sentence is `template` formatted over `values` (SI), units as the fields ask.

    Parameters
    ----------
    question
        the question in words.
    template
        str.format template; a field's spec may end in a unit (`{x:.3g mm}`, `{x:.3g ~m/s}`, module docstring).
    values
        the named SI values (a run's parameters and quantities).

    Raises
    ------
    KeyError
        the template names a value that `values` lacks.
    ValueError
        a field names an unknown unit.
    """
    formatter = _Quoting()
    sentence = formatter.vformat(template, (), values)
    return Answer(question, sentence, dict(formatter.quoted))
