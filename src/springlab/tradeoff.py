"""What accuracy each integrator buys for how much compute, and where it stops being trustworthy.

Three measurements, each checked against theory:

1. **The trade-off** (`tradeoff`): every integrator x a log-spaced range of
   timesteps on one scenario, run batched (`mujoco.batch.Batch`, one
   simulation per (integrator, dt), bit-identical to a plain loop). For every
   run: the max relative error against the scene's exact reference (computed
   exactly as `springlab run` computes it), the steps and the wall time; per
   integrator the observed order of accuracy (the fitted slope of log error
   vs log dt over the asymptotic range); the Pareto front of error vs cost;
   and for a tolerance the cheapest (integrator, dt) that meets it, verified
   by running it (`recommend`, also behind `run --integrator auto --tol TOL`).
2. **The stability map** (`measure_boundaries`, `amplification_map`): on
   m x'' + d x' + k x = 0 the measured omega*dt at which each integrator's
   response starts to grow, per damping ratio, against the theory in
   `simulate.stability_limit`, and the per-step amplification factor of
   MuJoCo's one-step map over a (zeta, omega*dt) grid.
3. **The extremes** (`extremes_table`) and **the energy** (`energy_histories`):
   stiff, light, undamped-long and hugely overdamped sliders at 0.5x, 0.99x and
   1.01x each stability limit, each run classified accurate / inaccurate /
   diverged with what to use instead; and the undamped energy of every
   integrator against its exact discrete-map formula.

Wall time. Batched runs share threads, so their wall time is no per-run cost.
`wall_time_s` of a configuration is measured by running that configuration
alone, on the calling thread, exactly as `springlab run` steps it (one
`mujoco.rollout` call; best of `timing_repeats`). Runs longer than
`TIMING_STEPS` are timed over their first `TIMING_STEPS` steps and scaled by
steps: MuJoCo's cost per step on a fixed model and integrator does not depend
on dt or on the state. Divide by the duration for the wall time per simulated
second.

The MuJoCo step maps on the 1-DOF slider (omega = sqrt(k/m), zeta =
d/(2 sqrt(k m)), y = omega*dt, measured in tests/test_stability.py):

* euler, implicit, implicitfast: identical; semi-implicit (symplectic) Euler
  with implicit joint damping, v' = (v - dt k/m x)/(1 + 2 zeta y),
  x' = x + dt v'. Stable while y < 2 zeta + 2 sqrt(zeta^2 + 1). Undamped it
  conserves I = v^2 + omega^2 x^2 - dt omega^2 x v exactly, so the energy
  stays between I/(2(1 + y/2)) and I/(2(1 - y/2)) [per unit mass].
* rk4: the classical map R(dt A), R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24;
  undamped the energy is multiplied by |R(iy)|^2 = 1 - y^6/72 + y^8/576
  every step.
* discrete: backward Euler, (m + dt d + dt^2 k) a = -k x - d v - dt k v,
  v' = v + dt a, x' = x + dt v'; undamped the energy is multiplied by
  1/(1 + y^2) every step. Never unstable.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
import pathlib
import time as _time
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import mujoco
import numpy as np
from mujoco import batch as _mjbatch
from mujoco import rollout as _rollout

from . import api, compare, outputs, scenes
from .errors import BadInputError, DivergedError
from .scene import Scenario, Scene, Setup
from .simulate import (
    BAD_WARNINGS,
    INTEGRATORS,
    ORDERS,
    Trajectory,
    check_diverged,
    check_timing,
    cut_at_stop,
    initial_state,
    integrator_id,
    quiet_mujoco,
    stability_limit,
)

#: stability_limit scans for rk4; the tables ask for the same few values many times
_limit = functools.lru_cache(maxsize=None)(stability_limit)

_STATE = mujoco.mjtState
#: what the batched runner records after every step: time, qpos, qvel, act
_RECORD_SPEC = int(_STATE.mjSTATE_TIME | _STATE.mjSTATE_QPOS | _STATE.mjSTATE_QVEL | _STATE.mjSTATE_ACT)
_FULL = int(_STATE.mjSTATE_FULLPHYSICS)
_CTRL = int(_STATE.mjSTATE_CTRL)

#: the sweep spans omega_max*dt from SWEEP_TOP down by SWEEP_DECADES decades
SWEEP_TOP = 1.0
SWEEP_DECADES = 3.0
#: timesteps in the default sweep (>= 12 by contract)
SWEEP_POINTS = 13
#: most steps one sweep run may take; the smallest dt is raised to respect it
MAX_SWEEP_STEPS = 200_000
#: runs longer than this are timed over their first TIMING_STEPS steps and scaled
TIMING_STEPS = 4000
#: the order fit keeps errors below this (beyond it the leading term no longer dominates) ...
FIT_MAX_ERROR = 0.1
#: ... and above this many times the round-off allowance 100 eps per step (compare.ROUNDOFF_PER_STEP)
FIT_ROUNDOFF_FACTOR = 10.0
#: the order is the slope over this many of the finest such runs ...
FIT_POINTS = 4
#: ... none of which may lie off the fitted line by more than this factor
FIT_MAX_SCATTER = 1.5
#: a refined timestep for a tolerance is predicted with this margin, then verified by running it
REFINE_SAFETY = 0.9

WALL_TIME_BASIS = (
    "each configuration run alone on one thread as `springlab run` steps it (one mujoco.rollout call),"
    f" best of 3; runs over {TIMING_STEPS} steps timed on their first {TIMING_STEPS} steps and scaled by steps"
)


# -- the batched runner --------------------------------------------------------


@dataclasses.dataclass
class Job:
    """One simulation of a batch.

    Attributes:
      model: the compiled model; jobs sharing one model object run on it with
        per-simulation timestep and integrator (Batch.expand), jobs with
        different models each run on a copy of theirs (Batch.set_models).
      integrator: one of INTEGRATORS.
      dt: timestep [s].
      steps: number of steps.
      setup: initial state and controls (control: (nu,) or (steps, nu), held over each step).
      stop: the scene's stop condition (Scene.stop_condition), applied as `simulate` applies it.
    """

    model: mujoco.MjModel
    integrator: str
    dt: float
    steps: int
    setup: Setup
    stop: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None


def _controls(job: Job) -> np.ndarray | None:
    """(steps, nu) controls of a job, or None for a model without actuators."""
    nu = job.model.nu
    if not nu:
        return None
    control = np.zeros(nu) if job.setup.control is None else np.asarray(job.setup.control, float)
    return np.broadcast_to(control, (job.steps, nu))


def run_batched(jobs: Sequence[Job], *, nthread: int = 0) -> list[Trajectory | DivergedError]:
    """Run every job in one `mujoco.batch.Batch`; bit-identical to `simulate.simulate` per job.

    Jobs of different lengths share the batch: the runner advances all
    unfinished simulations together, segment by segment, so no simulation
    takes a step it does not need.

    Args:
      jobs: the simulations.
      nthread: threads of the batch (0: one per CPU).

    Returns:
      Per job its Trajectory (t = 0 included; wall_time_s is nan: batched runs
      share threads, see `time_run` for a per-run cost), or the DivergedError
      describing how it blew up (MuJoCo's BADQPOS/BADQVEL/BADQACC warnings, a
      silent reset, non-finite values).
    """
    if not jobs:
        return []
    for job in jobs:
        integrator_id(job.integrator)
    base = jobs[0].model
    shared = all(job.model is base for job in jobs)
    if not shared and any(
        job.model.nq != base.nq or job.model.nv != base.nv or job.model.na != base.na or job.model.nu != base.nu
        for job in jobs
    ):
        raise BadInputError("batched jobs with different models need the same nq, nv, na and nu")
    with quiet_mujoco():
        batch = _mjbatch.Batch(base, nsim=len(jobs), nthread=nthread)
        if shared:
            batch.expand("opt.timestep")[:] = [job.dt for job in jobs]
            batch.expand("opt.integrator")[:] = [INTEGRATORS[job.integrator] for job in jobs]
        else:
            models = []
            for job in jobs:
                model = copy.copy(job.model)
                model.opt.timestep = job.dt
                model.opt.integrator = INTEGRATORS[job.integrator]
                models.append(model)
            batch.set_models(models)
        nq, nv, na = base.nq, base.nv, base.na
        starts = []
        for i, job in enumerate(jobs):
            state0 = initial_state(job.model, job.setup.qpos, job.setup.qvel, job.setup.act)
            batch.time[i] = 0.0
            batch.qpos[i] = state0[1 : 1 + nq]
            batch.qvel[i] = state0[1 + nq : 1 + nq + nv]
            if na:
                batch.act[i] = state0[1 + nq + nv : 1 + nq + nv + na]
            starts.append(np.concatenate([[0.0], state0[1 : 1 + nq + nv + na]]))
        batch.warning[:] = 0
        controls = [_controls(job) for job in jobs]
        steps = np.array([job.steps for job in jobs])
        records: list[list[np.ndarray]] = [[] for _ in jobs]
        done = 0
        for end in np.unique(steps):
            ids = np.flatnonzero(steps >= end).astype(np.int32)
            count = int(end - done)
            control = None
            if base.nu:
                control = np.stack([controls[i][done:end] for i in ids])
            out = batch.rollout(count, control=control, record=[_RECORD_SPEC], ids=ids)[_RECORD_SPEC]
            for row, i in enumerate(ids):
                records[i].append(out[row])
            done = int(end)
        warnings = np.array(batch.warning)
    results: list[Trajectory | DivergedError] = []
    for i, job in enumerate(jobs):
        states = np.concatenate([starts[i][None], *records[i]])
        trajectory = Trajectory(
            time=states[:, 0],
            qpos=states[:, 1 : 1 + nq],
            qvel=states[:, 1 + nq : 1 + nq + nv],
            act=states[:, 1 + nq + nv :],
            integrator=job.integrator,
            dt=job.dt,
            wall_time_s=math.nan,
        )
        fired = [name for name, w in zip(("BADQPOS", "BADQVEL", "BADQACC"), BAD_WARNINGS) if warnings[i, w, 1] > 0]
        if job.stop is not None:
            trajectory, stopped = cut_at_stop(trajectory, job.stop)
            if stopped:
                fired = []  # as simulate: warnings may come from steps after the event
        try:
            check_diverged(trajectory, job.dt, ["unstable"] if fired else [])
        except DivergedError as error:
            why = f"; MuJoCo flagged {'/'.join(fired)} (NaN or |value| > 1e10, then reset)" if fired else ""
            results.append(DivergedError(f"{error}{why}"))
            continue
        results.append(trajectory)
    return results


def time_run(job: Job, *, repeats: int = 3, max_steps: int = TIMING_STEPS) -> float:
    """Wall time [s] of one job run alone on the calling thread, as `simulate` steps it.

    Best of `repeats`; a job longer than `max_steps` is timed over its first
    `max_steps` steps and scaled by steps (MuJoCo's cost per step does not
    depend on dt or on the state).
    """
    model = job.model
    model.opt.integrator = INTEGRATORS[job.integrator]
    model.opt.timestep = job.dt
    timed = max(1, min(job.steps, max_steps))
    state0 = initial_state(model, job.setup.qpos, job.setup.qvel, job.setup.act)
    controls = None
    if model.nu:
        controls = np.ascontiguousarray(_controls(job)[:timed])[None]
    data = mujoco.MjData(model)
    out = np.empty((1, timed, state0.size))
    sensors = np.empty((1, timed, model.nsensordata))
    best = math.inf
    with quiet_mujoco():
        for _ in range(max(1, repeats)):
            start = _time.perf_counter()
            _rollout.rollout(
                [model],
                [data],
                state0[None],
                controls,
                control_spec=_CTRL,
                state=out,
                sensordata=sensors,
                nstep=timed,
                skip_checks=True,
            )
            best = min(best, _time.perf_counter() - start)
    return best * job.steps / timed


# -- the sweep -----------------------------------------------------------------


@dataclasses.dataclass
class Run:
    """One (integrator, dt) of a sweep.

    Attributes:
      integrator: integrator name.
      dt: timestep [s].
      steps: steps taken.
      max_rel_error: max over the compared columns of max |sim - ref| / max |ref| [-]; None if diverged.
      wall_time_s: wall time of the run alone [s] (see module docstring).
      diverged: the run blew up (detected, never reported as a result).
      detail: how it diverged, for people.
    """

    integrator: str
    dt: float
    steps: int
    max_rel_error: float | None
    wall_time_s: float
    diverged: bool = False
    detail: str = ""

    def row(self) -> dict[str, Any]:
        """The JSON row: integrator, dt, max_rel_error, steps, wall_time_s, diverged."""
        return {
            "integrator": self.integrator,
            "dt": self.dt,
            "max_rel_error": self.max_rel_error,
            "steps": self.steps,
            "wall_time_s": self.wall_time_s,
            "diverged": self.diverged,
        }


@dataclasses.dataclass
class Tradeoff:
    """A speed-accuracy sweep of one scenario.

    Attributes:
      scene, scenario: names.
      parameters: the parameter values used (SI).
      overrides: the parameters the caller set (re-applied when verifying a recommendation).
      duration: simulated time of every run [s].
      runs: every (integrator, dt), grouped by integrator, dt descending.
      orders: integrator -> observed order of accuracy (None: too few asymptotic points).
      pareto: the runs no other run beats in both error and wall time, cheapest first.
      recommendation: for a tolerance, the verified cheapest setting (see `recommend`).
      sweep_wall_time_s: wall time of the whole sweep, timing pass included [s].
    """

    scene: str
    scenario: str
    parameters: dict[str, float]
    overrides: dict[str, Any]
    duration: float
    runs: list[Run]
    orders: dict[str, float | None]
    pareto: list[Run]
    recommendation: dict[str, Any] | None = None
    sweep_wall_time_s: float = 0.0

    def as_json(self) -> dict[str, Any]:
        """{"runs", "orders", "pareto", "recommendation"} plus the scene, scenario, duration and basis."""
        return {
            "scene": self.scene,
            "scenario": self.scenario,
            "duration": self.duration,
            "parameters": dict(self.parameters),
            "runs": [r.row() for r in self.runs],
            "orders": dict(self.orders),
            "pareto": [r.row() for r in self.pareto],
            "recommendation": self.recommendation,
            "wall_time_basis": WALL_TIME_BASIS,
            "sweep_wall_time_s": self.sweep_wall_time_s,
        }


def fastest_rate(scene: Scene, model: mujoco.MjModel, params: dict[str, float], scenario: Scenario) -> float | None:
    """The largest |eigenvalue| [1/s] of the scenario's motion, or None if the scene knows none.

    From the scene's modes (an overdamped mode's fast root omega (zeta + sqrt(zeta^2 - 1))),
    else from the spectral radius of the exact reference's system matrix.
    """
    rates = []
    for omega, zeta in scene.modes(model, params, scenario):
        rates.append(omega * (zeta + math.sqrt(zeta * zeta - 1)) if zeta > 1 else omega)
    if rates:
        return max(rates)
    if scenario.exact:
        reference = scene.reference(model, params, scenario, np.array([0.0]))
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
    **parameters: Any,
) -> Tradeoff:
    """Run every integrator at every timestep on one scenario, batched, and measure the trade.

    Args:
      scene: scene name or object.
      scenario: scenario name (None: the scene's default); it needs an exact reference.
      integrators: integrator names (default: all five).
      dts: timesteps [s] (default: `timestep_grid` from the scenario's fastest rate).
      duration: simulated time [s] (None: the scenario's).
      timing_repeats: timed repetitions per configuration (best is kept).
      nthread: threads of the batch (0: one per CPU).
      **parameters: scene parameters in SI units.

    Returns:
      The Tradeoff (runs, orders, Pareto front; no recommendation).

    Raises:
      BadInputError: unknown names, non-physical values, a scenario without exact reference.
    """
    started = _time.perf_counter()
    scene_obj, chosen, params = api.prepare(scene, scenario, parameters)
    model = scene_obj.build(params, chosen)
    if not sweepable(scene_obj, chosen, params, model):
        valid = [s.name for s in scene_obj.scenarios.values() if sweepable(scene_obj, s, None)]
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
        dts = timestep_grid(fastest_rate(scene_obj, model, params, chosen), duration)
        dts = _accepted_grid(dts, lambda dt: _setup_or_none(scene_obj, model, params, chosen, dt, duration))
    stop = scene_obj.stop_condition(model, params, chosen)
    jobs = []
    for dt in dts:
        steps = check_timing(dt, duration)
        setup = scene_obj.setup(model, params, chosen, steps, dt)
        jobs.extend(Job(model, name, dt, steps, setup, stop) for name in integrators)
    outcomes = run_batched(jobs, nthread=nthread)
    runs = []
    for job, outcome in zip(jobs, outcomes):
        error, detail, steps = None, "", job.steps
        if isinstance(outcome, DivergedError):
            detail = str(outcome)
        else:
            steps = outcome.steps  # a stop condition may end a run early, as in `springlab run`
            try:
                result = api.evaluate(scene_obj, chosen, params, model, outcome)
                error = max(e["max_rel"] for e in result.summary["errors"].values())
            except DivergedError as blown:
                detail = str(blown)
        wall = time_run(job, repeats=timing_repeats)
        runs.append(Run(job.integrator, job.dt, steps, error, wall, diverged=error is None, detail=detail))
    runs.sort(key=lambda r: (integrators.index(r.integrator), -r.dt))
    orders = {name: observed_order([r for r in runs if r.integrator == name]) for name in integrators}
    return Tradeoff(
        scene=scene_obj.name,
        scenario=chosen.name,
        parameters=params,
        overrides=dict(parameters),
        duration=duration,
        runs=runs,
        orders=orders,
        pareto=pareto_front(runs),
        sweep_wall_time_s=_time.perf_counter() - started,
    )


def sweepable(
    scene: Scene, scenario: Scenario, params: dict[str, float] | None, model: mujoco.MjModel | None = None
) -> bool:
    """Whether the scenario has an exact reference trajectory to sweep errors against (scenarios
    validated by scalar checks alone, like the non-linear ones, have none)."""
    if not scenario.exact:
        return False
    if params is None:
        params = scene.resolve(scenario, {})
    model = scene.build(params, scenario) if model is None else model
    return scene.reference(model, params, scenario, np.zeros(1)) is not None


def _setup_or_none(scene: Scene, model, params, scenario, dt: float, duration: float) -> Setup | None:
    """The scenario's setup at dt [s], or None when the scene rejects that dt."""
    try:
        return scene.setup(model, params, scenario, check_timing(dt, duration), dt)
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
    log_dt, log_error = np.log([r.dt for r in points]), np.log([r.max_rel_error for r in points])
    slope, intercept = np.polyfit(log_dt, log_error, 1)
    if np.max(np.abs(log_error - (slope * log_dt + intercept))) > math.log(FIT_MAX_SCATTER):
        return None
    return float(slope)


def pareto_front(runs: Iterable[Run]) -> list[Run]:
    """Runs that no other run beats in both error and wall time, cheapest first (diverged runs excluded)."""
    candidates = sorted((r for r in runs if not r.diverged), key=lambda r: (r.wall_time_s, r.max_rel_error))
    front, best = [], math.inf
    for r in candidates:
        if r.max_rel_error < best:
            front.append(r)
            best = r.max_rel_error
    return front


# -- the recommendation ------------------------------------------------------------


def _candidates(result: Tradeoff, tol: float) -> list[tuple[float, str, float, bool]]:
    """(predicted wall time [s], integrator, dt [s], refined) settings expected to meet tol.

    Per integrator: its cheapest grid run within tol, and a larger dt predicted
    from that run's error and the integrator's order, err ~ dt^p, with margin
    REFINE_SAFETY, kept below the next larger grid dt (which failed).
    """
    out = []
    for name in dict.fromkeys(r.integrator for r in result.runs):
        runs = sorted((r for r in result.runs if r.integrator == name), key=lambda r: r.dt)
        passing = [r for r in runs if not r.diverged and r.max_rel_error <= tol]
        if not passing:
            continue
        grid = min(passing, key=lambda r: r.wall_time_s)
        out.append((grid.wall_time_s, name, grid.dt, False))
        larger = [r for r in runs if r.dt > grid.dt]
        order = result.orders.get(name)
        order = order if order is not None and abs(order - ORDERS[name]) <= 0.5 else ORDERS[name]
        if grid.max_rel_error > 0:
            predicted = grid.dt * (REFINE_SAFETY * tol / grid.max_rel_error) ** (1.0 / order)
        else:
            predicted = grid.dt
        ceiling = larger[0].dt if larger else 2 * grid.dt
        refined = round_down(min(predicted, ceiling * REFINE_SAFETY))
        if refined > grid.dt:
            steps = check_timing(refined, result.duration)
            out.append((grid.wall_time_s * steps / grid.steps, name, refined, True))
    return sorted(out)


def recommend(result: Tradeoff, tol: float, *, timing_repeats: int = 3) -> dict[str, Any]:
    """The cheapest (integrator, dt) meeting `tol`, verified by running it with `api.run`.

    Candidates come from the sweep (`_candidates`), cheapest predicted first;
    the first one whose verification run meets tol wins, and its error and
    wall time (measured as the sweep's) are reported.

    Args:
      result: a sweep of the scenario.
      tol: relative tolerance [-] on every compared column.

    Returns:
      {"tol", "integrator", "dt", "max_rel_error", "wall_time_s"}; integrator,
      dt, max_rel_error and wall_time_s are None when no setting of the sweep
      meets tol.
    """
    tol = compare.check_tolerance(tol)
    for _, name, dt, _refined in _candidates(result, tol):
        try:
            run = api.run(
                result.scene,
                result.scenario,
                integrator=name,
                dt=dt,
                duration=result.duration,
                tol=tol,
                **result.overrides,
            )
        except DivergedError:
            continue
        if not run.summary["passed"]:
            continue
        scene_obj = scenes.get(result.scene)
        chosen = scene_obj.scenario(result.scenario)
        steps = run.trajectory.steps
        job = Job(run.model, name, dt, steps, scene_obj.setup(run.model, run.parameters, chosen, steps, dt))
        error = max(e["max_rel"] for e in run.summary["errors"].values())
        return {
            "tol": tol,
            "integrator": name,
            "dt": dt,
            "max_rel_error": error,
            "wall_time_s": time_run(job, repeats=timing_repeats),
        }
    return {"tol": tol, "integrator": None, "dt": None, "max_rel_error": None, "wall_time_s": None}


def tradeoff(
    scene: str | Scene,
    scenario: str | None = None,
    *,
    tol: float | None = None,
    duration: float | None = None,
    **parameters: Any,
) -> Tradeoff:
    """`sweep` plus, with `tol` [-], the verified cheapest setting that meets it (`recommend`)."""
    if tol is not None:
        tol = compare.check_tolerance(tol)
    started = _time.perf_counter()
    result = sweep(scene, scenario, duration=duration, **parameters)
    if tol is not None:
        result.recommendation = recommend(result, tol)
    result.sweep_wall_time_s = _time.perf_counter() - started
    return result


def auto_setting(
    scene: str | Scene,
    scenario: str | None,
    *,
    tol: float | None,
    dt: float | None = None,
    duration: float | None = None,
    **parameters: Any,
) -> tuple[str, float]:
    """(integrator, dt [s]) for `integrator='auto'`: the verified cheapest setting meeting `tol`.

    Raises:
      BadInputError: no tol, a dt given (auto chooses it), or no setting meets tol.
    """
    if tol is None:
        raise BadInputError("integrator 'auto' needs tol, the relative error to meet (e.g. --tol 1e-6)")
    if dt is not None:
        raise BadInputError("integrator 'auto' chooses dt itself; drop dt (--dt) or name an integrator")
    result = tradeoff(scene, scenario, tol=tol, duration=duration, **parameters)
    pick = result.recommendation
    if pick["integrator"] is None:
        best = min((r for r in result.runs if not r.diverged), key=lambda r: r.max_rel_error, default=None)
        reach = (
            f"; the best reached is {best.max_rel_error:.2g} ({best.integrator}, dt = {best.dt:g} s)" if best else ""
        )
        raise BadInputError(
            f"no integrator and timestep of the sweep meets tol = {tol:g} on {result.scene}"
            f" {result.scenario}{reach}; valid: a tol it can reach"
        )
    return pick["integrator"], pick["dt"]


# -- the stability map ---------------------------------------------------------

#: damping ratios of the default boundary measurement (the contract needs 0, 0.1, 1, 10)
STABILITY_ZETAS = (0.0, 0.1, 0.5, 1.0, 2.0, 10.0)
#: with --full
FULL_STABILITY_ZETAS = (0.0, 0.01, 0.05, 0.1, 0.2, 0.5, 0.8, 1.0, 1.5, 2.0, 5.0, 10.0, 30.0, 100.0)
#: steps per growth test; growth test: max |z| over the second half > GROWTH_FACTOR x over the first half
GROWTH_STEPS = 1000
GROWTH_FACTOR = 2.0
#: boundary search: omega*dt from SEARCH_START, doubling up to SEARCH_STOP, then bisection to this ratio
SEARCH_START = 0.05
SEARCH_STOP = 1.0e4
SEARCH_PRECISION = 1.0e-4
#: measured boundaries must be within this relative distance of the theory
BOUNDARY_TOLERANCE = 0.02


def _oscillator(damping: float = 0.0) -> tuple[mujoco.MjModel, Scene, Scenario, dict[str, float]]:
    """The slider scene's model as a unit oscillator: m = 1 kg, k = 1 N/m (omega = 1 rad/s, omega*dt = dt)."""
    scene = scenes.get("slider")
    chosen = scene.scenario("free")
    params = scene.resolve(chosen, {"mass": 1.0, "stiffness": 1.0, "damping": damping, "x0": 1.0, "v0": 0.0})
    return scene.build(params, chosen), scene, chosen, params


class _GrowthTester:
    """Runs the unit oscillator (x0 = 1, v0 = 0) per (integrator, zeta) at given omega*dt, batched,
    and says whether its response grows (GROWTH_FACTOR over GROWTH_STEPS, or MuJoCo flags a blow-up)."""

    def __init__(self, pairs: Sequence[tuple[str, float]], steps: int, nthread: int = 0):
        self.model, *_ = _oscillator()
        self.steps = steps
        with quiet_mujoco():
            self.batch = _mjbatch.Batch(self.model, nsim=len(pairs), nthread=nthread)
            self.batch.expand("opt.integrator")[:] = [INTEGRATORS[name] for name, _ in pairs]
            self.batch.expand("dof_damping")[:] = [[2.0 * zeta] for _, zeta in pairs]
            self.timestep = self.batch.expand("opt.timestep")

    def grows(self, ids: np.ndarray, omega_dt: np.ndarray) -> np.ndarray:
        """Per simulation id: does the response grow at omega*dt (== dt [s] here)?"""
        batch, half = self.batch, self.steps // 2
        self.timestep[ids] = omega_dt
        batch.time[ids] = 0.0
        batch.qpos[ids] = 1.0
        batch.qvel[ids] = 0.0
        batch.warning[ids] = 0
        with quiet_mujoco():
            out = batch.rollout(self.steps, record=[_RECORD_SPEC], ids=ids)[_RECORD_SPEC]
        radius = np.hypot(out[:, :, 1], out[:, :, 2])  # |(omega x, v)| with omega = 1
        early = np.maximum(np.max(radius[:, :half], axis=1), 1.0)
        late = np.max(radius[:, half:], axis=1)
        flagged = np.array(batch.warning)[ids][:, BAD_WARNINGS, 1].sum(axis=1) > 0
        finite = np.isfinite(radius).all(axis=1)
        with np.errstate(invalid="ignore"):
            return flagged | ~finite | ~(late <= GROWTH_FACTOR * early)


def measure_boundaries(
    integrators: Iterable[str] = tuple(INTEGRATORS),
    zetas: Iterable[float] = STABILITY_ZETAS,
    *,
    steps: int = GROWTH_STEPS,
    nthread: int = 0,
) -> list[dict[str, Any]]:
    """Measured stability boundary omega*dt [-] per (integrator, zeta) against `simulate.stability_limit`.

    On the slider scene's model as a unit oscillator: starting at omega*dt =
    SEARCH_START, doubling until the response grows (GROWTH_FACTOR over
    `steps` steps, or MuJoCo flags a blow-up), then bisecting (geometrically)
    between the last stable and the first growing omega*dt down to a ratio of
    1 + SEARCH_PRECISION. All pairs advance together in one batch.

    Returns:
      Rows {"integrator", "zeta", "measured_omega_dt", "theory_omega_dt",
      "relative_difference", "within_tolerance"}; measured is inf when nothing
      grew up to SEARCH_STOP.
    """
    pairs = [(name, float(z)) for name in integrators for z in zetas]
    for name, zeta in pairs:
        integrator_id(name)
        if not (math.isfinite(zeta) and zeta >= 0):
            raise BadInputError(f"zeta must be a finite number >= 0, got {zeta!r}")
    tester = _GrowthTester(pairs, steps, nthread)
    n = len(pairs)
    low = np.zeros(n)  # largest omega*dt seen stable
    high = np.full(n, math.inf)  # smallest omega*dt seen growing
    probe = np.full(n, SEARCH_START)
    active = np.ones(n, bool)
    while active.any():
        ids = np.flatnonzero(active).astype(np.int32)
        grows = tester.grows(ids, probe[ids])
        for i, grew in zip(ids, grows):
            if grew:
                high[i] = probe[i]
            else:
                low[i] = probe[i]
            if math.isinf(high[i]):
                probe[i] = 2 * low[i]
                active[i] = probe[i] <= SEARCH_STOP
            elif low[i] == 0:
                probe[i] = high[i] / 2
            elif high[i] / low[i] > 1 + SEARCH_PRECISION:
                probe[i] = math.sqrt(low[i] * high[i])
            else:
                active[i] = False
    rows = []
    for i, (name, zeta) in enumerate(pairs):
        measured = math.sqrt(low[i] * high[i]) if math.isfinite(high[i]) else math.inf
        theory = stability_limit(name, zeta)
        if math.isinf(measured) and math.isinf(theory):
            difference = 0.0
        elif math.isinf(measured) or math.isinf(theory):
            difference = math.inf
        else:
            difference = abs(measured - theory) / theory
        rows.append(
            {
                "integrator": name,
                "zeta": zeta,
                "measured_omega_dt": measured,
                "theory_omega_dt": theory,
                "relative_difference": difference,
                "within_tolerance": difference <= BOUNDARY_TOLERANCE,
            }
        )
    return rows


def one_step_maps(integrator: str, zetas: np.ndarray, omega_dts: np.ndarray, *, nthread: int = 0) -> np.ndarray:
    """MuJoCo's one-step map of the unit oscillator, measured: (len(zetas), len(omega_dts), 2, 2).

    Column j is the state after one step from the unit state e_j = (x, v), so
    z_{n+1} = M z_n exactly for this linear system.
    """
    model, *_ = _oscillator()
    zz, hh = np.meshgrid(np.asarray(zetas, float), np.asarray(omega_dts, float), indexing="ij")
    cells = zz.size
    with quiet_mujoco():
        batch = _mjbatch.Batch(model, nsim=2 * cells, nthread=nthread)
        batch.expand("opt.integrator")[:] = INTEGRATORS[integrator]
        batch.expand("dof_damping")[:] = np.repeat(2.0 * zz.ravel(), 2)[:, None]
        batch.expand("opt.timestep")[:] = np.repeat(hh.ravel(), 2)
        batch.qpos[:] = np.tile([[1.0], [0.0]], (cells, 1))
        batch.qvel[:] = np.tile([[0.0], [1.0]], (cells, 1))
        batch.step()
        after = np.column_stack([batch.qpos[:, 0], batch.qvel[:, 0]]).reshape(cells, 2, 2)
    return after.transpose(0, 2, 1).reshape(*zz.shape, 2, 2)


def amplification_map(
    integrators: Iterable[str] = tuple(INTEGRATORS),
    zetas: np.ndarray | None = None,
    omega_dts: np.ndarray | None = None,
) -> dict[str, Any]:
    """Spectral radius [-] of MuJoCo's measured one-step map over a (zeta, omega*dt) grid, per integrator.

    > 1 means the response grows by that factor per step (unstable). Returns
    {"zetas", "omega_dts", "radius": integrator -> (len(zetas), len(omega_dts))}.
    """
    zetas = np.concatenate([[0.0], np.geomspace(1e-2, 100.0, 40)]) if zetas is None else np.asarray(zetas)
    omega_dts = np.geomspace(1e-2, 1e3, 120) if omega_dts is None else np.asarray(omega_dts)
    radius = {}
    for name in integrators:
        maps = one_step_maps(name, zetas, omega_dts)
        radius[name] = np.max(np.abs(np.linalg.eigvals(maps)), axis=-1)
    return {"zetas": zetas, "omega_dts": omega_dts, "radius": radius}


# -- the extremes ----------------------------------------------------------------

#: a run is "accurate" within this max relative error [-]
ACCURACY = 1e-2
#: timesteps of the extremes table, as fractions of each integrator's stability limit
LIMIT_FRACTIONS = (0.5, 0.99, 1.01)
#: every extremes run takes at least this many steps (so an instability shows) and at most MAX_EXTREME_STEPS
MIN_EXTREME_STEPS = 2000
MAX_EXTREME_STEPS = 70_000
#: an advised setting is run (its row added) when it takes at most this many steps; --full: always
VERIFY_STEPS = 200_000
#: MuJoCo treats |qpos|, |qvel| or |qacc| beyond this as a blow-up and resets (mjMAXVAL in mjtype.h)
MUJOCO_MAXVAL = 1e10
#: integrators the advice chooses from (euler and implicit equal implicitfast on these scenes)
ADVICE_INTEGRATORS = ("rk4", "implicitfast", "discrete")
#: steps per integrator of the quick cost calibration behind the advice
_CALIBRATION_STEPS = 2000


@dataclasses.dataclass(frozen=True)
class ExtremeCase:
    """A slider at an extreme: mass [kg], stiffness [N/m], damping ratio [-], released from x0 [m] at rest.

    duration_periods: simulated time in natural periods 2 pi / omega, or None to use
    `slow_time_constants` time constants of the slow root (overdamped cases). The
    motion is linear, so x0 only scales it; it is chosen to keep the peak
    acceleration omega^2 x0 well inside MuJoCo's 1e10 limit, except in the case
    that shows that limit.
    """

    name: str
    description: str
    mass: float
    stiffness: float
    zeta: float
    x0: float = 0.1
    duration_periods: float | None = None
    slow_time_constants: float | None = None

    @property
    def omega(self) -> float:
        """Natural frequency [rad/s]."""
        return math.sqrt(self.stiffness / self.mass)

    @property
    def damping(self) -> float:
        """Damping coefficient [N s/m]."""
        return 2.0 * self.zeta * math.sqrt(self.stiffness * self.mass)

    @property
    def duration(self) -> float:
        """Simulated time [s] the case asks for."""
        if self.duration_periods is not None:
            return self.duration_periods * 2 * math.pi / self.omega
        slow = self.omega * (self.zeta - math.sqrt(self.zeta**2 - 1)) if self.zeta > 1 else self.omega * self.zeta
        return self.slow_time_constants / slow

    @property
    def peak_acceleration(self) -> float:
        """omega^2 x0 [m/s^2], the acceleration at release."""
        return self.omega**2 * abs(self.x0)


EXTREME_CASES = (
    ExtremeCase(
        "stiff",
        "k = 1e12 N/m, m = 1 kg, zeta = 0.05, x0 = 1e-5 m, 20 periods",
        1.0,
        1e12,
        0.05,
        x0=1e-5,
        duration_periods=20,
    ),
    ExtremeCase(
        "stiff-large-x0",
        "k = 1e12 N/m, m = 1 kg, zeta = 0.05, x0 = 0.1 m: |qacc| = 1e11 m/s^2",
        1.0,
        1e12,
        0.05,
        x0=0.1,
        duration_periods=20,
    ),
    ExtremeCase(
        "light",
        "m = 1e-9 kg, k = 100 N/m, zeta = 0.05, x0 = 1e-4 m, 20 periods",
        1e-9,
        100.0,
        0.05,
        x0=1e-4,
        duration_periods=20,
    ),
    ExtremeCase(
        "undamped-long",
        "m = 1 kg, k = 100 N/m, zeta = 0, x0 = 0.1 m, 1e4 periods",
        1.0,
        100.0,
        0.0,
        duration_periods=1e4,
    ),
    ExtremeCase(
        "overdamped",
        "m = 1 kg, k = 100 N/m, zeta = 1e4, x0 = 0.1 m, 3 slow time constants",
        1.0,
        100.0,
        1e4,
        slow_time_constants=3,
    ),
)
FULL_EXTREME_CASES = EXTREME_CASES + (
    ExtremeCase(
        "stiff-1e6",
        "k = 1e6 N/m, m = 1 kg, zeta = 0.05, x0 = 1e-3 m, 20 periods",
        1.0,
        1e6,
        0.05,
        x0=1e-3,
        duration_periods=20,
    ),
    ExtremeCase(
        "light-1e-5",
        "m = 1e-5 kg, k = 100 N/m, zeta = 0.05, x0 = 0.01 m, 20 periods",
        1e-5,
        100.0,
        0.05,
        x0=0.01,
        duration_periods=20,
    ),
    ExtremeCase(
        "overdamped-100",
        "m = 1 kg, k = 100 N/m, zeta = 100, x0 = 0.1 m, 3 slow time constants",
        1.0,
        100.0,
        100.0,
        slow_time_constants=3,
    ),
)


def _case_model(case: ExtremeCase) -> tuple[mujoco.MjModel, Scene, Scenario, dict[str, float]]:
    scene = scenes.get("slider")
    chosen = scene.scenario("free")
    params = scene.resolve(
        chosen, {"mass": case.mass, "stiffness": case.stiffness, "damping": case.damping, "x0": case.x0, "v0": 0.0}
    )
    return scene.build(params, chosen), scene, chosen, params


def _sample_steps(steps: int, count: int = 2000) -> np.ndarray:
    """Step indices in [0, steps] to evaluate a long run at: dense early, quasi-random (no aliasing with
    the motion's period), and the last step."""
    golden = (np.arange(1, count + 1) * 0.6180339887498949) % 1.0
    early = np.arange(min(steps, 200) + 1)
    picks = np.concatenate([early, np.floor(golden * steps), np.geomspace(1, max(steps, 1), 400).round(), [steps]])
    return np.unique(picks.astype(np.int64))


def predicted_error(case: ExtremeCase, integrator: str, dt: float, context) -> float:
    """Max relative error [-] of a run of `case`, from MuJoCo's measured one-step map.

    The slider is linear, so a run is z_n = M^n z_0 exactly, with M measured
    by stepping the case's own model once from two independent states. The
    error against the exact reference is taken over `_sample_steps` of the run,
    as max |sim - ref| / max |ref| per column (pos, vel); cheap for any length.
    """
    model, scene, chosen, params = context
    steps = max(1, round(case.duration / dt))
    work = copy.copy(model)
    work.opt.integrator = INTEGRATORS[integrator]
    work.opt.timestep = dt
    data = mujoco.MjData(work)
    columns = []
    scale = (case.x0, case.omega * case.x0)  # unit states scaled to the case's amplitude (MuJoCo's range)
    with quiet_mujoco():
        for j in range(2):
            mujoco.mj_resetData(work, data)
            data.qpos[0], data.qvel[0] = (scale[0], 0.0) if j == 0 else (0.0, scale[1])
            mujoco.mj_step(work, data)
            columns.append(np.array([data.qpos[0], data.qvel[0]]) / scale[j])
    one_step = np.column_stack(columns)
    values, vectors = np.linalg.eig(one_step)
    n = _sample_steps(steps)
    coefficients = np.linalg.solve(vectors, np.array([case.x0, 0.0], complex))
    with np.errstate(over="ignore", invalid="ignore"):
        powers = values[None, :] ** n[:, None]
        states = ((vectors[None, :, :] * (powers * coefficients[None, :])[:, None, :]).sum(-1)).real
    if not np.isfinite(states).all():
        return math.inf
    reference = scene.reference(model, params, chosen, n * dt)
    errors = []
    for k, series in ((0, reference.pos["slider"]), (1, reference.vel["slider"])):
        peak = float(np.max(np.abs(series)))
        errors.append(float(np.max(np.abs(states[:, k] - series))) / peak if peak > 0 else 0.0)
    return max(errors)


def _advice(case: ExtremeCase, context, costs: dict[str, float]) -> dict[str, Any]:
    """The cheapest setting predicted (`predicted_error`) to hold ACCURACY/2 over the case's duration.

    Per integrator of ADVICE_INTEGRATORS: the largest dt (bisection in log dt,
    at most 0.9x its stability limit) whose predicted error is within half the
    accuracy threshold; cost = steps x the measured cost per step. For a case
    beyond MuJoCo's value limit no dt helps, and the advice says so.
    """
    if case.peak_acceleration >= MUJOCO_MAXVAL or case.omega * abs(case.x0) >= MUJOCO_MAXVAL:
        return {
            "integrator": None,
            "dt": None,
            "steps": None,
            "predicted_error": None,
            "phrase": (
                f"no dt helps: MuJoCo resets any |qacc| > {MUJOCO_MAXVAL:.0e} m/s^2 (mjMAXVAL), and"
                f" omega^2 x0 = {case.peak_acceleration:.1e}; rescale units or amplitude"
            ),
        }
    best = None
    target = ACCURACY / 2
    for name in ADVICE_INTEGRATORS:
        high = min(0.9 * _limit(name, case.zeta) / case.omega, case.duration / 10)
        low = case.duration / 1e12
        if predicted_error(case, name, high, context) <= target:
            dt = high
        else:
            for _ in range(16):  # 12 decades to within 2 %
                mid = math.sqrt(low * high)
                if predicted_error(case, name, mid, context) <= target:
                    low = mid
                else:
                    high = mid
            dt = low
        dt = round_down(dt)
        steps = max(1, round(case.duration / dt))
        cost = steps * costs[name]
        if best is None or cost < best["cost_s"]:
            best = {
                "integrator": name,
                "dt": dt,
                "steps": steps,
                "cost_s": cost,
                "predicted_error": predicted_error(case, name, dt, context),
            }
    best["phrase"] = (
        f"use {best['integrator']} with dt <= {best['dt']:.2g} s ({best['steps']:.2g} steps,"
        f" predicted error {best['predicted_error']:.1g})"
    )
    return best


def extremes_table(
    cases: Sequence[ExtremeCase] = EXTREME_CASES, *, verify_steps: int = VERIFY_STEPS, nthread: int = 0
) -> list[dict[str, Any]]:
    """Run every case x integrator at LIMIT_FRACTIONS of its stability limit; classify each run.

    discrete has no limit: its rows use the euler limit's fractions, to show it
    stays stable where the others do not. Durations: the case's, stretched to
    MIN_EXTREME_STEPS steps and cut at MAX_EXTREME_STEPS (each row says its own).
    Each case also gets a row for its advised setting (`_advice`), run in full
    over the case's duration when it takes at most `verify_steps` steps.

    Returns:
      One row per run: kind ('limit' or 'advised'), case, description,
      integrator, fraction (of limit_of's stability limit; None for advised
      rows), limit_of, omega_dt, limit_omega_dt, dt, duration, steps, outcome
      ('accurate' | 'inaccurate' | 'diverged'), max_rel_error (None if
      diverged), detail (how it diverged), advice (one phrase: which
      integrator and dt to use instead).
    """
    jobs, meta = [], []
    contexts = {}
    for case in cases:
        context = _case_model(case)
        model, scene, chosen, params = context
        contexts[case.name] = context
        for name in INTEGRATORS:
            limit_name = "euler" if name == "discrete" else name
            limit = _limit(limit_name, case.zeta)
            for fraction in LIMIT_FRACTIONS:
                dt = fraction * limit / case.omega
                steps = min(max(round(case.duration / dt), MIN_EXTREME_STEPS), MAX_EXTREME_STEPS)
                setup = scene.setup(model, params, chosen, steps, dt)
                jobs.append(Job(model, name, dt, steps, setup))
                meta.append(("limit", case, name, fraction, limit, limit_name))
    costs = {}
    model, scene, chosen, params = contexts[cases[0].name]
    for name in ADVICE_INTEGRATORS:  # cost per step: the same for every case (one model structure)
        setup = scene.setup(model, params, chosen, _CALIBRATION_STEPS, 1e-3)
        calm = copy.copy(model)  # a calm model for timing: unit oscillator values, no MuJoCo resets
        calm.body_mass[:] = 1.0
        calm.jnt_stiffness[:] = 1.0
        calm.dof_damping[:] = 0.1
        costs[name] = time_run(Job(calm, name, 1e-3, _CALIBRATION_STEPS, setup)) / _CALIBRATION_STEPS
    advice = {case.name: _advice(case, contexts[case.name], costs) for case in cases}
    for case in cases:
        pick = advice[case.name]
        if pick["integrator"] is None or pick["steps"] > verify_steps:
            continue
        model, scene, chosen, params = contexts[case.name]
        setup = scene.setup(model, params, chosen, pick["steps"], pick["dt"])
        jobs.append(Job(model, pick["integrator"], pick["dt"], pick["steps"], setup))
        meta.append(
            ("advised", case, pick["integrator"], None, _limit(pick["integrator"], case.zeta), pick["integrator"])
        )
    outcomes = run_batched(jobs, nthread=nthread)
    rows = []
    for job, outcome, (kind, case, name, fraction, limit, limit_name) in zip(jobs, outcomes, meta):
        outcome_name, error, detail = _classify(*contexts[case.name], outcome)
        pick = advice[case.name]
        if kind == "advised":
            phrase = f"the advice, run over the whole {case.duration:.3g} s"
        else:
            phrase = _advice_phrase(outcome_name, name, job.dt, limit, pick)
        rows.append(
            {
                "kind": kind,
                "case": case.name,
                "description": case.description,
                "integrator": name,
                "fraction": fraction,
                "limit_of": limit_name,
                "omega_dt": job.dt * case.omega,
                "limit_omega_dt": limit,
                "dt": job.dt,
                "duration": job.dt * job.steps,
                "steps": job.steps,
                "outcome": outcome_name,
                "max_rel_error": error,
                "detail": detail,
                "advice": phrase,
            }
        )
    return rows


def _classify(model, scene, chosen, params, outcome) -> tuple[str, float | None, str]:
    """('accurate' | 'inaccurate' | 'diverged', max relative error or None, divergence detail)."""
    if isinstance(outcome, DivergedError):
        return "diverged", None, str(outcome)
    try:
        result = api.evaluate(scene, chosen, params, model, outcome)
    except DivergedError as error:
        return "diverged", None, str(error)
    error = max(e["max_rel"] for e in result.summary["errors"].values())
    return ("accurate" if error <= ACCURACY else "inaccurate"), error, ""


def _advice_phrase(outcome: str, integrator: str, dt: float, limit: float, pick: dict) -> str:
    if pick["integrator"] is None:
        return pick["phrase"]
    if outcome == "diverged":
        return f"unstable past omega*dt = {limit:.3g}: {pick['phrase']}"
    if outcome == "inaccurate":
        return f"stable but too coarse: {pick['phrase']}"
    if pick["integrator"] == integrator and pick["dt"] <= dt * 1.0001:
        return "fine as is"
    return f"fine; cheapest for {ACCURACY:.0%}: {pick['phrase']}"


# -- the energy ----------------------------------------------------------------

#: the integrators that share MuJoCo's semi-implicit Euler map on these scenes
EULER_FAMILY = ("euler", "implicit", "implicitfast")
#: omega*dt and length of the energy runs
ENERGY_OMEGA_DT = 0.2
ENERGY_PERIODS = 200


def energy_formula(
    integrator: str, omega_dt: float, steps: np.ndarray, x0: float = 1.0, v0: float = 0.0, omega: float = 1.0
) -> dict[str, np.ndarray | float]:
    """The exact energy of each integrator's undamped step map, E_n / E_0 [-].

    euler, implicit, implicitfast (symplectic Euler): I = v^2 + omega^2 x^2 -
    dt omega^2 x v is invariant, so E_n/E_0 lies in [I/(2(1 + y/2)),
    I/(2(1 - y/2))] / E_0 (y = omega*dt, E per unit mass) and reaches both
    ends; returns "low", "high" (for x0 != 0, v0 = 0: 1/(1 + y/2), 1/(1 - y/2)).
    rk4: "ratio" = (1 - y^6/72 + y^8/576)^n. discrete: "ratio" = (1 + y^2)^-n.
    """
    y = omega_dt
    steps = np.asarray(steps, float)
    if integrator in EULER_FAMILY:
        energy0 = 0.5 * (v0**2 + omega**2 * x0**2)
        invariant = v0**2 + omega**2 * x0**2 - y * omega * x0 * v0
        return {"low": invariant / (2 * (1 + y / 2)) / energy0, "high": invariant / (2 * (1 - y / 2)) / energy0}
    if integrator == "rk4":
        return {"ratio": (1 - y**6 / 72 + y**8 / 576) ** steps}
    if integrator == "discrete":
        return {"ratio": (1 + y * y) ** -steps}
    raise BadInputError(f"unknown integrator {integrator!r}; valid: {', '.join(INTEGRATORS)}")


def energy_histories(
    omega_dt: float = ENERGY_OMEGA_DT, periods: float = ENERGY_PERIODS, *, nthread: int = 0
) -> dict[str, Any]:
    """Energy of every integrator on the undamped slider (scenario `undamped`) against its formula.

    The energy E = m v^2/2 + k x^2/2 [J] is computed from qpos and qvel
    (MuJoCo's data.energy lags a step). Returns {"omega_dt", "periods",
    "time_periods": (n,), "ratio": integrator -> E_n/E_0 (n,), "rows": per
    integrator a summary with the formula and its largest deviation}.
    """
    scene = scenes.get("slider")
    chosen = scene.scenario("undamped")
    params = scene.resolve(chosen, {})
    model = scene.build(params, chosen)
    m, k, _ = scene.physical(model)
    omega = math.sqrt(k / m)
    dt = omega_dt / omega
    steps = round(periods * 2 * math.pi / omega_dt)
    setup = scene.setup(model, params, chosen, steps, dt)
    jobs = [Job(model, name, dt, steps, setup) for name in INTEGRATORS]
    outcomes = run_batched(jobs, nthread=nthread)
    x0, v0 = params["x0"], params["v0"]
    energy0 = 0.5 * m * v0**2 + 0.5 * k * x0**2
    n = np.arange(steps + 1)
    ratio, rows = {}, []
    for name, trajectory in zip(INTEGRATORS, outcomes):
        if isinstance(trajectory, DivergedError):
            raise trajectory
        x, v = trajectory.qpos[:, 0], trajectory.qvel[:, 0]
        energy = 0.5 * m * v**2 + 0.5 * k * x**2
        ratio[name] = energy / energy0
        formula = energy_formula(name, omega_dt, n, x0, v0, omega)
        row = {
            "integrator": name,
            "omega_dt": omega_dt,
            "steps": steps,
            "final_ratio": float(ratio[name][-1]),
            "min_ratio": float(ratio[name].min()),
            "max_ratio": float(ratio[name].max()),
        }
        if "ratio" in formula:
            row["formula"] = "(1 - y^6/72 + y^8/576)^n" if name == "rk4" else "(1 + y^2)^-n"
            row["formula_final_ratio"] = float(formula["ratio"][-1])
            row["max_relative_deviation"] = float(np.max(np.abs(ratio[name] / formula["ratio"] - 1)))
        else:
            invariant = (v**2 + omega**2 * x**2 - dt * omega**2 * x * v) / (
                v0**2 + omega**2 * x0**2 - dt * omega**2 * x0 * v0
            )
            row["formula"] = "E/E0 in [1/(1 + y/2), 1/(1 - y/2)] (invariant v^2 + w^2 x^2 - dt w^2 x v)"
            row["formula_low"], row["formula_high"] = float(formula["low"]), float(formula["high"])
            row["max_relative_deviation"] = float(np.max(np.abs(invariant - 1)))
        rows.append(row)
    return {
        "omega_dt": omega_dt,
        "periods": periods,
        "time_periods": n * omega_dt / (2 * math.pi),
        "ratio": ratio,
        "rows": rows,
    }


def stability_report(*, full: bool = False, nthread: int = 0) -> dict[str, Any]:
    """Boundaries, extremes and energy: `springlab stability`'s JSON (plus the map and energy series).

    full: more damping ratios, more extreme cases, and the advice of every
    extremes case run in full, however many steps it takes (slower: tens of seconds).
    """
    started = _time.perf_counter()
    boundaries = measure_boundaries(zetas=FULL_STABILITY_ZETAS if full else STABILITY_ZETAS, nthread=nthread)
    extremes = extremes_table(
        FULL_EXTREME_CASES if full else EXTREME_CASES, verify_steps=10**9 if full else VERIFY_STEPS, nthread=nthread
    )
    energy = energy_histories(nthread=nthread)
    return {
        "boundaries": boundaries,
        "extremes": extremes,
        "energy": energy["rows"],
        "growth_test": (
            f"response |(omega x, v)| over steps {GROWTH_STEPS // 2}..{GROWTH_STEPS} exceeds"
            f" {GROWTH_FACTOR:g}x its maximum over the first {GROWTH_STEPS // 2}, or MuJoCo flags"
            " a blow-up"
        ),
        "accuracy_threshold": ACCURACY,
        "wall_time_s": _time.perf_counter() - started,
        "_energy_series": energy,
    }


def report_json(report: dict[str, Any]) -> dict[str, Any]:
    """The report without its plot-only series."""
    return {k: v for k, v in report.items() if not k.startswith("_")}


# -- tradeoff_plots --------------------------------------------------------------

_COLORS = {
    "euler": "#1f77b4",
    "implicit": "#17becf",
    "implicitfast": "#2ca02c",
    "rk4": "#d62728",
    "discrete": "#9467bd",
}
_STYLES = {"euler": "-", "implicit": "--", "implicitfast": ":", "rk4": "-", "discrete": "-"}


def _figure(ncols: int, figsize: tuple[float, float], **options):
    """A bare matplotlib Figure and its axes: no pyplot, so a caller's backend and figures stay untouched."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout=options.pop("layout", None))
    return fig, fig.subplots(1, ncols, **options)


def _save(fig, path: str | pathlib.Path) -> pathlib.Path:
    path = pathlib.Path(path)
    outputs.prepare_directory(path.parent)
    with outputs.atomic_path(path) as temporary:
        fig.savefig(temporary, dpi=110, format="png")
    return path


def plot_tradeoff(result: Tradeoff, path: str | pathlib.Path) -> pathlib.Path:
    """Two log-log panels: error vs dt (with the observed orders) and error vs wall time (Pareto front)."""
    fig, (left, right) = _figure(2, (12, 5))
    diverged = sum(r.diverged for r in result.runs)
    floor = 1e-17
    for name in dict.fromkeys(r.integrator for r in result.runs):
        runs = [r for r in result.runs if r.integrator == name and not r.diverged]
        if not runs:
            continue
        order = result.orders.get(name)
        label = f"{name} (order {order:.2f})" if order is not None else name
        errors = [max(r.max_rel_error, floor) for r in runs]
        left.loglog([r.dt for r in runs], errors, _STYLES[name], marker="o", ms=3, color=_COLORS[name], label=label)
        right.loglog(
            [r.wall_time_s for r in runs], errors, _STYLES[name], marker="o", ms=3, color=_COLORS[name], label=name
        )
    front = result.pareto
    right.step(
        [r.wall_time_s for r in front],
        [max(r.max_rel_error, floor) for r in front],
        where="post",
        color="black",
        lw=1.2,
        alpha=0.7,
        label="Pareto front",
    )
    pick = result.recommendation
    if pick and pick.get("integrator"):
        right.axhline(pick["tol"], color="gray", lw=0.8, ls="--")
        right.plot(
            [pick["wall_time_s"]],
            [max(pick["max_rel_error"], floor)],
            "*",
            ms=14,
            color="gold",
            markeredgecolor="black",
            label=f"tol {pick['tol']:g}: {pick['integrator']}, dt = {pick['dt']:g} s",
        )
    left.set_xlabel("timestep dt [s]")
    left.set_ylabel("max relative error [-]")
    left.set_title("error vs timestep (slope = order)")
    right.set_xlabel("wall time of the run [s]")
    right.set_ylabel("max relative error [-]")
    right.set_title("error vs cost")
    for axis in (left, right):
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=8)
    note = f"; {diverged} diverged runs not shown" if diverged else ""
    fig.suptitle(f"{result.scene} / {result.scenario}: {len(result.runs)} runs over {result.duration:g} s{note}")
    fig.tight_layout()
    return _save(fig, path)


def plot_stability(
    report: dict[str, Any], path: str | pathlib.Path, amplification: dict[str, Any] | None = None
) -> pathlib.Path:
    """Per integrator: measured per-step amplification over (zeta, omega*dt), theory boundary, measured boundary."""
    from matplotlib.colors import TwoSlopeNorm

    amplification = amplification_map() if amplification is None else amplification
    zetas, omega_dts = amplification["zetas"], amplification["omega_dts"]
    names = list(amplification["radius"])
    fig, axes = _figure(len(names), (3.4 * len(names) + 1.5, 4.4), sharey=True, layout="constrained")
    axes = np.atleast_1d(axes)
    norm = TwoSlopeNorm(vmin=-3.0, vcenter=0.0, vmax=3.0)
    theory_zetas = np.concatenate([[0.0], np.geomspace(1e-2, 100.0, 200)])
    image = None
    for axis, name in zip(axes, names):
        log_radius = np.log10(np.clip(amplification["radius"][name], 1e-300, None))
        image = axis.pcolormesh(
            zetas, omega_dts, np.clip(log_radius, -3, 3).T, cmap="RdBu_r", norm=norm, shading="nearest"
        )
        theory = [stability_limit(name, z) for z in theory_zetas]
        if all(math.isinf(t) for t in theory):
            axis.text(0.5, 0.5, "no limit: never unstable", transform=axis.transAxes, ha="center", fontsize=9)
        else:
            axis.plot(theory_zetas, theory, color="black", lw=1.2, label="theory")
        rows = [r for r in report["boundaries"] if r["integrator"] == name and math.isfinite(r["measured_omega_dt"])]
        axis.plot(
            [r["zeta"] for r in rows],
            [r["measured_omega_dt"] for r in rows],
            "o",
            mfc="none",
            color="gold",
            mew=1.5,
            label="measured (growth test)",
        )
        axis.set_xscale("symlog", linthresh=0.01)
        axis.set_yscale("log")
        axis.set_ylim(omega_dts[0], omega_dts[-1])
        axis.set_xlabel("damping ratio zeta [-]")
        axis.set_title(name)
        axis.legend(fontsize=7, loc="upper left")
    axes[0].set_ylabel("omega * dt [-]")
    fig.colorbar(image, ax=list(axes), label="log10 per-step amplification (> 0: grows)", shrink=0.85)
    fig.suptitle("stability map: MuJoCo's measured one-step amplification, theory (line), measured boundary (o)")
    return _save(fig, path)


def plot_energy(series: dict[str, Any], path: str | pathlib.Path) -> pathlib.Path:
    """E/E0 over time of every integrator on the undamped slider, each against its exact formula."""
    fig, (euler, rk4, discrete) = _figure(3, (15, 4.4))
    t = series["time_periods"]
    y = series["omega_dt"]
    n = np.arange(len(t))
    first = t <= 3.0
    for name in EULER_FAMILY:
        euler.plot(t[first], series["ratio"][name][first] - 1, _STYLES[name], color=_COLORS[name], lw=1.2, label=name)
    euler.axhline(1 / (1 - y / 2) - 1, color="black", lw=0.8, ls="--", label="1/(1 - y/2) - 1 (sharp bound)")
    euler.axhline(1 / (1 + y / 2) - 1, color="black", lw=0.8, ls=":", label="1/(1 + y/2) - 1")
    euler.set_title("euler family: bounded oscillation (first 3 periods)")
    stride = max(1, len(t) // 4000)
    rk4.plot(t[::stride], series["ratio"]["rk4"][::stride] - 1, color=_COLORS["rk4"], lw=2.5, alpha=0.6, label="rk4")
    rk4.plot(
        t,
        energy_formula("rk4", y, n)["ratio"] - 1,
        color="black",
        lw=0.8,
        ls="--",
        label="(1 - y^6/72 + y^8/576)^n - 1",
    )
    rk4.set_title("rk4: slow decay")
    discrete.semilogy(
        t[::stride],
        series["ratio"]["discrete"][::stride],
        color=_COLORS["discrete"],
        lw=2.5,
        alpha=0.6,
        label="discrete",
    )
    discrete.semilogy(
        t, energy_formula("discrete", y, n)["ratio"], color="black", lw=0.8, ls="--", label="(1 + y^2)^-n"
    )
    discrete.set_title("discrete: decay by 1/(1 + y^2) per step")
    euler.set_ylabel("E/E0 - 1 [-]")
    rk4.set_ylabel("E/E0 - 1 [-]")
    discrete.set_ylabel("E/E0 [-]")
    for axis in (euler, rk4, discrete):
        axis.set_xlabel("time [periods]")
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    fig.suptitle(f"undamped slider, omega*dt = y = {y:g}: energy from qpos/qvel vs each step map's exact formula")
    fig.tight_layout()
    return _save(fig, path)


def write_tradeoff(result: Tradeoff, directory: str | pathlib.Path) -> list[pathlib.Path]:
    """Write DIR/tradeoff.json and DIR/tradeoff.png."""
    written = outputs.write_text_files(directory, {"tradeoff.json": outputs.dumps(result.as_json()) + "\n"})
    written.append(plot_tradeoff(result, pathlib.Path(directory) / "tradeoff.png"))
    return written


def write_stability(report: dict[str, Any], directory: str | pathlib.Path) -> list[pathlib.Path]:
    """Write DIR/stability.json, DIR/stability.png (map) and DIR/energy.png."""
    written = outputs.write_text_files(directory, {"stability.json": outputs.dumps(report_json(report)) + "\n"})
    written.append(plot_stability(report, pathlib.Path(directory) / "stability.png"))
    written.append(plot_energy(report["_energy_series"], pathlib.Path(directory) / "energy.png"))
    return written
