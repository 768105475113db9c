"""How much model does a question need? The three-axis trade: model size x integrator x timestep.

For a scene that declares its model size a parameter (`Scene.refinable`, a
springlab.scenes.capabilities.refine.RefinableSpec) and a question (a quantity its runs measure, with the same
quantity of the discretized model solved exactly and of the continuum), the study runs every size x
integrator x timestep and splits each run's error against the continuum into

* discretization: the discretized model's exact answer against the continuum's (depends on the size only);
* integration: the run against the discretized model's exact answer (depends on integrator and dt).

The timestep grid of each size follows its fastest mode w_max (from the scene's `modes`): w_max dt in
`OMEGA_DT`, from well inside every explicit integrator's stability limit to far beyond it (where only an
integrator without one survives), each lowered to divide the scene's declared switch time where it has one.
Refining the size costs twice: each step costs more (more degrees of
freedom) and, for an integrator with a stability limit, w_max grows with the size, so the largest stable
dt shrinks; `SizeCost` reports both and their product, the cost of a simulated second at the stability
limit. For a tolerance, the cheapest run (wall time) whose error bound (discretization + integration:
the parts' signs differ between integrators and sizes, so their sum is not counted on to cancel) meets it is
verified by a fresh run at that setting (springlab.runs.run.run_scenario: validated as `springlab run`
validates it) and reported with both parts of its error.

Chunks (one size's runs) go through springlab.studies.executor like every sweep: locally, on a local
dask cluster or on a running scheduler; the errors and steps are the same everywhere, wall times are
measured where the runs ran (one mujoco.rollout call each).
"""

from __future__ import annotations

import dataclasses
import math
import time as _time
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab import display, scenes, tables
from springlab.answer import Answer
from springlab.errors import BadInputError, DivergedError
from springlab.files import Output, json_ready
from springlab.runs import compare
from springlab.runs.run import run_scenario
from springlab.scenes.base import Scene
from springlab.scenes.capabilities.refine import RefinableSpec
from springlab.scenes.declarations import keyword_parameters, refuse_text
from springlab.sim.batch import TIMING_STEPS, time_run
from springlab.sim.simulate import INTEGRATORS, MAX_STEPS, check_timing, integrator_id

from . import answers
from .executor import Executor
from .settings import (
    COST_BASIS,
    Recommendation,
    Run,
    RunFields,
    Setting,
    Verification,
    beyond,
    cheapest_verified,
    counted_cost,
    pareto_front,
    work_per_evaluation,
)

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure

#: w_max dt of every size's timestep grid: inside every limit (0.2) ... explicit Euler's 2 (1.9), RK4's
#: 2.83 (2.8), far beyond both (8, 30)
OMEGA_DT = (0.2, 0.5, 1.0, 1.9, 2.8, 8.0, 30.0)
#: runs beyond this many steps are left out of the grid (the finest dt of a large size)
MAX_REFINE_STEPS = 400_000
#: runs per chunk
CHUNK_RUNS = 12

WALL_TIME_BASIS = (
    "each run alone on one thread as `springlab run` steps it (one mujoco.rollout call), timed where it ran: a"
    " sweep run its own rollout; the recommendation's best of 3, over its first"
    f" {TIMING_STEPS} steps and scaled by steps when it is longer"
)


