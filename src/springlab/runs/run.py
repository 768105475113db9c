"""One run: a scene's scenario at an explicit setting, compared with its exact solution -> `Result`.

`run_scenario` is the run at a setting you name (integrator and dt, or the scene's validated
default). It lives here, below the studies, because studies are built from it: the trade-off
verifies its recommendation with it, the families run their members with it, the fit runs the
identified scene with it. `springlab.run` and `springlab.validate`, the public API, are in
springlab.studies.auto: they add `integrator='auto'`, which picks the setting by a trade-off
study (springlab.studies.tradeoff), so it cannot live in the layer that study is built on.
`run_scenario` therefore refuses 'auto' and says where it is.

`Result` holds the run's facts as attributes (`passed`, `verdict`, `message`, `errors`,
`tolerance`, `quantities`, `checks`, the series), `to_dict()` (summary.json) and `to_pandas()`
(trajectory.csv); `ValidationRow` is one row of `springlab validate`'s table. Both live in
springlab.runs.result and are importable from here.

>>> import springlab
>>> result = springlab.run("slider", "exercise")
>>> result.quantities["regime"]
'overdamped'
>>> result.verdict
<Verdict.PASS: 'PASS'>
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Iterator
from typing import Any

import numpy as np

from springlab import scenes
from springlab.answer import Answer
from springlab.errors import BadInputError, DivergedError, ParameterError, SpringlabError
from springlab.exact.linear import single_threaded_blas
from springlab.scenes.base import Case, Check, Scenario, Scene
from springlab.sim.simulate import (
    INTEGRATORS,
    MAX_STEPS,
    MAX_VALUE,
    Trajectory,
    beyond_mujoco_limits,
    check_timing,
    integrator_id,
)

from . import compare
from .compare import ColumnError, Verdict
from .result import Result, ValidationRow

__all__ = [
    "BLOWUP_RATIO",
    "Result",
    "ValidationRow",
    "evaluate",
    "exact_scenarios",
    "prepare",
    "run_scenario",
    "scene_and_scenario",
]

#: a run whose error exceeds this many times its signal has blown up, flagged or not
BLOWUP_RATIO = 1e3
#: integrator 'auto' is a study above this layer
_AUTO_ELSEWHERE = (
    "integrator 'auto' needs a sweep of every integrator: call springlab.run / springlab.validate"
    " (springlab.studies.auto), or name one of euler, implicit, implicitfast, rk4, discrete"
)


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
    **parameters: float,
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
        (springlab.studies.auto.run), not this function's (see the module docstring).
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
        The Result; `result.passed` says whether every compared column is within
        its tolerance and, without `tol`, the run is inside the range of its error
        estimate; `result.verdict` says which (a Verdict) and `result.message` why.

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
    default_integrator, default_dt = scene_obj.setting(chosen)
    integrator = default_integrator if integrator is None else integrator
    integrator_id(integrator)
    dt = default_dt if dt is None else dt
    duration = chosen.duration if duration is None else duration
    steps = check_timing(dt, duration)
    if tol is not None:
        tol = compare.check_tolerance(tol)
    # the exact side on one BLAS thread (exact.linear.single_threaded_blas): a cold validate spent more CPU in
    # OpenBLAS's threads waiting on each other (the stay cable's 198-state Lyapunov solves) than in MuJoCo
    with single_threaded_blas(), _within_double_precision(scene_obj, chosen, params):
        case = Case.compiled(scene_obj, chosen, params)
        setup = case.setup(steps, dt)
        try:
            trajectory = case.simulate(integrator, dt, duration, setup=setup)
        except DivergedError as error:
            beyond = beyond_mujoco_limits(case.model, setup.qpos, setup.qvel, setup.act, setup.control)
            raise DivergedError(f"{error}{_stability_advice(case, integrator, dt, duration, beyond)}") from None
        return evaluate(case, trajectory, tol)


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


def evaluate(case: Case, trajectory: Trajectory, tol: float | None = None, *, checks: bool = True) -> Result:
    """Compare a finished run of `case` with its reference: errors, tolerance, checks, verdict -> Result.

    Shared by `run` and the batched studies (springlab.studies.tradeoff, springlab.studies.extremes), so every path judges a run
    the same way. Raises DivergedError for a run whose error dwarfs its signal. `checks=False` leaves
    the scene's checks out (a study that measures the same claims itself over many runs, e.g.
    springlab.studies.friction_settings, verifies its pick with a full run). The exact side runs on one BLAS
    thread, as `run_scenario`'s: the same numbers on any machine, whatever its cores.
    """
    with single_threaded_blas():
        return _evaluate(case, trajectory, tol, checks=checks)


def _evaluate(case: Case, trajectory: Trajectory, tol: float | None, *, checks: bool) -> Result:
    """`evaluate`'s body (on one BLAS thread)."""
    scene, scenario, params = case.scene, case.scenario, case.params
    columns = case.joint_columns(trajectory)
    pos = {j: c[0] for j, c in columns.items()}
    vel = {j: c[1] for j, c in columns.items()}
    reference = case.reference(trajectory.time, dt=trajectory.dt) if scenario.exact else None
    errors: dict[str, ColumnError] = {}
    per_column: dict[str, float] = {}
    tolerance, basis, passed, validity = None, "", None, None
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
        errors = compare.column_errors(simulated, exact, reference.scales)
        worst = max(e.max_rel for e in errors.values())
        if not math.isfinite(worst) or worst > BLOWUP_RATIO:
            advice = _stability_advice(case, trajectory.integrator, trajectory.dt, trajectory.time[-1])
            raise DivergedError(
                f"simulation diverged: error {worst:.3g} times the signal ({trajectory.integrator},"
                f" dt = {trajectory.dt:g} s){advice}"
            )
        if tol is not None:
            # measured against the exact reference: true at any dt, no estimate involved
            per_column = {column: tol for column in errors}
            basis = "requested tolerance"
        elif reference.system is not None and reference.tolerance_of is None:
            predicted = compare.tolerances(reference, trajectory.integrator, trajectory.dt, trajectory.time)
            per_column = {c: min(v, compare.CERTIFIED_CAP) for c, v in predicted.items()}
            basis = compare.TOLERANCE_BASIS + (f"; {reference.tolerance_basis}" if reference.tolerance_basis else "")
            if any(v > compare.CERTIFIED_CAP for v in predicted.values()):
                basis += f"; capped at {compare.CERTIFIED_CAP:g}, the most a PASS certifies without --tol"
        else:
            stated = (
                reference.tolerance_of(trajectory.integrator)
                if reference.tolerance_of is not None
                else reference.tolerance
            )
            assert stated is not None, "a reference without `system` states its tolerance"
            per_column = {column: min(stated, compare.CERTIFIED_CAP) for column in errors}
            basis = reference.tolerance_basis
        if tol is None and reference.system is not None:
            # a leading-order tolerance holds only inside the range of its estimate (compare.estimate_range)
            span = float(trajectory.time[-1] - trajectory.time[0])
            validity = compare.estimate_range(
                compare.system_rates(reference), trajectory.integrator, trajectory.dt, max(span, trajectory.dt)
            )
        per_column = {column: float(value) for column, value in per_column.items()}
        tolerance = max(per_column.values())
        passed = all(errors[c].max_rel <= per_column[c] for c in errors)
        if validity is not None and not validity.inside:
            passed = False  # the tolerance is no tolerance here: nothing is certified
    claims = case.checks(trajectory) if scenario.exact and checks else []
    held = tuple(_capped(check, tol) for check in claims)
    if held:
        # a scenario without compared columns is held to its checks alone
        passed = all(c.passed for c in held) and passed is not False
    limits = tuple(case.model_limits(trajectory))
    if limits:
        passed = False  # matching the reference proves nothing once the equations no longer hold
    verdict: Verdict | None
    if limits:
        verdict = Verdict.OUTSIDE_MODEL
    elif passed is None:
        verdict = None
    elif validity is not None and not validity.inside:
        verdict = Verdict.NOT_VALIDATED
    else:
        verdict = Verdict.PASS if passed else Verdict.FAIL
    quantities = case.quantities(trajectory)
    duration = trajectory.steps * trajectory.dt  # MuJoCo's time accumulates dt: rounding
    return Result(
        scene=scene.name,
        scenario=scenario.name,
        integrator=trajectory.integrator,
        dt=trajectory.dt,
        duration=duration,
        steps=trajectory.steps,
        wall_time_s=trajectory.wall_time_s,
        parameters=dict(params),
        quantities=quantities,
        errors=errors,
        tolerance=tolerance,
        tolerance_basis=basis,
        passed=passed,
        verdict=verdict,
        estimate_range=validity,
        checks=held,
        model_limits=limits,
        time=trajectory.time,
        pos=pos,
        vel=vel,
        ref_pos=dict(reference.pos) if reference else {},
        ref_vel=dict(reference.vel) if reference else {},
        case=case,
        trajectory=trajectory,
        column_tolerances=per_column,
        answer=_answer(case, trajectory, quantities, errors, tolerance),
        grid_notes=tuple(case.grid_notes(trajectory.dt)),
    )


