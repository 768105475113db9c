"""`springlab audit MODEL`: which integrator and timestep any MuJoCo model needs, how close to blowing up
it is, and what accuracy each setting buys for its compute.

1. Linear analysis at the operating point (springlab.exact.model_at_point): modes [Hz], damping ratios, the
   physically unstable ones, the fastest.
2. Stability limits per integrator (springlab.studies.audit.limits): predicted from the modes
   (springlab.exact.predicted_limits), measured on MuJoCo's one-step map (springlab.exact.map_limits),
   confirmed by runs of the nonlinear model just below and above; the margin of the model's own timestep;
   constraint time constants shorter than 2 dt.
3. Accuracy vs cost (springlab.studies.audit.sweep): every integrator over a timestep grid from the perturbed
   operating point (springlab.exact.point_facts.start_near), batched, against the exact solution of the
   linearization (linear models) or a converged RK4 reference; observed orders, the Pareto front, and the
   cheapest setting meeting tol, verified by a run of its own.

`audit(model, ...)` checks the options (springlab.studies.audit.options), loads the model once
(springlab.studies.audit.source), then gathers the facts at the operating point in one pass below the study: the
model held there once (`ModelAtPoint`), what its modes predict, where the runs start, and what MuJoCo does there
(springlab.exact.point_facts.PointFacts: the fine run from the start, the run from the point left alone, the
one-step-map limits). The named steps that follow judge those facts and run what they call for (confirmations,
the sweep, the reference), and return an `Audit` (springlab.studies.audit.results), whose words are
springlab.studies.audit.text.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Mapping, Sequence
from types import MappingProxyType

import mujoco
import numpy as np

from springlab.errors import DivergedError
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.point_facts import PointFacts, Start, start_near
from springlab.exact.predicted_limits import Prediction, predictions
from springlab.sim.batch import Job
from springlab.sim.simulate import INTEGRATORS, Setup, Trajectory
from springlab.studies.executor import Executor
from springlab.studies.settings import (
    Recommendation,
    Run,
    Setting,
    Verification,
    beyond,
    cheapest_verified,
    counted_cost,
    observed_order,
    pareto_front,
    work_per_evaluation,
)

from .creep import creep_at
from .limits import CONFIRM_ABOVE, ConstraintFlag, Limit, RunProbe, constraint_flags, stability_limits
from .options import DEFAULT_PERTURB, DEFAULT_TOL, Options, check_options, resolve_duration
from .parts import Excitation, Linearity, OwnSetting, PointReport, ReferenceUsed, Timings
from .results import Audit
from .ship import Runner, ship
from .source import Source, load
from .start import REST_FRACTION, check_perturbation, excitation, point_report, rest_within
from .sweep import (
    MAX_SAMPLES,
    REFERENCE_FRACTION,
    ExactReference,
    Reference,
    checkpoint_spacing,
    converged_reference,
    cost_per_step,
    grid_for,
    linearity_change,
    linearity_tolerance,
    reference_step,
    run_error,
    sweep_runs,
)
from .text import NO_MOTION, NO_PICK

#: a recommended timestep keeps this fraction of its integrator's measured stability limit
RECOMMEND_LIMIT_FRACTION = 0.9
_NAMES = {value: name for name, value in INTEGRATORS.items()}


def audit(
    model: mujoco.MjModel | str | os.PathLike[str],
    *,
    keyframe: str | int | None = None,
    settle_s: float | None = None,
    tol: float = DEFAULT_TOL,
    integrators: Sequence[str] | None = None,
    dts: Sequence[float] | None = None,
    duration: float | None = None,
    perturb: float = DEFAULT_PERTURB,
    nthread: int = 0,
    executor: Executor | None = None,
) -> Audit:
    """Audit a model: modes, stability limits, accuracy vs cost, and the cheapest setting meeting `tol`.

    Parameters
    ----------
    model
        an MjModel, a path to an MJCF (or URDF MuJoCo loads), or a shipped scene name.
    keyframe
        operating point, keyframe name or index (default: the first keyframe, else qpos0 at rest).
    settle_s
        let the model move from there for this long [s] (its own integrator and timestep, controls held)
        and audit it where it comes to rest, or to its steady contact state (None: no settling).
    tol
        tolerance on the error of springlab.studies.audit.sweep [-], in (0, 1).
    integrators
        names to sweep, e.g. ["rk4", "euler"] (default: all five).
    dts
        timesteps [s] to sweep, e.g. [2e-3, 1e-3] (default: a 12-point grid over up to 3 decades below 1.2x
        the largest confirmed stability limit, whose top is a multiple of the model's own timestep); they
        must share at least 10 common multiples within the duration (timesteps that divide the largest do).
    duration
        simulated time of every run [s] (default 1 s; a scene: its scenario's).
    perturb
        size of the start's perturbation of the operating point [m or rad]; velocities get perturb /
        duration [m/s or rad/s], controls perturb x their half range (springlab.studies.audit.start).
    nthread
        threads of the batched runs (0: one per CPU) when no executor is given.
    executor
        where the simulations run (the limit confirmations and brute-force runs, the sweep, the RK4
        reference's levels; springlab.studies.audit.ship): None or a local Executor, this process as always;
        `Executor(workers=N)` or `Executor(scheduler=ADDRESS)`, dask workers, which rebuild the model from
        its file's text and named files (or a scene by name; an MjModel passed in memory cannot be sent:
        BadInputError). The numbers are identical either way; linearization, timings and the
        verification run stay here.

    Returns
    -------
    The Audit.

    Raises
    ------
    BadInputError
        bad input, before anything is computed: no such model file or scene, a model MuJoCo cannot compile,
        an option out of range, or the command line's string where a sequence is asked (`dts="1e-3,2e-3"`).
    UnknownNameError
        an unknown integrator (an unknown keyframe is a BadInputError listing the valid ones).

    Examples
    --------
    >>> import springlab
    >>> result = springlab.audit("slider", integrators=["rk4", "euler"], dts=[0.02, 0.01, 0.005])
    >>> result.recommendation.integrator, result.own.stable
    ('rk4', True)
    """
    clock = _Clock()
    options = check_options(tol=tol, perturb=perturb, settle_s=settle_s, integrators=integrators, dts=dts)
    source = load(model)
    runs_for = resolve_duration(duration, source.duration)
    check_perturbation(source.model, options.perturb)
    run = _runner(source, executor, nthread)
    # the facts first: the point, what its modes predict, where runs start, what MuJoCo does there (one pass)
    at = ModelAtPoint.at(source.model, keyframe, settle_s=options.settle_s)
    names = list(dict.fromkeys([*options.integrators, _NAMES[int(at.model.opt.integrator)]]))
    predicted = predictions(at, names)
    start = start_near(at, options.perturb, runs_for, source.start)
    facts = PointFacts.measure(
        at,
        start.setup,
        runs_for,
        guesses={name: prediction.limit_s for name, prediction in predicted.items()},
        above=CONFIRM_ABOVE,
        rest_within=rest_within(options.perturb),
    )
    # then the verdicts on them, and the runs they call for
    limits = _limits(at, start, options, facts, predicted, runs_for, run)
    clock.stamp("limits")
    swept = _sweep(at, start.setup, options, limits.limits, runs_for, run)
    clock.stamp("sweep")
    judged = _reference(at, start, options, limits.point_state, swept, run)
    clock.stamp("reference")
    scored = _score(at, start, options, limits, swept, judged, run)
    clock.stamp("end")
    return Audit(
        model=source.label,
        linear=at.linear,
        start=start.setup,
        duration=swept.duration,
        tol=options.tol,
        perturb=options.perturb,
        stability=MappingProxyType(limits.limits),
        own=scored.own,
        constraints=limits.flags,
        is_linear=judged.is_linear,
        linearity=judged.linearity,
        reference=judged.used,
        runs=scored.runs,
        orders=MappingProxyType(scored.orders),
        pareto=scored.pareto,
        recommendation=scored.recommendation,
        timings=clock.timings(),
        point_state=limits.point_state,
        excitation=judged.excitation,
    )


class _Clock:
    """Wall time of the audit's stages [s]: `stamp(name)` at the end of each."""

    def __init__(self) -> None:
        self.stamps = {"start": time.perf_counter()}

    def stamp(self, name: str) -> None:
        self.stamps[name] = time.perf_counter()

    def timings(self) -> Timings:
        at = self.stamps
        return Timings(
            linearization_and_limits_s=at["limits"] - at["start"],
            sweep_s=at["sweep"] - at["limits"],
            reference_s=at["reference"] - at["sweep"],
            total_s=at["end"] - at["start"],
        )


def _runner(source: Source, executor: Executor | None, nthread: int) -> Runner:
    """Where the runs go: this process, or dask workers that rebuild the model from `ship`'s payload."""
    distributed = executor is not None and executor.distributed
    run = Runner(executor, ship(source.origin, source.model) if distributed else None, nthread)
    if distributed:
        assert executor is not None  # distributed implies an executor
        _ = executor.client  # an unreachable scheduler is exit 2 now, not after the limit scan
    return run


@dataclasses.dataclass(frozen=True)
class _Limits:
    """Step 2's findings: the stability limits, the operating point's state, and how brute-force runs start."""

    limits: dict[str, Limit]
    point_state: PointReport
    probe: RunProbe
    flags: tuple[ConstraintFlag, ...]


def _limits(
    at: ModelAtPoint,
    start: Start,
    options: Options,
    facts: PointFacts,
    predicted: Mapping[str, Prediction],
    duration: float,
    run: Runner,
) -> _Limits:
    """Step 2: the constraint settings the model's own timestep breaks; the operating point's state (what is
    active there and along the fine run from the start, its creep); then every swept integrator's and the model's
    own integrator's stability limit (`limits.stability_limits`: the map's, confirmed by runs, or runs')."""
    model = at.model
    flags = tuple(constraint_flags(model, float(model.opt.timestep)))
    point_state = point_report(at, facts, options.settle_s, options.perturb)
    if not point_state.at_rest:  # what keeps it moving: creep under dry friction, or motion that dies out
        creep, helps = creep_at(at, facts.rest, duration, REST_FRACTION * options.perturb)
        point_state = dataclasses.replace(point_state, creep=creep, settling_helps=helps)
    qvel = start.setup.qvel
    start_speed = float(abs(qvel).max(initial=0.0)) if qvel is not None else 0.0
    gravity = float(math.hypot(*model.opt.gravity))
    probe = RunProbe(start.setup, duration, max(facts.watch.peak_speed, start_speed), gravity, duration / 10)
    limits = stability_limits(at, predicted, facts.maps, run=run, probe=probe)
    return _Limits(limits, point_state, probe, flags)


@dataclasses.dataclass(frozen=True)
class _Swept:
    """Step 3's runs: (integrator, dt) -> Trajectory or DivergedError, on a grid that shares checkpoints."""

    outcomes: dict[tuple[str, float], Trajectory | DivergedError]
    dts: tuple[float, ...]
    spacing: float
    duration: float

    @property
    def probe(self) -> Trajectory | DivergedError:
        """The finest RK4 run: the linearity probe, the excitation's witness and the reference's coarsest level."""
        return self.outcomes[("rk4", min(self.dts))]


def _sweep(
    at: ModelAtPoint, start: Setup, options: Options, limits: Mapping[str, Limit], duration: float, run: Runner
) -> _Swept:
    """Step 3: every integrator over the grid (given, or `sweep.grid_for` the limits), plus the model's own
    setting and RK4 at the finest timestep, batched; every run ends on a common checkpoint."""
    own = (_NAMES[int(at.model.opt.integrator)], float(at.model.opt.timestep))
    dts = list(options.dts) if options.dts is not None else grid_for(limits, duration, own[1])
    spacing = checkpoint_spacing(dts, duration)
    run_duration = spacing * math.floor(duration / spacing * (1 + 1e-12))  # every run ends on a common time
    extra = [own, ("rk4", min(dts))]  # the own setting; the linearity probe and coarsest reference
    outcomes = sweep_runs(at.model, start, list(options.integrators), dts, run_duration, extra=extra, run=run)
    return _Swept(outcomes, tuple(dts), spacing, run_duration)


@dataclasses.dataclass(frozen=True)
class _Judged:
    """Step 4's verdicts: what the start moved, whether the motion is linear, and the reference."""

    excitation: Excitation
    linearity: Linearity
    is_linear: bool
    reference: Reference
    used: ReferenceUsed


def _reference(
    at: ModelAtPoint, start: Start, options: Options, point_state: PointReport, swept: _Swept, run: Runner
) -> _Judged:
    """Step 4: the excitation and linearity verdicts from the finest RK4 run, then the reference: the exact
    solution of the linearization where the motion is linear and unconstrained, else a converged RK4 run."""
    probe = swept.probe
    moved = excitation(at.model, start, probe, options.perturb, swept.duration)
    change = math.inf if isinstance(probe, DivergedError) else linearity_change(at, probe)
    threshold = linearity_tolerance(at.linear, options.tol, swept.duration)
    is_linear = change <= threshold and point_state.linear_map  # with constraints active: no linear reference
    reference: Reference
    if is_linear:
        reference = ExactReference(at, start.setup)
    else:
        step = reference_step(list(swept.dts), swept.spacing)
        coarse = probe if isinstance(probe, Trajectory) else None
        reference = converged_reference(at, start.setup, step, swept.duration, options.tol, coarse=coarse, run=run)
    used = _reference_used(reference, options.tol, swept.spacing)
    return _Judged(moved, Linearity(change, threshold), is_linear, reference, used)


def _reference_used(reference: Reference, tol: float, spacing: float) -> ReferenceUsed:
    """What audit.json says of the reference."""
    return ReferenceUsed(
        kind=reference.kind,
        error_estimate=reference.error_estimate,
        dt=reference.dt,
        converged=reference.error_estimate <= REFERENCE_FRACTION * tol,
        compared_at=f"every step of each run (every k-th for at most {MAX_SAMPLES})",
        common_time_spacing_s=spacing,
    )


@dataclasses.dataclass(frozen=True)
class _Scored:
    """Step 5's scores: every run's error and cost, the orders, the own setting, the recommendation."""

    runs: tuple[Run, ...]
    orders: dict[str, float | None]
    own: OwnSetting
    pareto: tuple[Run, ...]
    recommendation: Recommendation[Run]


def _score(
    at: ModelAtPoint, start: Start, options: Options, limits: _Limits, swept: _Swept, judged: _Judged, run: Runner
) -> _Scored:
    """Step 5: each run's error against the reference, its counted cost (springlab.studies.settings: what ranks)
    and its measured time (steps x the integrator's measured time per step: reported beside), the observed
    orders, the own setting's verdict, and the cheapest verified setting meeting tol."""
    model, reference = at.model, judged.reference
    own_name, own_dt = _NAMES[int(model.opt.integrator)], float(model.opt.timestep)
    names, dts = options.integrators, swept.dts
    middle = sorted(dts)[len(dts) // 2]
    per_step = {name: cost_per_step(model, start.setup, name, middle) for name in dict.fromkeys([*names, own_name])}
    work = work_per_evaluation(model)
    # timestep by timestep: the integrators' runs at one dt share the reference's samples (Reference.sampled)
    errors = {(name, dt): run_error(at, swept.outcomes[(name, dt)], reference) for dt in dts for name in names}
    runs = []
    for name in names:
        confirmed = limits.limits[name].confirmed_limit_s  # only a confirmed limit makes a run beyond it
        for dt in dts:
            error = errors[(name, dt)]
            steps = round(swept.duration / dt)
            setting = Setting(name, dt)
            cost = counted_cost(name, steps, work)
            runs.append(Run(setting, steps, error, cost, per_step[name] * steps, error is None, beyond(dt, confirmed)))
    orders = {name: _order([r for r in runs if r.integrator == name], reference.error_estimate) for name in names}
    own_outcome = swept.outcomes[(own_name, own_dt)]
    own_limit = limits.limits[own_name]
    own_steps = round(swept.duration / own_dt)
    behaviour, growth = _behaviour(at, own_limit, own_dt, own_outcome, limits.probe, run)
    own = OwnSetting(
        integrator=own_name,
        dt=own_dt,
        stable=behaviour == "stable",
        error=run_error(at, own_outcome, reference),
        margin=own_limit.margin,
        wall_time_s=per_step[own_name] * own_steps,
        margin_confirmed=None if own_limit.limit_dt_s is None else bool(own_limit.confirmed),
        cost=counted_cost(own_name, own_steps, work),
        behaviour=behaviour,
        growth=growth,
    )
    front = tuple(pareto_front(runs))
    if judged.excitation.any_motion:
        recommendation = _recommend(at, start.setup, runs, limits.limits, options.tol, swept.duration, reference)
    else:  # every setting reproduces a model that does not move: nothing to verify
        recommendation = Recommendation(options.tol, None, None, False, None, NO_MOTION)
    return _Scored(tuple(runs), orders, own, front, recommendation)


#: past a confirmed limit, a run "grew" when its largest deviation from the operating point reached this many
#: times its start's ...
GROWN = 10.0
#: ... and it "saturates" (rather than "grows") when its second half reaches at most this many times its first
#: half's largest deviation
LEVELLED = 2.0


def _behaviour(
    at: ModelAtPoint,
    limit: Limit,
    own_dt: float,
    own_outcome: Trajectory | DivergedError,
    probe: RunProbe,
    run: Runner,
) -> tuple[str, float | None]:
    """What runs of the own setting show, in one word (parts.BEHAVIOURS), and the growth of its brute-force run.

    Below a confirmed limit (or with none): "stable" unless a run blows up (the brute force's bracket when the
    limit came from runs). At or past a confirmed limit never "stable": a brute-force run from the audit's start
    says which of "blows up", "spins", "saturates", "grows" or "bounded" it is (`_shown_by`). An unconfirmed
    figure alone never decides."""
    if isinstance(own_outcome, DivergedError):
        return "blows up", None
    if limit.method == "nonlinear runs":
        bounded = limit.runs_bounded_dt_s
        return ("blows up" if bounded is None or bounded < own_dt else "stable"), None
    confirmed = limit.confirmed_limit_s
    if confirmed is None or own_dt < confirmed:
        return "stable", None
    outcome = run([Job(at.model, limit.integrator, own_dt, probe.steps(own_dt), probe.start)])[0]
    if probe.blew_up(outcome, own_dt) or isinstance(outcome, DivergedError):
        return "blows up", None
    return _shown_by(at, outcome)


def _shown_by(at: ModelAtPoint, trajectory: Trajectory) -> tuple[str, float]:
    """A bounded run past a confirmed limit in one word: "spins" (a hinge more than a turn from the point),
    "saturates" (its deviation from the point grew GROWN-fold and its second half stays within LEVELLED x its
    first half's), "grows" (grew, still growing) or "bounded" (did not grow GROWN-fold); and the growth [-]."""
    model, point = at.model, at.point
    rows = np.unique(np.linspace(0, len(trajectory.time) - 1, min(len(trajectory.time), 2000)).astype(int))
    deviation = np.zeros((len(rows), model.nv))
    for k, row in enumerate(rows):
        mujoco.mj_differentiatePos(model, deviation[k], 1.0, point.qpos, trajectory.qpos[row])
    size = np.max(np.abs(deviation), axis=1)
    growth = float(size.max() / max(size[0], 1e-300))
    hinges = [int(model.jnt_dofadr[j]) for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]
    if hinges and float(np.max(np.abs(deviation[:, hinges]))) > 2 * math.pi:
        return "spins", growth
    if growth < GROWN:
        return "bounded", growth
    half = len(size) // 2
    return ("saturates" if size[half:].max() <= LEVELLED * size[:half].max() else "grows"), growth


def _order(runs: list[Run], reference_error: float) -> float | None:
    """springlab.studies.settings' observed order over the runs clear of the error floor.

    The floor: the reference's own error estimate, or where the errors stop falling at the fine end (from
    the finest run, coarser runs whose error is not at least sqrt(dt ratio) above the next finer one's: a
    first-order method rises by the full ratio). Runs within 10x the floor are left out: there the
    reference or round-off, not the integrator, sets the error.
    """
    # (dt [s], error [-]) of the runs with an error, finest first
    finest_first = sorted(((r.dt, r.error) for r in runs if r.error is not None and r.error > 0), key=lambda p: p[0])
    floor = reference_error
    for (finer_dt, finer_error), (coarser_dt, coarser_error) in zip(finest_first, finest_first[1:]):
        if coarser_error > finer_error * math.sqrt(coarser_dt / finer_dt):
            break
        floor = max(floor, finer_error, coarser_error)
    return observed_order([r for r in runs if r.error is None or r.error > 10 * floor])


def _recommend(
    at: ModelAtPoint,
    start: Setup,
    runs: list[Run],
    limits: Mapping[str, Limit],
    tol: float,
    duration: float,
    reference: Reference,
) -> Recommendation[Run]:
    """springlab.studies.settings.cheapest_verified over the swept settings within RECOMMEND_LIMIT_FRACTION of
    their integrator's stability limit: ranked by counted work (no timer: the same audit gives the same pick),
    each verified by a run of its own (springlab.sim.simulate, not the batch). Meeting tol means error + the
    reference's own error estimate <= tol, so a reference that did not fully converge cannot pass a setting
    that misses tol."""
    budget = tol - reference.error_estimate

    def inside(row: Run) -> bool:
        limit = limits[row.integrator].limit_dt_s
        return limit is None or row.dt <= RECOMMEND_LIMIT_FRACTION * limit

    def verify(row: Run) -> Verification:
        try:
            trajectory = at.simulate(row.integrator, row.dt, duration, start)
        except DivergedError:
            return Verification(False, None)
        error = run_error(at, trajectory, reference)
        return Verification(error is not None and error <= budget, error)

    return cheapest_verified(
        [r for r in runs if inside(r)],
        tol,
        verify,
        budget=budget,
        none_text=NO_PICK.format(tol=tol),
    )