@dataclasses.dataclass(frozen=True)
class RefineRun(RunFields):
    """One (size, integrator, dt) of the study: the shared row (`run`) and the question's three values.

    Attributes
    ----------
    run
        the shared row (springlab.studies.settings.Run): its setting holds the size as an option, its error is
        `error_bound` (what the study ranks by), its cost the counted work, its time the measured wall time.
    size
        the model's size (e.g. elements).
    value, exact, continuum
        the question's measured value, the discretized model's exact one and the continuum's (None: diverged).
    """

    run: Run
    size: int
    value: float | None
    exact: float | None
    continuum: float | None

    @property
    def wall_time_s(self) -> float:
        """Wall time of the run [s] (WALL_TIME_BASIS), reported beside its counted cost."""
        return self.run.time_s

    @property
    def error(self) -> float | None:
        """|value - continuum| / |continuum| [-]: the whole error of the answer (None: diverged)."""
        if self.value is None or self.continuum is None or not math.isfinite(self.value):
            return None
        return abs(self.value - self.continuum) / abs(self.continuum)

    @property
    def error_bound(self) -> float | None:
        """discretization_error + integration_error [-]: a bound on the error that does not count on the two
        parts cancelling (their signs depend on the integrator and the size; the study ranks runs by this)."""
        return bound(self.exact, self.continuum, self.value)

    @property
    def discretization_error(self) -> float | None:
        """|exact - continuum| / |continuum| [-]: the model's size alone."""
        if self.exact is None or self.continuum is None:
            return None
        return abs(self.exact - self.continuum) / abs(self.continuum)

    @property
    def integration_error(self) -> float | None:
        """|value - exact| / |exact| [-]: the integrator and dt alone."""
        if self.value is None or self.exact is None or not math.isfinite(self.value):
            return None
        return abs(self.value - self.exact) / abs(self.exact)

    def to_dict(self) -> dict[str, Any]:
        """refine.json's row: size, integrator, dt [s], steps, value, exact, continuum, error,
        discretization_error, integration_error, error_bound, wall_time_s [s], cost [DOF-evaluations], diverged,
        beyond_limit."""
        return {
            "size": self.size,
            "integrator": self.integrator,
            "dt": self.dt,
            "steps": self.steps,
            "value": self.value,
            "exact": self.exact,
            "continuum": self.continuum,
            "error": self.error,
            "discretization_error": self.discretization_error,
            "integration_error": self.integration_error,
            "error_bound": self.error_bound,
            "wall_time_s": self.wall_time_s,
            "cost": self.cost,
            "diverged": self.diverged,
            "beyond_limit": self.beyond_limit,
        }


def bound(exact: float | None, continuum: float | None, value: float | None) -> float | None:
    """|exact - continuum| / |continuum| + |value - exact| / |exact| [-]: the error bound of an answer (None:
    a value missing or not finite)."""
    if value is None or exact is None or continuum is None or not math.isfinite(value):
        return None
    return abs(exact - continuum) / abs(continuum) + abs(value - exact) / abs(exact)


@dataclasses.dataclass(frozen=True)
class SizeCost:
    """What one size costs: per step, and per simulated second at each integrator's stability limit.

    Attributes
    ----------
    size
        the model's size.
    fastest_rate_rad_s
        w_max of the model [rad/s].
    discretization_error
        the question's discretization error at this size [-].
    cost_per_step_s
        integrator -> the fewest seconds of wall time per step over its runs [s].
    stable_dt_s
        integrator -> the largest stable dt on w_max [s] (None: no limit).
    cost_per_simulated_second_s
        integrator -> cost_per_step / stable_dt: wall time per simulated second at the limit (None: no limit).
    """

    size: int
    fastest_rate_rad_s: float
    discretization_error: float | None
    cost_per_step_s: dict[str, float]
    stable_dt_s: dict[str, float | None]
    cost_per_simulated_second_s: dict[str, float | None]

    def to_dict(self) -> dict[str, Any]:
        """refine.json's `sizes` row."""
        return {
            "size": self.size,
            "fastest_rate_rad_s": self.fastest_rate_rad_s,
            "discretization_error": self.discretization_error,
            "cost_per_step_s": dict(self.cost_per_step_s),
            "stable_dt_s": dict(self.stable_dt_s),
            "cost_per_simulated_second_s": dict(self.cost_per_simulated_second_s),
        }


#: refine.json's names for the recommendation's keys: its `error` is the error against the continuum (a detail),
#: the kernel's error is the bound the tolerance holds
RECOMMENDATION_NAMES = {"tolerance": "tol", "error": "error_bound", "time_s": "wall_time_s"}
#: the recommendation's own numbers, null until a verification run gives them
NO_DETAILS = dict.fromkeys(("size", "error", "discretization_error", "integration_error", "verdict"))