def _answer(
    case: Case, trajectory: Trajectory, quantities: dict[str, Any], errors: dict[str, ColumnError], tol: float | None
) -> Answer | None:
    """The scenario's question and this run's answer (`Scene.answer`), from its parameters, quantities and facts."""
    # what an answer may quote besides the parameters and quantities: the run's own facts
    facts: dict[str, Any] = {
        "integrator": trajectory.integrator,
        "dt_s": trajectory.dt,
        "duration_s": trajectory.steps * trajectory.dt,
    }
    if errors:
        facts["max_rel_error"] = max(e.max_rel for e in errors.values())
        facts["tolerance"] = tol
    return case.scene.answer(case.scenario.name, {**facts, **case.params, **quantities})


def _capped(check: Check, tol: float | None) -> Check:
    """A check whose relative error a PASS certifies, with its tolerance capped at compare.CERTIFIED_CAP
    unless the caller asked for a tolerance (the same cap as the compared columns); a check that
    follows the run's tolerance (`Check.follows_tol`) is held to the requested one."""
    if tol is not None and check.follows_tol:
        return dataclasses.replace(check, tolerance=tol, basis=f"{check.basis}; held to the requested tolerance")
    if tol is not None or not check.certifies_error or check.reference == 0 or check.tolerance <= compare.CERTIFIED_CAP:
        return check
    basis = f"{check.basis}; capped at {compare.CERTIFIED_CAP:g}, the most a PASS certifies without --tol"
    return dataclasses.replace(check, tolerance=compare.CERTIFIED_CAP, basis=basis)


