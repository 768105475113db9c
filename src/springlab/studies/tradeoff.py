"""What accuracy each integrator buys for how much compute: the speed-accuracy sweep.

Every integrator x a log-spaced range of timesteps on one scenario, run
batched (`batch.run_batched`, one simulation per (integrator, dt),
bit-identical to a plain loop). For every run: the max relative error against
the scene's exact reference (computed exactly as `springlab run` computes it),
the steps and the wall time (`batch.time_run`: the run alone, see
springlab.sim.batch); per integrator the observed order of accuracy (the fitted
slope of log error vs log dt over the asymptotic range); the Pareto front of
error vs cost; and for a tolerance the cheapest (integrator, dt) that meets
it, verified by running it (`recommend`; springlab.studies.auto builds
`integrator='auto'` on it).
"""

from __future__ import annotations

import dataclasses
import math
import time as _time
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab import display, scenes, tables
from springlab.answer import Answer
from springlab.errors import BadInputError, DivergedError
from springlab.files import Output, json_ready
from springlab.runs import compare
from springlab.runs.compare import Verdict
from springlab.runs.run import evaluate, run_scenario
from springlab.scenes.base import Case, Scenario, Scene
from springlab.scenes.declarations import keyword_parameters, refuse_text
from springlab.sim.batch import TIMING_STEPS, run_batched, time_run
from springlab.sim.simulate import INTEGRATORS, ORDERS, Setup, check_timing, integrator_id

from . import answers
from .executor import Executor, chunked
from .settings import (
    COST_BASIS,
    COST_UNIT,
    Recommendation,
    Run,
    RunFields,
    Setting,
    Verification,
    beyond,
    cheapest_verified,
    counted_cost,
    limit_dt,
    observed_order,
    pareto_front,
    work_per_evaluation,
)

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure

#: the sweep spans omega_max*dt from SWEEP_TOP down by SWEEP_DECADES decades
SWEEP_TOP = 1.0
SWEEP_DECADES = 3.0
#: timesteps in the default sweep (>= 12 by contract)
SWEEP_POINTS = 13
#: (integrator, dt) runs per chunk of the grid (one batched call each)
CHUNK_RUNS = 16
#: most steps one sweep run may take; the smallest dt is raised to respect it
MAX_SWEEP_STEPS = 200_000
#: a refined timestep for a tolerance is predicted with this margin, then verified by running it
REFINE_SAFETY = 0.9

WALL_TIME_BASIS = (
    "each configuration run alone on one thread as `springlab run` steps it (one mujoco.rollout call),"
    f" best of 3; runs over {TIMING_STEPS} steps timed on their first {TIMING_STEPS} steps and scaled by steps"
)


# -- the sweep -----------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class TradeoffRun(RunFields):
    """One (integrator, dt) of the sweep: the shared row (`run`: setting, steps, error, counted cost,
    measured wall time, diverged, beyond the stability limit) and what `springlab run` says of it.

    Attributes
    ----------
    run
        the shared row (springlab.studies.settings.Run): its error is max_rel_error.
    verdict
        what `springlab run` says of the same setting (a springlab.runs.compare.Verdict: PASS,
        FAIL or NOT_VALIDATED); None if diverged or not run (a predicted setting).
    """

    run: Run
    verdict: Verdict | None = None

    @property
    def max_rel_error(self) -> float | None:
        """max over the compared columns of max |sim - ref| / max |ref| [-]; None if diverged."""
        return self.run.error

    @property
    def wall_time_s(self) -> float:
        """Wall time of the run alone [s] (WALL_TIME_BASIS), reported beside its counted cost."""
        return self.run.time_s

    @property
    def error(self) -> float:
        """max_rel_error of a run that did not diverge [-] (filter out diverged runs first)."""
        if self.run.error is None:
            raise ValueError(f"{self.integrator} at dt = {self.dt:g} s diverged: it has no error")
        return self.run.error

    @property
    def validated(self) -> bool:
        """Whether the run is inside the range of its error estimate (its verdict means something)."""
        return self.verdict in (Verdict.PASS, Verdict.FAIL)

    def to_dict(self) -> dict[str, Any]:
        """The JSON row: integrator, dt [s], max_rel_error [-], steps, wall_time_s [s], cost [DOF-evaluations],
        diverged, beyond_limit, verdict."""
        return {
            "integrator": self.integrator,
            "dt": self.dt,
            "max_rel_error": self.max_rel_error,
            "steps": self.steps,
            "wall_time_s": self.wall_time_s,
            "cost": self.cost,
            "diverged": self.diverged,
            "beyond_limit": self.beyond_limit,
            "verdict": None if self.verdict is None else str(self.verdict),
        }


