"""springlab's single-run API: run a scene's scenario at an explicit setting, validate scenes.

`integrator='auto'` is a study built on top of this layer (springlab.studies.auto,
which is what springlab.run and springlab.validate are).

>>> import springlab
>>> result = springlab.run("slider", "exercise")
>>> result.summary["quantities"]["regime"]
'overdamped'
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import pathlib
from collections.abc import Iterator
from typing import Any

import mujoco
import numpy as np

from springlab import scenes
from springlab.errors import BadInputError, DivergedError, ParameterError, SpringlabError
from springlab.files import csv_text, dumps, write_text_files
from springlab.scenes.base import Check, Scenario, Scene
from springlab.sim.simulate import (
    INTEGRATORS,
    MAX_STEPS,
    MAX_VALUE,
    Trajectory,
    beyond_mujoco_limits,
    check_timing,
    integrator_id,
    simulate,
)

from . import compare

#: the verdict of a run that left its scene's equations (Scene.model_limits), whatever its errors
OUTSIDE_MODEL = "not validated: outside the scene's model"
#: a run whose error exceeds this many times its signal has blown up, flagged or not
BLOWUP_RATIO = 1e3
#: integrator 'auto' is a study above this layer
_AUTO_ELSEWHERE = (
    "integrator 'auto' needs a sweep of every integrator: call springlab.run / springlab.validate"
    " (springlab.studies.auto), or name one of euler, implicit, implicitfast, rk4, discrete"
)


@dataclasses.dataclass
class Result:
    """One run of a scenario: the trajectory, its reference, errors and summary.

    Attributes
    ----------
    scene, scenario
        the names run.
    parameters
        parameter name -> value used (SI).
    time
        (n,) [s], one row per physics step, t = 0 included.
    pos, vel
        joint -> simulated position [m] / velocity [m/s] series.
    ref_pos, ref_vel
        joint -> exact series (empty where no reference exists).
    summary
        the summary.json dict (see README).
    model
        the compiled MjModel that ran.
    trajectory
        the raw Trajectory.
    """

    scene: str
    scenario: str
    parameters: dict[str, float]
    time: np.ndarray
    pos: dict[str, np.ndarray]
    vel: dict[str, np.ndarray]
    ref_pos: dict[str, np.ndarray]
    ref_vel: dict[str, np.ndarray]
    summary: dict[str, Any]
    model: mujoco.MjModel
    trajectory: Trajectory

    def columns(self) -> dict[str, np.ndarray]:
        """trajectory.csv's columns in order: time, <joint>_pos/_vel, then the references."""
        out = {"time": self.time}
        for joint in self.pos:
            out[f"{joint}_pos"] = self.pos[joint]
            out[f"{joint}_vel"] = self.vel[joint]
        for joint in self.ref_pos:
            out[f"{joint}_pos_ref"] = self.ref_pos[joint]
            out[f"{joint}_vel_ref"] = self.ref_vel[joint]
        return out


def prepare(
    scene: str | Scene, scenario: str | None, parameters: dict[str, Any]
) -> tuple[Scene, Scenario, dict[str, float]]:
    """Resolve names and parameters; return (Scene, Scenario, params)."""
    scene = scenes.get(scene) if isinstance(scene, str) else scene
    chosen = scene.scenario(scenario)
    return scene, chosen, scene.resolve(chosen, parameters)