def _stability_advice(case: Case, integrator: str, dt: float, duration: float, beyond: str | None = None) -> str:
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
    modes = case.modes()
    for omega, zeta in modes:
        limit = case.stability_limit(integrator, omega, zeta)
        ratio = omega * dt / limit
        if worst is None or ratio > worst[0]:
            worst = (ratio, omega, zeta, limit)
    if worst is None:
        # no oscillating mode (a driven free mass): no timestep limit applies, only MuJoCo's cap
        return (
            f": {case.scene.name} has no mode whose stability limits dt, so a position, velocity or acceleration"
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
    stable = [name for name in INTEGRATORS if all(w * dt < case.stability_limit(name, w, z) for w, z in modes)]
    others = f"an integrator stable at this dt ({', '.join(stable)})" if stable else "integrator 'discrete'"
    smaller = limit / omega
    exceeds = f": omega*dt = {omega * dt:.4g} exceeds the {integrator} stability limit {limit:.4g} {mode}"
    if duration / smaller > MAX_STEPS:
        return f"{exceeds}; the dt it needs (< {smaller:.3g} s) would take more than {MAX_STEPS} steps, so use {others}"
    return f"{exceeds}; use dt < {smaller:.3g} s or {others}"


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


def scene_and_scenario(result: Result) -> tuple[Scene, Scenario]:
    """(Scene, Scenario) objects of a Result (its case's)."""
    return result.case.scene, result.case.scenario