@dataclasses.dataclass(frozen=True, repr=False)
class Refinement(display.Shown):
    """The three-axis trade of one question (`refine`).

    `to_dict()` is refine.json (what `springlab refine --json` prints), `to_pandas()` one row per run.

    Attributes
    ----------
    scene, scenario
        names.
    quantity, description
        the measured quantity's name and what it is in words (`question`: the study's question).
    size_parameter, size_description
        the parameter that sets the size and what it counts.
    duration
        simulated time of every run [s].
    overrides
        parameters the caller set.
    runs
        every run, by size, integrator, dt descending.
    sizes
        one SizeCost per size.
    pareto
        the runs no other beats in both error bound and counted cost, cheapest first (never a diverged run or
        one beyond its integrator's stability limit).
    discretization_order
        observed order of the discretization error in the size (fitted; None: too few points).
    expected_order
        the order the scene declares.
    cost_growth
        integrator -> fitted exponent of cost_per_simulated_second_s in the size (None: no limit or too few).
    step_cost_growth
        fitted exponent of the cheapest cost_per_step_s in the size.
    recommendation
        with a tolerance, the verified cheapest setting.
    sweep_wall_time_s
        wall time of the whole study [s].
    """

    scene: str
    scenario: str
    quantity: str
    description: str
    size_parameter: str
    size_description: str
    duration: float
    overrides: dict[str, Any]
    runs: tuple[RefineRun, ...] = dataclasses.field(repr=False)
    sizes: tuple[SizeCost, ...] = dataclasses.field(repr=False)
    pareto: tuple[RefineRun, ...] = dataclasses.field(repr=False)
    discretization_order: float | None
    expected_order: float
    cost_growth: dict[str, float | None]
    step_cost_growth: float | None
    recommendation: Recommendation[RefineRun] | None = None
    sweep_wall_time_s: float = 0.0

    @property
    def question_answer(self) -> Answer:
        """The question and its answer: the verified pick (or why none) and the discretization's order."""
        say = answers.Quoter()
        pick = self.recommendation
        within = f" within {pick.tolerance:g} (relative) of the continuum's value" if pick is not None else ""
        question = (
            f"How large a model ({self.size_parameter}), which integrator and which timestep does {self.description}"
            f" of {self.scene} / {self.scenario} need{within}, for the least work?"
        )
        order = self.discretization_order
        trend = (
            f"the discretization error falls as {self.size_parameter}^-{say('discretization_order', order, spec='.2f')}"
            f" (expected {self.expected_order:g})"
            if order is not None
            else "too few sizes for the discretization's order"
        )
        if pick is None:
            front = say("pareto", len(self.pareto), spec="d")
            return say.answer(
                question, f"{answers.capital(trend)}; the Pareto front has {front} settings (no tolerance asked)."
            )
        tolerance = say("tolerance", pick.tolerance, spec="g")
        if not pick.found or pick.row is None or pick.dt is None:
            return say.answer(question, f"No setting meets {tolerance}: {pick.text} {answers.capital(trend)}.")
        details = pick.details
        parts = ", ".join(
            f"{words} {say(key, details[key], spec='.2g')}"
            for words, key in (("discretization", "discretization_error"), ("integration", "integration_error"))
            if details.get(key) is not None
        )
        return say.answer(
            question,
            f"{self.size_parameter} = {say('size', pick.row.size, spec='g')} with {pick.integrator} at"
            f" {say.dt('dt_s', pick.dt)} is the cheapest setting within {tolerance}: its verification run's error"
            f" bound is {say('error_bound', pick.error or 0.0, spec='.2g')}"
            + (f" ({parts})" if parts else "")
            + f". {answers.capital(trend)}.",
        )

    @property
    def question(self) -> str:
        """What the study asks, in words (`question_answer`)."""
        return self.question_answer.question

    @property
    def answer(self) -> str:
        """The answer in words with units (`question_answer`)."""
        return self.question_answer.answer

    def _shown(self) -> display.Summary:
        """The refinement as a notebook shows it: the recommendation first, the orders, then the sizes."""
        pick = self.recommendation
        names = list(dict.fromkeys(n for c in self.sizes for n in c.cost_per_step_s))
        if pick is None:
            verdict, ok, message = "no tol", None, self.description
        elif pick.found:
            verdict = (
                f"{self.size_parameter} {pick.details['size']}, {pick.integrator} at dt = {display.number(pick.dt)} s"
            )
            ok, message = pick.verified, f"{pick.text} (`springlab run`: {pick.details['verdict']})"
        else:
            verdict, ok, message = "no setting meets tol", False, pick.text
        return display.Summary(
            "Refinement",
            f"{self.scene} / {self.scenario}",
            verdict,
            ok,
            message,
            (
                display.Fact("quantity", self.quantity),
                display.Fact("discretization order", self.discretization_order),
                display.Fact("expected order", self.expected_order),
                display.Fact("step cost growth", self.step_cost_growth),
                display.Fact("runs", len(self.runs)),
            ),
            display.table(
                (self.size_parameter, "discretization error [-]", *(f"{n} cost per step [s]" for n in names)),
                [(c.size, c.discretization_error, *(c.cost_per_step_s.get(n) for n in names)) for c in self.sizes],
            ),
        )

    def plot(self) -> Figure:
        """Error against size, against dt and against wall time (`springlab.plots.refine.refine_figure`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """refine.json: question, answer, scene, scenario, quantity, description, size_parameter, size_description, duration,
        parameters, runs, sizes, pareto, discretization_order, expected_order, cost_growth, step_cost_growth,
        recommendation, cost_basis, wall_time_basis, sweep_wall_time_s (plain JSON values)."""
        pick = self.recommendation
        return json_ready(
            {
                "scene": self.scene,
                "scenario": self.scenario,
                **self.question_answer.to_dict(),
                "quantity": self.quantity,
                "description": self.description,
                "size_parameter": self.size_parameter,
                "size_description": self.size_description,
                "duration": self.duration,
                "parameters": dict(self.overrides),
                "runs": [r.to_dict() for r in self.runs],
                "sizes": [s.to_dict() for s in self.sizes],
                "pareto": [r.to_dict() for r in self.pareto],
                "discretization_order": self.discretization_order,
                "expected_order": self.expected_order,
                "cost_growth": dict(self.cost_growth),
                "step_cost_growth": self.step_cost_growth,
                "recommendation": None if pick is None else {**NO_DETAILS, **pick.to_dict(RECOMMENDATION_NAMES)},
                "cost_basis": COST_BASIS,
                "wall_time_basis": WALL_TIME_BASIS,
                "sweep_wall_time_s": self.sweep_wall_time_s,
            }
        )

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab refine --output DIR` writes (springlab.outputs.write): refine.json, refine.png."""
        return Output.json("refine.json", self.to_dict()), Output("refine.png")

    def to_pandas(self) -> pandas.DataFrame:
        """One row per run: refine.json's `runs` columns plus `pareto` (on the front) (needs pandas)."""
        front = {id(r) for r in self.pareto}
        return tables.to_pandas([{**r.to_dict(), "pareto": id(r) in front} for r in self.runs])


