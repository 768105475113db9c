"""The public run: `springlab.run` and `springlab.validate` are `run` and `validate` here, and nowhere else.

They are the explicit-setting run (springlab.runs.run.run_scenario) plus `integrator='auto'`:
the cheapest setting that meets a tolerance, chosen by a study (springlab.studies.tradeoff: a
sweep of every integrator and timestep, then the verified cheapest setting meeting `tol`) and
then run. That is why the public run lives in the studies layer while the explicit-setting run
lives below it, in springlab.runs: the trade-off study (and the families, the fit) are built
from the explicit-setting run, and the public one is built from the trade-off. Code inside the
package calls `run_scenario` when it names its setting and could not import this module without
a cycle (the studies); the command line, the demo and users call `run` and `validate`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

from springlab.errors import BadInputError
from springlab.runs.model_run import ModelRun, run_model
from springlab.runs.run import Result, ValidationRow, exact_scenarios, run_scenario
from springlab.scenes.base import Scene
from springlab.scenes.declarations import keyword_parameters
from springlab.sim import model_files

from .tradeoff import sweepable, tradeoff

#: what validate notes on a scenario 'auto' cannot sweep
NO_SWEEP_NOTE = "no reference trajectory for 'auto' to sweep: the scene's validated setting"


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

    Raises
    ------
    BadInputError
        no tol, a dt given (auto chooses it), or no setting meets tol.
    """
    if tol is None:
        raise BadInputError("integrator 'auto' needs tol, the relative error to meet (e.g. --tol 1e-6)")
    if dt is not None:
        raise BadInputError("integrator 'auto' chooses dt itself; drop dt (--dt) or name an integrator")
    result = tradeoff(scene, scenario, tol=tol, duration=duration, **parameters)
    pick = result.recommendation
    assert pick is not None, "a sweep with tol always answers, if only with integrator None"
    if pick.integrator is None or pick.dt is None:
        best = min((r for r in result.runs if not r.diverged), key=lambda r: r.error, default=None)
        reach = f"; the best reached is {best.error:.2g} ({best.integrator}, dt = {best.dt:g} s)" if best else ""
        raise BadInputError(
            f"no integrator and timestep of the sweep meets tol = {tol:g} on {result.scene}"
            f" {result.scenario}{reach}; valid: a tol it can reach"
        )
    return pick.integrator, pick.dt


def run(
    model: str,
    scenario: str | None = None,
    *,
    integrator: str | None = None,
    dt: float | None = None,
    duration: float | None = None,
    tol: float | None = None,
    keyframe: str | int | None = None,
    **parameters: float,
) -> Result | ModelRun:
    """Simulate a scenario headless in MuJoCo and compare it with its exact solution (`springlab.run`),
    or run a model file (nothing to compare with: a `ModelRun`, "not validated").

    The explicit-setting run (springlab.runs.run.run_scenario), where `integrator='auto'` first
    picks the cheapest setting meeting `tol` (`auto_setting`); a model file's run is
    springlab.runs.model_run.run_model (its own integrator and timestep unless given).

    Parameters
    ----------
    model
        scene name (see `springlab list`), or a model file (MJCF, a path ending in .xml).
    scenario
        scenario name (None: the scene's default); not for a model file.
    integrator
        one of 'euler', 'implicit', 'implicitfast', 'rk4', 'discrete'
        (None: the scene's validated default), or 'auto': the cheapest setting
        that meets `tol`, measured by springlab.studies.tradeoff (then dt must be None).
    dt
        timestep [s] (None: the scene's validated default, or auto's).
    duration
        simulated time [s] (None: the scenario's).
    tol
        relative accuracy [-] to hold the run to instead of the integrator's
        predicted error (see springlab.runs.compare); needed by 'auto'; not for a model file.
    keyframe
        a model file's start: a keyframe name or index (None: the first keyframe, else qpos0 at rest).
    **parameters
        scene parameters in SI units, e.g. mass=2.0 [kg] (numbers; none is named like an option,
        springlab.scenes.declarations.STUDY_OPTIONS); not for a model file.

    Returns
    -------
    Result or ModelRun
        A scene's Result: `passed`, `verdict` and `message` say how the run compares with its exact
        solution; `to_dict()` is summary.json, `to_pandas()` trajectory.csv. A model file's ModelRun:
        the same files, `verdict` "not validated", `passed` None.

    Raises
    ------
    BadInputError
        unknown names, non-physical values (a string where a number goes), bad dt/duration; for
        'auto' no tol, a dt given, or no setting meeting tol.
    DivergedError
        the simulation blew up (nothing is returned for it).
    TypeError
        an old keyword spelling (`scene=`, `parameters={...}`) or another study's option.
    """
    parameters = keyword_parameters("run", parameters)
    if model_files.is_model_file(model):
        given = [
            name for name, value in (("scenario", scenario), ("tol", tol), *parameters.items()) if value is not None
        ]
        if given:
            raise BadInputError(f"{given[0]} applies to a scene, not to a model file ({model})")
        return run_model(model, keyframe=keyframe, integrator=integrator, dt=dt, duration=duration)
    if keyframe is not None:
        raise BadInputError(f"keyframe applies to a model file (MODEL.xml), not to the scene {model!r}")
    return run_scene(model, scenario, integrator=integrator, dt=dt, duration=duration, tol=tol, **parameters)


