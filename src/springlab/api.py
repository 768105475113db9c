"""springlab's single-run API: run a scene's scenario at an explicit setting, validate scenes.

`integrator='auto'` is a study built on top of this layer (springlab.auto,
which is what springlab.run and springlab.validate are).

>>> import springlab
>>> result = springlab.run("slider", "exercise")
>>> result.summary["quantities"]["regime"]
'overdamped'
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import mujoco
import numpy as np

from . import compare, scenes
from .errors import BadInputError, DivergedError
from .scene import Check, Scenario, Scene
from .simulate import Trajectory, check_timing, integrator_id, simulate

#: the verdict of a run that left its scene's equations (Scene.model_limits), whatever its errors
OUTSIDE_MODEL = "not validated: outside the scene's model"
#: a run whose error exceeds this many times its signal has blown up, flagged or not
BLOWUP_RATIO = 1e3
#: integrator 'auto' is a study above this layer
_AUTO_ELSEWHERE = (
    "integrator 'auto' needs a sweep of every integrator: call springlab.run / springlab.validate"
    " (springlab.auto), or name one of euler, implicit, implicitfast, rk4, discrete"
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


def run(
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
        (springlab.auto.run), not this function's.
    dt
        timestep [s] (None: the scene's validated default).
    duration
        simulated time [s] (None: the scenario's).
    tol
        relative accuracy [-] to hold the run to instead of the integrator's
        predicted error (see springlab.compare).
    **parameters
        scene parameters in SI units, e.g. mass=2.0 [kg].

    Returns
    -------
    Result
        The Result; `result.summary["passed"]` says whether every compared column
        is within its tolerance and, without `tol`, the run is inside the range of
        its error estimate; `result.summary["verdict"]` says which ('PASS', 'FAIL',
        or springlab.compare.NOT_VALIDATED, with `estimate_range["reason"]`).

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
        raise DivergedError(f"{error}{_stability_advice(scene_obj, model, params, chosen, integrator, dt)}") from None
    return evaluate(scene_obj, chosen, params, model, trajectory, tol)


def evaluate(
    scene: Scene,
    scenario: Scenario,
    params: dict[str, float],
    model: mujoco.MjModel,
    trajectory: Trajectory,
    tol: float | None = None,
) -> Result:
    """Compare a finished run with its reference: errors, tolerance, checks, summary -> Result.

    Shared by `run` and the batched studies (springlab.tradeoff, springlab.extremes), so every path judges a run
    the same way. Raises DivergedError for a run whose error dwarfs its signal.
    """
    columns = scene.joint_columns(model, trajectory)
    pos = {j: c[0] for j, c in columns.items()}
    vel = {j: c[1] for j, c in columns.items()}
    reference = scene.reference(model, params, scenario, trajectory.time, dt=trajectory.dt) if scenario.exact else None
    errors, tolerance, basis, passed, validity = {}, None, "", None, None
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
            raise DivergedError(
                f"simulation diverged: error {worst:.3g} times the signal ({trajectory.integrator},"
                f" dt = {trajectory.dt:g} s){_stability_advice(scene, model, params, scenario, trajectory.integrator, trajectory.dt)}"
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


def _stability_advice(scene: Scene, model, params, scenario, integrator: str, dt: float) -> str:
    """': omega*dt = ... exceeds the <integrator> stability limit ...; use ...' or ''."""
    worst = None
    for omega, zeta in scene.modes(model, params, scenario):
        limit = scene.stability_limit(model, params, scenario, integrator, omega, zeta)
        ratio = omega * dt / limit
        if worst is None or ratio > worst[0]:
            worst = (ratio, omega, zeta, limit)
    if worst is None:
        return ""
    ratio, omega, zeta, limit = worst
    if not math.isfinite(limit):
        return f": omega*dt = {omega * dt:.4g} (zeta = {zeta:.3g})"
    verdict = "exceeds" if ratio > 1 else "is within"
    return (
        f": omega*dt = {omega * dt:.4g} {verdict} the {integrator} stability limit {limit:.4g}"
        f" (omega = {omega:.4g} rad/s, zeta = {zeta:.3g}); use dt < {limit / omega:.3g} s or integrator 'discrete'"
    )


def validate(
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
        springlab.validate's, see springlab.auto.validate).
    tol
        relative tolerance [-] to hold every run to (None: the predicted error).

    Returns
    -------
    list[dict[str, Any]]
        One row per scenario: scene, scenario, integrator, dt, steps, max_rel_error,
        tolerance, tolerance_basis, passed, verdict, wall_time_s, note (only for a run
        that is not validated: why, and the largest dt inside), and checks (the scenario's
        Check dicts; a scenario without compared columns shows its tightest check
        in max_rel_error/tolerance).
    """
    if integrator == "auto":
        raise BadInputError(_AUTO_ELSEWHERE)
    return [
        validation_row(run(scene.name, scenario.name, integrator=integrator, dt=dt, tol=tol))
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
    else:
        # no compared columns: the row shows the check closest to (or furthest past) its tolerance
        tightest = max(checks, key=lambda c: c["error"] / c["tolerance"] if c["tolerance"] > 0 else math.inf)
        worst, tolerance = tightest["error"], tightest["tolerance"]
        basis = f"{tightest['name']}: {tightest['basis']}"
    row = {
        "scene": s["scene"],
        "scenario": s["scenario"],
        "integrator": s["integrator"],
        "dt": s["dt"],
        "steps": s["steps"],
        "max_rel_error": worst,
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
