"""What the tests hold outputs to: the documented keys and types (docs/json.md), shared by several test files."""

from __future__ import annotations

from typing import Any

#: summary.json's keys, in order (docs/json.md, `run --json`)
SUMMARY_KEYS = [
    "scene",
    "scenario",
    "question",
    "answer",
    "answer_numbers",
    "integrator",
    "dt",
    "duration",
    "steps",
    "wall_time_s",
    "parameters",
    "quantities",
    "errors",
    "tolerance",
    "tolerance_basis",
    "passed",
    "verdict",
    "estimate_range",
    "checks",
    "model_limits",
    "grid_notes",
]


def plain_json(value: Any) -> bool:
    """Whether `value` is made of JSON's types only (what every `to_dict()` promises)."""
    if isinstance(value, dict):
        return all(isinstance(k, str) and plain_json(v) for k, v in value.items())
    if isinstance(value, list):
        return all(plain_json(v) for v in value)
    return value is None or type(value) in (str, int, float, bool)
