"""Error against cost of a model file: every integrator over a timestep grid against a converged run of the same
model, and the cheapest setting that meets a tolerance.

`springlab tradeoff gripper.xml --tol 1e-3` runs the model from its keyframe (as `springlab run MODEL.xml` does:
the keyframe's controls held, no perturbation) at each integrator and timestep, and measures each run against
a *converged reference of the same model*: MuJoCo's RK4 at a much smaller timestep, halved until its
Richardson error estimate is a hundredth of the tolerance (the audit's reference,
springlab.studies.audit.sweep.converged_reference; the error measure is the audit's too, `run_error`: the
largest position and velocity error relative to the motion's own size). A scene's trade-off measures against
its exact solution; a model file has none, so this error is the *integration* error only: the reference has
MuJoCo's soft contacts, regularised friction and every other model approximation built in, and cannot see
them. Every output says so (`reference.note`, the text's second line).

The ranking is the settings kernel's (springlab.studies.settings): counted work, the Pareto front, observed
orders, and `cheapest_verified`, whose verification is a run of its own on `springlab run MODEL.xml`'s path
(springlab.sim.simulate) against the same reference, with the reference's own estimated error added.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time as _time
from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np

from springlab import display
from springlab.answer import Answer
from springlab.errors import BadInputError, DivergedError
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.operating_point import operating_point
from springlab.files import Output, json_ready
from springlab.runs import compare
from springlab.runs.model_run import DEFAULT_DURATION, integrator_name
from springlab.sim import model_files
from springlab.sim.simulate import INTEGRATORS, Setup, Trajectory, check_timing, integrator_id, simulate

from . import answers
from .audit.ship import Runner, ship
from .audit.sweep import (
    MIN_CHECKPOINTS,
    REFERENCE_FRACTION,
    Reference,
    checkpoint_spacing,
    converged_reference,
    default_grid,
    reference_step,
    run_error,
    sweep_runs,
)
from .executor import Executor
from .settings import (
    COST_BASIS,
    Recommendation,
    Run,
    Setting,
    Verification,
    cheapest_verified,
    counted_cost,
    observed_order,
    pareto_front,
    work_per_evaluation,
)

#: the tolerance the reference converges for when none is asked [-]
DEFAULT_TOL = 1e-3
#: the default grid: this many timesteps over this many decades, the largest this multiple of the model's own
GRID_POINTS = 8
GRID_DECADES = 2.0
GRID_TOP_OVER_OWN = 4.0
#: what the error is measured against, in words (text and JSON)
REFERENCE_NOTE = (
    "error against a converged run of the same model (RK4 at a much smaller dt): integration error only;"
    " MuJoCo's own model error (soft contacts, regularised friction, constraint softness) is in the reference"
    " too and invisible to it"
)


@dataclasses.dataclass(frozen=True, repr=False)
class ModelTradeoff(display.Shown):
    """A model file's error against cost over integrators and timesteps, against a converged run of itself.

    Attributes
    ----------
    model
        the model file as given.
    start
        where every run starts (a keyframe, or qpos0 at rest).
    duration
        simulated time of every run [s].
    reference
        the converged RK4 run every error is measured against: `kind`, `dt` [s], `error_estimate` [-].
    converged
        whether the reference's own error estimate reached REFERENCE_FRACTION x the tolerance.
    runs
        one `Run` per integrator and timestep of the grid (error [-] against the reference).
    own
        the run at the model's own integrator and timestep.
    pareto
        the runs no other beats in both counted work and error.
    orders
        integrator -> observed order of its error in dt (None: too few runs in the asymptotic range).
    tolerance
        the tolerance [-] asked (None: no recommendation asked).
    recommendation
        the cheapest verified setting meeting `tolerance` (None without one).
    wall_time_s
        wall time of the whole study [s].
    executor
        where the runs ran.
    moves
        whether the reference moves at all from the start (False: a model at rest there; every error is then
        round-off and nothing was measured).
    """

    model: str
    start: str
    duration: float
    reference: Reference
    converged: bool
    runs: tuple[Run, ...]
    own: Run
    pareto: tuple[Run, ...]
    orders: dict[str, float | None]
    tolerance: float | None
    recommendation: Recommendation[Run] | None
    wall_time_s: float
    executor: str
    moves: bool = True

    @property
    def question_answer(self) -> Answer:
        """The question and its answer: the pick (or the own setting's error), against what it is measured."""
        say = answers.Quoter()
        question = (
            f"Which integrator and timestep reproduce {self.model} from {self.start} over"
            f" {answers.written(self.duration, '~s')}"
            + (f" within tol {self.tolerance:g}" if self.tolerance is not None else "")
            + ", measured against a converged run of the same model?"
        )
        own = self.own
        mine = f"Your setting, {own.integrator} at {say.dt('own_dt_s', own.dt)}, " + (
            "diverges" if own.error is None else f"has error {say('own_error', own.error)}"
        )
        pick = self.recommendation
        if pick is None:
            chosen = ""
        elif pick.found and pick.integrator is not None and pick.dt is not None and pick.error is not None:
            chosen = (
                f"; the cheapest within tol is {pick.integrator} at {say.dt('pick_dt_s', pick.dt)}, error"
                f" {say('pick_error', pick.error)} (verified by a run)"
            )
        else:
            chosen = "; no setting of the sweep meets tol"
        basis = "" if self.converged else " The reference did NOT converge: errors near its own are not resolved."
        if not self.moves:
            basis += f" The model does not move from {self.start}: nothing was measured (give a keyframe that moves)."
        return say.answer(
            question,
            f"{mine}{chosen}. This is integration error only: MuJoCo's model error (soft contacts, regularised"
            f" friction) is in the reference too and invisible to it.{basis}",
        )

    def to_dict(self) -> dict[str, Any]:
        """tradeoff.json of a model file (what `springlab tradeoff MODEL.xml --json` prints; docs/json.md)."""
        return json_ready(
            {
                **self.question_answer.to_dict(),
                "model": self.model,
                "start": self.start,
                "duration": self.duration,
                "reference": {
                    "kind": self.reference.kind,
                    "integrator": "rk4",
                    "dt": self.reference.dt,
                    "error_estimate": self.reference.error_estimate,
                    "converged": self.converged,
                    "note": REFERENCE_NOTE,
                },
                "moves": self.moves,
                "error_measure": "max over the run of |q - q_ref| / max |q_ref - q(0)| and |v - v_ref| / max |v_ref|"
                " (positions in the tangent space), the larger",
                "own_setting": self.own.to_dict(),
                "runs": [run.to_dict() for run in self.runs],
                "pareto": [run.to_dict() for run in self.pareto],
                "orders": dict(self.orders),
                "tolerance": self.tolerance,
                "recommendation": None if self.recommendation is None else self.recommendation.to_dict(),
                "cost_basis": COST_BASIS,
                "wall_time_s": self.wall_time_s,
                "executor": self.executor,
            }
        )

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab tradeoff MODEL.xml --output DIR` writes (springlab.outputs.write): tradeoff.json,
        tradeoff.png."""
        return Output.json("tradeoff.json", self.to_dict()), Output("tradeoff.png")

    def _shown(self) -> display.Summary:
        """The study as a notebook shows it: the reference, the own setting, the pick."""
        pick = self.recommendation
        return display.Summary(
            "ModelTradeoff",
            f"{self.model} from {self.start}",
            "not validated" if pick is None else ("meets tol" if pick.found else "no setting meets tol"),
            None if pick is None else pick.found,
            REFERENCE_NOTE,
            (
                display.Fact("runs", len(self.runs)),
                display.Fact("reference dt", self.reference.dt, "s"),
                display.Fact("reference error estimate", self.reference.error_estimate),
                display.Fact("own setting", f"{self.own.integrator} at {self.own.dt:g} s"),
                display.Fact("own error", self.own.error),
                display.Fact("wall time", self.wall_time_s, "s"),
            ),
        )


def _run(
    setting: Setting, outcome: Trajectory | DivergedError, at: ModelAtPoint, reference: Reference, work: float
) -> Run:
    """The kernel's Run of one outcome: its error against the reference and its counted work."""
    if isinstance(outcome, DivergedError):
        return Run(setting, 0, None, math.inf, diverged=True, detail=str(outcome))
    steps = len(outcome.time) - 1
    return Run(setting, steps, run_error(at, outcome, reference), counted_cost(setting.integrator, steps, work))


def model_tradeoff(
    model: str | os.PathLike[str],
    *,
    keyframe: str | int | None = None,
    tol: float | None = None,
    duration: float | None = None,
    integrators: Sequence[str] | None = None,
    dts: Sequence[float] | None = None,
    executor: Executor | None = None,
) -> ModelTradeoff:
    """Every integrator over a timestep grid on a model file, against a converged run of the same model.

    Parameters
    ----------
    model
        the path of an MJCF (or URDF MuJoCo loads) file.
    keyframe
        where every run starts (None: the first keyframe, else qpos0 at rest); its controls are held.
    tol
        recommend the cheapest setting whose error is within this [-] (None: no recommendation; the
        reference converges for DEFAULT_TOL).
    duration
        simulated time of every run [s] (None: 1 s).
    integrators
        the integrators to sweep (None: all five).
    dts
        the timesteps [s] (None: GRID_POINTS from GRID_TOP_OVER_OWN x the model's own over GRID_DECADES, each the
        largest divided by a small whole number so that every run shares the reference's steps).
    executor
        where the runs go (None: locally, one batch).

    Returns
    -------
    ModelTradeoff
        runs, front, orders and the recommendation, every error labelled as against the same model.

    Raises
    ------
    BadInputError
        no such file or keyframe, a bad tol, duration, integrator or timestep, or a reference that cannot converge.
    """
    started = _time.perf_counter()
    text = os.fspath(model)
    mj_model = model_files.load(text)
    point = operating_point(mj_model, keyframe)
    if tol is not None and not (compare.check_tolerance(tol) < 1.0):
        raise BadInputError(f"tol must be in (0, 1) (a relative error), got {tol!r}")
    duration = DEFAULT_DURATION if duration is None else duration
    own = Setting(integrator_name(mj_model), float(mj_model.opt.timestep))
    check_timing(own.dt, duration)
    names = list(dict.fromkeys(integrators)) if integrators else list(INTEGRATORS)
    for name in names:
        integrator_id(name)
    grid = sorted({float(d) for d in dts}, reverse=True) if dts else _default_grid(own.dt, duration)
    for dt in grid:
        check_timing(dt, duration)
    spacing = checkpoint_spacing([*grid, own.dt], duration)
    start = Setup(qpos=point.qpos, qvel=point.qvel, act=point.act, control=point.ctrl if mj_model.nu else None)
    at = ModelAtPoint(mj_model, point)
    runner = Runner(executor, ship(("path", text), mj_model) if executor is not None and executor.distributed else None)
    outcomes = sweep_runs(mj_model, start, names, grid, duration, extra=[(own.integrator, own.dt)], run=runner)
    step = reference_step([*grid, own.dt], spacing)
    finest = outcomes.get(("rk4", 2 * step))
    coarse = finest if isinstance(finest, Trajectory) else None
    reference = converged_reference(at, start, step, duration, tol or DEFAULT_TOL, coarse=coarse, run=runner)
    work = work_per_evaluation(mj_model)
    by_setting = {s: _run(Setting(*s), o, at, reference, work) for s, o in outcomes.items()}
    runs = tuple(by_setting[(name, dt)] for name in names for dt in grid)
    own_run = by_setting[(own.integrator, own.dt)]
    orders = {name: observed_order([r for r in runs if r.integrator == name]) for name in names}
    recommendation = None
    if tol is not None:
        recommendation = cheapest_verified(
            runs,
            tol,
            lambda row: _verify(mj_model, start, row, duration, at, reference, tol),
            budget=tol - reference.error_estimate,
            error_words="error against the converged run of the same model",
        )
    return ModelTradeoff(
        model=text,
        start=point.label,
        duration=float(duration),
        reference=reference,
        converged=reference.error_estimate <= REFERENCE_FRACTION * (tol or DEFAULT_TOL),
        runs=runs,
        own=own_run,
        pareto=tuple(pareto_front(runs)),
        orders=orders,
        tolerance=tol,
        recommendation=recommendation,
        wall_time_s=_time.perf_counter() - started,
        executor="local" if executor is None else executor.describe(),
        moves=_moves(reference),
    )


def _moves(reference: Reference) -> bool:
    """Whether a converged reference moves at all from its start (positions or velocities change)."""
    trajectory = getattr(reference, "trajectory", None)
    if trajectory is None:
        return True
    return bool(np.any(trajectory.qpos != trajectory.qpos[0]) or np.any(trajectory.qvel != trajectory.qvel[0]))


def _default_grid(own_dt: float, duration: float) -> list[float]:
    """GRID_POINTS timesteps [s] from GRID_TOP_OVER_OWN x own_dt (at most duration / MIN_CHECKPOINTS) down."""
    top = min(GRID_TOP_OVER_OWN * own_dt, duration / MIN_CHECKPOINTS)
    return default_grid(top, GRID_POINTS, GRID_DECADES)


def _verify(
    model: mujoco.MjModel, start: Setup, row: Run, duration: float, at: ModelAtPoint, reference: Reference, tol: float
) -> Verification:
    """A candidate run again on `springlab run MODEL.xml`'s path (sim.simulate, not batched), against the same
    reference: it passes when its error plus the reference's own estimated error is within `tol`."""
    try:
        outcome: Trajectory | DivergedError = simulate(
            model,
            integrator=row.integrator,
            dt=row.dt,
            duration=duration,
            qpos=start.qpos,
            qvel=start.qvel,
            act=start.act,
            control=start.control,
        )
    except DivergedError as diverged:
        outcome = diverged
    measured = run_error(at, outcome, reference)
    return Verification(measured is not None and measured + reference.error_estimate <= tol, measured)