def _round_sig(value: float, digits: int = 3) -> float:
    return float(f"{value:.{digits - 1}e}")


def refinable_scenes() -> list[str]:
    """Names of the scenes that declare a model size (`Scene.refinable`)."""
    return [name for name, scene in scenes.SCENES.items() if scene.refinable is not None]


def _spec_of(scene: Scene):
    spec = scene.refinable
    if spec is None:
        raise BadInputError(
            f"{scene.name} has no model size to refine; scenes that have one: {', '.join(refinable_scenes()) or 'none'}"
        )
    return spec


def _checked_sizes(scene: Scene, spec: RefinableSpec, sizes: Sequence[int] | None) -> list[int]:
    """The model sizes to sweep, sorted and distinct (BadInputError for none, or one that is not a whole
    number within the size parameter's range)."""
    sizes = list(spec.sizes if sizes is None else sizes)
    size_parameter = scene.parameters[spec.size]
    if not sizes:
        raise BadInputError(f"give at least one {spec.size}")
    for size in sizes:
        checked = size_parameter.check(size)
        if checked != round(checked):
            raise BadInputError(f"{spec.size} must be whole numbers, got {size!r}")
    return sorted({int(round(s)) for s in sizes})


def _plans(
    scene: Scene,
    spec: RefinableSpec,
    scenario: str,
    sizes: list[int],
    integrators: list[str],
    omega_dt: Sequence[float],
    duration: float,
    parameters: dict[str, Any],
) -> list[tuple[int, float, dict[str, float | None], list[float]]]:
    """Per size: (size, its fastest mode [rad/s], integrator -> stability limit of w dt [-] (None: none),
    the timesteps [s] of the grid that fit the run's step budget)."""
    plans = []
    for size in sizes:
        case = scenes.case(scene, scenario, {**parameters, spec.size: size})
        params, modes = case.params, case.modes()
        fastest = max(omega for omega, _ in modes)
        limits: dict[str, float | None] = {}
        for name in integrators:
            ratio = min(case.stability_limit(name, omega, zeta) / omega for omega, zeta in modes)
            limits[name] = ratio if math.isfinite(ratio) else None
        dts = sorted({_on_grid(_round_sig(f / fastest), params.get(spec.switch_time)) for f in omega_dt}, reverse=True)
        dts = [dt for dt in dts if duration / dt <= min(MAX_REFINE_STEPS, MAX_STEPS) and dt <= duration / 4]
        plans.append((size, fastest, limits, dts))
    return plans


