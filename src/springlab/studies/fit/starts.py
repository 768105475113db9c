"""Multi-start fits: several independent optimizations of one record, the best final cost wins.

A least-squares fit of a ring-down is not convex in the frequency: a start
far from the true omega_n can stop in a local minimum that matches a few
cycles and misses the rest. `fit(..., starts=N)` therefore runs N independent
`sysid.optimize` calls and keeps the one with the lowest final cost:

* start 1 is the single fit's own start (linear prediction and linear least
  squares, springlab.studies.fit.models), so `starts=1` is exactly the single fit;
* starts 2..N spread the *nonlinear* free names (omega_n, zeta, mass,
  stiffness, damping, delay) over the box bounds of start 1 (less the 1e-3 of
  the range at each end that sysid keeps a start off a bound) with a scrambled
  Sobol sequence of fixed seed (`SEED`): log-uniform where the bounds are
  positive and span a decade or more (a stiffness from k/100 to 100 k),
  uniform otherwise (a damping ratio from 0). The names that enter the
  response linearly (x0, v0, offset) keep start 1's values: Levenberg-Marquardt
  sets them in its first step wherever the nonlinear ones start.

Each start is one chunk on springlab's Executor (springlab.studies.executor): the
payload is plain data (`StartChunk`: scene and scenario names, the scene's parameters, the
record, the start's values, the bounds, the grid) and `run_start`
rebuilds the scene's MjSpec on whichever process runs it. Every start runs on
the same simulation grid so the final costs compare like for like: start 1's
grid (chosen for the fit's accuracy at its values, springlab.studies.fit.engine), made finer where needed
so that RK4 stays stable at the fastest pole anywhere in the box (|s| dt <= `engine.STABLE_RATE_DT`;
RK4's real-axis limit is 2.785), because the optimizer may step to any corner;
the winner is the first start whose cost is within 0.01 / dof (relative) of the
lowest: statistically the same point (`SAME_IN_SE` below, since a cost excess of
d^2 / dof relative is a Mahalanobis distance of d standard errors), so start 1
wins whenever it found the minimum (then `starts=N` equals the single fit up to
the RK4 bias of a finer grid, < 1e-7 relative). The result is the same bit for
bit locally and on a dask cluster: same chunks, same code, the choice made in
the caller over the results in start order.

A start *reached the best minimum* when every free name lies within
`SAME_IN_SE` of its standard error of the best start's estimate (statistically
the same point: a tenth of what the record can resolve), or within
`SAME_RELATIVE` of the optimizer's scale of the name when the record is exact
and the standard error vanishes (the accuracy an exact record is fitted to).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from springlab import scenes
from springlab.errors import BadInputError, DivergedError
from springlab.studies.executor import Executor, resolve
from springlab.studies.fit import data as fit_data

from .engine import Problem, residual_rms, solve
from .models import model_of

#: free names that enter the response linearly: they keep start 1's values in every start
LINEAR = ("x0", "v0", "offset", "a0", "jerk")
#: seed of the scrambled Sobol sequence of starts 2..N (fixed: the same starts every time)
SEED = 20260513
#: a start at the best minimum lies within this many standard errors of the best estimate [-]
SAME_IN_SE = 0.1
#: ... or within this fraction of the optimizer's scale of a name (exact records, standard error ~ 0) [-]
SAME_RELATIVE = 1e-6
#: bounds spanning at least this ratio (and positive) are sampled log-uniformly
LOG_SPAN = 10.0


def check_count(starts: Any) -> int:
    """`starts` as an int >= 1, or BadInputError (exit 2)."""
    if isinstance(starts, bool) or not isinstance(starts, (int, np.integer)) or starts < 1:
        raise BadInputError(f"--starts must be an integer >= 1 (1: the single linear-algebra start), got {starts!r}")
    return int(starts)


def nonlinear(free: list[str]) -> list[str]:
    """The free names the starts spread (those not entering the response linearly)."""
    return [name for name in free if name not in LINEAR]


def check_spreadable(free: list[str], starts: int) -> None:
    """BadInputError when several starts are asked of a fit that is linear in every free name."""
    if starts > 1 and not nonlinear(free):
        raise BadInputError(
            f"--starts {starts}: {', '.join(free)} enter the record linearly, so the single start is already"
            " the unique minimum; free a nonlinear name (omega_n, zeta, stiffness, damping, mass, delay) or drop --starts"
        )


def sample(start: dict[str, float], bounds: dict[str, tuple[float, float]], free: list[str], count: int) -> list:
    """`count` start dicts: `start` first, then scrambled Sobol points over the nonlinear names' bounds.

    Parameters
    ----------
    start
        every fit name's value at start 1 (SI).
    bounds
        free name -> (low, high) box bounds [the name's unit].
    free
        the fitted names.
    count
        number of starts (>= 1).
    """
    starts = [dict(start)]
    names = nonlinear(free)
    if count == 1 or not names:
        return starts
    from scipy.stats import qmc  # here: scipy.stats costs ~0.5 s of start-up to every command

    sampler = qmc.Sobol(d=len(names), scramble=True, seed=SEED)
    # a power of two keeps Sobol's balance (and scipy quiet); its first count - 1 points are used
    unit = sampler.random_base2(max(math.ceil(math.log2(count - 1)), 0))[: count - 1]
    for row in unit:
        values = dict(start)
        for name, u in zip(names, row):
            low, high = bounds[name]
            logarithmic = low > 0 and high / low >= LOG_SPAN  # a bound at 0 (a damping) is sampled uniformly
            # the interior sysid starts from (fit_engine._parameter_dict keeps a start 1e-3 of the range off a bound)
            low, high = low + 1e-3 * (high - low), high - 1e-3 * (high - low)
            if logarithmic:
                values[name] = float(math.exp(math.log(low) + u * (math.log(high) - math.log(low))))
            else:
                values[name] = float(low + u * (high - low))
        starts.append(values)
    return starts


def grid_rate(problem: Problem, bounds: dict[str, tuple[float, float]]) -> float:
    """The fastest pole [1/s] anywhere in the box: every start's grid keeps RK4 stable there
    (|s| dt <= engine.STABLE_RATE_DT).

    The fastest pole grows monotonically with omega_n, zeta, stiffness and damping and falls with the mass, so
    its largest value over the box is at a corner of the nonlinear names' bounds.
    """
    names = nonlinear(problem.free)
    fastest = 0.0
    for corner in range(2 ** len(names)):
        values = dict(problem.start)
        values.update({n: bounds[n][(corner >> i) & 1] for i, n in enumerate(names)})
        fastest = max(fastest, problem.fastest_rate(values))
    return fastest


@dataclasses.dataclass(frozen=True)
class StartChunk:
    """One start of a multi-start fit: plain data, the worker rebuilds the scene's model.

    Attributes
    ----------
    scene
        the scene's name.
    scenario
        the scenario's name.
    base
        (name, value) pairs: the scene's parameters, SI.
    record
        the measured record (its arrays travel with it).
    free
        the fitted names, in order.
    grid_start
        (name, value) pairs: start 1's values, which set every start's simulation grid.
    bounds
        (name, (low, high)) box bounds of the free names [the name's unit].
    modal
        whether the fit is in modal names (omega_n, zeta).
    force
        the step force of a forced record [N].
    rate
        the fastest pole in the box the grid keeps stable [1/s].
    index
        this start's place, 0 for start 1.
    start
        (name, value) pairs: this start's values.
    """

    scene: str
    scenario: str
    base: tuple[tuple[str, float], ...]
    record: fit_data.Record
    free: tuple[str, ...]
    grid_start: tuple[tuple[str, float], ...]
    bounds: tuple[tuple[str, tuple[float, float]], ...]
    modal: bool
    force: float
    rate: float
    index: int = 0
    start: tuple[tuple[str, float], ...] = ()


def run_start(payload: StartChunk, nthread: int = 0) -> dict[str, Any]:
    """One start's optimization; a module-level function of plain data (dask ships it to workers).

    Parameters
    ----------
    payload
        the start.
    nthread
        rollout threads (1 on a dask worker; otherwise the fit's own choice).

    Returns
    -------
    dict
        the start (clamped into the bounds) and sysid's solution: `x`, `jacobian`, `residuals` (scaled),
        `failed` (why the start could not be simulated, or ''),
        `status`, `iterations`, `scale`, `cost` (half the sum of squared scaled residuals, inf if not finite),
        `residual_rms` [signal unit], `rollouts`, `rollout_time_s`, `wall_time_s` [s].
    """
    how = model_of(scenes.get(payload.scene))
    chosen = how.scene.scenario(payload.scenario)
    record = payload.record
    free = list(payload.free)
    grid_start = dict(payload.grid_start)
    problem = Problem(how, chosen, dict(payload.base), record, free, grid_start, payload.modal, payload.force)
    problem.set_grid(grid_start, stable_rate=payload.rate)
    problem.start = dict(payload.start)
    problem.bounds = {name: (low, high) for name, (low, high) in payload.bounds}
    if nthread == 1:
        problem.threads = 1
    try:
        solved = solve(problem, record)
    except (ValueError, ArithmeticError) as error:  # a candidate MuJoCo could not simulate: this start failed
        x = np.array([problem.start[n] for n in free])
        return {
            "index": payload.index,
            "start": dict(problem.start),
            "x": x,
            "failed": f"{type(error).__name__}: {error}",
            "status": "failed",
            "iterations": 0,
            "scale": np.abs(x),
            "cost": math.inf,
            "residual_rms": math.inf,
            "rollouts": problem.rollouts,
            "rollout_time_s": problem.rollout_time,
            "wall_time_s": 0.0,
        }
    residual = np.concatenate(solved["residuals"])
    cost = 0.5 * float(residual @ residual)
    return {
        "index": payload.index,
        "start": dict(problem.start),
        "x": np.asarray(solved["x"], float),
        "failed": "",
        "jacobian": solved["jacobian"],
        "residuals": [np.asarray(r, float) for r in solved["residuals"]],
        "status": solved["status"],
        "iterations": solved["iterations"],
        "scale": np.asarray(solved["scale"], float),
        "cost": cost if math.isfinite(cost) else math.inf,
        "residual_rms": residual_rms(problem, residual),
        "rollouts": problem.rollouts,
        "rollout_time_s": problem.rollout_time,
        "wall_time_s": solved["wall_time_s"],
    }


def run(problem: Problem, count: int, executor: Executor | None = None) -> tuple[dict[str, Any], dict[str, Any]]:
    """Run `count` starts of `problem` on the executor; set `problem` to the best one.

    Parameters
    ----------
    problem
        the fit's problem at start 1 (its grid is every start's).
    count
        number of starts (>= 2).
    executor
        where the starts run (None: one after the other in this process).

    Returns
    -------
    (solved, runs)
        the best start's solution (the shape `fit_engine.solve` returns) and the starts' record for `summary`.
    """
    free, record = problem.free, problem.record
    bounds = {name: problem.how.bounds(name, problem.start[name], record) for name in free}
    rate = grid_rate(problem, bounds)
    common = StartChunk(
        scene=problem.how.name,
        scenario=problem.scenario.name,
        base=tuple(problem.base.items()),
        record=record,
        free=tuple(free),
        grid_start=tuple(problem.start.items()),
        bounds=tuple(bounds.items()),
        modal=problem.modal,
        force=problem.force,
        rate=rate,
    )
    problem.set_grid(problem.start, stable_rate=rate)
    starts = sample(problem.start, bounds, free, count)
    payloads = [dataclasses.replace(common, index=i, start=tuple(values.items())) for i, values in enumerate(starts)]
    runner = resolve(executor)
    results = runner.map(run_start, payloads, description="fit starts", unit="start")
    costs = np.array([r["cost"] for r in results])
    dof = max(record.time.size - len(free), 1)
    best = int(np.flatnonzero(costs <= costs.min() * (1.0 + SAME_IN_SE**2 / dof))[0])
    chosen = results[best]
    if chosen["failed"]:
        raise DivergedError(f"every one of the {count} starts failed to simulate; start 1: {results[0]['failed']}")
    problem.start = dict(chosen["start"])
    problem.rollouts, problem.rollout_time = chosen["rollouts"], chosen["rollout_time_s"]
    solved = {key: chosen[key] for key in ("x", "jacobian", "residuals", "status", "iterations", "wall_time_s")}
    solved["scale"] = chosen["scale"]
    return solved, {"results": results, "best": best, "executor": runner.describe(), "bounds": bounds}


def starts_entry(runs: dict[str, Any] | None, free: list[str], covariance: np.ndarray, unit: str) -> dict[str, Any]:
    """fit.json's `starts` entry: count, how many reached the best minimum, the spread, the best start.

    Parameters
    ----------
    runs
        `run`'s record (None: the single start).
    free
        the fitted names, in order.
    covariance
        (p, p) covariance of the final estimate [units of the names].
    unit
        the record's signal unit (of `residual_rms`).
    """
    if runs is None:
        return {"count": 1, "best": 1, "at_best_minimum": 1, "method": "the linear-algebra start only"}
    results, best = runs["results"], runs["best"]
    x_best = results[best]["x"]
    standard_error = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    tolerance = np.maximum(SAME_IN_SE * standard_error, SAME_RELATIVE * np.abs(results[best]["scale"]))
    at_best = [bool(np.all(np.abs(r["x"] - x_best) <= tolerance)) for r in results]
    estimates = np.array([r["x"] for r in results])
    reached = estimates[np.array(at_best)]
    return {
        "count": len(results),
        "best": best + 1,
        "at_best_minimum": int(sum(at_best)),
        "method": "start 1: linear algebra; starts 2..N: scrambled Sobol (seed"
        f" {SEED}) over start 1's bounds of {', '.join(nonlinear(free))}, log-uniform where they span a decade",
        "tolerance": {
            "rule": f"every free name within max({SAME_IN_SE} standard errors, {SAME_RELATIVE:g} x its scale)"
            " of the best start's estimate",
            "per_name": dict(zip(free, tolerance.tolist())),
        },
        "spread": {n: [float(estimates[:, i].min()), float(estimates[:, i].max())] for i, n in enumerate(free)},
        "spread_at_best_minimum": {
            n: [float(reached[:, i].min()), float(reached[:, i].max())] for i, n in enumerate(free)
        },
        "bounds": {n: list(runs["bounds"][n]) for n in free},
        "rollouts": int(sum(r["rollouts"] for r in results)),
        "executor": runs["executor"],
        "runs": [
            {
                "start": r["index"] + 1,
                "from": {n: float(r["start"][n]) for n in free},
                "estimate": dict(zip(free, r["x"].tolist())),
                "cost": r["cost"],
                "residual_rms": r["residual_rms"],
                "residual_rms_unit": unit,
                "status": r["status"],
                "failed": r["failed"],
                "iterations": r["iterations"],
                "wall_time_s": r["wall_time_s"],
                "at_best_minimum": flag,
            }
            for r, flag in zip(results, at_best)
        ],
    }


def line(starts: dict[str, Any]) -> str:
    """The terminal's one line about the starts ('' for a single start)."""
    if starts["count"] == 1:
        return ""
    runs = starts["runs"]
    best = runs[starts["best"] - 1]
    others = [r["residual_rms"] for r in runs if not r["at_best_minimum"]]
    elsewhere = (
        f"; {len(others)} stopped elsewhere at residual RMS {min(others):.3g} to {max(others):.3g}"
        f" {best['residual_rms_unit']} (best {best['residual_rms']:.3g})"
        if others
        else ""
    )
    which = " (the linear-algebra start)" if starts["best"] == 1 else ""
    return (
        f"  starts: {starts['count']} on {starts['executor']}, {starts['at_best_minimum']} reached the best minimum,"
        f" best start {starts['best']}{which}{elsewhere}"
    )
