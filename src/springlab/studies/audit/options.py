"""The audit's options, checked before any work: one `BadInputError` naming what was wrong and what is valid.

`check_options(...)` gives the frozen `Options` the audit runs with; `resolve_duration` adds the model's own
default duration (a scene's scenario duration) once the model is loaded.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

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
    integrators: Sequence[str] | None,
    dts: Sequence[float] | None,
) -> Options:
    """The checked options (see `Options`); `integrators` and `dts` are typed sequences (the command line parses
    its "a,b" and "LOW:HIGH:N" strings itself: springlab.cli).

    Raises
    ------
    BadInputError
        a tolerance outside (0, 1), a negative or non-finite perturbation or settling time, a string or an
        empty list where a sequence of integrators is asked, or timesteps that are not finite numbers > 0.
    UnknownNameError
        an unknown integrator (the message lists the valid ones).
    """
    tol = compare.check_tolerance(tol)
    if tol >= 1:
        raise BadInputError(f"tol must be a relative error in (0, 1), got {tol!r}")
    perturb = check_number("perturb", perturb, allow_zero=True)
    if settle_s is not None:
        settle_s = check_number("settle", settle_s, allow_zero=True)
    return Options(tol, perturb, settle_s, _integrators(integrators), _timesteps(dts))


def resolve_duration(duration: float | None, default: float | None) -> float:
    """The simulated time of every run [s]: `duration`, else the model's own `default` (a scene's scenario),
    else DEFAULT_DURATION.

    Raises
    ------
    BadInputError
        not a finite number > 0.
    """
    return check_number("duration", duration if duration is not None else default or DEFAULT_DURATION)


def check_number(name: str, value: Any, *, allow_zero: bool = False) -> float:
    """`value` as a float when it is a finite number > 0 (>= 0 with `allow_zero`), else BadInputError."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise BadInputError(f"{name} must be a finite number {bound}, got {value!r}")
    return float(value)


def _integrators(names: Sequence[str] | None) -> tuple[str, ...]:
    """The integrators to sweep, in the order given, each once (None: all five)."""
    if names is None:
        return tuple(INTEGRATORS)
    if isinstance(names, str):
        raise BadInputError(
            f"integrators takes a sequence of names, e.g. integrators=['rk4', 'euler'], not the string {names!r}"
        )
    unique = tuple(dict.fromkeys(names))
    for name in unique:
        integrator_id(name)
    if not unique:
        raise BadInputError(f"integrators needs at least one of {', '.join(INTEGRATORS)}")
    return unique


def _timesteps(dts: Sequence[float] | None) -> tuple[float, ...] | None:
    """The timesteps to sweep [s], largest first, each once (None: the default grid)."""
    if dts is None:
        return None
    if isinstance(dts, str):
        raise BadInputError(
            f"dts takes a sequence of timesteps in seconds, e.g. dts=[0.002, 0.001], not the string {dts!r}"
            " (the command line's --dt 'a,b,c' or 'LOW:HIGH:N')"
        )
    try:
        values = [float(dt) for dt in dts]
    except (TypeError, ValueError):
        raise BadInputError(
            f"dts takes a sequence of timesteps in seconds, e.g. dts=[0.002, 0.001]; got {dts!r}"
        ) from None
    if not values or any(not (math.isfinite(v) and v > 0) for v in values):
        raise BadInputError(f"every dt must be a finite number > 0 s, got {list(dts)!r}")
    return tuple(sorted(set(values), reverse=True))