def refine(
    model: str | Scene,
    question: str | None = None,
    *,
    tol: float | None = None,
    sizes: Sequence[int] | None = None,
    integrators: Iterable[str] = tuple(INTEGRATORS),
    duration: float | None = None,
    omega_dt: Sequence[float] = OMEGA_DT,
    executor: Executor | None = None,
    **parameters: float,
) -> Refinement:
    """Sweep size x integrator x timestep for one question and, with `tol`, find the cheapest verified setting.

    Parameters
    ----------
    model
        scene name or object; it declares `refinable`.
    question
        the quantity to answer (None: the scene's first question).
    tol
        relative tolerance [-] on the answer against the continuum (None: no recommendation).
    sizes
        model sizes (None: the scene's default sizes).
    integrators
        integrator names (default: all five).
    duration
        simulated time [s] (None: the question's scenario's).
    omega_dt
        the timestep grid of each size as w_max dt [-] (default OMEGA_DT).
    executor
        where the chunks run (None: locally).
    **parameters
        other scene parameters (SI); the size parameter is the study's.

    Returns
    -------
    Refinement
        runs, per-size costs, Pareto front, observed orders and (with tol) the recommendation.

    Raises
    ------
    BadInputError
        a scene without a model size, an unknown question or integrator, bad sizes or tolerance, the
        command line's strings ('4,8,16', 'rk4,euler').
    TypeError
        an old keyword spelling (`scene=`) or another study's option.
    """
    started = _time.perf_counter()
    parameters = keyword_parameters("refine", parameters)
    refuse_text("sizes", sizes, "a sequence of whole numbers, e.g. sizes=(4, 8, 16)", numbers=True)
    refuse_text("integrators", integrators, "a sequence of names, e.g. integrators=['rk4', 'euler']")
    refuse_text("omega_dt", omega_dt, "a sequence of numbers, e.g. omega_dt=(0.5, 1.0)", numbers=True)
    scene_obj = scenes.get(model) if isinstance(model, str) else model
    spec = _spec_of(scene_obj)
    try:
        asked = spec.question(question)
    except KeyError:
        valid = ", ".join(q.name for q in spec.questions)
        raise BadInputError(f"{scene_obj.name} has no refinable question {question!r}; valid: {valid}") from None
    if spec.size in parameters:
        raise BadInputError(f"the study sets {spec.size} itself; choose the sizes with sizes= (--sizes)")
    if tol is not None:
        tol = compare.check_tolerance(tol)
    integrators = list(integrators)
    for name in integrators:
        integrator_id(name)
    sizes = _checked_sizes(scene_obj, spec, sizes)
    scenario = scene_obj.scenario(asked.scenario)
    duration = scenario.duration if duration is None else duration
    check_timing(duration / 2, duration)

    plans = _plans(scene_obj, spec, asked.scenario, sizes, integrators, omega_dt, duration, parameters)
    reference = scene_obj.name if scenes.SCENES.get(scene_obj.name) is scene_obj else scene_obj
    payloads = []
    for size, _, limits, dts in plans:
        pairs = [(name, dt) for dt in dts for name in integrators]
        for start in range(0, len(pairs), CHUNK_RUNS):
            payloads.append(
                RefineChunk(
                    scene=reference,
                    scenario=asked.scenario,
                    question=(asked.name, asked.exact, asked.continuum),
                    parameters=tuple({**parameters, spec.size: size}.items()),
                    size=size,
                    size_parameter=spec.size,
                    limits=tuple(limits.items()),
                    duration=duration,
                    pairs=tuple(pairs[start : start + CHUNK_RUNS]),
                )
            )
    runner = Executor(progress=False) if executor is None else executor
    outcomes = runner.map(refine_chunk, payloads, description="refine", sizes=[len(p.pairs) for p in payloads])
    runs = [run for part in outcomes for run in part]
    runs.sort(key=lambda r: (r.size, integrators.index(r.integrator), -r.dt))
    costs = _size_costs(plans, runs, integrators)
    front = pareto_front(runs)
    recommendation = _recommend(scene_obj, asked, spec.size, runs, tol, duration, parameters) if tol else None
    return Refinement(
        scene=scene_obj.name,
        scenario=asked.scenario,
        quantity=asked.name,
        description=asked.description,
        size_parameter=spec.size,
        size_description=spec.description,
        duration=duration,
        overrides=dict(parameters),
        runs=tuple(runs),
        sizes=tuple(costs),
        pareto=tuple(front),
        discretization_order=_order([(c.size, c.discretization_error) for c in costs]),
        expected_order=spec.order,
        cost_growth={
            name: _slope([(c.size, c.cost_per_simulated_second_s.get(name)) for c in costs]) for name in integrators
        },
        step_cost_growth=_slope([(c.size, min(c.cost_per_step_s.values(), default=None)) for c in costs]),
        recommendation=recommendation,
        sweep_wall_time_s=_time.perf_counter() - started,
    )