#: tradeoff.json's names for the recommendation's keys (the names it has always had)
RECOMMENDATION_NAMES = {"tolerance": "tol", "error": "max_rel_error", "time_s": "wall_time_s"}


@dataclasses.dataclass(frozen=True, repr=False)
class Tradeoff(display.Shown):
    """A speed-accuracy sweep of one scenario.

    `to_dict()` is tradeoff.json (what `springlab tradeoff --json` prints), `to_pandas()` one
    row per run.

    Attributes
    ----------
    scene, scenario
        names.
    parameters
        the parameter values used (SI).
    overrides
        the parameters the caller set (re-applied when verifying a recommendation).
    duration
        simulated time of every run [s].
    runs
        every (integrator, dt), grouped by integrator, dt descending.
    orders
        integrator -> observed order of accuracy (None: too few asymptotic points).
    pareto
        the runs no other run beats in both error and counted cost, cheapest first (never a diverged run
        or one beyond its integrator's stability limit).
    recommendation
        for a tolerance, the verified cheapest setting (see `recommend`); None without one.
    limits
        integrator -> its stability limit on the scenario's modes [s] (None: none known).
    sweep_wall_time_s
        wall time of the whole sweep, timing pass included [s].
    """

    scene: str
    scenario: str
    parameters: dict[str, float]
    overrides: dict[str, Any]
    duration: float
    runs: tuple[TradeoffRun, ...] = dataclasses.field(repr=False)
    orders: dict[str, float | None]
    pareto: tuple[TradeoffRun, ...] = dataclasses.field(repr=False)
    recommendation: Recommendation[TradeoffRun] | None = None
    sweep_wall_time_s: float = 0.0
    limits: dict[str, float | None] = dataclasses.field(default_factory=dict)

    @property
    def question_answer(self) -> Answer:
        """The question (with a tolerance: the cheapest setting that meets it) and its answer in one or two
        sentences with units: the verified pick (or why none), the observed orders."""
        say = answers.Quoter()
        pick = self.recommendation
        over = f"{self.scene} / {self.scenario} over {answers.written(self.duration, '~s', '.4g')}"
        if pick is None:
            question = (
                f"How does the error of {over} fall with the timestep, and what does each integrator's accuracy cost?"
            )
        else:
            question = f"Which integrator and timestep simulate {over} within {pick.tolerance:g} (relative) for the least work?"
        said = [f"{name} {say(f'order_{name}', p, spec='.2f')}" for name, p in self.orders.items() if p is not None]
        orders = (
            f"observed orders of accuracy: {', '.join(said)}" if said else "no observed order (too few accurate runs)"
        )
        if pick is None:
            valid = [r for r in self.runs if r.run.valid]
            if not valid:
                return say.answer(
                    question, f"No setting ran valid (each diverged or ran beyond its stability limit); {orders}."
                )
            best = min(valid, key=lambda r: r.run.error or 0.0)  # valid: a finite error
            return say.answer(
                question,
                f"{answers.capital(orders)}; the most accurate valid run, {best.integrator} at {say.dt('best_dt_s', best.dt)},"
                f" has a max relative error of {say('best_max_rel_error', best.run.error or 0.0, spec='.2g')}.",
            )
        tolerance = say("tolerance", pick.tolerance, spec="g")
        if not pick.found or pick.row is None or pick.dt is None:
            return say.answer(question, f"No setting meets {tolerance}: {pick.text} {answers.capital(orders)}.")
        return say.answer(
            question,
            f"{pick.integrator} at {say.dt('dt_s', pick.dt)} ({say('cost', pick.row.cost, spec='.4g')} {COST_UNIT} of"
            f" counted work) is the cheapest setting within {tolerance}: its verification run's max relative error is"
            f" {say('max_rel_error', pick.error or 0.0, spec='.2g')}. {answers.capital(orders)}.",
        )

    @property
    def question(self) -> str:
        """What the trade-off asks, in words (`question_answer`)."""
        return self.question_answer.question

    @property
    def answer(self) -> str:
        """The answer in words with units (`question_answer`)."""
        return self.question_answer.answer

    def _shown(self) -> display.Summary:
        """The trade-off as a notebook shows it: the recommendation first, the orders, then the runs."""
        pick = self.recommendation
        if pick is None:
            verdict, ok, message = "no tol", None, "the trade alone (give tol for a recommendation)"
        elif pick.found:
            verdict, ok, message = f"{pick.integrator} at dt = {display.number(pick.dt)} s", True, pick.text
        else:
            verdict, ok, message = "no setting meets tol", False, pick.text
        facts = [display.Fact("duration", self.duration, "s"), display.Fact("runs", len(self.runs))]
        facts += [display.Fact(f"order of {name}", order) for name, order in self.orders.items()]
        return display.Summary(
            "Tradeoff",
            f"{self.scene} / {self.scenario}",
            verdict,
            ok,
            message,
            tuple(facts),
            display.table(
                ("integrator", "dt [s]", "max rel error [-]", "wall time [s]", "diverged"),
                [(r.integrator, r.dt, r.max_rel_error, r.wall_time_s, r.diverged) for r in self.runs],
            ),
        )

    def plot(self) -> Figure:
        """Error against dt (the observed orders) and against wall time, with the Pareto front (`springlab.plots.charts.tradeoff_figure`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """tradeoff.json: scene, scenario, duration, parameters, runs, orders, pareto, recommendation,
        stability_limits, cost_basis, wall_time_basis, sweep_wall_time_s (plain JSON values)."""
        pick = self.recommendation
        return json_ready(
            {
                **self.question_answer.to_dict(),
                "scene": self.scene,
                "scenario": self.scenario,
                "duration": self.duration,
                "parameters": dict(self.parameters),
                "runs": [r.to_dict() for r in self.runs],
                "orders": dict(self.orders),
                "pareto": [r.to_dict() for r in self.pareto],
                "recommendation": None if pick is None else pick.to_dict(RECOMMENDATION_NAMES),
                "stability_limits": dict(self.limits),
                "cost_basis": COST_BASIS,
                "wall_time_basis": WALL_TIME_BASIS,
                "sweep_wall_time_s": self.sweep_wall_time_s,
            }
        )

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab tradeoff --output DIR` writes (springlab.outputs.write): tradeoff.json, tradeoff.png."""
        return Output.json("tradeoff.json", self.to_dict()), Output("tradeoff.png")

    def to_pandas(self) -> pandas.DataFrame:
        """One row per run: tradeoff.json's `runs` columns plus `pareto` (on the Pareto front) (needs pandas)."""
        front = {id(r) for r in self.pareto}
        return tables.to_pandas([{**r.to_dict(), "pareto": id(r) in front} for r in self.runs])


