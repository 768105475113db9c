"""From measurements to a model: identify a scene's parameters from a recorded signal.

`fit(scene, data)` reads a record (springlab.studies.fit.data), decides what may be
fitted (springlab.studies.fit.models), and identifies it with MuJoCo in the loop using
MuJoCo's own system-identification toolbox, `mujoco.sysid`: parameters with
bounds, residuals from MuJoCo rollouts of the scene, `sysid.optimize`
(springlab.studies.fit.engine), then `sysid.calculate_intervals` for the covariance and
95 % intervals (Student t on n - p degrees of freedom, noise variance from the
residual). Derived quantities (omega_n, zeta from k, d, m, or k, d from
omega_n, zeta given m) carry intervals by the delta method. Every estimate is cross-checked
against the closed form (springlab.analytic) fitted independently with scipy.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from springlab import progress, scenes
from springlab.errors import BadInputError, ParameterError, SpringlabError
from springlab.runs.run import Result, run_scenario
from springlab.scenes.base import Scenario, Scene
from springlab.scenes.declarations import keyword_parameters
from springlab.studies.executor import Executor
from springlab.studies.fit import data as fit_data
from springlab.studies.fit import reductions
from springlab.studies.fit import release as fit_release
from springlab.studies.fit import results as fit_results
from springlab.studies.fit import starts as fit_starts

from .engine import Problem, accuracy, check_identifiable, choose_dt, residual_rms, solve
from .models import ALIASES, FitModel, PolynomialModel, model_of, not_fittable
from .results import FitResult

#: samples per simulation step from which the record is called denser than the model needs
DENSE = 4.0


def _canonical(name: str) -> str:
    return ALIASES.get(name, name)


def fit(
    model: str,
    data: fit_data.DataSource,
    scenario: str | None = None,
    *,
    map: Mapping[str, str] | None = None,  # noqa: A002 - the CLI's --map
    free: Sequence[str] | None = None,
    scale: float | None = None,
    time_scale: float | None = None,
    start: float | None = None,
    degree: int | None = None,
    run_scene: bool = True,
    starts: int = 1,
    workers: int | None = None,
    scheduler: str | None = None,
    executor: Executor | None = None,
    show_progress: bool | None = None,
    **parameters: float,
) -> FitResult:
    """Identify the scene `model` from the record in `data` (a CSV file, a mapping of arrays or a DataFrame).

    Parameters
    ----------
    model
        A scene that declares a fit (`Scene.fit`; `fittable()` lists them).
    data
        A CSV file with a header, a mapping of column name -> array ({'time': t, 'slider_pos': x}) or a
        pandas DataFrame: `time` [s] and one signal `<joint>_pos` [m], `<joint>_vel` [m/s] or
        `<joint>_acc` [m/s^2] (see springlab.studies.fit.data; units the column names state are applied).
    scenario
        The scene's scenario the record shows (None: the fit's default for the scene).
    map
        Column -> springlab name, e.g. {'t': 'time', 'x_mm': 'slider_pos'}.
    free
        Names to fit, e.g. ['omega_n', 'zeta'] (None: the scene's declared default; see springlab.studies.fit.models).
    scale
        Factor [SI per unit of the data] applied to the signal, e.g. 0.001 for mm (None: the unit the
        column states, else SI). Given, it wins over the column's unit.
    time_scale
        Factor [s per unit of the data] applied to the time, e.g. 0.001 for ms (None: as `scale`).
    start
        Release time [s, after `time_scale`]: the record before it is dropped (None: detected).
    degree
        A polynomial fit only: its degree, 0 to the highest it declares (frees its coefficients x0, v0, ...
        in order); None: chosen, from the highest down while the highest coefficient's 95 % interval contains 0.
    run_scene
        Also run the identified scene (FitResult.run) for trajectory.csv.
    starts
        Independent optimizations (springlab.studies.fit.starts): 1 is the linear-algebra start alone;
        N > 1 adds N - 1 starts spread over the nonlinear free names' bounds and keeps the lowest cost.
    workers, scheduler, executor
        Where the starts run (springlab.studies.executor): a LocalCluster of `workers`
        processes, a running dask scheduler's address, or an Executor; none: in this process. Same numbers
        either way. A single start always runs in this process.
    show_progress
        Progress bars while a large file is read and a long record (more than reductions.BLOCK samples) is
        fitted (None: on a terminal only; False: never).
    **parameters
        Fixed values: scene parameters (e.g. mass=2.0 [kg]) and
        x0 [m], v0 [m/s], offset [signal unit], delay [s].

    Returns
    -------
    FitResult
        Estimates with 95 % intervals, derived quantities, verdict.

    Raises
    ------
    BadInputError
        Bad file or names, a free set the record cannot identify, the command line's strings, an
        executor and workers/scheduler. (TypeError: an old keyword spelling or another study's option.)
    """
    parameters = _typed(parameters, map, free, executor is not None and (workers, scheduler) != (None, None))
    starts = fit_starts.check_count(starts)
    scene_obj, how = _fitted_scene(model)
    scenario = how.scenarios[0] if scenario is None else scenario
    chosen = _fitted_scenario(scene_obj, how, scenario)
    nuisance = _nuisance(scene_obj, parameters)
    base = scene_obj.resolve(chosen, {k: v for k, v in parameters.items() if k not in nuisance})
    # a fitted delay models the held part before a release itself: keep it in the record
    wants_delay = any("delay" in str(item) for item in (free or ()))
    record = fit_data.load(
        data,
        (how.joint,),
        mapping={} if map is None else {str(k): str(v) for k, v in map.items()},
        scale=scale,
        time_scale=time_scale,
        start=start,
        signals=how.signals,
        show_progress=show_progress,
    )
    free_given = bool(free)
    free = _free_names(how, free, degree, record)
    forced, force = _step_force(how, scenario, base)
    _check_free(how, free, nuisance, base, forced, record, starts)
    modal = how.modal(free)
    fixed = dict(nuisance) | {k: base[k] for k in ("x0", "v0") if k in parameters and k in base}
    # a held start is dropped only when the data show it beyond their noise (springlab.studies.fit.release)
    record, release = fit_release.decide(how, record, base, fixed, free, force, given=start, delay=wants_delay)
    if not isinstance(how, PolynomialModel):
        fixed |= _initial_state(how, record, base, free, fixed)
    return _solved(
        how,
        chosen,
        base,
        record,
        free,
        fixed,
        modal,
        force,
        starts=starts,
        executor=executor,
        workers=workers,
        scheduler=scheduler,
        choose_degree=isinstance(how, PolynomialModel) and not free_given and degree is None,
        run_scene=run_scene,
        release=release,
        show_progress=show_progress,
    )


def _initial_state(
    how: FitModel, record: fit_data.Record, base: dict[str, float], free: list[str], fixed: dict[str, float]
) -> dict[str, float]:
    """An initial state neither fitted nor given: x0 [m] the first sample (a position record; else the
    equilibrium), v0 [m/s] at rest."""
    state = {}
    if "x0" not in free and "x0" not in fixed:
        state["x0"] = float(record.values[0]) if record.signal == "pos" else how.equilibrium(base)
    if "v0" not in free and "v0" not in fixed:
        state["v0"] = 0.0
    return state


def _solved(
    how: FitModel,
    chosen: Scenario,
    base: dict[str, float],
    record: fit_data.Record,
    free: list[str],
    fixed: dict[str, float],
    modal: bool,
    force: float,
    *,
    starts: int,
    executor: Executor | None,
    workers: int | None,
    scheduler: str | None,
    choose_degree: bool,
    run_scene: bool,
    release: fit_release.Release,
    show_progress: bool | None,
) -> FitResult:
    """`fit`'s optimization (its starts on `executor`, or an own one of `workers`/`scheduler` for several),
    the polynomial degree where it is chosen, then the FitResult."""
    # a long record's fit takes seconds: its stages on a terminal (a short one's would only flicker)
    long = record.time.size > reductions.BLOCK
    with progress.bar(
        2, description="fitting: optimizing", unit="stage", enabled=show_progress if long else False
    ) as bar:
        if starts > 1 and executor is None:
            with Executor(workers=workers, scheduler=scheduler, progress=False) as own:
                problem, solved, runs = _identify(how, chosen, base, record, free, fixed, modal, force, starts, own)
        else:
            problem, solved, runs = _identify(how, chosen, base, record, free, fixed, modal, force, starts, executor)
        if choose_degree:
            assert isinstance(how, PolynomialModel), "only a polynomial fit chooses its degree"
            problem, solved, runs = _chosen_degree(
                how, chosen, base, record, free, fixed, modal, force, problem, solved, runs
            )
        bar.update(1)
        bar.set_description("fitting: intervals, cross-check, scene run")
        result = _finish(problem, solved, runs, run_scene, release)
        bar.update(1)
    return result


def _fitted_scene(scene: str) -> tuple[Scene, FitModel]:
    """The scene named `scene` and how it is fitted (BadInputError for one that declares no fit)."""
    if scene not in scenes.SCENES:
        raise not_fittable(scene)
    scene_obj = scenes.get(scene)
    return scene_obj, model_of(scene_obj)


def _step_force(how: FitModel, scenario: str, base: dict[str, float]) -> tuple[bool, float]:
    """(whether the scenario applies a step force, that force [N] or 0)."""
    force_name = how.step_force(scenario)
    forced = force_name is not None and base.get(force_name, 0.0) != 0.0
    force = base.get(force_name, 0.0) if force_name is not None and forced else 0.0
    return forced, force


def _check_free(
    how: FitModel,
    free: list[str],
    nuisance: dict[str, float],
    base: dict[str, float],
    forced: bool,
    record: fit_data.Record,
    starts: int,
) -> None:
    """BadInputError unless the record can identify `free` (the model's own rules, the starts' spread, and
    at least two samples more than free names)."""
    how.check_free(free, nuisance, base, forced, record.signal)
    fit_starts.check_spreadable(free, starts)
    if len(free) + 2 > record.time.size:
        raise BadInputError(
            f"{record.time.size} samples cannot fit {len(free)} parameters; a fit needs at least {len(free) + 2}"
        )


def _fitted_scenario(scene: Scene, how: FitModel, scenario: str) -> Scenario:
    """The scenario `fit` identifies: one the scene's fit declares (BadInputError naming them otherwise)."""
    if scenario not in how.scenarios:
        valid = ", ".join(how.scenarios)
        if scenario not in scene.scenarios:
            raise BadInputError(f"unknown scenario {scenario!r} of {scene.name}; a fit takes one of: {valid}")
        raise BadInputError(f"{scene.name} {scenario} cannot be fitted from a record; a fit takes one of: {valid}")
    return scene.scenario(scenario)


def _nuisance(scene: Scene, parameters: Mapping[str, Any]) -> dict[str, float]:
    """The fixed values among `parameters` that are not the scene's: x0 [m], v0 [m/s], offset [signal unit],
    delay [s] (ParameterError for a value that is not a finite number)."""
    nuisance = {}
    for name, value in parameters.items():
        if name in ("x0", "v0", "offset", "delay") and name not in scene.parameters:
            try:
                nuisance[name] = float(value)
            except (TypeError, ValueError):
                nuisance[name] = math.nan
            if not math.isfinite(nuisance[name]):
                raise ParameterError(f"{name} must be a finite number, got {value!r}")
    return nuisance


def _chosen_degree(
    how: PolynomialModel,
    chosen: Scenario,
    base: dict[str, float],
    record: fit_data.Record,
    free: list[str],
    fixed: dict[str, float],
    modal: bool,
    force: float,
    problem: Problem,
    solved: dict[str, Any],
    runs: dict[str, Any] | None,
) -> tuple[Problem, dict[str, Any], dict[str, Any] | None]:
    """A polynomial fit whose degree is chosen: drop the highest coefficient while its 95 % interval contains
    0 (a note on the record says so); the (problem, solved, runs) of the degree kept."""
    result = _finish(problem, solved, None, run_scene=False)
    while len(free) > 1:
        low, high = result.estimates[free[-1]]["ci95"]
        if not low <= 0.0 <= high:
            break
        note = f"degree chosen: {free[-1]}'s 95 % interval [{low:.3g}, {high:.3g}] contains 0"
        record = dataclasses.replace(record, notes=(*record.notes, note))
        free = free[:-1]
        problem, solved, runs = _identify(how, chosen, base, record, free, fixed, modal, force)
        result = _finish(problem, solved, None, run_scene=False)
    return problem, solved, runs


def _identify(
    how: FitModel,
    chosen: Scenario,
    base: dict[str, float],
    record: fit_data.Record,
    free: list[str],
    fixed: dict[str, float],
    modal: bool,
    force: float,
    starts: int = 1,
    executor: Executor | None = None,
) -> tuple[Problem, dict[str, Any], dict[str, Any] | None]:
    """The start(s), the problem and sysid's solution (the best start's, and the starts' record or None);
    the grid refined once if the estimate is faster than the start."""
    start_values = _start(how, record, base, fixed, free, force)
    problem = Problem(how, chosen, base, record, free, start_values, modal, force)
    runs = None
    if starts == 1:
        solved = solve(problem, record)
    else:
        solved, runs = fit_starts.run(problem, starts, executor)
    # the grid was chosen at the start: refine it once where the estimate needs a finer one, or where the
    # simulation, measured against the closed form at the estimate, moves it more than the fit allows
    estimate = problem.values(solved["x"])
    needed, facts = choose_dt(problem, estimate, describe=False)  # set_grid describes a refined grid
    numerics = accuracy(problem, solved)
    ratio = numerics["ratio"]
    if not (ratio > 1.0 or problem.dt > 1.5 * needed):
        solved["accuracy"] = numerics  # the estimate's, on the grid it was solved on: `_finish` reads it
    else:
        problem.start = dict(estimate)
        if ratio > 1.0 and problem.dt * (0.8 / ratio) ** 0.25 < needed:
            # the error grows as dt^4: 0.8 of what the fit allows
            needed = problem.dt * (0.8 / ratio) ** 0.25
            why = f"the simulation moved an estimate by {ratio:.3g} x what the fit allows at dt = {problem.dt:.4g} s"
            facts["rule"] = f"{why}; refined as dt^4"
        else:
            facts["rule"] = f"{facts['rule']}, at the estimate"
        problem.grid = facts
        problem.set_grid(estimate, dt=needed)
        solved = solve(problem, record)
    return problem, solved, runs


def _start(
    how: FitModel,
    record: fit_data.Record,
    base: dict[str, float],
    fixed: dict[str, float],
    free: list[str],
    force: float,
) -> dict[str, float]:
    """Start values; with a free delay, from the part after the detected release, shifted to it."""
    if "delay" not in free:
        return how.start(record, base, fixed, free, force)
    found = fit_release.held_start(how, record, base, fixed, [n for n in free if n != "delay"], force)
    delay = found.start_s - record.origin if found.decision == "held" else 0.0
    after = record.time >= record.origin + delay
    shifted = dataclasses.replace(
        record, time=record.time[after], values=record.values[after], origin=record.origin + delay
    )
    values = how.start(shifted, base, fixed, free, force)
    values["delay"] = delay
    return values


def _free_names(how: FitModel, free: Sequence[str] | None, degree: int | None, record: fit_data.Record) -> list[str]:
    if degree is not None:
        return how.free_of_degree(degree, record.signal)
    if free is None or len(free) == 0:
        return how.free_by_default(record.signal)
    names = []
    for item in free:
        name = _canonical(str(item).strip())
        if name and name not in names:
            names.append(name)
    if not names:
        raise BadInputError("--free needs at least one name")
    return names


def _typed(parameters: Mapping[str, Any], mapping: object, free: object, two_executors: bool) -> dict[str, Any]:
    """The scene's parameters (old spellings refused), after refusing the command line's strings (the library
    takes a mapping and a sequence of names; `springlab fit` parses --map's COLUMN=NAME and --free's NAME,NAME)
    and an executor given beside workers or a scheduler."""
    if two_executors:
        raise BadInputError("give an executor or workers/scheduler, not both")
    if mapping is not None and not isinstance(mapping, Mapping):
        raise BadInputError(
            f"map takes a mapping of file column -> springlab name, e.g. map={{'t': 'time'}}, not {mapping!r}"
            " (the command line's COLUMN=NAME is springlab fit --map's)"
        )
    if isinstance(free, str) or (free is not None and any("," in str(name) for name in free)):  # type: ignore[attr-defined]
        raise BadInputError(
            f"free takes a sequence of names, e.g. free=['omega_n', 'zeta'], not the command line's {free!r}"
        )
    return keyword_parameters("fit", parameters)


def _finish(
    problem: Problem,
    solved: dict[str, Any],
    runs: dict[str, Any] | None,
    run_scene: bool,
    release: fit_release.Release | None = None,
) -> FitResult:
    """The FitResult: intervals, derived quantities, cross-check, the starts' record (`runs`: None for a single
    start), the decision on where the motion starts (`release`) and the identified scene's run."""
    how, record, free = problem.how, problem.record, problem.free
    spacing = problem.grid.get("median_sample_spacing_s") or 0.0
    if spacing > 0 and problem.dt >= DENSE * spacing:
        note = (
            f"data denser than the model needs: {problem.dt / spacing:.3g} samples per simulation step of"
            f" {problem.dt:.3g} s (the model runs at the step its accuracy needs and is read at every sample)"
        )
        if problem.compression is not None:
            note += (
                f"; fitted on {problem.compression.rows} rows that reduce the {problem.samples} samples"
                " exactly (the same estimates and intervals; docs/fit.md, big files)"
            )
        record = dataclasses.replace(record, notes=(*record.notes, note))
    x, jacobian = solved["x"], solved["jacobian"]
    check_identifiable(problem, jacobian)
    # in parameters scaled to O(1): sysid's zero-eigenvalue threshold is relative, and k ~ 1e6 N/m beside
    # an offset ~ 1e-3 m would otherwise look singular
    scale = np.array(solved["scale"])
    n, p = record.time.size, len(free)
    covariance, half = fit_results.intervals(solved["residuals"], jacobian * scale, n)
    covariance = np.asarray(covariance, float) * np.outer(scale, scale)
    half = np.asarray(half, float) * scale
    dof = n - p
    values = problem.values(x)
    if problem.compression is None:
        residual = np.concatenate(solved["residuals"]) * problem.scale
        fitted = record.values + residual
        rms = float(np.sqrt(np.mean(residual**2)))
    else:  # sysid saw the reduced rows: the signal at every sample from one more rollout at the estimate
        fitted = problem.signal(values)
        rms = residual_rms(problem, np.concatenate(solved["residuals"]))
    units = how.units()
    estimates: dict[str, dict[str, Any]] = {}
    for i, name in enumerate(free):
        unit = record.unit if name == "offset" else units[name]
        estimates[name] = {
            "value": float(x[i]),
            "ci95": fit_results.interval(float(x[i]), float(half[i])),
            "unit": unit,
        }
    sd = np.sqrt(np.clip(np.diag(covariance), 1e-300, None))
    correlation = covariance / np.outer(sd, sd)
    quantile = fit_results.t_quantile(dof)
    derived = fit_results.delta_intervals(
        lambda v: how.derived(problem.values(v), problem.base, problem.modal),
        x,
        covariance,
        quantile,
        how.derived_units(),
    )
    same = {"omega_n_rad_s": "omega_n", "damping_ratio": "zeta"}
    derived = {k: v for k, v in derived.items() if k not in free and same.get(k) not in free}
    params = how.scene_params(values, problem.base, problem.modal)
    curves = _curves(problem, x, covariance, quantile) if isinstance(how, PolynomialModel) else {}
    numerics = solved["accuracy"] if "accuracy" in solved else accuracy(problem, solved)
    cross = fit_results.cross_check(problem, x, half, fitted, numerics["effect"], scale)
    judged = fit_results.convergence(problem, solved, covariance, numerics, cross)
    level = values["offset"] + (how.equilibrium(params) if record.signal == "pos" else 0.0)
    run, run_note = None, ""
    if run_scene:
        v0 = estimates.get("v0")
        moving = v0 is not None and not v0["ci95"][0] <= 0.0 <= v0["ci95"][1]  # v0 = 0 is not plausible
        run, run_note = _scene_run(problem, values, params, moving)
    return FitResult(
        scene=how.name,
        scenario=problem.scenario.name,
        kind=how.kind,
        record=record,
        free=tuple(free),
        estimates=estimates,
        derived=derived,
        correlation=correlation,
        covariance=covariance,
        residual_rms=rms,
        dof=dof,
        parameters=params,
        fitted=fitted,
        cross_check=cross,
        optimizer={
            "method": "mujoco.sysid.optimize (mujoco.minimize Levenberg-Marquardt), MuJoCo RK4 rollouts",
            "status": solved["status"],
            "iterations": solved["iterations"],
            "rollouts": problem.rollouts,
            "rollout_time_s": problem.rollout_time,
            "time_per_rollout_s": problem.rollout_time / max(problem.rollouts, 1),
            "wall_time_s": solved["wall_time_s"],
            "dt": problem.dt,
            "steps": problem.steps,
            "integrator": "rk4",
        },
        converged=judged["converged"],
        convergence=judged,
        timestep=fit_results.timestep(problem.grid, numerics),
        run=run,
        run_note=run_note,
        curves=curves,
        amplitude=how.amplitude(fitted, level),
        starts=fit_starts.starts_entry(runs, list(free), covariance, record.unit),
        release=release.to_dict() if release is not None else {},
    )


def _curves(problem: Problem, x: np.ndarray, covariance: np.ndarray, quantile: float) -> dict[str, Any]:
    """A polynomial's x(t), v(t), a(t) with 95 % bands on 41 times over the record."""
    t = np.linspace(0.0, problem.span, 41)
    out: dict[str, Any] = {"time_s": (t + problem.record.origin).tolist()}
    for signal in ("pos", "vel", "acc"):

        def curve(vector: np.ndarray, signal: str = signal) -> dict[str, float]:
            values = problem.values(vector)
            y = problem.how.closed_form(t, problem.base, values, signal)
            return {str(i): float(v) for i, v in enumerate(y)}

        bands = fit_results.delta_intervals(curve, x, covariance, quantile)
        key = {"pos": "x_m", "vel": "v_m_s", "acc": "a_m_s2"}[signal]
        out[key] = [bands[str(i)]["value"] for i in range(t.size)]
        out[key + "_ci95_halfwidth"] = [bands[str(i)]["ci95"][1] - bands[str(i)]["value"] for i in range(t.size)]
    return out


def _scene_run(
    problem: Problem, values: dict[str, float], params: dict[str, float], moving: bool
) -> tuple[Result | None, str]:
    """The identified scene's own run over the record's span, or (None, why not)."""
    overrides, note = problem.how.run_parameters(params, values, moving)
    try:
        run = run_scenario(problem.how.name, problem.scenario.name, duration=problem.span, **overrides)
    except SpringlabError as error:
        return None, f"the identified scene could not be run: {error}"
    return run, note