def run_scene(
    scene: str,
    scenario: str | None = None,
    *,
    integrator: str | None = None,
    dt: float | None = None,
    duration: float | None = None,
    tol: float | None = None,
    **parameters: float,
) -> Result:
    """`run` on a scene (its arguments): the explicit-setting run, or 'auto''s verified cheapest setting."""
    if integrator == "auto":
        integrator, dt = auto_setting(scene, scenario, tol=tol, dt=dt, duration=duration, **parameters)
    return run_scenario(scene, scenario, integrator=integrator, dt=dt, duration=duration, tol=tol, **parameters)


def validate(
    model: str | Sequence[str] | None = None,
    *,
    integrator: str | None = None,
    dt: float | None = None,
    tol: float | None = None,
) -> list[ValidationRow]:
    """Run every scenario that has an exact reference and tabulate it (`springlab.validate`).

    Each scenario runs at the scene's validated setting, or at `integrator` / `dt`, or with
    `integrator='auto'` at the cheapest setting that meets `tol`, chosen per scenario.

    Parameters
    ----------
    model
        a scene name, or scene names, to validate (None or empty: all).
    integrator
        integrator name, None (the scenes' own) or 'auto'.
    dt
        timestep [s] (None: the scenes' own; must be None with 'auto').
    tol
        relative tolerance [-] to hold every run to (None: the predicted error).

    Returns
    -------
    list[ValidationRow]
        One row per scenario, in catalogue order (`row.to_dict()` is a row of `springlab validate
        --json`). With 'auto', a scenario validated by scalar checks alone (nothing for 'auto' to
        sweep) runs at the scene's validated setting and its row's `note` says so.

    Raises
    ------
    UnknownNameError
        a scene name springlab does not have.
    BadInputError
        bad integrator, dt or tol; for 'auto' no tol, a dt given, or no setting meeting tol.
    DivergedError
        a run blew up.
    """
    names = [model] if isinstance(model, str) else None if model is None else list(model)
    rows = []
    for scene, scenario in exact_scenarios(names):
        if integrator == "auto" and not sweepable(scene, scenario, None):
            row = ValidationRow.of(run_scenario(scene.name, scenario.name))
            rows.append(dataclasses.replace(row, note=NO_SWEEP_NOTE))
            continue
        rows.append(ValidationRow.of(run_scene(scene.name, scenario.name, integrator=integrator, dt=dt, tol=tol)))
    return rows
