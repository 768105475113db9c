"""The audit's result: `Audit`, immutable, its facts as attributes (`audit.recommendation.dt`,
`audit.own.stable`, `audit.stability["rk4"].limit_dt_measured_s`, ...); `Audit.to_dict()` is audit.json,
`Audit.to_pandas()` the sweep's table and `Audit.message` its words (springlab.studies.audit.text).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from springlab import display, tables
from springlab.answer import Answer
from springlab.exact.linearize import Linearization
from springlab.files import Output
from springlab.sim.simulate import Setup
from springlab.studies import answers
from springlab.studies.settings import COST_BASIS, Recommendation, Run

from . import text
from .limits import ConstraintFlag, Limit
from .parts import Excitation, Linearity, OwnSetting, PointReport, ReferenceUsed, Timings

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure

#: audit.json's names for the recommendation's keys (the names it has always had)
RECOMMENDATION_NAMES = {"time_s": "wall_time_s"}

#: what audit.json says counts as numerically unstable
STABILITY_CRITERION = (
    "numerically unstable: the measured one-step map amplifies a mode more than the exact flow"
    " exp(lambda dt) does, by more than 1e-4 per step"
)


@dataclasses.dataclass(frozen=True, repr=False)
class Audit(display.Shown):
    """An audit of one model (springlab.studies.audit.audit says how it is made); `to_dict()` is audit.json and
    `audit --json`.

    Attributes
    ----------
    model
        where the model came from (path, scene name or "<MjModel>").
    linear
        the linearization at the operating point (its `point`, `modes`, `fastest`).
    start
        the perturbed start of the sweep runs.
    duration
        simulated time of every run [s].
    tol
        tolerance of the recommendation [-].
    perturb
        size of the initial perturbation [m or rad].
    stability
        integrator -> `Limit` (predicted / measured / confirmed stability limit [s], margin [-]).
    own
        the model's own setting (`OwnSetting`).
    constraints
        constraint settings the own timestep breaks (solref timeconst < 2 dt).
    is_linear, linearity
        the linearity verdict and its measure (`Linearity`).
    reference
        the reference of the sweep (`ReferenceUsed`).
    runs
        the sweep, per integrator, largest dt first (springlab.studies.settings.Run: the setting, steps, error
        [-], counted cost [DOF-evaluations], measured time [s]; `to_pandas()` is their table).
    orders
        integrator -> observed order (None: no clean power law, e.g. contacts).
    pareto
        runs no other beats in both error and counted cost, cheapest first (springlab.studies.settings
        .pareto_front: never a diverged run or one beyond its integrator's confirmed limit).
    recommendation
        the cheapest setting in counted work meeting tol, verified by a run of its own
        (springlab.studies.settings.Recommendation: the same audit gives the same pick).
    timings
        wall time of each stage [s] (`Timings`).
    point_state
        what constrains the operating point and the motion, whether it is at rest (`PointReport`).
    excitation
        how the start moves the model and what moved (`Excitation`).
    """

    model: str
    linear: Linearization
    start: Setup
    duration: float
    tol: float
    perturb: float
    stability: Mapping[str, Limit]
    own: OwnSetting
    constraints: tuple[ConstraintFlag, ...]
    is_linear: bool
    linearity: Linearity
    reference: ReferenceUsed
    runs: tuple[Run, ...]
    orders: Mapping[str, float | None]
    pareto: tuple[Run, ...]
    recommendation: Recommendation[Run]
    timings: Timings
    point_state: PointReport
    excitation: Excitation

    @property
    def own_ok(self) -> bool:
        """The model's own setting is stable and meets tol (exit 0 of the CLI; otherwise 1)."""
        return bool(self.own.stable) and self.own.error is not None and self.own.error <= self.tol

    @property
    def mode_count(self) -> str:
        """'6 modes (2 rigid)': how the text and audit.png count the modes (a complex pair is one mode)."""
        return text.mode_count(self.linear.modes)

    @property
    def message(self) -> str:
        """A few lines for people (what `springlab audit` prints; springlab.studies.audit.text): modes, what
        holds the operating point, the own setting's margin and error, the recommendation, warnings (not at
        rest, no motion, broken constraints, an unconverged reference)."""
        return text.message(self)

    @property
    def question_answer(self) -> Answer:
        """The question and its answer: the own setting's stability and error, the verified cheapest setting."""
        say = answers.Quoter()
        own, pick = self.own, self.recommendation
        tolerance = f"{self.tol:g}"
        question = (
            f"Is {self.model}'s own setting ({own.integrator}, dt = {answers.written(own.dt, '~s')}) stable and within"
            f" {tolerance} over {answers.written(self.duration, '~s')}, and which setting is the cheapest that is?"
        )
        limit = self.stability[own.integrator]
        if not own.stable:
            state = f"is unstable (a run of it {own.behaviour})"
        elif limit.limit_dt_s is not None and limit.confirmed and own.margin is not None:
            state = (
                f"is stable with margin {say('own_margin', own.margin, spec='.3g')}x (its limit"
                f" {say.dt('limit_dt_s', limit.limit_dt_s)})"
            )
        else:
            state = "is stable (its run stays bounded)"
        error = (
            "not compared"
            if own.error is None
            else f"{say('own_error', own.error, spec='.2g')}, {'within' if own.error <= self.tol else 'outside'} {tolerance}"
        )
        head = f"Its own setting {state}; its error is {error}."
        creep = self.point_state.creep
        if creep:  # the sweep's errors are against the same soft-friction model: they cannot see its creep
            head += (
                f" {creep[0].body!r} creeps at {say('creep_speed_m_s', creep[0].speed_m_s, 'mm/s')} though Coulomb"
                " friction holds it: MuJoCo's soft-friction model error, which no integrator or timestep removes"
                " (springlab friction-settings measures it and finds the settings that stop it)."
            )
        if not pick.found or pick.dt is None:
            return say.answer(question, f"{head} No verified setting meets {tolerance}.")
        caveat = ", against a converged run of the same soft-friction model: it does not see the creep" if creep else ""
        return say.answer(
            question,
            f"{head} The cheapest verified setting within {tolerance} is {pick.integrator} at"
            f" {say.dt('dt_s', pick.dt)}, error {say('error', pick.error or 0.0, spec='.2g')}{caveat}.",
        )

    @property
    def question(self) -> str:
        """What the audit asks, in words (`question_answer`)."""
        return self.question_answer.question

    @property
    def answer(self) -> str:
        """The answer in words with units (`question_answer`)."""
        return self.question_answer.answer

    def _shown(self) -> display.Summary:
        """The audit as a notebook shows it: whether the model's own setting meets tol, then the numbers."""
        own, pick = self.own, self.recommendation
        return display.Summary(
            "Audit",
            self.model,
            f"own setting {'meets' if self.own_ok else 'misses'} tol {self.tol:g}",
            self.own_ok,
            self.message.split("\n")[0],
            (
                display.Fact("own setting", f"{own.integrator} at dt = {own.dt:g} s"),
                display.Fact("own error", own.error),
                display.Fact("stability margin", own.margin),
                display.Fact("modes", self.mode_count),
                display.Fact(
                    "recommended", f"{pick.integrator} at dt = {display.number(pick.dt)} s" if pick.integrator else None
                ),
                display.Fact("recommended error", pick.error),
                display.Fact("wall time", self.timings.total_s, "s"),
            ),
            display.table(
                ("integrator", "limit dt [s]", "method"),
                [(name, limit.limit_dt_s, limit.method) for name, limit in self.stability.items()],
            ),
        )

    def plot(self) -> Figure:
        """The modes, the stability limits against the own setting, and error against cost (`springlab.plots.audit.audit_figure`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """audit.json and `springlab audit --json`: the model, its operating point, modes, stability limits,
        own setting, sweep and recommendation, plus linearity, orders, pareto, reference, constraints and timings."""
        fastest = self.linear.fastest
        return {
            **self.question_answer.to_dict(),
            "model": self.model,
            "operating_point": self.linear.point.to_dict(),
            "operating_point_state": self.point_state.to_dict(),
            "perturb": self.perturb,
            "excitation": self.excitation.to_dict(),
            "duration_s": self.duration,
            "linear": self.is_linear,
            "linearity": self.linearity.to_dict(),
            "modes": [m.to_dict() for m in self.linear.modes],
            "fastest_mode": fastest.to_dict() if fastest else None,
            "stability": {name: limit.to_dict() for name, limit in self.stability.items()},
            "stability_criterion": STABILITY_CRITERION,
            "own_setting": self.own.to_dict(),
            "constraints_broken": [c.to_dict() for c in self.constraints],
            "reference": self.reference.to_dict(),
            "sweep": [sweep_row(r) for r in self.runs],
            "orders": dict(self.orders),
            "pareto": [sweep_row(r) for r in self.pareto],
            "recommendation": self.recommendation.to_dict(RECOMMENDATION_NAMES),
            "cost_basis": COST_BASIS,
            "timings_s": self.timings.to_dict(),
        }

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab audit --output DIR` writes (springlab.outputs.write): audit.json, audit.png."""
        return Output.json("audit.json", self.to_dict()), Output("audit.png")

    def to_pandas(self) -> pandas.DataFrame:
        """The sweep as a DataFrame, one row per (integrator, dt): the rows of `to_dict()["sweep"]`
        (integrator, dt [s], steps, error [-], wall_time_s [s], cost [DOF-evaluations], diverged, beyond_limit);
        pandas is optional."""
        return tables.to_pandas([sweep_row(r) for r in self.runs])


def sweep_row(run: Run) -> dict[str, Any]:
    """A run as a row of audit.json's "sweep" and "pareto": {"integrator", "dt" [s], "steps", "error" [-],
    "wall_time_s" [s] (measured, reported), "cost" [DOF-evaluations] (counted, ranked on), "diverged",
    "beyond_limit"}."""
    return {
        "integrator": run.integrator,
        "dt": run.dt,
        "steps": run.steps,
        "error": run.error,
        "wall_time_s": run.time_s,
        "cost": run.cost,
        "diverged": run.diverged,
        "beyond_limit": run.beyond_limit,
    }