def fastest_rate(case: Case) -> float | None:
    """The largest |eigenvalue| [1/s] of the case's motion, or None if the scene knows none.

    From the scene's modes (an overdamped mode's fast root omega (zeta + sqrt(zeta^2 - 1))),
    else from the spectral radius of the exact reference's system matrix.
    """
    rates = []
    for omega, zeta in case.modes():
        rates.append(omega * (zeta + math.sqrt(zeta * zeta - 1)) if zeta > 1 else omega)
    if rates:
        return max(rates)
    if case.scenario.exact:
        reference = case.reference(np.array([0.0]), dt=case.scenario.dt or case.scene.dt)
        if reference is not None and reference.system is not None:
            radius = float(np.max(np.abs(np.linalg.eigvals(reference.system))))
            return radius if radius > 0 else None
    return None


def _round_sig(value: float, digits: int = 3) -> float:
    return float(f"{value:.{digits - 1}e}")


def round_down(value: float, digits: int = 2) -> float:
    """`value` > 0 rounded down to `digits` significant digits (a timestep must not grow by rounding)."""
    unit = 10.0 ** (math.floor(math.log10(value)) - digits + 1)
    mantissa = math.floor(value / unit * (1 + 1e-12))
    out = float(f"{mantissa * unit:.{digits - 1}e}")
    return out if out <= value else float(f"{(mantissa - 1) * unit:.{digits - 1}e}")