def run_scenario(
    scene: str,
    scenario: str | None = None,
    *,
    integrator: str | None = None,
    dt: float | None = None,
    duration: float | None = None,
    tol: float | None = None,
    **parameters: Any,
) -> Result:
    """Simulate a scenario headless in MuJoCo and compare it with its exact solution.

    Parameters
    ----------
    scene
        scene name (see `springlab list`).
    scenario
        scenario name (None: the scene's default).
    integrator
        one of 'euler', 'implicit', 'implicitfast', 'rk4', 'discrete'
        (None: the scene's validated default). 'auto' is springlab.run's
        (springlab.studies.auto.run), not this function's.
    dt
        timestep [s] (None: the scene's validated default).
    duration
        simulated time [s] (None: the scenario's).
    tol
        relative accuracy [-] to hold the run to instead of the integrator's
        predicted error (see springlab.runs.compare).
    **parameters
        scene parameters in SI units, e.g. mass=2.0 [kg].

    Returns
    -------
    Result
        The Result; `result.summary["passed"]` says whether every compared column
        is within its tolerance and, without `tol`, the run is inside the range of
        its error estimate; `result.summary["verdict"]` says which ('PASS', 'FAIL',
        or springlab.runs.compare.NOT_VALIDATED, with `estimate_range["reason"]`).

    Raises
    ------
    BadInputError
        unknown names, non-physical values, bad dt/duration.
    DivergedError
        the simulation blew up (nothing is returned for it).
    """
    if integrator == "auto":
        raise BadInputError(_AUTO_ELSEWHERE)
    scene_obj, chosen, params = prepare(scene, scenario, parameters)
    integrator = scene_obj.integrator if integrator is None else integrator
    integrator_id(integrator)
    dt = (chosen.dt or scene_obj.dt) if dt is None else dt
    duration = chosen.duration if duration is None else duration
    steps = check_timing(dt, duration)
    if tol is not None:
        tol = compare.check_tolerance(tol)
    with _within_double_precision(scene_obj, chosen, params):
        model = scene_obj.build(params, chosen)
        setup = scene_obj.setup(model, params, chosen, steps, dt)
        try:
            trajectory = simulate(
                model,
                integrator=integrator,
                dt=dt,
                duration=duration,
                qpos=setup.qpos,
                qvel=setup.qvel,
                act=setup.act,
                control=setup.control,
                stop=scene_obj.stop_condition(model, params, chosen),
            )
        except DivergedError as error:
            beyond = beyond_mujoco_limits(model, setup.qpos, setup.qvel, setup.act, setup.control)
            advice = _stability_advice(scene_obj, model, params, chosen, integrator, dt, duration, beyond)
            raise DivergedError(f"{error}{advice}") from None
        return evaluate(scene_obj, chosen, params, model, trajectory, tol)


@contextlib.contextmanager
def _within_double_precision(scene: Scene, scenario: Scenario, params: dict[str, float]) -> Iterator[None]:
    """Turn arithmetic that breaks down at extreme parameter values into one ParameterError.

    Each value is checked against its range, but products of valid values can still
    leave double precision (force_frequency = 1e300: omega^2 overflows; mass = 1e300:
    rates underflow to 0). Such a run has no meaningful answer: exit 2, one line,
    naming the most extreme value, instead of a traceback.
    """
    try:
        yield
    except SpringlabError:
        raise
    except (ArithmeticError, np.linalg.LinAlgError, ValueError) as error:
        name, value = max(params.items(), key=lambda item: abs(math.log10(abs(item[1]))) if item[1] else 0.0)
        raise ParameterError(
            f"{scene.name} {scenario.name} cannot be computed in double precision at these values (the most"
            f" extreme: {name} = {value:g}): {type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''}"
            "; choose less extreme ones"
        ) from None


