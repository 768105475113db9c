"""The audit's options, checked before any work: one `BadInputError` naming what was wrong and what is valid.

`check_options(...)` gives the frozen `Options` the audit runs with; `resolve_duration` adds the model's own
default duration (a scene's scenario duration) once the model is loaded.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from springlab.errors import BadInputError
from springlab.runs import compare
from springlab.sim.simulate import INTEGRATORS, integrator_id

#: defaults of the command line and the API
DEFAULT_TOL = 1e-3
DEFAULT_DURATION = 1.0
DEFAULT_PERTURB = 1e-3


@dataclasses.dataclass(frozen=True)
class Options:
    """What the audit was asked, checked.

    Attributes
    ----------
    tol
        tolerance of the recommendation [-], in (0, 1).
    perturb
        size of the start's perturbation of the operating point [m or rad], >= 0.
    settle_s
        how long the model settles before it is audited [s] (None: not at all).
    integrators
        the integrators to sweep, in the order given, without repeats.
    dts
        the timesteps to sweep [s], largest first (None: the default grid).
    """

    tol: float
    perturb: float
    settle_s: float | None
    integrators: tuple[str, ...]
    dts: tuple[float, ...] | None


def check_options(
    *,
    tol: float,
    perturb: float,
    settle_s: float | None,
    integrators: Sequence[str] | str | None,
    dts: Sequence[float] | str | None,
) -> Options:
    """The checked options (see `Options`).

    Raises
    ------
    BadInputError
        a tolerance outside (0, 1), a negative or non-finite perturbation or settling time, an empty list of
        integrators, or timesteps that are not finite numbers > 0.
    UnknownNameError
        an unknown integrator (the message lists the valid ones).
    """
    tol = compare.check_tolerance(tol)
    if tol >= 1:
        raise BadInputError(f"tol must be a relative error in (0, 1), got {tol!r}")
    perturb = check_number("perturb", perturb, allow_zero=True)
    if settle_s is not None:
        settle_s = check_number("settle", settle_s, allow_zero=True)
    names = _integrators(integrators)
    steps = parse_dts(dts)
    return Options(tol, perturb, settle_s, tuple(names), None if steps is None else tuple(steps))


def resolve_duration(duration: float | None, default: float | None) -> float:
    """The simulated time of every run [s]: `duration`, else the model's own `default` (a scene's scenario),
    else DEFAULT_DURATION.

    Raises
    ------
    BadInputError
        not a finite number > 0.
    """
    return check_number("duration", duration if duration is not None else default or DEFAULT_DURATION)


def parse_dts(spec: Any) -> list[float] | None:
    """--dt: None, a list of seconds, "a,b,c", or a range "LOW:HIGH:N" (N log-spaced values, each snapped to
    HIGH / m for an integer m so that they share checkpoints); returned largest first."""
    if spec is None:
        return None
    if isinstance(spec, str):
        text = spec.strip()
        try:
            if ":" in text:
                low_text, high_text, count_text = text.split(":")
                low, high, count = float(low_text), float(high_text), int(count_text)
                if not (0 < low < high and math.isfinite(high) and count >= 2):
                    raise ValueError
                values = sorted({high / round(high / v) for v in np.geomspace(low, high, count)}, reverse=True)
            else:
                values = [float(v) for v in text.split(",") if v.strip()]
        except ValueError:
            raise BadInputError(
                f"--dt must be seconds 'a,b,c' or a range 'LOW:HIGH:N' with 0 < LOW < HIGH, N >= 2; got {spec!r}"
            ) from None
    else:
        values = [float(v) for v in spec]
    if not values or any(not (math.isfinite(v) and v > 0) for v in values):
        raise BadInputError(f"every dt must be a finite number > 0 s, got {spec!r}")
    return sorted(set(values), reverse=True)


def check_number(name: str, value: Any, *, allow_zero: bool = False) -> float:
    """`value` as a float when it is a finite number > 0 (>= 0 with `allow_zero`), else BadInputError."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise BadInputError(f"{name} must be a finite number {bound}, got {value!r}")
    return float(value)


def _integrators(names: Any) -> list[str]:
    if names is None:
        return list(INTEGRATORS)
    if isinstance(names, str):
        names = [n.strip() for n in names.split(",") if n.strip()]
    names = list(dict.fromkeys(names))
    for name in names:
        integrator_id(name)
    if not names:
        raise BadInputError(f"--integrators needs at least one of {', '.join(INTEGRATORS)}")
    return names