def timestep_grid(
    rate: float | None,
    duration: float,
    *,
    points: int = SWEEP_POINTS,
    top: float = SWEEP_TOP,
    decades: float = SWEEP_DECADES,
) -> list[float]:
    """Log-spaced timesteps [s], largest first, rounded to 3 significant digits.

    From omega*dt = `top` down `decades` decades for the fastest rate omega [1/s]
    (without a rate: from duration/20), the smallest raised to keep every run
    within MAX_SWEEP_STEPS steps.
    """
    high = top / rate if rate else duration / 20
    high = min(high, duration / 4)
    low = max(high * 10.0**-decades, duration / MAX_SWEEP_STEPS)
    if low >= high:
        raise BadInputError(
            f"duration {duration:g} s is too long to sweep {points} timesteps within"
            f" {MAX_SWEEP_STEPS} steps per run; use a shorter --duration"
        )
    grid = [_round_sig(high * (low / high) ** (j / (points - 1))) for j in range(points)]
    return sorted(set(grid), reverse=True)


def sweep(
    scene: str | Scene,
    scenario: str | None = None,
    *,
    integrators: Iterable[str] = tuple(INTEGRATORS),
    dts: Sequence[float] | None = None,
    duration: float | None = None,
    timing_repeats: int = 3,
    nthread: int = 0,
    executor: Executor | None = None,
    **parameters: Any,
) -> Tradeoff:
    """Run every integrator at every timestep on one scenario, batched, and measure the trade.

    Parameters
    ----------
    scene
        scene name or object.
    scenario
        scenario name (None: the scene's default); it needs an exact reference.
    integrators
        integrator names (default: all five).
    dts
        timesteps [s] (default: `timestep_grid` from the scenario's fastest rate).
    duration
        simulated time [s] (None: the scenario's).
    timing_repeats
        timed repetitions per configuration (best is kept).
    nthread
        threads of the batch (0: one per CPU) when no executor is given.
    executor
        where the grid's chunks run (None: locally); errors and steps are the same whichever
        runs them. Wall times are always measured here, each run alone (batch.time_run).
    **parameters
        scene parameters in SI units.

    Returns
    -------
    Tradeoff
        The Tradeoff (runs, orders, Pareto front; no recommendation).

    Raises
    ------
    BadInputError
        unknown names, non-physical values, a scenario without exact reference.
    """
    started = _time.perf_counter()
    case = scenes.case(scene, scenario, parameters)
    scene_obj, chosen, params = case.scene, case.scenario, case.params
    if not sweepable(scene_obj, chosen, case):
        valid = [s.name for s in scene_obj.scenarios.values() if sweepable(scene_obj, s)]
        raise BadInputError(
            f"scenario {chosen.name!r} of {scene_obj.name} has no exact reference trajectory to"
            f" measure errors against; valid: {', '.join(valid) or 'none in this scene'}"
        )
    integrators = list(integrators)
    for name in integrators:
        integrator_id(name)
    duration = chosen.duration if duration is None else duration
    check_timing(duration / 2, duration)
    if dts is None:
        dts = timestep_grid(fastest_rate(case), duration)
        dts = _accepted_grid(dts, lambda dt: _setup_or_none(case, dt, duration))
    pairs = [(name, float(dt)) for dt in dts for name in integrators]
    # a catalogue scene travels by name (workers rebuild it); another Scene object only runs locally
    reference = scene_obj.name if scenes.SCENES.get(scene_obj.name) is scene_obj else scene_obj
    runner = Executor(nthread=nthread, progress=False) if executor is None else executor
    pieces = chunked(len(pairs), CHUNK_RUNS)
    payloads = [
        GridChunk(reference, chosen.name, tuple(parameters.items()), duration, tuple(pairs[p.start : p.stop]))
        for p in pieces
    ]
    outcomes = [o for part in runner.map(grid_chunk, payloads, description="tradeoff") for o in part]
    limits = stability_limits(case, integrators)
    work = work_per_evaluation(case.model)
    runs = []
    for (name, dt), (error, detail, steps, verdict) in zip(pairs, outcomes):
        wall = time_run(case.job(name, dt, check_timing(dt, duration)), repeats=timing_repeats)
        run = Run(
            Setting(name, dt),
            steps,
            error,
            counted_cost(name, steps, work),
            wall,
            diverged=error is None,
            beyond_limit=beyond(dt, limits[name]),
            detail=detail,
        )
        runs.append(TradeoffRun(run, verdict))
    runs.sort(key=lambda r: (integrators.index(r.integrator), -r.dt))
    orders = {name: observed_order([r for r in runs if r.integrator == name]) for name in integrators}
    return Tradeoff(
        scene=scene_obj.name,
        scenario=chosen.name,
        parameters=params,
        overrides=dict(parameters),
        duration=duration,
        runs=tuple(runs),
        orders=orders,
        pareto=tuple(pareto_front(runs)),
        sweep_wall_time_s=_time.perf_counter() - started,
        limits=limits,
    )


