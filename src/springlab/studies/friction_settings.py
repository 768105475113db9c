"""How far MuJoCo's regularised dry friction drifts from Coulomb's, and what the settings that shrink it cost.

MuJoCo's dry friction (a joint's `frictionloss`, a contact's friction cone) is a soft constraint: a
block that should stick creeps, and one that should stop turns round a little early and never quite
stops. A scene that declares `Scene.dry_friction` (springlab.scenes.capabilities.friction.DryFrictionSpec)
has exact Coulomb answers and takes MuJoCo's friction settings as parameters; this study reads the
declaration (it never names a scene) and, per declared case (a scenario),

* runs every combination of the settings that act on its kind of friction (joint or contact: a
  setting that MuJoCo's docs say does not act on it is not swept; the scene's tests check those
  claims on MuJoCo itself), every integrator and every declared timestep: one row per run, with
  the run's error against the exact solution (max_rel of the compared columns, as `springlab run`
  measures it; its checks are left to the verification), each declared measure's error (stop
  position, stop time, creep velocity, slide acceleration ...) and the run's wall time;
* separates the two errors: the **model error** of a setting is the error left as dt -> 0, read
  from RK4 at the smallest timestep and shown to have converged (the next larger timestep gives
  the same error within `CONVERGED`); the rest of a run's error is integration error;
* finds the Pareto front of error vs counted work, and for a tolerance the cheapest run within it
  (springlab.studies.settings: counted work, steps x evaluations per step x the model's work per
  evaluation, in which a NoSlip iteration counts; equal work goes to the more accurate, and no timer
  decides), verified by running that setting as `springlab run` does (with its convergence checks); where
  no run meets the tolerance it says which floor stops it: MuJoCo's (the best setting's model
  error is above the tolerance: no integrator or timestep helps) or the integration's.

MuJoCo's own defaults (their settings, its default integrator and timestep, read from MuJoCo) are
the baseline every answer is measured against. The runs are cut into chunks of
`CHUNK_RUNS` and run on the executor (locally, or on dask workers that rebuild each model from
the scene's MJCF); each run's CPU time, reported beside its counted work, is its own `mujoco.rollout`
call, alone on one thread.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time as _time
from collections.abc import Mapping, Sequence
from typing import Any

import mujoco
import numpy as np

from springlab import scenes
from springlab.errors import BadInputError, DivergedError
from springlab.runs import compare
from springlab.runs.run import evaluate, prepare, run_scenario
from springlab.scenes.base import Scene
from springlab.scenes.capabilities.friction import DryFrictionSpec, FrictionCase, FrictionMeasure
from springlab.scenes.declarations import keyword_parameters, refuse_text
from springlab.sim.simulate import INTEGRATORS, check_timing, integrator_id

from .executor import Executor, chunked, resolve
from .friction_results import (
    MODEL_INTEGRATOR,
    CaseStudy,
    FrictionSettings,
    ModelError,
    SettingRun,
    error_text,
)
from .settings import (
    Recommendation,
    Run,
    Setting,
    Verification,
    cheapest_verified,
    counted_cost,
    pareto_front,
    work_per_evaluation,
)

#: runs per chunk (a few seconds of work each)
CHUNK_RUNS = 48
#: a setting's error has converged in dt when the two smallest timesteps agree within this fraction [-]
CONVERGED = 0.1
#: runs at the sweep's smallest dt (no run at dt/2 measured their integration error) and the rest: the pick
#: verifies at most this many candidates, cheapest first
MAX_VERIFIED = 200


def mujoco_defaults() -> tuple[str, float]:
    """(integrator name, timestep [s]) of a fresh MuJoCo model: MuJoCo's own defaults, read from MuJoCo."""
    option = mujoco.MjSpec().option
    name = next(n for n, value in INTEGRATORS.items() if value == int(option.integrator))
    return name, float(option.timestep)


# -- the sweep -------------------------------------------------------------------------


def declaration(scene: str | Scene) -> tuple[Scene, DryFrictionSpec]:
    """(the scene, its DryFrictionSpec), or BadInputError naming the scenes that declare one."""
    scene_obj = scenes.get(scene) if isinstance(scene, str) else scene
    if scene_obj.dry_friction is None:
        declared = [name for name, s in scenes.SCENES.items() if s.dry_friction is not None]
        raise BadInputError(
            f"{scene_obj.name} declares no dry-friction cases (Scene.dry_friction); valid: {', '.join(declared) or 'none'}"
        )
    return scene_obj, scene_obj.dry_friction