def evaluate(
    scene: Scene,
    scenario: Scenario,
    params: dict[str, float],
    model: mujoco.MjModel,
    trajectory: Trajectory,
    tol: float | None = None,
) -> Result:
    """Compare a finished run with its reference: errors, tolerance, checks, summary -> Result.

    Shared by `run` and the batched studies (springlab.studies.tradeoff, springlab.studies.extremes), so every path judges a run
    the same way. Raises DivergedError for a run whose error dwarfs its signal.
    """
    columns = scene.joint_columns(model, trajectory)
    pos = {j: c[0] for j, c in columns.items()}
    vel = {j: c[1] for j, c in columns.items()}
    reference = scene.reference(model, params, scenario, trajectory.time, dt=trajectory.dt) if scenario.exact else None
    errors, tolerance, basis, passed, validity = {}, None, "", None, None
    if reference is not None and not all(
        np.isfinite(v).all() for v in (*reference.pos.values(), *reference.vel.values())
    ):
        # e.g. damping = 1e300: the run may be fine, the closed form overflows; not a divergence
        raise ParameterError(
            f"the exact solution of {scene.name} {scenario.name} is not finite in double precision at these"
            f" parameter values ({', '.join(f'{k}={v:g}' for k, v in params.items())}); choose less extreme ones"
        )
    if reference is not None:
        simulated = {f"{j}_{k}": (pos if k == "pos" else vel)[j] for j in reference.pos for k in ("pos", "vel")}
        exact = {
            f"{j}_{k}": (reference.pos if k == "pos" else reference.vel)[j]
            for j in reference.pos
            for k in ("pos", "vel")
        }
        errors = compare.column_errors(simulated, exact)
        worst = max(e["max_rel"] for e in errors.values())
        if not math.isfinite(worst) or worst > BLOWUP_RATIO:
            advice = _stability_advice(
                scene, model, params, scenario, trajectory.integrator, trajectory.dt, trajectory.time[-1]
            )
            raise DivergedError(
                f"simulation diverged: error {worst:.3g} times the signal ({trajectory.integrator},"
                f" dt = {trajectory.dt:g} s){advice}"
            )
        if tol is not None:
            # measured against the exact reference: true at any dt, no estimate involved
            per_column = {column: tol for column in errors}
            basis = "requested tolerance"
        elif reference.system is not None:
            predicted = compare.tolerances(reference, trajectory.integrator, trajectory.dt, trajectory.time)
            per_column = {c: min(v, compare.CERTIFIED_CAP) for c, v in predicted.items()}
            basis = compare.TOLERANCE_BASIS + (f"; {reference.tolerance_basis}" if reference.tolerance_basis else "")
            if any(v > compare.CERTIFIED_CAP for v in predicted.values()):
                basis += f"; capped at {compare.CERTIFIED_CAP:g}, the most a PASS certifies without --tol"
            span = float(trajectory.time[-1] - trajectory.time[0])
            validity = compare.estimate_range(
                compare.system_rates(reference), trajectory.integrator, trajectory.dt, max(span, trajectory.dt)
            )
        else:
            assert reference.tolerance is not None, "a reference without `system` states its tolerance"
            per_column = {column: min(reference.tolerance, compare.CERTIFIED_CAP) for column in errors}
            basis = reference.tolerance_basis
        tolerance = max(per_column.values())
        passed = all(errors[c]["max_rel"] <= per_column[c] for c in errors)
        if validity is not None and not validity.inside:
            passed = False  # the tolerance is no tolerance here: nothing is certified
    checks = [
        _capped(check, tol).as_dict()
        for check in (scene.checks(model, params, scenario, trajectory) if scenario.exact else [])
    ]
    if checks:
        # a scenario without compared columns is held to its checks alone
        passed = all(c["passed"] for c in checks) and passed is not False
    limits = scene.model_limits(model, params, scenario, trajectory)
    if limits:
        passed = False  # matching the reference proves nothing once the equations no longer hold
    if limits:
        verdict = OUTSIDE_MODEL
    elif passed is None:
        verdict = None
    elif validity is not None and not validity.inside:
        verdict = compare.NOT_VALIDATED
    else:
        verdict = compare.PASS if passed else compare.FAIL
    summary = {
        "scene": scene.name,
        "scenario": scenario.name,
        "integrator": trajectory.integrator,
        "dt": trajectory.dt,
        "duration": trajectory.steps * trajectory.dt,  # MuJoCo's time accumulates dt: rounding
        "steps": trajectory.steps,
        "wall_time_s": trajectory.wall_time_s,
        "parameters": dict(params),
        "quantities": scene.quantities(model, params, scenario, trajectory),
        "errors": errors,
        "tolerance": tolerance,
        "tolerance_basis": basis,
        "passed": passed,
        "verdict": verdict,
        "estimate_range": None
        if validity is None
        else {
            "inside": validity.inside,
            # null, never a string: inf factor = a diverging tail, no largest dt = every dt is inside
            "error_bound_factor": validity.factor if math.isfinite(validity.factor) else None,
            "largest_dt_inside_s": validity.largest_dt if math.isfinite(validity.largest_dt) else None,
            "reason": validity.reason(),
        },
        "checks": checks,
        "model_limits": limits,
    }
    return Result(
        scene=scene.name,
        scenario=scenario.name,
        parameters=dict(params),
        time=trajectory.time,
        pos=pos,
        vel=vel,
        ref_pos=dict(reference.pos) if reference else {},
        ref_vel=dict(reference.vel) if reference else {},
        summary=summary,
        model=model,
        trajectory=trajectory,
    )