def stability_limits(case: Case, integrators: Iterable[str]) -> dict[str, float | None]:
    """integrator -> the largest stable dt [s] on the case's modes (the scene's `stability_limit` on each;
    None: the integrator has no limit, or the scene declares no modes)."""
    modes = case.modes()

    def limit(name: str) -> float | None:
        return limit_dt(modes, lambda omega, zeta: case.stability_limit(name, omega, zeta))

    return {name: limit(name) for name in integrators}


@dataclasses.dataclass(frozen=True)
class GridChunk:
    """A chunk of the tradeoff grid: plain data, the worker rebuilds the model from the scene's MJCF.

    Attributes
    ----------
    scene
        the scene's name (a Scene object outside the catalogue runs only locally).
    scenario
        the scenario's name.
    parameters
        (name, value) pairs: the scene's overrides, SI.
    duration
        simulated time of every run [s].
    pairs
        (integrator, dt [s]) of each run.
    """

    scene: str | Scene
    scenario: str
    parameters: tuple[tuple[str, Any], ...]
    duration: float
    pairs: tuple[tuple[str, float], ...]


def grid_chunk(payload: GridChunk, nthread: int = 0) -> list[tuple[float | None, str, int, Verdict | None]]:
    """One chunk of the grid as one batched call: per (integrator, dt) of the payload's pairs,
    (max relative error [-] or None if it diverged, why it diverged, steps taken, the run's verdict).

    A module-level function of plain data for dask workers: the model is rebuilt here from the
    scene's MJCF and the payload's parameters, exactly as the caller built it.
    """
    case = scenes.case(payload.scene, payload.scenario, dict(payload.parameters))
    duration = payload.duration
    jobs = [case.job(name, dt, check_timing(dt, duration)) for name, dt in payload.pairs]
    out: list[tuple[float | None, str, int, Verdict | None]] = []
    for job, outcome in zip(jobs, run_batched(jobs, nthread=nthread)):
        if isinstance(outcome, DivergedError):
            out.append((None, str(outcome), job.steps, None))
            continue
        try:
            # judged exactly as `springlab run` judges it: the reference is built for this run's own dt
            result = evaluate(case, outcome)
        except DivergedError as blown:
            out.append((None, str(blown), outcome.steps, None))
            continue
        # a stop condition may end a run early, as in `springlab run`
        out.append((result.max_rel_error, "", outcome.steps, result.verdict))
    return out


