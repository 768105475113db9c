"""`integrator='auto'`: the cheapest setting that meets a tolerance, chosen by the sweep, then run.

`run` and `validate` are `runs.run` and `runs.validate` plus `integrator='auto'`
(springlab.run and springlab.validate are these): the single-run API knows
only explicit settings, and the automatic one is a study (springlab.studies.tradeoff:
a sweep of every integrator and timestep, then the verified cheapest setting
meeting `tol`) composed on top of it.
"""

from __future__ import annotations

from typing import Any

from springlab.errors import BadInputError
from springlab.runs.run import Result, exact_scenarios, run_scenario, validate_scenarios, validation_row
from springlab.scenes.base import Scene

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
    if pick["integrator"] is None:
        best = min((r for r in result.runs if not r.diverged), key=lambda r: r.error, default=None)
        reach = f"; the best reached is {best.error:.2g} ({best.integrator}, dt = {best.dt:g} s)" if best else ""
        raise BadInputError(
            f"no integrator and timestep of the sweep meets tol = {tol:g} on {result.scene}"
            f" {result.scenario}{reach}; valid: a tol it can reach"
        )
    return pick["integrator"], pick["dt"]


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
    """`runs.run`, where `integrator='auto'` first picks the cheapest setting meeting `tol` (`auto_setting`).

    Parameters
    ----------
    scene
        scene name (see `springlab list`).
    scenario
        scenario name (None: the scene's default).
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
        predicted error (see springlab.runs.compare); needed by 'auto'.
    **parameters
        scene parameters in SI units, e.g. mass=2.0 [kg].

    Returns
    -------
    Result
        The Result (see `runs.run`).

    Raises
    ------
    BadInputError
        unknown names, non-physical values, bad dt/duration; for
        'auto' no tol, a dt given, or no setting meeting tol.
    DivergedError
        the simulation blew up (nothing is returned for it).
    """
    if integrator == "auto":
        integrator, dt = auto_setting(scene, scenario, tol=tol, dt=dt, duration=duration, **parameters)
    return run_scenario(scene, scenario, integrator=integrator, dt=dt, duration=duration, tol=tol, **parameters)


def validate(
    scene_names: list[str] | None = None,
    *,
    integrator: str | None = None,
    dt: float | None = None,
    tol: float | None = None,
) -> list[dict[str, Any]]:
    """`runs.validate`, where `integrator='auto'` picks per scenario the cheapest setting meeting `tol`.

    Parameters
    ----------
    scene_names
        scenes to validate (None: all).
    integrator
        integrator name, None (the scenes' own) or 'auto'.
    dt
        timestep [s] (None: the scenes' own; must be None with 'auto').
    tol
        relative tolerance [-] to hold every run to (None: the predicted error).

    Returns
    -------
    list[dict[str, Any]]
        The rows of `runs.validate`; a scenario validated by scalar checks alone
        (nothing for 'auto' to sweep) runs at the scene's validated setting and
        its row carries a "note" saying so.
    """
    if integrator != "auto":
        return validate_scenarios(scene_names, integrator=integrator, dt=dt, tol=tol)
    rows = []
    for scene, scenario in exact_scenarios(scene_names):
        if not sweepable(scene, scenario, None):
            row = validation_row(run_scenario(scene.name, scenario.name))
            row["note"] = NO_SWEEP_NOTE
            rows.append(row)
            continue
        rows.append(validation_row(run(scene.name, scenario.name, integrator="auto", dt=dt, tol=tol)))
    return rows