@dataclasses.dataclass(frozen=True)
class RefineChunk:
    """A chunk of one model size: plain data, the worker rebuilds the model from the scene's MJCF.

    Attributes
    ----------
    scene
        the scene's name (a Scene object outside the catalogue runs only locally).
    scenario
        the scenario's name.
    question
        (quantity, its exact value, its continuum value): the names of the three in the scene's quantities.
    parameters
        (name, value) pairs: the scene's overrides with the size, SI.
    size
        the model size [-].
    size_parameter
        the parameter that sets it.
    limits
        (integrator, largest stable dt [s] or None) pairs at this size.
    duration
        simulated time of every run [s].
    pairs
        (integrator, dt [s]) of each run.
    """

    scene: str | Scene
    scenario: str
    question: tuple[str, str, str]
    parameters: tuple[tuple[str, Any], ...]
    size: int
    size_parameter: str
    limits: tuple[tuple[str, float | None], ...]
    duration: float
    pairs: tuple[tuple[str, float], ...]


def refine_chunk(payload: RefineChunk, nthread: int = 0) -> list[RefineRun]:
    """One chunk of one size: each (integrator, dt) run alone, its question's three values read from the
    scene's quantities, its counted cost from the model and its stability limit from the payload's limits (a
    module-level function of plain data for dask workers; the model is rebuilt here)."""
    case = scenes.case(payload.scene, payload.scenario, dict(payload.parameters))
    name, exact_name, continuum_name = payload.question
    duration, size = payload.duration, payload.size
    limits = dict(payload.limits)
    work = work_per_evaluation(case.model)
    out = []
    for integrator, dt in payload.pairs:
        steps = check_timing(dt, duration)
        setting = Setting(integrator, dt, ((payload.size_parameter, float(size)),))
        past = beyond(dt, limits[integrator])
        setup = case.setup(steps, dt)
        try:
            trajectory = case.simulate(integrator, dt, duration, setup=setup)
        except DivergedError as error:
            cost = counted_cost(integrator, steps, work)
            run = Run(setting, steps, None, cost, diverged=True, beyond_limit=past, detail=str(error))
            out.append(RefineRun(run, size, None, None, None))
            continue
        quantities = case.quantities(trajectory)
        value = quantities.get(name)
        value = float(value) if value is not None and math.isfinite(float(value)) else None
        exact, continuum = float(quantities[exact_name]), float(quantities[continuum_name])
        run = Run(
            setting,
            trajectory.steps,
            bound(exact, continuum, value),
            counted_cost(integrator, trajectory.steps, work),
            # the run's own rollout, alone on this thread, is its timing: no second run only to time it
            time_run(case.job(integrator, dt, steps, setup=setup), repeats=1, measured=trajectory.wall_time_s),
            diverged=value is None,
            beyond_limit=past,
            detail="" if value is not None else f"the run measured no {name}",
        )
        out.append(RefineRun(run, size, value, exact, continuum))
    return out