def sweepable(scene: Scene, scenario: Scenario, case: Case | None = None) -> bool:
    """Whether the scenario has an exact reference trajectory to sweep errors against (scenarios
    validated by scalar checks alone, like the non-linear ones, have none), at `case` (None: the
    scenario at its default parameters)."""
    if not scenario.exact:
        return False
    case = scene.case(scenario) if case is None else case
    return case.reference(np.zeros(1), dt=scenario.dt or scene.dt) is not None


def _setup_or_none(case: Case, dt: float, duration: float) -> Setup | None:
    """The case's setup at dt [s], or None when the scene rejects that dt."""
    try:
        return case.setup(check_timing(dt, duration), dt)
    except BadInputError:
        return None


def _accepted_grid(dts: Sequence[float], setup: Callable[[float], Setup | None]) -> list[float]:
    """The grid with every dt the scene rejects (e.g. a dt that must divide an input's switching times)
    replaced by the nearest accepted value 2^a 5^b within a factor 2, or dropped."""
    grid = []
    for dt in dts:
        if setup(dt) is not None:
            grid.append(dt)
            continue
        decade = 10.0 ** math.floor(math.log10(dt))
        nice = [m * decade * f for m in (1, 1.25, 1.6, 2, 2.5, 3.2, 4, 5, 6.25, 8) for f in (0.1, 1, 10)]
        nice = sorted((c for c in nice if dt / 2 <= c <= dt * 2), key=lambda c: abs(math.log(c / dt)))
        grid.extend(
            next(
                (
                    [_round_sig(c)]
                    for c in nice
                    if _round_sig(c) not in grid and _round_sig(c) not in dts and setup(_round_sig(c)) is not None
                ),
                [],
            )
        )
    if len(grid) < 3:
        raise BadInputError(
            f"the scene accepts too few of the timesteps {', '.join(f'{d:g}' for d in dts)} s"
            " to sweep; pass dts the scene accepts"
        )
    return sorted(set(grid), reverse=True)


# -- the recommendation ------------------------------------------------------------


def _candidates(result: Tradeoff, tol: float) -> list[TradeoffRun]:
    """The settings expected to meet tol, as rows (springlab.studies.settings.cheapest_verified ranks them).

    Per integrator: its cheapest grid run within tol (the fewest steps), and a larger dt predicted from that
    run's error and the integrator's order, err ~ dt^p, with margin REFINE_SAFETY, kept below the next larger
    grid dt (which failed): a row not run, its error the prediction, its cost counted as the grid's.
    """
    out = []
    for name in dict.fromkeys(r.integrator for r in result.runs):
        runs = sorted((r for r in result.runs if r.integrator == name), key=lambda r: r.dt)
        passing = [r for r in runs if r.run.valid and r.error <= tol]
        if not passing:
            continue
        grid = min(passing, key=lambda r: (r.steps, -r.dt))
        out.append(grid)
        larger = [r for r in runs if r.dt > grid.dt]
        order = result.orders.get(name)
        order = order if order is not None and abs(order - ORDERS[name]) <= 0.5 else ORDERS[name]
        if grid.error > 0:
            predicted = grid.dt * (REFINE_SAFETY * tol / grid.error) ** (1.0 / order)
        else:
            predicted = grid.dt
        ceiling = larger[0].dt if larger else 2 * grid.dt
        refined = round_down(min(predicted, ceiling * REFINE_SAFETY))
        if refined > grid.dt:
            steps = check_timing(refined, result.duration)
            run = Run(
                Setting(name, refined),
                steps,
                grid.error * (refined / grid.dt) ** order,
                grid.cost * steps / grid.steps,
                beyond_limit=beyond(refined, result.limits.get(name)),
                detail=f"predicted from dt = {grid.dt:g} s at order {order:g}",
            )
            out.append(TradeoffRun(run))
    return out