def grid(
    spec: DryFrictionSpec,
    case: FrictionCase,
    integrators: Sequence[str],
    dts: Sequence[float],
    values: Mapping[str, Sequence[float]] | None = None,
) -> list[list[tuple[dict[str, float], str, float]]]:
    """Every (settings, integrator, dt) of a case, in groups of one setting and integrator at every dt, largest
    first (a run and its run at dt/2 side by side: the chunk measures their difference). A value MuJoCo
    would raise at a dt (SolverSetting.floor_in_dt) is left out there: the run at the raised value repeats it."""
    settings = spec.settings_of(case.friction)
    axes = [tuple((values or {}).get(s.name, s.values)) for s in settings]
    out: list[list[tuple[dict[str, float], str, float]]] = []
    for combination in itertools.product(*axes):
        chosen = {s.name: float(v) for s, v in zip(settings, combination)}
        kept = [
            float(dt)
            for dt in dts
            if not any(s.floor_in_dt is not None and chosen[s.name] < s.floor_in_dt * dt for s in settings)
        ]
        out.extend([(dict(chosen), name, dt) for dt in kept] for name in integrators)
    return [group for group in out if group]


#: a first-order method's error at dt is twice its change when dt is halved (the integration error
#: estimate of a run from its run at dt/2; the same factor as the friction scene's convergence check)
SAFETY = 2.0


def _change(coarse, fine) -> float:
    """max over the compared columns of max |col(dt) - col(dt/2)| at the common samples, over the column's scale
    (the scale its max_rel is relative to: max_abs / max_rel) [-]."""
    worst = 0.0
    for column, error in coarse.errors.items():
        if error.max_rel <= 0:
            continue
        joint, kind = column.rsplit("_", 1)
        a = (coarse.pos if kind == "pos" else coarse.vel)[joint]
        b = (fine.pos if kind == "pos" else fine.vel)[joint][::2]
        n = min(len(a), len(b))
        worst = max(worst, float(np.max(np.abs(a[:n] - b[:n]))) / (error.max_abs / error.max_rel))
    return worst


#: one run of a chunk: ((setting, value) pairs, integrator, dt [s])
SettingJob = tuple[tuple[tuple[str, float], ...], str, float]


@dataclasses.dataclass(frozen=True)
class SettingsChunk:
    """A chunk of one case's runs: plain data, the worker rebuilds each model from the scene's MJCF.

    Attributes
    ----------
    scene
        the scene's name (a Scene object outside the catalogue runs only locally).
    scenario
        the case's scenario.
    overrides
        (name, value) pairs: the scene's parameters given, SI (not the swept settings).
    duration
        simulated time of every run [s].
    measures
        (quantity, scale) of each of the case's measures (FrictionMeasure).
    groups
        runs of one setting and integrator, dt halving (`grid`).
    """

    scene: str | Scene
    scenario: str
    overrides: tuple[tuple[str, Any], ...]
    duration: float
    measures: tuple[tuple[str, str | None], ...]
    groups: tuple[tuple[SettingJob, ...], ...]


def chunk_of(
    scene: str | Scene,
    case: FrictionCase,
    overrides: Mapping[str, Any],
    duration: float,
    groups: Sequence[Sequence[tuple[dict[str, float], str, float]]],
) -> SettingsChunk:
    """The payload that runs `groups` (`grid`'s) of a case."""
    return SettingsChunk(
        scene,
        case.scenario,
        tuple(overrides.items()),
        duration,
        tuple((m.quantity, m.scale) for m in case.measures),
        tuple(tuple((tuple(settings.items()), name, dt) for settings, name, dt in group) for group in groups),
    )