def _on_grid(dt: float, period: float | None) -> float:
    """dt [s], lowered to period / ceil(period / dt) when a switch time `period` [s] must fall on the step grid."""
    if not period:
        return dt
    return period / math.ceil(period / dt * (1 - 1e-12))


def _size_costs(plans, runs: Sequence[RefineRun], integrators: Sequence[str]) -> list[SizeCost]:
    costs = []
    for size, fastest, limits, _ in plans:
        mine = [r for r in runs if r.size == size and not r.diverged and r.steps > 0]
        per_step = {}
        for name in integrators:
            times = [r.wall_time_s / r.steps for r in mine if r.integrator == name]
            if times:
                per_step[name] = float(min(times))
        per_second = {
            name: (per_step[name] / limits[name] if name in per_step and limits[name] else None) for name in integrators
        }
        discretization = next((r.discretization_error for r in mine if r.discretization_error is not None), None)
        costs.append(SizeCost(size, fastest, discretization, per_step, dict(limits), per_second))
    return costs


def _slope(points: Sequence[tuple[float, float | None]]) -> float | None:
    """Least-squares slope of log y vs log x over the points with y > 0 (None: fewer than 3)."""
    kept = [(x, y) for x, y in points if y is not None and y > 0 and math.isfinite(y)]
    if len(kept) < 3:
        return None
    slope, _ = np.polyfit(np.log([x for x, _ in kept]), np.log([y for _, y in kept]), 1)
    return float(slope)


def _order(points: Sequence[tuple[float, float | None]]) -> float | None:
    """The observed order of the discretization error: -slope of log error vs log size over the finest three
    sizes whose error is above 1e-13 (round-off of the exact values)."""
    kept = [(x, y) for x, y in points if y is not None and y > 1e-13]
    slope = _slope(kept[-3:])
    return None if slope is None else -slope


def _recommend(
    scene: Scene, asked, size_parameter: str, runs: Sequence[RefineRun], tol: float, duration: float, overrides
) -> Recommendation[RefineRun]:
    """The cheapest run (counted work) whose error bound meets tol, verified by run_scenario at its setting (the
    next if it fails): springlab.studies.settings.cheapest_verified."""

    def verify(candidate: RefineRun) -> Verification:
        try:
            result = run_scenario(
                scene.name,
                asked.scenario,
                integrator=candidate.integrator,
                dt=candidate.dt,
                duration=duration,
                **{**overrides, size_parameter: candidate.size},
            )
        except DivergedError:
            return Verification(False, None)
        value = result.quantities.get(asked.name)
        exact, continuum = result.quantities[asked.exact], result.quantities[asked.continuum]
        value = float(value) if value is not None else None
        error_bound = bound(exact, continuum, value)
        if value is None or error_bound is None or error_bound > tol:
            return Verification(False, error_bound)
        wall = time_run(result.case.job(candidate.integrator, candidate.dt, result.steps))
        details = {
            "size": candidate.size,
            "error": abs(value - continuum) / abs(continuum),
            "discretization_error": abs(exact - continuum) / abs(continuum),
            "integration_error": abs(value - exact) / abs(exact),
            "verdict": None if result.verdict is None else str(result.verdict),
        }
        return Verification(True, error_bound, wall, details)

    def describe(setting: Setting) -> str:
        return f"{size_parameter} = {setting.option_values[size_parameter]:g}, {setting.integrator} at dt = {setting.dt:.3g} s"

    return cheapest_verified(
        runs, tol, verify, describe=describe, error_words="error bound (discretization + integration)"
    )