def recommend(result: Tradeoff, tol: float, *, timing_repeats: int = 3) -> Recommendation[TradeoffRun]:
    """The cheapest (integrator, dt) meeting `tol`, verified by running it with `runs.run.run_scenario`.

    Candidates come from the sweep (`_candidates`), ranked by counted cost (steps x evaluations per step,
    springlab.studies.settings): the first one whose verification run passes `springlab run`'s check at tol
    wins, and its error and wall time (measured as the sweep's, reported beside the cost) are kept.

    Parameters
    ----------
    result
        a sweep of the scenario.
    tol
        relative tolerance [-] on every compared column.
    timing_repeats
        timed repetitions of the verified setting (best is kept).

    Returns
    -------
    Recommendation
        the verified setting; `found` False (integrator, dt and error None) when no setting of the sweep
        meets tol.
    """
    tol = compare.check_tolerance(tol)

    def verify(candidate: TradeoffRun) -> Verification:
        try:
            run = run_scenario(
                result.scene,
                result.scenario,
                integrator=candidate.integrator,
                dt=candidate.dt,
                duration=result.duration,
                tol=tol,
                **result.overrides,
            )
        except DivergedError:
            return Verification(False, None)
        if not run.passed:
            return Verification(False, run.max_rel_error)
        job = run.case.job(candidate.integrator, candidate.dt, run.steps)
        return Verification(True, run.max_rel_error, time_run(job, repeats=timing_repeats))

    return cheapest_verified(_candidates(result, tol), tol, verify)


def tradeoff(
    model: str | Scene,
    scenario: str | None = None,
    *,
    tol: float | None = None,
    duration: float | None = None,
    integrators: Sequence[str] | None = None,
    dts: Sequence[float] | None = None,
    executor: Executor | None = None,
    **parameters: float,
) -> Tradeoff:
    """Error against cost of every integrator and timestep on one scenario, and the cheapest verified setting.

    `sweep` (its grid on `executor`) plus, with `tol`, the verified cheapest setting that meets it
    (`recommend`), ranked by counted work so the same call gives the same pick (`springlab tradeoff`).

    Parameters
    ----------
    model
        scene name (see `springlab list`) or a Scene.
    scenario
        scenario name (None: the scene's default); it needs an exact reference.
    tol
        relative error [-] the recommended setting must meet (None: no recommendation).
    duration
        simulated time [s] (None: the scenario's).
    integrators
        the integrators swept, e.g. ['euler', 'rk4'] (None: MuJoCo's five).
    dts
        the timesteps swept [s] (None: `timestep_grid` from the scenario's fastest rate).
    executor
        where the grid's chunks run (None: locally); the numbers are the same wherever they ran.
    **parameters
        scene parameters in SI units, e.g. mass=2.0 [kg].

    Returns
    -------
    Tradeoff
        runs, orders, the Pareto front, and with `tol` the `recommendation`; `to_dict()` is tradeoff.json.

    Raises
    ------
    BadInputError
        unknown names, non-physical values, a bad tol, a scenario without exact reference.
    TypeError
        an old keyword spelling (`scene=`) or another study's option.
    """
    overrides = keyword_parameters("tradeoff", parameters)
    if tol is not None:
        tol = compare.check_tolerance(tol)
    started = _time.perf_counter()
    refuse_text("integrators", integrators, "a sequence of names, e.g. integrators=['rk4', 'euler']")
    refuse_text("dts", dts, "a sequence of timesteps [s], e.g. dts=(0.002, 0.001)", numbers=True)
    swept = tuple(INTEGRATORS) if integrators is None else tuple(integrators)
    result = sweep(model, scenario, integrators=swept, dts=dts, duration=duration, executor=executor, **overrides)
    recommendation = recommend(result, tol) if tol is not None else None
    return dataclasses.replace(result, recommendation=recommendation, sweep_wall_time_s=_time.perf_counter() - started)
