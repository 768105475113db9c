"""The friction-settings study's results (springlab.studies.friction_settings): its rows, each setting's model
error, each case's sweep with its front and pick, and the study; `to_dict()` of `FrictionSettings` is
friction_settings.json. The rows hold the shared row of springlab.studies.settings (`run`), the fronts and
picks are its Pareto front and Recommendation.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab import display, tables
from springlab.answer import Answer
from springlab.files import Output, json_ready, number_text
from springlab.scenes.capabilities.friction import FrictionMeasure, SolverSetting

from . import answers
from .settings import COST_BASIS, Recommendation, Run, RunFields

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure

#: the integrator whose error at the smallest timestep is a setting's model error (the highest order)
MODEL_INTEGRATOR = "rk4"

#: the pick's JSON keys under the names friction_settings.json has always used
PICK_NAMES = {"tolerance": "tol", "error": "verified_error", "time_s": "cpu_time_s"}


@dataclasses.dataclass(frozen=True)
class SettingRun(RunFields):
    """One run of the sweep: a case at one combination of settings, one integrator and timestep.

    Attributes
    ----------
    run
        the shared row (springlab.studies.settings.Run): the settings as options, steps, max_rel_error as its
        error, counted work as its cost, the CPU time as its time.
    scenario
        the case's scenario.
    settings
        scene parameter -> value of every swept setting.
    integration_error
        SAFETY x max |x(dt) - x(dt/2)| over the compared columns' scales [-]: this run's integration error,
        measured against the same setting's run at dt/2 (None: the sweep has no run at dt/2).
    measures
        declared quantity -> its error (relative, or absolute in its unit; FrictionMeasure).
    values
        declared quantity -> the run's value of it (SI).
    """

    run: Run
    scenario: str
    settings: dict[str, float]
    integration_error: float | None
    measures: dict[str, float | None]
    values: dict[str, float | None]

    @property
    def cpu_time_s(self) -> float:
        """The CPU time of the simulation on its one thread [s] (`time.thread_time` around its `mujoco.rollout`
        call), reported beside its counted work."""
        return self.run.time_s

    @property
    def max_rel_error(self) -> float | None:
        """max over the compared columns of max |sim - exact| / scale [-] (None: diverged)."""
        return self.run.error

    @property
    def error(self) -> float:
        """max_rel_error of a run that did not diverge [-] (for the Pareto front)."""
        if self.run.error is None:
            raise ValueError(f"{self.integrator} at dt = {self.dt:g} s diverged: it has no error")
        return self.run.error

    def to_dict(self) -> dict[str, Any]:
        """The JSON row: scenario, settings, integrator, dt [s], steps, cpu_time_s [s], cost [DOF-evaluations],
        max_rel_error, integration_error, measures, values, diverged, detail."""
        return json_ready(
            {
                "scenario": self.scenario,
                "settings": dict(self.settings),
                "integrator": self.integrator,
                "dt": self.dt,
                "steps": self.steps,
                "cpu_time_s": self.cpu_time_s,
                "cost": self.cost,
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
        out.update(steps=self.steps, cpu_time_s=self.cpu_time_s, cost=self.cost, max_rel_error=self.max_rel_error)
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
        the runs no other beats in both error and counted work, cheapest first.
    pick
        for a tolerance, the verified cheapest run (springlab.studies.settings.Recommendation: its `row`, the
        verification's `error`, `text`; `details` its `speedup` over MuJoCo's defaults in CPU time and its
        `work_vs_default` in counted work); None without one.
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
    pick: Recommendation[SettingRun] | None = None

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
                f"at MuJoCo's defaults ({default.integrator}, dt = {answers.written(default.dt, '~s')}) its error is"
                f" {default.max_rel_error:.2g}{values}."
            )
        if model is not None and model.model_error is not None:
            trend = f"{MODEL_INTEGRATOR} gives {', '.join(error_text(e) for e in model.errors)} at dt = {', '.join(f'{d:g}' for d in model.dts)} s"
            if model.converged:
                parts.append(f"That is MuJoCo's model error, not the integration's: {trend}, the same as dt -> 0.")
            else:
                parts.append(
                    f"Part of it is integration error even at the smallest dt: {trend}, still falling as dt -> 0."
                )
        if self.pick is not None:
            pick = self.pick
            if pick.row is not None:
                ratio = pick.details.get("work_vs_default")
                cost = f"{ratio:.2g}x the counted work of MuJoCo's defaults" if ratio else "work unknown"
                values = _values_text(self.measures, pick.row.values)
                ties = f"; {len(pick.ties)} other settings tie with it in counted work" if pick.ties else ""
                parts.append(
                    f"Cheapest setting meeting {pick.tolerance:g}: {self.describe(pick.row.settings)} with"
                    f" {pick.row.integrator} at dt = {answers.written(pick.row.dt, '~s')}, error {error_text(pick.error)}{values}"
                    f" (verified by a run), {cost}{ties}."
                )
            else:
                parts.append(pick.text)
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
                "pick": None if self.pick is None else _pick_dict(self.pick),
                "answer": self.answer(),
                "runs": [r.to_dict() for r in self.runs],
            }
        )


@dataclasses.dataclass(frozen=True)
class HeldBody:
    """A body that dry friction holds in a model file, through a run of the whole hold.

    Attributes
    ----------
    name
        the body's name.
    size_m
        its size [m]: the largest extent of its colliding geoms' bounding boxes (tol's length scale).
    holders
        the bodies touching it at the operating point (empty: a joint's frictionloss holds it).
    coulomb_margin
        how many times the force friction carries it could carry, early in the hold [-] (above 1: Coulomb
        friction holds it, so any slip is MuJoCo's model error; None: friction carried no force).
    creep_velocity_m_s
        its mean speed over the second half of the time it was held [m/s] (None: the run diverged).
    slip_m
        the largest distance of its centre of mass from where the hold started while it was held [m] (None:
        diverged).
    lost_at_s
        when it first touched none of its holders [s] (None: held throughout).
    """

    name: str
    size_m: float
    holders: tuple[str, ...]
    coulomb_margin: float | None
    creep_velocity_m_s: float | None
    slip_m: float | None
    lost_at_s: float | None

    def to_dict(self) -> dict[str, Any]:
        """{"name", "size_m", "holders", "coulomb_margin", "creep_velocity_m_s", "slip_m", "lost_at_s"}."""
        return json_ready(dataclasses.asdict(self))

    def state(self, hold_s: float) -> str:
        """'creeps at 7.7 mm/s and falls out of the grip at t = 7.61 s' or '... slips 0.2 mm over 60 s'."""
        if self.creep_velocity_m_s is None or self.slip_m is None:
            return "diverges"
        creep = speed_text(self.creep_velocity_m_s)
        if self.lost_at_s is not None:
            return f"creeps at {creep} and falls out of the grip at t = {self.lost_at_s:.3g} s"
        return f"creeps at {creep}, slipping {distance_text(self.slip_m)} over {hold_s:g} s"


@dataclasses.dataclass(frozen=True)
class HoldReport:
    """The facts of a model file's hold (springlab.studies.friction_hold), beside its one case "hold".

    Attributes
    ----------
    model
        the model file.
    operating_point
        where the hold starts, e.g. "keyframe 'grasp'".
    hold_s
        the hold [s].
    window_s
        the sweep runs' length [s] (their slip over the rest of the hold is their creep velocity times it).
    tol
        the slip allowed over the hold, in body sizes [-].
    bodies
        the held bodies through a run of the whole hold at the model's own settings.
    skipped
        settings not swept, and why.
    pick_bodies
        the held bodies through the pick's verification run (empty: no pick).
    friction_only
        where the pick changes how stiff the contact is (solref, solimp), the cheapest verified setting that
        leaves those as they are (None: the pick already does, or there is no pick).
    friction_only_bodies
        the held bodies through its verification run.
    """

    model: str
    operating_point: str
    hold_s: float
    window_s: float
    tol: float
    bodies: tuple[HeldBody, ...]
    skipped: tuple[str, ...] = ()
    pick_bodies: tuple[HeldBody, ...] = ()
    friction_only: Recommendation[SettingRun] | None = None
    friction_only_bodies: tuple[HeldBody, ...] = ()

    def allowed(self) -> str:
        """'1 mm (0.025 of the 40 mm body)': tol in metres and body sizes."""
        size = min(b.size_m for b in self.bodies)
        return f"{distance_text(self.tol * size)} ({self.tol:g} of the {distance_text(size)} body)"

    def answer(self, case: CaseStudy) -> str:
        """What the hold says: the margin, the creep at the model's own settings, that neither integrator nor
        timestep removes it, and the cheapest setting that holds (or why none does)."""
        parts = []
        for body in self.bodies:
            margin = body.coulomb_margin
            holds = (
                f"Coulomb friction holds {body.name!r} with margin {margin:.3g}x"
                if margin is not None and margin > 1
                else f"Coulomb friction cannot hold {body.name!r} (margin {margin:.3g}x): its slip is physics, not creep"
                if margin is not None
                else f"friction carries no force on {body.name!r}"
            )
            parts.append(
                f"{holds}; at the model's own settings ({case.default.integrator if case.default else '?'}, dt ="
                f" {case.default.dt if case.default else math.nan:g} s, {case.describe(case.default.settings) if case.default else '?'}) it"
                f" {body.state(self.hold_s)}."
            )
        spread = self.creep_spread(case)
        if spread:
            parts.append(spread)
        pick = case.pick
        if pick is not None and pick.row is not None:
            ratio = pick.details.get("work_vs_default")
            cost = f"{ratio:.3g}x the counted work of the model's own settings" if ratio else "work unknown"
            held = "; ".join(f"{b.name!r} {b.state(self.hold_s)}" for b in self.pick_bodies)
            parts.append(
                f"Cheapest setting that keeps it within {self.allowed()} over {self.hold_s:g} s:"
                f" {case.describe(pick.row.settings)} with {pick.row.integrator} at dt = {pick.row.dt:g} s, {cost}"
                f" (verified by a run of the whole hold: {held})."
            )
        elif pick is not None:
            parts.append(pick.text)
        other = self.friction_only
        if other is not None and other.row is not None:
            ratio = other.details.get("work_vs_default")
            held = "; ".join(f"{b.name!r} {b.state(self.hold_s)}" for b in self.friction_only_bodies)
            parts.append(
                f"Without changing how stiff the contact is (solref, solimp): {case.describe(other.row.settings)}"
                f" with {other.row.integrator} at dt = {other.row.dt:g} s, {ratio:.3g}x the counted work ({held})."
            )
        elif other is not None:
            parts.append(f"Nothing cheaper holds it without changing how stiff the contact is: {other.text}")
        return " ".join(parts)

    def creep_spread(self, case: CaseStudy) -> str:
        """'Integrator and timestep do not remove it: ...' from the sweep's runs at the model's own settings."""
        if case.default is None:
            return ""
        own = [r for r in case.runs if r.settings == case.default.settings and r.run.valid]
        creeps = [r.values.get("creep_velocity_m_s") for r in own]
        finite = [c for c in creeps if c is not None]
        if len(finite) < 2:
            return ""
        names = ", ".join(dict.fromkeys(r.integrator for r in own))
        steps = ", ".join(f"{d * 1e3:g}" for d in sorted({r.dt for r in own}, reverse=True))
        return (
            f"That is MuJoCo's soft-friction model error, which integrator and timestep do not remove: {names} at"
            f" dt = {steps} ms all creep at {speed_text(min(finite))} to {speed_text(max(finite))} over the first"
            f" {self.window_s:g} s."
        )

    def to_dict(self) -> dict[str, Any]:
        """friction_settings.json's "hold": model, operating_point, hold_s, window_s, tol, allowed_slip_m, bodies,
        skipped, pick_bodies, friction_only (a pick's shape, or null), friction_only_bodies."""
        return json_ready(
            {
                "model": self.model,
                "operating_point": self.operating_point,
                "hold_s": self.hold_s,
                "window_s": self.window_s,
                "tol": self.tol,
                "allowed_slip_m": self.tol * min(b.size_m for b in self.bodies),
                "bodies": [b.to_dict() for b in self.bodies],
                "skipped": list(self.skipped),
                "pick_bodies": [b.to_dict() for b in self.pick_bodies],
                "friction_only": None if self.friction_only is None else _pick_dict(self.friction_only),
                "friction_only_bodies": [b.to_dict() for b in self.friction_only_bodies],
            }
        )


def speed_text(value: float) -> str:
    """A speed [m/s] in mm/s or um/s, three digits: '7.69 mm/s', '0.41 um/s'."""
    return f"{value * 1e3:.3g} mm/s" if abs(value) >= 1e-4 else f"{value * 1e6:.3g} um/s"


def distance_text(value: float) -> str:
    """A distance [m] in mm or um, three digits: '1 mm', '40 mm', '3.2 um'."""
    return f"{value * 1e3:.3g} mm" if abs(value) >= 1e-4 else f"{value * 1e6:.3g} um"


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
    hold
        a model file's hold (springlab.studies.friction_hold; None: a scene's study).
    """

    scene: str
    overrides: dict[str, Any]
    tol: float | None
    integrators: tuple[str, ...]
    dts: tuple[float, ...]
    mujoco_default: tuple[str, float]
    cases: tuple[CaseStudy, ...]
    wall_time_s: float = 0.0
    hold: HoldReport | None = None

    @property
    def runs(self) -> int:
        """Runs in the sweep."""
        return sum(len(c.runs) for c in self.cases)

    def answer_by_case(self) -> str:
        """How much MuJoCo's friction drifts and what it costs to make it stop, one paragraph per case."""
        return "\n".join(self.case_answer(case) for case in self.cases)

    def case_answer(self, case: CaseStudy) -> str:
        """One case's answer: a model file's hold in its own words, a scene's case as `CaseStudy.answer`."""
        return case.answer() if self.hold is None else self.hold.answer(case)

    @property
    def question_answer(self) -> Answer:
        """The question and its answer: per case, the error at MuJoCo's defaults and the verified cheapest
        setting, one clause each (a model file's hold: its own words, `HoldReport.answer`)."""
        say = answers.Quoter()
        integrator, dt = self.mujoco_default
        within = f", and which solver setting is the cheapest within {self.tol:g}" if self.tol is not None else ""
        if self.hold is not None:
            hold = self.hold
            question = (
                f"How fast do the bodies dry friction holds in {hold.model} creep over {answers.written(hold.hold_s, '~s')}"
                f" at its own settings, and which settings keep the slip within {hold.allowed()}?"
            )
            numbers = {
                f"{b.name}_creep_velocity_m_s": b.creep_velocity_m_s
                for b in hold.bodies
                if b.creep_velocity_m_s is not None
            }
            return answers.of_words(question, " ".join(hold.answer(case) for case in self.cases), numbers)
        question = (
            f"How far from the exact Coulomb answer is MuJoCo's dry friction in {', '.join(c.scenario for c in self.cases)}"
            f" at its defaults ({integrator}, dt = {answers.written(dt, '~s')}){within}?"
        )
        parts = []
        # MuJoCo's defaults are a run of the sweep only where its integrator and timestep were swept
        swept = integrator in self.integrators and any(math.isclose(dt, d) for d in self.dts)
        for case in self.cases:
            default, pick, name = case.default, case.pick, case.scenario
            if default is not None and default.max_rel_error is not None:
                at_default = f"error {say(f'{name}_default_error', default.max_rel_error, spec='.2g')} at the defaults"
            else:
                at_default = (
                    "diverged at the defaults" if swept else "MuJoCo's defaults not in the sweep (--integrators, --dt)"
                )
            if pick is None:
                parts.append(f"{name}: {at_default}")
            elif pick.row is not None and pick.found:
                parts.append(
                    f"{name}: {at_default}; cheapest within {pick.tolerance:g}: {case.describe(pick.row.settings)} with"
                    f" {pick.row.integrator} at {say.dt(f'{name}_pick_dt_s', pick.row.dt)}, error"
                    f" {say(f'{name}_pick_error', pick.error or 0.0, spec='.2g')}"
                )
            else:
                parts.append(f"{name}: {at_default}; no verified setting within {pick.tolerance:g}")
        return say.answer(question, ". ".join(parts) + ".")

    @property
    def question(self) -> str:
        """What the study asks, in words (`question_answer`)."""
        return self.question_answer.question

    @property
    def answer(self) -> str:
        """The answer in words with units (`question_answer`)."""
        return self.question_answer.answer

    def _shown(self) -> display.Summary:
        """The study as a notebook shows it: the picks first (or that none was asked for), then the runs."""
        picks = [c.pick for c in self.cases]
        if self.tol is None:
            verdict, ok = "measured (no tol)", None
        elif all(p is not None and p.found for p in picks):
            verdict, ok = f"a verified setting for tol {self.tol:g} in every case", True
        else:
            verdict, ok = f"no verified setting for tol {self.tol:g} in some case", False
        return display.Summary(
            "FrictionSettings",
            f"{self.scene}: {', '.join(c.scenario for c in self.cases)}",
            verdict,
            ok,
            self.answer,
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
        """friction_settings.json: scene, tol, integrators, dts, mujoco_default, runs, wall_time_s, cases,
        cost_basis."""
        return json_ready(
            {
                **self.question_answer.to_dict(),
                "scene": self.scene,
                "parameters": dict(self.overrides),
                "tol": self.tol,
                "integrators": list(self.integrators),
                "dts": list(self.dts),
                "mujoco_default": {"integrator": self.mujoco_default[0], "dt": self.mujoco_default[1]},
                "runs": self.runs,
                "wall_time_s": self.wall_time_s,
                "cases": [c.to_dict() for c in self.cases],
                "cost_basis": COST_BASIS,
                **({} if self.hold is None else {"hold": self.hold.to_dict()}),
            }
        )

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab friction-settings --output DIR` writes (springlab.outputs.write):
        friction_settings.json, friction_settings.csv (one row per run, `SettingRun.row()`) and friction_settings.png."""
        rows = [r.row() for case in self.cases for r in case.runs]
        names = list(dict.fromkeys(name for row in rows for name in row))
        lines = [",".join(names)] + [",".join(_csv_cell(row.get(name)) for name in names) for row in rows]
        return (
            Output.json("friction_settings.json", self.to_dict()),
            Output("friction_settings.csv", "\n".join(lines) + "\n"),
            Output("friction_settings.png"),
        )

    def to_pandas(self) -> pandas.DataFrame:
        """One row per run of every case: settings, integrator, dt, steps, wall time, errors (needs pandas)."""
        return tables.to_pandas([r.row() for c in self.cases for r in c.runs])


def error_text(value: float | None) -> str:
    """An error [-] in two digits, or 'diverged' for None."""
    return "diverged" if value is None else f"{value:.2g}"


def _values_text(measures: Sequence[FrictionMeasure], values: Mapping[str, float | None]) -> str:
    """' (stop position -5.34 mm; creep velocity 1.8 mm/s)' for the measures with a value, each in the unit its
    name ends in (springlab.studies.answers)."""
    shown = [
        f"{m.label.split(' (')[0].split(' [')[0]} {answers.written(values[m.quantity] or 0.0, answers.unit_of(m.quantity))}"
        for m in measures
        if values.get(m.quantity) is not None and math.isfinite(values[m.quantity] or math.nan)
    ]
    return f" ({'; '.join(shown)})" if shown else ""


def _pick_dict(pick: Recommendation[SettingRun]) -> dict[str, Any]:
    """friction_settings.json's `pick`: tol, run (the row or null), verified_error, speedup, floor (the words where
    none meets tol, else ''), and the shared recommendation's keys."""
    out = {"run": None, "speedup": None, "work_vs_default": None, **pick.to_dict(PICK_NAMES)}
    out["run"] = None if pick.row is None else pick.row.to_dict()
    out["floor"] = "" if pick.found else pick.text
    return json_ready(out)


def _csv_cell(value: Any) -> str:
    """friction_settings.csv's text of a value: empty for None, true/false, floats in their shortest exact form."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value)).lower()
    if isinstance(value, (float, np.floating)):  # np.float64's own repr is `np.float64(0.1)` under numpy 2
        return number_text(value)
    return str(value)