def settings_chunk(payload: SettingsChunk, nthread: int = 0) -> list[dict[str, Any]]:
    """One chunk of runs (module-level, plain data: it runs on dask workers too).

    Each run is built from the scene's MJCF, set up and stepped as `springlab run` does (one
    `mujoco.rollout` call, alone on this thread: its CPU time, reported beside its counted work) and compared
    with its exact
    solution (`runs.run.evaluate`, checks left out); a run followed by its run at dt/2 gets its
    integration error estimate, SAFETY x their largest difference over the compared columns' scales.
    """
    rows = []
    wanted = {name for pair in payload.measures for name in pair if name}
    for group in payload.groups:
        settings, _, _ = group[0]
        # one case per setting: its runs at every integrator and dt share its model (simulate steps a copy)
        case = scenes.case(payload.scene, payload.scenario, {**dict(payload.overrides), **dict(settings)})
        work = work_per_evaluation(case.model)  # its NoSlip iterations count in its work per step
        previous = None
        for _, integrator, dt in group:
            steps = check_timing(dt, payload.duration)
            row: dict[str, Any] = {
                "steps": steps,
                "cpu_time_s": math.nan,
                "error": None,
                "integration_error": None,
                "quantities": {},
                "detail": "",
                "work": work,
            }
            setup = case.setup(steps, dt)
            try:
                start = _time.thread_time()
                trajectory = case.simulate(integrator, dt, payload.duration, setup=setup)
                row["cpu_time_s"] = _time.thread_time() - start
                result = evaluate(case, trajectory, checks=False)
            except DivergedError as blown:
                row["detail"] = str(blown)
                rows.append(row)
                previous = None
                continue
            if previous is not None and math.isclose(previous[0].dt, 2 * dt, rel_tol=1e-9):
                previous[1]["integration_error"] = SAFETY * _change(previous[0], result)
            row["error"] = result.max_rel_error
            row["quantities"] = {
                k: v
                for k, v in {**case.params, **result.quantities}.items()
                if k in wanted or k.removesuffix("_exact") in wanted
            }
            rows.append(row)
            previous = (result, row)
    return rows


def measure_error(measure: FrictionMeasure, quantities: Mapping[str, Any]) -> float | None:
    """The error of one declared measure in a run's quantities (None: the run has no value for it)."""
    value, exact = quantities.get(measure.quantity), quantities.get(measure.exact)
    if not isinstance(value, (int, float)) or not isinstance(exact, (int, float)):
        return None
    if not (math.isfinite(value) and math.isfinite(exact)):
        return None
    difference = abs(float(value) - float(exact))
    if measure.scale == "":
        return difference
    scale = abs(float(exact)) if measure.scale is None else abs(float(quantities.get(measure.scale, math.nan)))
    return difference / scale if scale > 0 and math.isfinite(scale) else None


