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
* finds the Pareto front of error vs CPU time, and for a tolerance the cheapest run within it (runs
  within COST_BAND of each other count as equally cheap, the more accurate wins), verified by running
  that setting as `springlab run` does (with its convergence checks); where
  no run meets the tolerance it says which floor stops it: MuJoCo's (the best setting's model
  error is above the tolerance: no integrator or timestep helps) or the integration's.

MuJoCo's own defaults (their settings, its default integrator and timestep, read from MuJoCo) are
the baseline every answer is measured against. The runs are cut into chunks of
`CHUNK_RUNS` and run on the executor (locally, or on dask workers that rebuild each model from
the scene's MJCF); each run's wall time is its own `mujoco.rollout` call, alone on one thread.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time as _time
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from springlab import display, scenes, tables
from springlab.errors import BadInputError, DivergedError
from springlab.files import json_ready
from springlab.runs import compare
from springlab.runs.run import evaluate, prepare, run_scenario
from springlab.scenes.base import Scene
from springlab.scenes.capabilities.friction import DryFrictionSpec, FrictionCase, FrictionMeasure, SolverSetting
from springlab.sim.simulate import INTEGRATORS, check_timing, integrator_id

from .executor import Executor, chunked, resolve

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure

#: runs per chunk (a few seconds of work each)
CHUNK_RUNS = 48
#: a setting's error has converged in dt when the two smallest timesteps agree within this fraction [-]
CONVERGED = 0.1
#: the integrator whose error at the smallest timestep is a setting's model error (the highest order)
MODEL_INTEGRATOR = "rk4"
#: runs whose CPU times are within this factor (the same band) count as equally cheap, and the more accurate
#: is picked: one setting's CPU time scatters by about this much between runs on a shared machine
COST_BAND = 1.25
#: runs at the sweep's smallest dt (no run at dt/2 measured their integration error) the pick verifies at
#: most, cheapest first, before the cheapest run the sweep measured within tol
MAX_VERIFIED = 200


def mujoco_defaults() -> tuple[str, float]:
    """(integrator name, timestep [s]) of a fresh MuJoCo model: MuJoCo's own defaults, read from MuJoCo."""
    option = mujoco.MjSpec().option
    name = next(n for n, value in INTEGRATORS.items() if value == int(option.integrator))
    return name, float(option.timestep)


# -- rows ------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class SettingRun:
    """One run of the sweep: a case at one combination of settings, one integrator and timestep.

    Attributes
    ----------
    scenario
        the case's scenario.
    settings
        scene parameter -> value of every swept setting.
    integrator
        integrator name.
    dt
        timestep [s].
    steps
        steps taken.
    cpu_time_s
        the CPU time of the simulation on its one thread [s]: its cost, unaffected by other processes
        sharing the machine (`time.thread_time` around the run's `mujoco.rollout` call).
    max_rel_error
        max over the compared columns of max |sim - exact| / scale [-] (None: diverged).
    integration_error
        SAFETY x max |x(dt) - x(dt/2)| over the compared columns' scales [-]: this run's integration error,
        measured against the same setting's run at dt/2 (None: the sweep has no run at dt/2).
    measures
        declared quantity -> its error (relative, or absolute in its unit; FrictionMeasure).
    values
        declared quantity -> the run's value of it (SI).
    diverged
        the run blew up (never reported as a result).
    detail
        how it diverged.
    """

    scenario: str
    settings: dict[str, float]
    integrator: str
    dt: float
    steps: int
    cpu_time_s: float
    max_rel_error: float | None
    integration_error: float | None
    measures: dict[str, float | None]
    values: dict[str, float | None]
    diverged: bool = False
    detail: str = ""

    @property
    def error(self) -> float:
        """max_rel_error of a run that did not diverge [-] (for the Pareto front)."""
        if self.max_rel_error is None:
            raise ValueError(f"{self.integrator} at dt = {self.dt:g} s diverged: it has no error")
        return self.max_rel_error

    def to_dict(self) -> dict[str, Any]:
        """The JSON row: scenario, settings, integrator, dt [s], steps, cpu_time_s [s], max_rel_error,
        integration_error, measures, values, diverged, detail."""
        return json_ready(
            {
                "scenario": self.scenario,
                "settings": dict(self.settings),
                "integrator": self.integrator,
                "dt": self.dt,
                "steps": self.steps,
                "cpu_time_s": self.cpu_time_s,
                "max_rel_error": self.max_rel_error,
                "integration_error": self.integration_error,
                "measures": dict(self.measures),
                "values": dict(self.values),
                "diverged": self.diverged,
                "detail": self.detail,
            }
        )

    def row(self) -> dict[str, Any]:
        """The flat CSV/DataFrame row: settings, measures (`error_<quantity>`) and values as columns."""
        out: dict[str, Any] = {"scenario": self.scenario, **self.settings, "integrator": self.integrator, "dt": self.dt}
        out.update(steps=self.steps, cpu_time_s=self.cpu_time_s, max_rel_error=self.max_rel_error)
        out["integration_error"] = self.integration_error
        out.update({f"error_{k}": v for k, v in self.measures.items()})
        out.update(dict(self.values))
        out["diverged"] = self.diverged
        return json_ready(out)


@dataclasses.dataclass(frozen=True)
class ModelError:
    """What one combination of settings leaves as dt -> 0: MuJoCo's model error at those settings.

    Attributes
    ----------
    settings
        scene parameter -> value.
    dts
        the timesteps [s], largest first.
    errors
        MODEL_INTEGRATOR's max_rel_error at each timestep (None: diverged).
    model_error
        the error at the smallest timestep [-] (None: diverged there).
    converged
        whether the two smallest timesteps agree within CONVERGED: the error no longer depends on dt.
    values
        declared quantity -> its value at the smallest timestep (SI).
    """

    settings: dict[str, float]
    dts: tuple[float, ...]
    errors: tuple[float | None, ...]
    model_error: float | None
    converged: bool
    values: dict[str, float | None]

    def to_dict(self) -> dict[str, Any]:
        """JSON: settings, dts [s], errors, model_error, converged, values."""
        return json_ready(
            {
                "settings": dict(self.settings),
                "dts": list(self.dts),
                "errors": list(self.errors),
                "model_error": self.model_error,
                "converged": self.converged,
                "values": dict(self.values),
            }
        )


@dataclasses.dataclass(frozen=True)
class Pick:
    """The cheapest run of a case within a tolerance, verified by running its setting as `springlab run` does.

    Attributes
    ----------
    tol
        the tolerance [-].
    run
        the sweep's row (None: no setting meets tol).
    verified_error
        the verification run's largest max_rel [-] (None with run).
    speedup
        MuJoCo's default run's CPU time over this one's [-] (< 1: it costs more).
    floor
        where no setting meets tol: which floor stops it, in words ('' when one does).
    """

    tol: float
    run: SettingRun | None
    verified_error: float | None
    speedup: float | None
    floor: str = ""

    @property
    def found(self) -> bool:
        """Whether a verified setting meets tol."""
        return self.run is not None

    def to_dict(self) -> dict[str, Any]:
        """JSON: tol, run (the row or null), verified_error, speedup, floor."""
        return json_ready(
            {
                "tol": self.tol,
                "run": None if self.run is None else self.run.to_dict(),
                "verified_error": self.verified_error,
                "speedup": self.speedup,
                "floor": self.floor,
            }
        )


@dataclasses.dataclass(frozen=True)
class CaseStudy:
    """The sweep of one case and what it says.

    Attributes
    ----------
    scenario, friction, question
        the declared case (FrictionCase).
    measures
        the declared measures (FrictionMeasure), in order.
    settings
        the swept settings (SolverSetting) of this case's friction.
    runs
        every run, in sweep order.
    default
        MuJoCo's defaults: its settings, integrator and timestep (None: not swept or diverged).
    model_errors
        one per combination of settings (ModelError), in sweep order.
    pareto
        the runs no other beats in both error and CPU time, cheapest first.
    pick
        for a tolerance, the verified cheapest run (Pick); None without one.
    """

    scenario: str
    friction: str
    question: str
    measures: tuple[FrictionMeasure, ...]
    settings: tuple[SolverSetting, ...]
    runs: tuple[SettingRun, ...] = dataclasses.field(repr=False)
    default: SettingRun | None
    model_errors: tuple[ModelError, ...] = dataclasses.field(repr=False)
    pareto: tuple[SettingRun, ...] = dataclasses.field(repr=False)
    pick: Pick | None = None

    @property
    def default_model(self) -> ModelError | None:
        """The model error of MuJoCo's default settings."""
        defaults = {s.name: s.mujoco_default for s in self.settings}
        return next((m for m in self.model_errors if m.settings == defaults), None)

    @property
    def best_model(self) -> ModelError | None:
        """The combination of settings with the smallest model error."""
        finite = [m for m in self.model_errors if m.model_error is not None]
        return min(finite, key=lambda m: m.model_error or 0.0) if finite else None

    def describe(self, settings: Mapping[str, float]) -> str:
        """Settings in words: only those that differ from MuJoCo's defaults ('MuJoCo's defaults' if none)."""
        changed = [
            f"{s.name} {s.word(settings[s.name])}" for s in self.settings if settings.get(s.name) != s.mujoco_default
        ]
        return ", ".join(changed) or "MuJoCo's defaults"

    def answer(self) -> str:
        """What the case says, in a few sentences (the demo's report and the terminal print it)."""
        parts = [f"{self.scenario} ({self.question})"]
        default, model = self.default, self.default_model
        if default is not None and default.max_rel_error is not None:
            values = _values_text(self.measures, default.values)
            parts.append(
                f"at MuJoCo's defaults ({default.integrator}, dt = {default.dt:g} s) its error is"
                f" {default.max_rel_error:.2g}{values}."
            )
        if model is not None and model.model_error is not None:
            trend = f"{MODEL_INTEGRATOR} gives {', '.join(_number(e) for e in model.errors)} at dt = {', '.join(f'{d:g}' for d in model.dts)} s"
            if model.converged:
                parts.append(f"That is MuJoCo's model error, not the integration's: {trend}, the same as dt -> 0.")
            else:
                parts.append(
                    f"Part of it is integration error even at the smallest dt: {trend}, still falling as dt -> 0."
                )
        if self.pick is not None:
            pick = self.pick
            if pick.run is not None:
                cost = f"{1 / pick.speedup:.2g}x the cost of MuJoCo's defaults" if pick.speedup else "cost unknown"
                values = _values_text(self.measures, pick.run.values)
                parts.append(
                    f"Cheapest setting meeting {pick.tol:g}: {self.describe(pick.run.settings)} with"
                    f" {pick.run.integrator} at dt = {pick.run.dt:g} s, error {_number(pick.verified_error)}{values}"
                    f" (verified by a run), {cost}."
                )
            else:
                parts.append(pick.floor)
        return " ".join(parts)

    def to_dict(self) -> dict[str, Any]:
        """JSON: scenario, friction_model, question, measures, default, model_errors, pareto, pick, answer, runs."""
        return json_ready(
            {
                "scenario": self.scenario,
                "friction_model": self.friction,
                "question": self.question,
                "measures": [{"quantity": m.quantity, "label": m.label, "scale": m.scale} for m in self.measures],
                "default": None if self.default is None else self.default.to_dict(),
                "default_model_error": None if self.default_model is None else self.default_model.to_dict(),
                "best_model_error": None if self.best_model is None else self.best_model.to_dict(),
                "model_errors": [m.to_dict() for m in self.model_errors],
                "pareto": [r.to_dict() for r in self.pareto],
                "pick": None if self.pick is None else self.pick.to_dict(),
                "answer": self.answer(),
                "runs": [r.to_dict() for r in self.runs],
            }
        )


@dataclasses.dataclass(frozen=True, repr=False)
class FrictionSettings(display.Shown):
    """The friction-settings study of one scene (`friction_settings`).

    `to_dict()` is friction_settings.json (what `springlab friction-settings --json` prints),
    `to_pandas()` one row per run.

    Attributes
    ----------
    scene
        the scene's name.
    overrides
        the parameters the caller set (SI).
    tol
        the tolerance the picks meet (None: no picks).
    integrators
        the integrators swept.
    dts
        the timesteps swept [s], largest first.
    mujoco_default
        (integrator, dt [s]) of MuJoCo's own defaults, the baseline.
    cases
        one CaseStudy per case.
    wall_time_s
        the study's wall time [s].
    """

    scene: str
    overrides: dict[str, Any]
    tol: float | None
    integrators: tuple[str, ...]
    dts: tuple[float, ...]
    mujoco_default: tuple[str, float]
    cases: tuple[CaseStudy, ...]
    wall_time_s: float = 0.0

    @property
    def runs(self) -> int:
        """Runs in the sweep."""
        return sum(len(c.runs) for c in self.cases)

    def answer(self) -> str:
        """How much MuJoCo's friction drifts and what it costs to make it stop, one paragraph per case."""
        return "\n".join(case.answer() for case in self.cases)

    def _shown(self) -> display.Summary:
        """The study as a notebook shows it: the picks first (or that none was asked for), then the runs."""
        picks = [c.pick for c in self.cases]
        if self.tol is None:
            verdict, ok = "measured (no tol)", None
        elif all(p is not None and p.run is not None for p in picks):
            verdict, ok = f"a verified setting for tol {self.tol:g} in every case", True
        else:
            verdict, ok = f"no verified setting for tol {self.tol:g} in some case", False
        return display.Summary(
            "FrictionSettings",
            f"{self.scene}: {', '.join(c.scenario for c in self.cases)}",
            verdict,
            ok,
            self.answer(),
            (
                display.Fact("runs", self.runs),
                display.Fact("integrators", ", ".join(self.integrators)),
                display.Fact("MuJoCo default", f"{self.mujoco_default[0]} at dt = {self.mujoco_default[1]:g} s"),
                display.Fact("wall time", self.wall_time_s, "s"),
            ),
            display.table(
                ("scenario", "settings", "integrator", "dt [s]", "max rel error [-]", "CPU time [s]"),
                [
                    (c.scenario, c.describe(r.settings), r.integrator, r.dt, r.max_rel_error, r.cpu_time_s)
                    for c in self.cases
                    for r in c.runs
                ],
            ),
        )

    def plot(self) -> Figure:
        """Per case, error against cost and against dt, the pick marked (`springlab.plots.friction_settings.friction_figure`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """friction_settings.json: scene, tol, integrators, dts, mujoco_default, runs, wall_time_s, cases."""
        return json_ready(
            {
                "scene": self.scene,
                "parameters": dict(self.overrides),
                "tol": self.tol,
                "integrators": list(self.integrators),
                "dts": list(self.dts),
                "mujoco_default": {"integrator": self.mujoco_default[0], "dt": self.mujoco_default[1]},
                "runs": self.runs,
                "wall_time_s": self.wall_time_s,
                "cases": [c.to_dict() for c in self.cases],
            }
        )

    def to_pandas(self) -> pandas.DataFrame:
        """One row per run of every case: settings, integrator, dt, steps, wall time, errors (needs pandas)."""
        return tables.to_pandas([r.row() for c in self.cases for r in c.runs])


def _number(value: float | None) -> str:
    return "diverged" if value is None else f"{value:.2g}"


def _values_text(measures: Sequence[FrictionMeasure], values: Mapping[str, float | None]) -> str:
    """'; creep velocity ... 1.8e-03' for the measures with a value."""
    shown = [
        f"{m.label.split(' (')[0].split(' [')[0]} {values[m.quantity]:.3g}"
        for m in measures
        if values.get(m.quantity) is not None and math.isfinite(values[m.quantity] or math.nan)
    ]
    return f" ({'; '.join(shown)})" if shown else ""


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


def settings_chunk(payload: dict[str, Any], nthread: int = 0) -> list[dict[str, Any]]:
    """One chunk of runs (module-level, plain data: it runs on dask workers too).

    payload: scene (name), scenario, overrides, duration [s], measures ((quantity, scale) pairs),
    groups (lists of (settings, integrator, dt) triples of one setting and integrator, dt halving).
    Each run is built from the scene's MJCF, set up and stepped as `springlab run` does (one
    `mujoco.rollout` call, alone on this thread: its CPU time is its cost) and compared with its exact
    solution (`runs.run.evaluate`, checks left out); a run followed by its run at dt/2 gets its
    integration error estimate, SAFETY x their largest difference over the compared columns' scales.
    """
    rows = []
    wanted = {name for pair in payload["measures"] for name in pair if name}
    for group in payload["groups"]:
        settings, _, _ = group[0]
        # one case per setting: its runs at every integrator and dt share its model (simulate steps a copy)
        case = scenes.case(payload["scene"], payload["scenario"], {**payload["overrides"], **settings})
        previous = None
        for _, integrator, dt in group:
            steps = check_timing(dt, payload["duration"])
            row: dict[str, Any] = {
                "steps": steps,
                "cpu_time_s": math.nan,
                "error": None,
                "integration_error": None,
                "quantities": {},
                "detail": "",
            }
            setup = case.setup(steps, dt)
            try:
                start = _time.thread_time()
                trajectory = case.simulate(integrator, dt, payload["duration"], setup=setup)
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
    scene: str | Scene,
    scenarios: Sequence[str] | None = None,
    *,
    tol: float | None = None,
    integrators: Sequence[str] | None = None,
    dts: Sequence[float] | None = None,
    values: Mapping[str, Sequence[float]] | None = None,
    executor: Executor | None = None,
    **parameters: Any,
) -> FrictionSettings:
    """Sweep MuJoCo's friction settings over a scene's declared dry-friction cases (see the module docstring).

    Parameters
    ----------
    scene
        a scene that declares `dry_friction`.
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
        parameter, fewer than two timesteps, a bad tolerance.
    """
    started = _time.perf_counter()
    scene_obj, spec = declaration(scene)
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
        payloads = [
            {
                "scene": reference,
                "scenario": case.scenario,
                "overrides": dict(parameters),
                "duration": scenario.duration,
                "measures": [(m.quantity, m.scale) for m in case.measures],
                "groups": groups[p.start : p.stop],
            }
            for p in pieces
        ]
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
    return SettingRun(
        scenario=case.scenario,
        settings=settings,
        integrator=integrator,
        dt=dt,
        steps=int(outcome["steps"]),
        cpu_time_s=float(outcome["cpu_time_s"]),
        max_rel_error=outcome["error"],
        integration_error=outcome["integration_error"],
        measures={m.quantity: None if diverged else measure_error(m, quantities) for m in case.measures},
        values={m.quantity: _finite(quantities.get(m.quantity)) for m in case.measures},
        diverged=diverged,
        detail=outcome["detail"],
    )


def pareto(runs: Sequence[SettingRun]) -> tuple[SettingRun, ...]:
    """The runs no other run beats in both error and CPU time, cheapest first (diverged runs left out)."""
    candidates = sorted(
        (r for r in runs if not r.diverged and math.isfinite(r.cpu_time_s)), key=lambda r: (r.cpu_time_s, r.error)
    )
    front, best = [], math.inf
    for r in candidates:
        if r.error < best:
            front.append(r)
            best = r.error
    return tuple(front)


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
        model_errors=_model_errors(runs, dts) if MODEL_INTEGRATOR in integrators else (),
        pareto=pareto(runs),
    )
    if tol is None:
        return study
    return dataclasses.replace(study, pick=_pick(scene, study, tol, parameters))


def _model_errors(runs: Sequence[SettingRun], dts: tuple[float, ...]) -> tuple[ModelError, ...]:
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


def _pick(scene: Scene, study: CaseStudy, tol: float, parameters: Mapping[str, Any]) -> Pick:
    """The cheapest run within tol whose setting a full run verifies, or why there is none."""
    candidates = sorted(
        (r for r in study.runs if not r.diverged and r.error <= tol and math.isfinite(r.cpu_time_s)),
        key=lambda r: (_cost_band(r.cpu_time_s), r.error),
    )
    # the verification reruns at dt/2 and needs SAFETY max |x(dt) - x(dt/2)| / scale <= tol too: the sweep
    # measured that for every run but those at its smallest dt; a run it already failed is not tried
    # runs it measured within tol pass for certain: try them last, and before them only the unmeasured runs
    # that are cheaper than the cheapest of them
    measured = [r for r in candidates if r.integration_error is not None and r.integration_error <= tol]
    cheapest = _cost_band(measured[0].cpu_time_s) if measured else math.inf
    unmeasured = [r for r in candidates if r.integration_error is None and _cost_band(r.cpu_time_s) < cheapest]
    hopeful = unmeasured[:MAX_VERIFIED] + measured
    baseline = study.default.cpu_time_s if study.default is not None else None
    tried = 0
    for candidate in hopeful:
        tried += 1
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
            continue
        if not run.passed:
            continue
        return Pick(
            tol=tol,
            run=candidate,
            verified_error=run.max_rel_error,
            speedup=baseline / candidate.cpu_time_s if baseline else None,
        )
    return Pick(tol=tol, run=None, verified_error=None, speedup=None, floor=_floor(study, tol, len(candidates), tried))


def _cost_band(seconds: float) -> int:
    """The band of COST_BAND in which a CPU time falls: runs in one band count as equally cheap."""
    return math.floor(math.log(max(seconds, 1e-12)) / math.log(COST_BAND))


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
        f" {_number(model.model_error if model else None)}): the integration is the floor, a smaller dt may reach it;"
        f" {closest}."
    )
