"""Every study's question and its answer in words, with each number in the unit a reader expects.

A study's result states its question and answers it in one or two sentences (`question`, `answer`): the
command prints them first, `to_dict()` carries them as `question` and `answer` beside the numbers they quote
(in SI), and both come from the one property, so the terminal and the JSON cannot disagree. The numbers in
the words come from the same fields `to_dict()` writes, through the functions below: a length in m, mm or µm,
a time in s, ms or µs, a speed in m/s, mm/s or µm/s, an angular speed in rpm, whichever keeps the mantissa
between 1 and 1000 (tests/test_study_answers.py reads the numbers back out of the words and finds each in
the JSON).
"""

from __future__ import annotations

import math

#: SI unit -> the scaled units a sentence may use, largest first: (name, factor to SI)
SCALES: dict[str, tuple[tuple[str, float], ...]] = {
    "m": (("m", 1.0), ("mm", 1e-3), ("µm", 1e-6), ("nm", 1e-9)),
    "s": (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6)),
    "m/s": (("m/s", 1.0), ("mm/s", 1e-3), ("µm/s", 1e-6), ("nm/s", 1e-9)),
    "m/s^2": (("m/s²", 1.0), ("mm/s²", 1e-3), ("µm/s²", 1e-6)),
    "rad/s": (("rpm", 2.0 * math.pi / 60.0),),
}

#: a quantity's name ends in its SI unit (DESIGN: `omega_rad_s`, `static_sag_m`): suffix -> unit
SUFFIXES = (
    ("_m_s2", "m/s^2"),
    ("_m_s", "m/s"),
    ("_rad_s", "rad/s"),
    ("_hz", "Hz"),
    ("_m", "m"),
    ("_s", "s"),
)


def unit_of(name: str) -> str:
    """The SI unit a quantity's name ends in ('' if none: a ratio or a count).

    Parameters
    ----------
    name
        e.g. 'stop_position_m', 'creep_velocity_m_s', 'damping_ratio'.
    """
    return next((unit for suffix, unit in SUFFIXES if name.endswith(suffix)), "")


def amount(value: float, unit: str, digits: int = 3) -> str:
    """`value` [unit, SI] in words with the scaled unit that keeps it readable: amount(0.0018, 'm/s') is
    '1.8 mm/s', amount(-0.00534, 'm') '-5.34 mm', amount(1.61, 's') '1.61 s'; a unit without scales is written
    as given ('800 N/m'), '' as a bare number.

    Parameters
    ----------
    value
        the value in SI.
    unit
        its SI unit ('m', 's', 'm/s', 'm/s^2', 'rad/s', 'Hz', or any other, written as is).
    digits
        significant digits.
    """
    if not math.isfinite(value):
        return f"{value} {unit}".strip()
    scales = SCALES.get(unit)
    if not scales:
        return f"{value:.{digits}g} {unit}".strip()
    name, factor = scales[-1]
    for name_, factor_ in scales:
        if abs(value) >= factor_ * (1.0 - 0.5 * 10.0 ** (1 - digits)):  # 0.9995 mm reads as 1 mm, not 1e+03 µm
            name, factor = name_, factor_
            break
    if value == 0.0:
        name, factor = scales[0]
    return f"{value / factor:.{digits}g} {name}"


def quantity(name: str, value: float, digits: int = 3) -> str:
    """A named quantity's value in words, its unit read from its name (`unit_of`, `amount`)."""
    return amount(value, unit_of(name), digits)


def dt_text(dt: float) -> str:
    """A timestep [s] in words: 'dt = 2 ms'."""
    return f"dt = {amount(dt, 's')}"


def error_text(value: float | None, digits: int = 2) -> str:
    """A relative error [-] in words: '3.1e-05' (or 'diverged' for None)."""
    return "diverged" if value is None else f"{value:.{digits}g}"


def question_answer(question: str, answer: str) -> dict[str, str]:
    """{"question", "answer"}: the two keys every study's JSON starts with."""
    return {"question": question, "answer": answer}