def _capped(check: Check, tol: float | None) -> Check:
    """A check whose relative error a PASS certifies, with its tolerance capped at compare.CERTIFIED_CAP
    unless the caller asked for a tolerance (the same cap as the compared columns)."""
    if tol is not None or not check.certifies_error or check.reference == 0 or check.tolerance <= compare.CERTIFIED_CAP:
        return check
    basis = f"{check.basis}; capped at {compare.CERTIFIED_CAP:g}, the most a PASS certifies without --tol"
    return dataclasses.replace(check, tolerance=compare.CERTIFIED_CAP, basis=basis)


def _stability_advice(
    scene: Scene,
    model,
    params,
    scenario,
    integrator: str,
    dt: float,
    duration: float,
    beyond: str | None = None,
) -> str:
    """Why a run diverged and what would help, as ': ...'.

    Never contradicts itself: a state past MuJoCo's own cap (`beyond`, see
    simulate.beyond_mujoco_limits) is not a timestep problem; a mode within its
    stability limit gets no "use a smaller dt"; a dt too small to reach in
    MAX_STEPS steps is not advised, the integrators stable at this dt are.
    """
    if beyond is not None:
        return (
            f": {beyond} is beyond MuJoCo's limit of {MAX_VALUE:g} on every position, velocity and acceleration"
            " (mjMAXVAL, SI units), so no timestep or integrator can run it; choose values that keep them below it"
        )
    worst = None
    modes = scene.modes(model, params, scenario)
    for omega, zeta in modes:
        limit = scene.stability_limit(model, params, scenario, integrator, omega, zeta)
        ratio = omega * dt / limit
        if worst is None or ratio > worst[0]:
            worst = (ratio, omega, zeta, limit)
    if worst is None:
        # no oscillating mode (a driven free mass): no timestep limit applies, only MuJoCo's cap
        return (
            f": {scene.name} has no mode whose stability limits dt, so a position, velocity or acceleration"
            f" passed MuJoCo's limit of {MAX_VALUE:g} (mjMAXVAL); choose values that keep them below it"
        )
    ratio, omega, zeta, limit = worst
    mode = f"(omega = {omega:.4g} rad/s, zeta = {zeta:.3g})"
    if ratio <= 1:
        within = (
            f"is within the {integrator} stability limit {limit:.4g}"
            if math.isfinite(limit)
            else f"meets no stability limit ({integrator} has none on this mode)"
        )
        return (
            f": omega*dt = {omega * dt:.4g} {within} {mode}, so this is not the timestep instability; look for"
            f" values that reach MuJoCo's limit of {MAX_VALUE:g} (mjMAXVAL) on a position, velocity or"
            " acceleration during the run"
        )
    stable = [
        name
        for name in INTEGRATORS
        if all(w * dt < scene.stability_limit(model, params, scenario, name, w, z) for w, z in modes)
    ]
    others = f"an integrator stable at this dt ({', '.join(stable)})" if stable else "integrator 'discrete'"
    smaller = limit / omega
    exceeds = f": omega*dt = {omega * dt:.4g} exceeds the {integrator} stability limit {limit:.4g} {mode}"
    if duration / smaller > MAX_STEPS:
        return f"{exceeds}; the dt it needs (< {smaller:.3g} s) would take more than {MAX_STEPS} steps, so use {others}"
    return f"{exceeds}; use dt < {smaller:.3g} s or {others}"


