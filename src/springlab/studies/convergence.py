"""What a sweep of runs says about an integrator: the runs, their observed order, the Pareto front.

Shared by the studies that sweep integrators and timesteps (springlab.studies.tradeoff on a scene,
springlab.studies.audit on any MJCF): one `Run` per (integrator, dt), the order of convergence fitted
over the runs in the asymptotic range, and the runs no other beats in both error and wall time.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable
from typing import Any

import numpy as np

from springlab.runs import compare
from springlab.runs.compare import Verdict

#: the order fit keeps errors below this (beyond it the leading term no longer dominates) ...
FIT_MAX_ERROR = 0.1


#: ... and above this many times the round-off allowance 100 eps per step (compare.ROUNDOFF_PER_STEP)
FIT_ROUNDOFF_FACTOR = 10.0


#: the order is the slope over this many of the finest such runs ...
FIT_POINTS = 4


#: ... none of which may lie off the fitted line by more than this factor
FIT_MAX_SCATTER = 1.5


@dataclasses.dataclass(frozen=True)
class Run:
    """One (integrator, dt) of a sweep.

    Attributes
    ----------
    integrator
        integrator name.
    dt
        timestep [s].
    steps
        steps taken.
    max_rel_error
        max over the compared columns of max |sim - ref| / max |ref| [-]; None if diverged.
    wall_time_s
        wall time of the run alone [s] (see module docstring).
    diverged
        the run blew up (detected, never reported as a result).
    detail
        how it diverged, for people.
    verdict
        what `springlab run` says of the same setting (a springlab.runs.compare.Verdict: PASS,
        FAIL or NOT_VALIDATED); None if diverged.
    """

    integrator: str
    dt: float
    steps: int
    max_rel_error: float | None
    wall_time_s: float
    diverged: bool = False
    detail: str = ""
    verdict: Verdict | None = None

    @property
    def validated(self) -> bool:
        """Whether the run is inside the range of its error estimate (its verdict means something)."""
        return self.verdict in (Verdict.PASS, Verdict.FAIL)

    @property
    def error(self) -> float:
        """max_rel_error of a run that did not diverge [-] (filter out diverged runs first)."""
        if self.max_rel_error is None:
            raise ValueError(f"{self.integrator} at dt = {self.dt:g} s diverged: it has no error")
        return self.max_rel_error

    def to_dict(self) -> dict[str, Any]:
        """The JSON row: integrator, dt [s], max_rel_error [-], steps, wall_time_s [s], diverged, verdict."""
        return {
            "integrator": self.integrator,
            "dt": self.dt,
            "max_rel_error": self.max_rel_error,
            "steps": self.steps,
            "wall_time_s": self.wall_time_s,
            "diverged": self.diverged,
            "verdict": None if self.verdict is None else str(self.verdict),
        }


def asymptotic_runs(runs: Iterable[Run]) -> list[Run]:
    """The runs whose error is in the asymptotic range: not diverged, at most FIT_MAX_ERROR,
    and above FIT_ROUNDOFF_FACTOR x the round-off allowance 100 eps per step."""
    keep = []
    for r in runs:
        if r.diverged or r.max_rel_error is None:
            continue
        floor = FIT_ROUNDOFF_FACTOR * compare.ROUNDOFF_PER_STEP * r.steps
        if floor < r.max_rel_error <= FIT_MAX_ERROR:
            keep.append(r)
    return keep


def observed_order(runs: Iterable[Run]) -> float | None:
    """Least-squares slope of log(error) vs log(dt) over the FIT_POINTS finest asymptotic runs.

    The finest: the order of accuracy is a statement about dt -> 0, and a
    method can show a higher slope at coarse steps (symplectic Euler's O(dt^2)
    phase error can dominate its bounded O(dt) error there). None: fewer than
    3 asymptotic timesteps, or errors that follow no power law (a point off
    the fitted line by more than FIT_MAX_SCATTER, e.g. when the error comes
    from how an input's switching times fall on the step grid, not from the
    integrator).
    """
    points = sorted(asymptotic_runs(runs), key=lambda r: r.dt)[:FIT_POINTS]
    if len({r.dt for r in points}) < 3:
        return None
    log_dt, log_error = np.log([r.dt for r in points]), np.log([r.error for r in points])
    slope, intercept = np.polyfit(log_dt, log_error, 1)
    if np.max(np.abs(log_error - (slope * log_dt + intercept))) > math.log(FIT_MAX_SCATTER):
        return None
    return float(slope)


def pareto_front(runs: Iterable[Run]) -> list[Run]:
    """Runs that no other run beats in both error and wall time, cheapest first (diverged runs excluded)."""
    candidates = sorted((r for r in runs if not r.diverged), key=lambda r: (r.wall_time_s, r.error))
    front, best = [], math.inf
    for r in candidates:
        if r.error < best:
            front.append(r)
            best = r.error
    return front