def friction_settings(
    model: str | Scene,
    scenarios: Sequence[str] | None = None,
    *,
    tol: float | None = None,
    integrators: Sequence[str] | None = None,
    dts: Sequence[float] | None = None,
    values: Mapping[str, Sequence[float]] | None = None,
    executor: Executor | None = None,
    **parameters: float,
) -> FrictionSettings:
    """Sweep MuJoCo's friction settings over a scene's declared dry-friction cases (see the module docstring).

    Parameters
    ----------
    model
        a scene that declares `dry_friction`, or its name.
    scenarios
        the cases to sweep (None: every declared one).
    tol
        the tolerance [-] each case's pick must meet (None: no picks).
    integrators
        the integrators swept (None: the declared ones).
    dts
        the timesteps swept [s] (None: the declared ones), at least two.
    values
        setting -> the values to sweep instead of the declared ones (a smaller study).
    executor
        where the chunks run (None: locally).
    **parameters
        scene parameters in SI units (not the swept settings).

    Returns
    -------
    FrictionSettings
        every run, the model errors, the Pareto fronts and (with tol) the verified picks.

    Raises
    ------
    BadInputError
        a scene without a declaration, an unknown scenario or integrator, a swept setting given as a
        parameter, fewer than two timesteps, a bad tolerance, the command line's strings ('0.002,0.001').
    TypeError
        an old keyword spelling (`scene=`) or another study's option.
    """
    started = _time.perf_counter()
    parameters = keyword_parameters("friction_settings", parameters)
    refuse_text("scenarios", scenarios, "a sequence of scenario names, e.g. ['incline_hold']")
    refuse_text("integrators", integrators, "a sequence of names, e.g. integrators=['rk4', 'euler']")
    refuse_text("dts", dts, "a sequence of timesteps [s], e.g. dts=(0.002, 0.001)", numbers=True)
    scene_obj, spec = declaration(model)
    if tol is not None:
        tol = compare.check_tolerance(tol)
    declared = [c.scenario for c in spec.cases]
    chosen_cases = [spec.case(s) if s in declared else None for s in (scenarios or declared)]
    if None in chosen_cases:
        unknown = next(s for s, c in zip(scenarios or [], chosen_cases) if c is None)
        raise BadInputError(f"{scene_obj.name} declares no dry-friction case {unknown!r}; valid: {', '.join(declared)}")
    swept = {s.name for s in spec.settings}
    clash = sorted(swept & set(parameters))
    if clash:
        raise BadInputError(f"{clash[0]} is one of the settings the study sweeps; it cannot also be --set")
    integrators = tuple(spec.integrators if integrators is None else integrators)
    for name in integrators:
        integrator_id(name)
    dts = tuple(sorted({float(d) for d in (spec.dts if dts is None else dts)}, reverse=True))
    if len(dts) < 2 or any(not (math.isfinite(d) and d > 0) for d in dts):
        raise BadInputError(f"the study needs at least two timesteps > 0 s to measure a convergence, got {list(dts)}")
    for name, chosen_values in (values or {}).items():
        if name not in swept or not chosen_values:
            raise BadInputError(
                f"values: {name!r} is no swept setting (valid: {', '.join(sorted(swept))}) or has no values"
            )
    runner = resolve(executor)
    reference = scene_obj.name if scenes.SCENES.get(scene_obj.name) is scene_obj else scene_obj
    studies = []
    for case in chosen_cases:
        assert case is not None
        _, scenario, params = prepare(scene_obj, case.scenario, parameters)  # bad parameters: before any run
        groups = grid(spec, case, integrators, dts, values)
        configs = [config for group in groups for config in group]
        pieces = chunked(len(groups), max(1, CHUNK_RUNS // len(dts)))
        payloads = [chunk_of(reference, case, parameters, scenario.duration, groups[p.start : p.stop]) for p in pieces]
        sizes = [sum(len(g) for g in groups[p.start : p.stop]) for p in pieces]
        outcomes = [
            row
            for part in runner.map(
                settings_chunk, payloads, description=f"friction settings: {case.scenario}", sizes=sizes
            )
            for row in part
        ]
        runs = tuple(_row(case, config, outcome) for config, outcome in zip(configs, outcomes))
        studies.append(_case_study(scene_obj, spec, case, runs, integrators, dts, parameters, tol))
    return FrictionSettings(
        scene=scene_obj.name,
        overrides=dict(parameters),
        tol=tol,
        integrators=integrators,
        dts=dts,
        mujoco_default=mujoco_defaults(),
        cases=tuple(studies),
        wall_time_s=_time.perf_counter() - started,
    )


def _row(case: FrictionCase, config: tuple[dict[str, float], str, float], outcome: dict[str, Any]) -> SettingRun:
    settings, integrator, dt = config
    quantities = outcome["quantities"]
    diverged = outcome["error"] is None
    steps = int(outcome["steps"])
    run = Run(
        Setting(integrator, dt, tuple(settings.items())),
        steps,
        outcome["error"],
        counted_cost(integrator, steps, outcome["work"]),
        float(outcome["cpu_time_s"]),
        diverged=diverged,
        detail=outcome["detail"],
    )
    return SettingRun(
        run=run,
        scenario=case.scenario,
        settings=settings,
        integration_error=outcome["integration_error"],
        measures={m.quantity: None if diverged else measure_error(m, quantities) for m in case.measures},
        values={m.quantity: _finite(quantities.get(m.quantity)) for m in case.measures},
    )


def _finite(value: Any) -> float | None:
    return float(value) if isinstance(value, (int, float)) and math.isfinite(value) else None


def _case_study(
    scene: Scene,
    spec: DryFrictionSpec,
    case: FrictionCase,
    runs: tuple[SettingRun, ...],
    integrators: tuple[str, ...],
    dts: tuple[float, ...],
    parameters: Mapping[str, Any],
    tol: float | None,
) -> CaseStudy:
    settings = spec.settings_of(case.friction)
    defaults = {s.name: s.mujoco_default for s in settings}
    integrator, dt = mujoco_defaults()
    default = next(
        (r for r in runs if r.settings == defaults and r.integrator == integrator and r.dt == dt and not r.diverged),
        None,
    )
    study = CaseStudy(
        scenario=case.scenario,
        friction=case.friction,
        question=case.question,
        measures=case.measures,
        settings=settings,
        runs=runs,
        default=default,
        model_errors=model_errors(runs, dts) if MODEL_INTEGRATOR in integrators else (),
        pareto=tuple(pareto_front(runs)),
    )
    if tol is None:
        return study
    return dataclasses.replace(study, pick=_pick(scene, study, tol, parameters))


def model_errors(runs: Sequence[SettingRun], dts: tuple[float, ...]) -> tuple[ModelError, ...]:
    """Per combination of settings: MODEL_INTEGRATOR's error at every dt, the last one its model error."""
    groups: dict[tuple, dict[float, SettingRun]] = {}
    for r in runs:
        if r.integrator == MODEL_INTEGRATOR:
            groups.setdefault(tuple(sorted(r.settings.items())), {})[r.dt] = r
    out = []
    for key, by_dt in groups.items():
        steps = tuple(d for d in dts if d in by_dt)
        errors = tuple(by_dt[d].max_rel_error for d in steps)
        finest = errors[-1] if errors else None
        converged = (
            len(errors) >= 2
            and finest is not None
            and errors[-2] is not None
            and abs(errors[-2] - finest) <= CONVERGED * max(finest, 1e-300)
        )
        out.append(
            ModelError(
                settings=dict(key),
                dts=steps,
                errors=errors,
                model_error=finest,
                converged=bool(converged),
                values=dict(by_dt[steps[-1]].values) if steps else {},
            )
        )
    return tuple(out)


def _pick(scene: Scene, study: CaseStudy, tol: float, parameters: Mapping[str, Any]) -> Recommendation[SettingRun]:
    """The cheapest run within tol (counted work, then error) whose setting a full run verifies, or why there is none.

    The verification reruns at dt/2 and needs SAFETY max |x(dt) - x(dt/2)| / scale <= tol too: the sweep measured
    that for every run but those at its smallest dt, and a run it already failed is not tried."""
    candidates = [
        r
        for r in study.runs
        if r.run.valid and r.error <= tol and (r.integration_error is None or r.integration_error <= tol)
    ]
    default = study.default

    def verify(candidate: SettingRun) -> Verification:
        try:
            run = run_scenario(
                scene.name,
                study.scenario,
                integrator=candidate.integrator,
                dt=candidate.dt,
                tol=tol,
                **{**parameters, **candidate.settings},
            )
        except DivergedError:
            return Verification(False, None)
        details = {
            "speedup": default.cpu_time_s / candidate.cpu_time_s if default is not None else None,
            "work_vs_default": candidate.cost / default.cost if default is not None else None,
        }
        return Verification(bool(run.passed), run.max_rel_error, candidate.cpu_time_s, details)

    def describe(setting: Setting) -> str:
        return f"{study.describe(setting.option_values)} with {setting.integrator} at dt = {setting.dt:g} s"

    pick = cheapest_verified(candidates, tol, verify, describe=describe, max_tries=MAX_VERIFIED)
    if pick.found:
        return pick
    tried = min(len(candidates), MAX_VERIFIED)
    return dataclasses.replace(pick, text=_floor(study, tol, len(candidates), tried))


def _floor(study: CaseStudy, tol: float, within: int = 0, tried: int = 0) -> str:
    """Which floor keeps every setting above tol, in words (`within` runs were within it, `tried` verified)."""
    finite = [r for r in study.runs if not r.diverged]
    if not finite:
        return f"No setting meets {tol:g}: every run diverged."
    if within:
        return (
            f"{within} runs are within {tol:g} of the exact answer, but none passes its verification ({tried}"
            f" tried): halving dt moves each by more than {tol:g} (the run has not converged at its dt, its agreement"
            " is partly luck), so the integration is the floor; a smaller dt may reach it."
        )
    best = min(finite, key=lambda r: r.error)
    model = study.best_model
    closest = f"the closest is {study.describe(best.settings)} with {best.integrator} at dt = {best.dt:g} s, error {best.error:.2g}"
    if model is not None and model.model_error is not None and model.model_error > tol:
        steady = "converged in dt" if model.converged else "still changing with dt"
        return (
            f"No setting meets {tol:g}, and MuJoCo's model is the floor: the best setting's error as dt -> 0 is"
            f" {model.model_error:.2g} ({study.describe(model.settings)}; {steady}), so no integrator or timestep"
            f" can go below it; {closest}."
        )
    return (
        f"No setting meets {tol:g} at the swept timesteps, but MuJoCo's model allows it (best model error"
        f" {error_text(model.model_error if model else None)}): the integration is the floor, a smaller dt may reach it;"
        f" {closest}."
    )