def validate_scenarios(
    scene_names: list[str] | None = None,
    *,
    integrator: str | None = None,
    dt: float | None = None,
    tol: float | None = None,
) -> list[dict[str, Any]]:
    """Run every scenario that has an exact reference at the scene's validated setting.

    Parameters
    ----------
    scene_names
        scenes to validate (None: all).
    integrator, dt
        override the scenes' default setting ('auto' is
        springlab.validate's, see springlab.studies.auto.validate).
    tol
        relative tolerance [-] to hold every run to (None: the predicted error).

    Returns
    -------
    list[dict[str, Any]]
        One row per scenario: scene, scenario, integrator, dt, steps, max_rel_error,
        measure, tolerance, tolerance_basis, passed, verdict, wall_time_s, note (only
        for a run that is not validated: why, and the largest dt inside), and checks
        (the scenario's Check dicts; a scenario without compared columns shows its
        tightest check in max_rel_error/tolerance, and `measure` says which:
        'trajectory max_rel', or '<check name> rel' / '<check name> abs').
    """
    if integrator == "auto":
        raise BadInputError(_AUTO_ELSEWHERE)
    return [
        validation_row(run_scenario(scene.name, scenario.name, integrator=integrator, dt=dt, tol=tol))
        for scene, scenario in exact_scenarios(scene_names)
    ]


def exact_scenarios(scene_names: list[str] | None = None) -> list[tuple[Scene, Scenario]]:
    """(scene, scenario) of every scenario with an exact solution, in catalogue order.

    Parameters
    ----------
    scene_names
        scenes to list (None or empty: all).

    Raises
    ------
    UnknownNameError
        a scene name springlab does not have.
    """
    names = list(scenes.SCENES) if not scene_names else scene_names
    pairs: list[tuple[Scene, Scenario]] = []
    for name in names:
        scene = scenes.get(name)
        pairs.extend((scene, scenario) for scenario in scene.scenarios.values() if scenario.exact)
    return pairs


def validation_row(result: Result) -> dict[str, Any]:
    """The `validate` table row of a run that has an exact reference."""
    s = result.summary
    checks = s.get("checks", [])
    if s["errors"]:
        worst, tolerance, basis = max(e["max_rel"] for e in s["errors"].values()), s["tolerance"], s["tolerance_basis"]
        measure = "trajectory max_rel"
    else:
        # no compared columns: the row shows the check closest to (or furthest past) its tolerance
        tightest = max(checks, key=lambda c: c["error"] / c["tolerance"] if c["tolerance"] > 0 else math.inf)
        worst, tolerance = tightest["error"], tightest["tolerance"]
        basis = f"{tightest['name']}: {tightest['basis']}"
        measure = f"{tightest['name']} {'rel' if tightest['reference'] != 0 else 'abs'}"
    row = {
        "scene": s["scene"],
        "scenario": s["scenario"],
        "integrator": s["integrator"],
        "dt": s["dt"],
        "steps": s["steps"],
        "max_rel_error": worst,
        "measure": measure,
        "tolerance": tolerance,
        "tolerance_basis": basis,
        "passed": s["passed"],
        "verdict": s.get("verdict"),
        "wall_time_s": s["wall_time_s"],
        "checks": checks,
    }
    validity = s.get("estimate_range")
    if s.get("model_limits"):
        row["note"] = f"{s['verdict']}: " + "; ".join(s["model_limits"])
    elif validity is not None and not validity["inside"]:
        row["note"] = f"{s['verdict']}: {validity['reason']}"
    return row


def write_run(directory: str | os.PathLike, result: Result, every: int = 1) -> list[pathlib.Path]:
    """Write a Result's trajectory.csv and summary.json into `directory`.

    The time column is k dt [s] for step k, exactly: the state after k steps is
    the state at k dt (MuJoCo's data.time accumulates dt and drifts by rounding).
    """
    columns = result.columns()
    columns["time"] = np.arange(len(columns["time"])) * float(result.summary["dt"])
    return write_text_files(
        directory,
        {
            "trajectory.csv": csv_text(columns, every),
            "summary.json": dumps(result.summary) + "\n",
        },
    )


def scene_and_scenario(result: Result) -> tuple[Scene, Scenario]:
    """(Scene, Scenario) objects of a Result."""
    scene = scenes.get(result.scene)
    return scene, scene.scenario(result.scenario)
