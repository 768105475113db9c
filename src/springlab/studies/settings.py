"""Which integrator, timestep and settings? What every such study shares, once.

The studies that sweep settings (springlab.studies.tradeoff on a scene, springlab.studies.refine over model
sizes, springlab.studies.friction_settings over MuJoCo's friction options, springlab.studies.audit on any
MJCF) each run a grid of settings, measure each run's error, and answer with the cheapest setting that
meets a tolerance. This module owns the parts they share:

* `Setting`: an integrator, a timestep and any further options (a model size, a solver option);
* `Run`: one run of a setting (steps, error, counted cost, measured time, diverged, beyond a stability
  limit); a study's own row holds one (`run`) beside its own numbers;
* `counted_cost`: the cost every ranking uses. Counted work, not a timer: steps x the integrator's model
  evaluations per step (`EVALUATIONS_PER_STEP`: rk4 4, the others 1) x the work of one evaluation
  (`work_per_evaluation`, read from the compiled model). The same grid gives the same costs on any
  machine and in any load, so the same command gives the same answer; the measured time of each run is
  reported beside it (`Run.time_s`), never ranked on;
* `pareto_front`: the runs no other beats in both cost and error. Diverged runs, runs beyond a known or
  predicted stability limit (a short run can end before its blow-up shows) and runs without an error
  are never on it;
* `observed_order`: the slope of log error vs log dt over the asymptotic runs;
* `cheapest_verified`: the candidates within the tolerance ranked by cost (then error, then the order the
  study listed them), each verified by a run of its own until one passes: a `Recommendation`, with the
  settings that tie with it in counted work, those within `TIMING_NOISE` of it (measured times could not
  have told them apart) and its sentence with units.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Generic, Protocol, TypeVar

import numpy as np

from springlab.runs import compare

if TYPE_CHECKING:
    import mujoco

#: model evaluations (forward passes) per step: RK4 evaluates the model at four stages, the others once
EVALUATIONS_PER_STEP: Mapping[str, int] = {"euler": 1, "implicit": 1, "implicitfast": 1, "rk4": 4, "discrete": 1}

#: the work of one NoSlip iteration, as a fraction of a model evaluation [-]. MuJoCo runs NoSlip's
#: Gauss-Seidel sweeps over the friction rows after the main solver in every evaluation (RK4's stages too).
#: Measured per step on the friction scene's four cases (`springlab friction-settings friction`, CPU time
#: per step with 3 iterations against none, each integrator): 0.02 (joint friction) to 0.14 (a box held on an
#: incline) per iteration; a tenth, stated here, is what the ranking counts
NOSLIP_ITERATION_WORK = 0.1

#: the unit of `Run.cost`
COST_UNIT = "DOF-evaluations"

#: what the cost counts, in words (printed beside it and in the JSON)
COST_BASIS = (
    "counted work: steps x model evaluations per step (rk4 4, the others 1) x degrees of freedom"
    f" x (1 + {NOSLIP_ITERATION_WORK:g} per NoSlip iteration); measured times are reported beside it, never ranked on"
)

#: measured times of one setting scatter by about this factor between runs on a shared machine (the
#: friction-settings sweep measured 1.2-1.3 per setting): settings whose counted costs are within it could
#: not be told apart by a timer, and the recommendation names them
TIMING_NOISE = 1.25

#: relative difference [-] below which two counted costs are the same (they are products of integers and a
#: stated factor: equal work, up to round-off)
SAME_COST = 1e-9

#: the order fit keeps errors below this (beyond it the leading term no longer dominates) ...
FIT_MAX_ERROR = 0.1
#: ... and above this many times the round-off allowance 100 eps per step (compare.ROUNDOFF_PER_STEP)
FIT_ROUNDOFF_FACTOR = 10.0
#: the order is the slope over this many of the finest such runs ...
FIT_POINTS = 4
#: ... none of which may lie off the fitted line by more than this factor
FIT_MAX_SCATTER = 1.5


def counted_cost(integrator: str, steps: int, work: float = 1.0) -> float:
    """Counted work of a run [DOF-evaluations]: steps x EVALUATIONS_PER_STEP[integrator] x `work`.

    Parameters
    ----------
    integrator
        MuJoCo integrator name.
    steps
        physics steps of the run.
    work
        the work of one model evaluation [DOF-evaluations] (`work_per_evaluation`; 1 for a one-DOF model).
    """
    return float(steps * EVALUATIONS_PER_STEP[integrator] * work)


def work_per_evaluation(model: mujoco.MjModel) -> float:
    """The work of one model evaluation [DOF-evaluations], from the compiled model: its degrees of freedom
    (MuJoCo's per-step work grows with them; at a few DOF a fixed overhead makes the measured time grow
    more slowly, which the measured times beside the cost show) x (1 + NOSLIP_ITERATION_WORK per NoSlip
    iteration)."""
    return float(max(1, model.nv)) * (1.0 + NOSLIP_ITERATION_WORK * int(model.opt.noslip_iterations))


# -- the setting and its run ----------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Setting:
    """What a study chooses: an integrator, a timestep and any further options.

    Attributes
    ----------
    integrator
        MuJoCo integrator name.
    dt
        timestep [s].
    options
        further (name, value) pairs in the study's order: a model size, MuJoCo solver options (SI).
    """

    integrator: str
    dt: float
    options: tuple[tuple[str, float], ...] = ()

    @property
    def option_values(self) -> dict[str, float]:
        """The options as a mapping (name -> value)."""
        return dict(self.options)

    def describe(self) -> str:
        """'n_elements 4, euler at dt = 0.08 s': the options, then the integrator and the timestep."""
        options = "".join(f"{name} {value:g}, " for name, value in self.options)
        return f"{options}{self.integrator} at dt = {self.dt:.3g} s"

    def to_dict(self) -> dict[str, Any]:
        """{"integrator", "dt" [s], "options" (name -> value)}."""
        return {"integrator": self.integrator, "dt": self.dt, "options": self.option_values}


@dataclasses.dataclass(frozen=True)
class Run:
    """One run of a setting: the row every settings study shares (a study's own row holds one as `run`).

    Attributes
    ----------
    setting
        the integrator, timestep and options.
    steps
        physics steps taken.
    error
        the error the study ranks by [-] (None: diverged, or the run measured nothing).
    cost
        counted work [DOF-evaluations] (`counted_cost`): what rankings and fronts use.
    time_s
        the measured time of the run alone on one thread [s], reported beside the cost (NaN: not measured).
    diverged
        the run blew up (detected; never a result).
    beyond_limit
        dt is above a known or predicted stability limit of the integrator: it did not blow up within the run,
        but a longer run would (never on a front, never recommended).
    detail
        how it diverged or why it has no error, for people.
    """

    setting: Setting
    steps: int
    error: float | None
    cost: float
    time_s: float = math.nan
    diverged: bool = False
    beyond_limit: bool = False
    detail: str = ""

    @property
    def run(self) -> Run:
        """The run itself (a study's row holds one as `run`; functions here take either)."""
        return self

    @property
    def integrator(self) -> str:
        """The setting's integrator name."""
        return self.setting.integrator

    @property
    def dt(self) -> float:
        """The setting's timestep [s]."""
        return self.setting.dt

    @property
    def valid(self) -> bool:
        """Whether the run is a result: not diverged, not beyond a stability limit, a finite error."""
        return not self.diverged and not self.beyond_limit and self.error is not None and math.isfinite(self.error)

    def to_dict(self) -> dict[str, Any]:
        """{"integrator", "dt" [s], "options", "steps", "error", "cost" [DOF-evaluations], "time_s" [s],
        "diverged", "beyond_limit", "detail"}."""
        return {
            **self.setting.to_dict(),
            "steps": self.steps,
            "error": self.error,
            "cost": self.cost,
            "time_s": self.time_s,
            "diverged": self.diverged,
            "beyond_limit": self.beyond_limit,
            "detail": self.detail,
        }


class HasRun(Protocol):
    """A study's row: anything that holds a `Run` (the kernel's `Run` holds itself)."""

    @property
    def run(self) -> Run: ...


R = TypeVar("R", bound=HasRun)


class RunFields:
    """The shared fields of a study's row that holds a `run`, read through to it (a mixin)."""

    run: Run

    @property
    def setting(self) -> Setting:
        """The run's setting."""
        return self.run.setting

    @property
    def integrator(self) -> str:
        """The run's integrator name."""
        return self.run.setting.integrator

    @property
    def dt(self) -> float:
        """The run's timestep [s]."""
        return self.run.setting.dt

    @property
    def steps(self) -> int:
        """Physics steps taken."""
        return self.run.steps

    @property
    def cost(self) -> float:
        """Counted work [DOF-evaluations]."""
        return self.run.cost

    @property
    def diverged(self) -> bool:
        """Whether the run blew up."""
        return self.run.diverged

    @property
    def beyond_limit(self) -> bool:
        """Whether dt is above a known or predicted stability limit."""
        return self.run.beyond_limit

    @property
    def detail(self) -> str:
        """How it diverged, for people."""
        return self.run.detail


def limit_dt(modes: Iterable[tuple[float, float]], omega_dt_limit: Callable[[float, float], float]) -> float | None:
    """The largest stable timestep [s] over a model's modes: min over the modes (omega [rad/s], zeta [-]) of
    `omega_dt_limit(omega, zeta)` / omega, the integrator's limit on omega dt (None: no limit, or no modes)."""
    ratio = min((omega_dt_limit(omega, zeta) / omega for omega, zeta in modes if omega > 0), default=math.inf)
    return ratio if math.isfinite(ratio) else None


def beyond(dt: float, limit: float | None) -> bool:
    """Whether dt [s] is above a stability limit [s] (None: the integrator has none), beyond round-off."""
    return limit is not None and dt > limit * (1 + 1e-9)


# -- what a sweep says -------------------------------------------------------------------------


def ranked(rows: Iterable[R], prefer: Callable[[R], float] | None = None) -> list[R]:
    """The rows in the order every ranking uses: counted cost, then the study's own preference among equal cost
    (`prefer`, smaller first, e.g. fewer settings changed; None: none), then error, then the order given (rows
    without an error last). Deterministic: nothing in it is measured by a timer."""
    listed = list(rows)

    def key(index: int) -> tuple[float, float, float, int]:
        run = listed[index].run
        preference = 0.0 if prefer is None else float(prefer(listed[index]))
        return (run.cost, preference, math.inf if run.error is None else run.error, index)

    return [listed[i] for i in sorted(range(len(listed)), key=key)]


def pareto_front(rows: Iterable[R]) -> list[R]:
    """The valid rows (`Run.valid`) no other valid row beats in both counted cost and error, cheapest first.

    Diverged rows, rows beyond a stability limit and rows without an error are never on it; of rows equal in
    both cost and error the first given stands for them.
    """
    front: list[R] = []
    best = math.inf
    for row in ranked(r for r in rows if r.run.valid):
        error = row.run.error
        assert error is not None  # valid
        if error < best:
            front.append(row)
            best = error
    return front


def asymptotic_runs(rows: Iterable[R]) -> list[R]:
    """The rows whose error is in the asymptotic range: not diverged, at most FIT_MAX_ERROR, and above
    FIT_ROUNDOFF_FACTOR x the round-off allowance 100 eps per step."""
    keep = []
    for row in rows:
        run = row.run
        if run.diverged or run.error is None:
            continue
        floor = FIT_ROUNDOFF_FACTOR * compare.ROUNDOFF_PER_STEP * run.steps
        if floor < run.error <= FIT_MAX_ERROR:
            keep.append(row)
    return keep


def observed_order(rows: Iterable[HasRun]) -> float | None:
    """Least-squares slope of log(error) vs log(dt) over the FIT_POINTS finest asymptotic runs.

    The finest: the order of accuracy is a statement about dt -> 0, and a method can show a higher slope at
    coarse steps (symplectic Euler's O(dt^2) phase error can dominate its bounded O(dt) error there). None:
    fewer than 3 asymptotic timesteps, or errors that follow no power law (a point off the fitted line by more
    than FIT_MAX_SCATTER, e.g. when the error comes from how an input's switching times fall on the step
    grid, not from the integrator).
    """
    points = sorted((r.run for r in asymptotic_runs(rows)), key=lambda r: r.dt)[:FIT_POINTS]
    if len({r.dt for r in points}) < 3:
        return None
    log_dt = np.log([r.dt for r in points])
    log_error = np.log([r.error or 0.0 for r in points])
    slope, intercept = np.polyfit(log_dt, log_error, 1)
    if np.max(np.abs(log_error - (slope * log_dt + intercept))) > math.log(FIT_MAX_SCATTER):
        return None
    return float(slope)


# -- the recommendation ------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Verification:
    """What a verification run of a candidate said.

    Attributes
    ----------
    passed
        it meets the tolerance (and whatever else the study checks, e.g. `springlab run`'s verdict).
    error
        its error [-] (None: it diverged).
    time_s
        its measured time [s] (NaN: not measured).
    details
        the study's own numbers of the run (e.g. the two parts of an error), kept on the recommendation.
    """

    passed: bool
    error: float | None
    time_s: float = math.nan
    details: Mapping[str, Any] = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class Recommendation(Generic[R]):
    """The cheapest setting that meets a tolerance, verified by a run of its own (`cheapest_verified`).

    Attributes
    ----------
    tolerance
        the tolerance [-] it meets.
    row
        the study's row of the chosen setting (None: no candidate passed).
    error
        the verification run's error [-] (None with row).
    verified
        whether a run of its own met the tolerance.
    time_s
        the measured time of its run [s], beside its counted cost (None with row).
    text
        the answer in words, with units (`sentence`).
    ties
        the settings within the tolerance whose counted cost equals its own (ranked after it by error).
    near
        the settings within the tolerance whose counted cost is within TIMING_NOISE of its own: measured
        times could not have told them apart.
    rejected
        cheaper candidates whose verification run failed.
    details
        the study's own numbers of the verification run.
    """

    tolerance: float
    row: R | None
    error: float | None
    verified: bool
    time_s: float | None
    text: str
    ties: tuple[Setting, ...] = ()
    near: tuple[Setting, ...] = ()
    rejected: int = 0
    details: Mapping[str, Any] = dataclasses.field(default_factory=dict)

    @property
    def found(self) -> bool:
        """Whether a verified setting meets the tolerance."""
        return self.verified and self.row is not None

    @property
    def setting(self) -> Setting | None:
        """The chosen setting (None: none)."""
        return None if self.row is None else self.row.run.setting

    @property
    def integrator(self) -> str | None:
        """The chosen integrator (None: none)."""
        return None if self.row is None else self.row.run.setting.integrator

    @property
    def dt(self) -> float | None:
        """The chosen timestep [s] (None: none)."""
        return None if self.row is None else self.row.run.setting.dt

    @property
    def cost(self) -> float | None:
        """The chosen setting's counted work [DOF-evaluations] (None: none)."""
        return None if self.row is None else self.row.run.cost

    def to_dict(self, names: Mapping[str, str] | None = None) -> dict[str, Any]:
        """{"integrator", "dt" [s], "error", "tolerance", "verified", "cost" [DOF-evaluations], "time_s" [s],
        "ties", "near" (lists of Setting.to_dict()), "rejected", "text"} and the details;
        `names` renames keys (a study keeps the names its JSON has always used)."""
        out: dict[str, Any] = {
            "integrator": self.integrator,
            "dt": self.dt,
            "error": self.error,
            "tolerance": self.tolerance,
            "verified": self.verified,
            "cost": self.cost,
            "time_s": self.time_s,
            "ties": [s.to_dict() for s in self.ties],
            "near": [s.to_dict() for s in self.near],
            "rejected": self.rejected,
            "text": self.text,
        }
        renamed = names or {}
        return {**{renamed.get(key, key): value for key, value in out.items()}, **self.details}


def cheapest_verified(
    rows: Iterable[R],
    tolerance: float,
    verify: Callable[[R], Verification],
    *,
    describe: Callable[[Setting], str] = Setting.describe,
    max_tries: int | None = None,
    budget: float | None = None,
    none_text: str = "",
    error_words: str = "error",
    prefer: Callable[[R], float] | None = None,
    tie_words: str = "less accurate or listed later in the sweep",
) -> Recommendation[R]:
    """The cheapest row within `tolerance` whose verification run passes.

    The candidates are the valid rows (`Run.valid`: never diverged or beyond a stability limit) whose error
    is at most `tolerance`, `ranked` by counted cost, then error, then the order given; each is verified in
    turn (`verify`) and the first that passes wins. No timer enters the choice: the same rows give the same
    recommendation however loaded the machine.

    Parameters
    ----------
    rows
        a study's rows (a predicted setting may be a row too: its error the prediction).
    tolerance
        the tolerance [-] on each row's error.
    verify
        runs a candidate's setting and says whether it passes (`Verification`).
    describe
        a setting in words for the sentence (default `Setting.describe`).
    max_tries
        verify at most this many candidates (None: all).
    budget
        the error [-] a row must have in the sweep to be a candidate (None: `tolerance`; a study whose
        reference carries an error of its own passes the tolerance less that error).
    none_text
        the sentence when no candidate passes (default: that no setting of the sweep meets the tolerance).
    error_words
        what the error is, in the sentence ('error', 'error bound (discretization + integration)').
    prefer
        the study's order among rows of equal counted cost, before their error (`ranked`; None: error decides).
    tie_words
        why the rows that tie in counted work rank after the pick, in the sentence.

    Returns
    -------
    Recommendation
        row None and verified False when no candidate passes.
    """
    most = tolerance if budget is None else budget
    candidates = ranked((r for r in rows if r.run.valid and r.run.error is not None and r.run.error <= most), prefer)
    rejected = 0
    for index, row in enumerate(candidates[:max_tries]):
        check = verify(row)
        if not check.passed:
            rejected += 1
            continue
        cost = row.run.cost
        later = candidates[index + 1 :]
        ties = tuple(r.run.setting for r in later if _same(r.run.cost, cost))
        near = tuple(r.run.setting for r in later if not _same(r.run.cost, cost) and r.run.cost <= cost * TIMING_NOISE)
        text = sentence(row.run, tolerance, check.error, ties, near, rejected, describe, error_words, tie_words)
        return Recommendation(
            tolerance=tolerance,
            row=row,
            error=check.error,
            verified=True,
            time_s=check.time_s if math.isfinite(check.time_s) else row.run.time_s,
            text=text,
            ties=ties,
            near=near,
            rejected=rejected,
            details=dict(check.details),
        )
    text = none_text or f"No setting of the sweep meets tol {tolerance:g}" + (
        f" ({rejected} within it in the sweep failed their verification runs)." if rejected else "."
    )
    return Recommendation(tolerance, None, None, False, None, text, rejected=rejected)


def _same(a: float, b: float) -> bool:
    return abs(a - b) <= SAME_COST * max(abs(a), abs(b))


def _listed(settings: Sequence[Setting], describe: Callable[[Setting], str], most: int = 3) -> str:
    """'a; b; c and 4 more': up to `most` settings in words."""
    shown = "; ".join(describe(s) for s in settings[:most])
    return shown + (f" and {len(settings) - most} more" if len(settings) > most else "")


def sentence(
    run: Run,
    tolerance: float,
    error: float | None,
    ties: Sequence[Setting],
    near: Sequence[Setting],
    rejected: int,
    describe: Callable[[Setting], str] = Setting.describe,
    error_words: str = "error",
    tie_words: str = "less accurate or listed later in the sweep",
) -> str:
    """The recommendation in words, with units: the setting, its steps and counted work, its verified error,
    the settings that tie with it or are within TIMING_NOISE of its counted work, the cheaper ones that failed."""
    verified = "n/a" if error is None else f"{error:.2g}"
    parts = [
        f"{describe(run.setting)} is the cheapest setting within tol {tolerance:g}: {run.steps} steps,"
        f" {run.cost:.4g} {COST_UNIT} of counted work; its verification run's {error_words} is {verified} (relative)."
    ]
    if ties:
        parts.append(f"It ties in counted work with {_listed(ties, describe)}, {tie_words}.")
    if near:
        parts.append(
            f"Within {TIMING_NOISE:g}x of its counted work: {_listed(near, describe)}; measured times could not tell"
            " them apart, so the counted work decides."
        )
    if rejected:
        parts.append(f"{rejected} cheaper candidate{'s' if rejected > 1 else ''} failed the verification run.")
    return " ".join(parts)
