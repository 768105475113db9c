"""A run's results: `Result` (one run of a scenario: its setting, series, errors and verdict) and
`ValidationRow` (one row of `springlab validate`'s table). `springlab.runs.run` makes them.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import warnings
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from springlab import display, tables
from springlab.answer import Answer
from springlab.files import Output, csv_text, json_ready
from springlab.scenes.base import Case, Check
from springlab.sim.simulate import Trajectory

from .compare import ColumnError, EstimateRange, Verdict

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure


def _read_only(values: np.ndarray) -> np.ndarray:
    """A read-only view of `values` (the array it views stays writable)."""
    view = np.asarray(values).view()
    view.setflags(write=False)
    return view


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Result(display.Shown):
    """One run of a scenario: its setting, its trajectory, the exact reference, errors and verdict.

    Immutable: the attributes cannot be rebound and the series are read-only arrays.
    `to_dict()` is summary.json (what `springlab run --json` prints), `to_pandas()` is
    trajectory.csv as a DataFrame (`summary`, the same facts in Python values, is deprecated).

    Attributes
    ----------
    scene, scenario
        the names run.
    integrator
        the integrator that ran.
    dt
        timestep [s].
    duration
        simulated time [s] (steps x dt; shorter than asked where a stop condition ended the run).
    steps
        physics steps taken.
    wall_time_s
        wall time of the simulation [s].
    parameters
        parameter name -> value used (SI).
    quantities
        named results of the scenario (SI; the name ends in its unit), as summary.json's `quantities`.
    errors
        compared column (`<joint>_pos`, `<joint>_vel`) -> its ColumnError (max_abs, max_rel);
        empty without an exact trajectory.
    tolerance
        the largest tolerance [-] a compared column is held to (None: no compared column).
    tolerance_basis
        why the tolerance is what it is (one line).
    column_tolerances
        compared column -> the tolerance [-] it is held to (not in summary.json).
    passed
        every compared column and check within its tolerance, inside the range of the error
        estimate and of the scene's model (None: nothing to validate against).
    verdict
        what the run is (Verdict: PASS, FAIL, NOT_VALIDATED, OUTSIDE_MODEL), None with `passed`.
    estimate_range
        whether the run is inside the range of its error estimate (None with a requested
        tolerance or without a linear reference).
    checks
        the scenario's scalar claims (scenes.declarations.Check), tolerances capped as summary.json shows them.
    model_limits
        why the run left its scene's model (empty: it did not).
    time
        (n,) [s], one row per physics step, t = 0 included (MuJoCo's clock).
    pos, vel
        joint -> simulated position [m] / velocity [m/s] series (hinges [rad], [rad/s]).
    ref_pos, ref_vel
        joint -> exact series (empty where no reference exists).
    case
        the scenario at its parameters with the compiled model that ran (springlab.scenes.base.Case).
    model
        the compiled MjModel that ran (`case.model`).
    trajectory
        the raw Trajectory.
    answer
        the question the scenario asks and this run's answer in words (springlab.answer.Answer; None where the
        scene states none): what `springlab run` prints first and summary.json's `question`, `answer` and
        `answer_numbers`.
    grid_notes
        what the step grid changed in the scenario's input (e.g. a ramp lasting 2.004 s instead of 2 s), one
        line each; the verdict line says them (empty: nothing).
    """

    scene: str
    scenario: str
    integrator: str
    dt: float
    duration: float
    steps: int
    wall_time_s: float
    parameters: dict[str, float]
    quantities: dict[str, Any] = dataclasses.field(repr=False)
    errors: dict[str, ColumnError]
    tolerance: float | None
    tolerance_basis: str = dataclasses.field(repr=False)
    passed: bool | None
    verdict: Verdict | None
    estimate_range: EstimateRange | None = dataclasses.field(repr=False)
    checks: tuple[Check, ...] = dataclasses.field(repr=False)
    model_limits: tuple[str, ...]
    time: np.ndarray = dataclasses.field(repr=False)
    pos: dict[str, np.ndarray] = dataclasses.field(repr=False)
    vel: dict[str, np.ndarray] = dataclasses.field(repr=False)
    ref_pos: dict[str, np.ndarray] = dataclasses.field(repr=False)
    ref_vel: dict[str, np.ndarray] = dataclasses.field(repr=False)
    case: Case = dataclasses.field(repr=False)
    trajectory: Trajectory = dataclasses.field(repr=False)
    column_tolerances: dict[str, float] = dataclasses.field(default_factory=dict, repr=False)
    answer: Answer | None = dataclasses.field(default=None, repr=False)
    grid_notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "time", _read_only(self.time))
        for name in ("pos", "vel", "ref_pos", "ref_vel"):
            object.__setattr__(self, name, {joint: _read_only(v) for joint, v in getattr(self, name).items()})

    @property
    def model(self) -> mujoco.MjModel:
        """The compiled MjModel that ran (`case.model`)."""
        return self.case.model

    @property
    def max_rel_error(self) -> float | None:
        """The largest max_rel [-] over the compared columns (None: no compared column)."""
        return max((e.max_rel for e in self.errors.values()), default=None)

    @property
    def message(self) -> str:
        """Why the run has its verdict, in one line (like scipy's `OptimizeResult.message`)."""
        if self.verdict is Verdict.OUTSIDE_MODEL:
            return "outside the scene's model: " + "; ".join(self.model_limits)
        if self.verdict is Verdict.NOT_VALIDATED and self.estimate_range is not None:
            return f"outside the range of the error estimate: {self.estimate_range.reason()}"
        if self.passed is None:
            return "no exact reference to compare with: nothing validated"
        over = [
            f"{column}: max relative error {e.max_rel:.3g} > tolerance {self.column_tolerances[column]:.3g}"
            for column, e in self.errors.items()
            if column in self.column_tolerances and not e.max_rel <= self.column_tolerances[column]
        ]
        over += [
            f"check {c.name}: error {c.error:.3g} > tolerance {c.tolerance:.3g}" for c in self.checks if not c.passed
        ]
        if over:
            return "; ".join(over)
        within = []
        if self.errors and self.column_tolerances:
            # the column closest to its own tolerance
            column = max(self.column_tolerances, key=lambda c: self.errors[c].max_rel / self.column_tolerances[c])
            within.append(
                f"every compared column within its tolerance, closest {column}: max relative error"
                f" {self.errors[column].max_rel:.3g} <= {self.column_tolerances[column]:.3g}"
            )
        if self.checks:
            within.append(f"{len(self.checks)} check{'s' if len(self.checks) > 1 else ''} within tolerance")
        return "; ".join([*within, *self.grid_notes])

    @property
    def summary(self) -> dict[str, Any]:
        """Deprecated: `to_dict()` (summary.json) or the attributes (`quantities`, `errors`, `passed` ...).

        The facts as summary.json's dict in Python values (inf where summary.json has null), kept for
        scripts written against it; it warns (DeprecationWarning) since issue 32.
        """
        warnings.warn(
            "Result.summary is deprecated: use Result.to_dict() (summary.json, what `springlab run --json`"
            " prints) or the attributes (result.quantities, result.errors, result.passed)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self._facts()

    def _facts(self) -> dict[str, Any]:
        """summary.json's dict in Python values (inf where summary.json has null)."""
        return {
            "scene": self.scene,
            "scenario": self.scenario,
            **(self.answer.to_dict() if self.answer is not None else {}),
            "integrator": self.integrator,
            "dt": self.dt,
            "duration": self.duration,
            "steps": self.steps,
            "wall_time_s": self.wall_time_s,
            "parameters": dict(self.parameters),
            "quantities": copy.deepcopy(self.quantities),
            "errors": {column: e.to_dict() for column, e in self.errors.items()},
            "tolerance": self.tolerance,
            "tolerance_basis": self.tolerance_basis,
            "passed": self.passed,
            "verdict": None if self.verdict is None else self.verdict.value,
            "estimate_range": None if self.estimate_range is None else self.estimate_range.to_dict(),
            "checks": [check.to_dict() for check in self.checks],
            "model_limits": list(self.model_limits),
            "grid_notes": list(self.grid_notes),
        }

    def _shown(self) -> display.Summary:
        """The run as a notebook shows it: verdict, setting, worst error against tolerance, quantities."""
        facts = [
            display.Fact("integrator", self.integrator),
            display.Fact("dt", self.dt, "s"),
            display.Fact("duration", self.duration, "s"),
            display.Fact("steps", self.steps),
            display.Fact("max relative error", self.max_rel_error),
            display.Fact("tolerance", self.tolerance),
            display.Fact("wall time", self.wall_time_s, "s"),
        ]
        facts += [
            display.Fact(name, value)
            for name, value in list(self.quantities.items())[:6]
            if isinstance(value, (int, float, np.floating)) and not isinstance(value, bool)
        ]
        if self.errors:
            rows = display.table(
                ("column", "max abs", "max rel [-]", "tolerance [-]"),
                [
                    (name, e.max_abs, e.max_rel, self.column_tolerances.get(name, self.tolerance))
                    for name, e in self.errors.items()
                ],
            )
        elif self.checks:
            rows = display.table(
                ("check", "value", "reference", "error", "tolerance", "passed"),
                [(c.name, c.value, c.reference, c.error, c.tolerance, c.passed) for c in self.checks],
            )
        else:
            rows = None
        return display.Summary(
            "Result",
            f"{self.scene} / {self.scenario}",
            None if self.verdict is None else str(self.verdict),
            self.passed,
            self.message,
            tuple(facts[:7]),
            rows,
            note=""
            if len(facts) <= 7
            else "quantities: " + ", ".join(f"{f.label} {display.number(f.value)}" for f in facts[7:]),
        )

    def plot(self) -> Figure:
        """Positions and velocities against time, the exact solution dashed, and |simulated - exact| with the tolerance (`springlab.plots.run.time_series`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """summary.json, exactly what `springlab run --json` prints (plain JSON values: inf and nan are None).

        Keys: scene, scenario, question, answer, answer_numbers (where the scene states a question),
        integrator, dt [s], duration [s], steps, wall_time_s [s], parameters, quantities, errors, tolerance,
        tolerance_basis, passed, verdict, estimate_range, checks, model_limits, grid_notes (see docs/runs.md).
        """
        return json_ready(self._facts())

    def outputs(self, every: int = 1) -> tuple[Output, ...]:
        """The files `springlab run --output DIR` writes (springlab.outputs.write): trajectory.csv and summary.json.

        The time column is k dt [s] for step k, exactly: the state after k steps is the state at k dt
        (MuJoCo's data.time accumulates dt and drifts by rounding).

        Parameters
        ----------
        every
            keep every `every`-th step in trajectory.csv (the last always), as `--record-every`.
        """
        return (
            Output("trajectory.csv", csv_text(self._csv_columns(), every)),
            Output.json("summary.json", self.to_dict()),
        )

    def columns(self) -> dict[str, np.ndarray]:
        """The series in trajectory.csv's order: time (MuJoCo's clock), <joint>_pos/_vel, then the references."""
        out = {"time": self.time}
        for joint in self.pos:
            out[f"{joint}_pos"] = self.pos[joint]
            out[f"{joint}_vel"] = self.vel[joint]
        for joint in self.ref_pos:
            out[f"{joint}_pos_ref"] = self.ref_pos[joint]
            out[f"{joint}_vel_ref"] = self.ref_vel[joint]
        return out

    def _csv_columns(self) -> dict[str, np.ndarray]:
        """trajectory.csv's columns: `columns()` with time = k dt for step k, exactly."""
        columns = self.columns()
        columns["time"] = np.arange(len(columns["time"])) * float(self.dt)
        return columns

    def to_pandas(self) -> pandas.DataFrame:
        """trajectory.csv as a DataFrame: one row per physics step, its columns and numbers (needs pandas).

        Columns: time [s] (k dt for step k), `<joint>_pos`, `<joint>_vel`, then `<joint>_pos_ref`,
        `<joint>_vel_ref` where an exact reference exists (SI units).
        """
        return tables.to_pandas({name: np.array(values, float) for name, values in self._csv_columns().items()})


@dataclasses.dataclass(frozen=True, repr=False)
class ValidationRow(display.Shown):
    """One row of the validation table (`springlab validate`, the demo's validation.json) for one run.

    A scenario without compared columns shows its tightest check in `max_rel_error` and
    `tolerance`, and `measure` says which: 'trajectory max_rel', or '<check name> rel' /
    '<check name> abs'.

    Attributes
    ----------
    scene, scenario, integrator
        the names run.
    dt
        timestep [s].
    steps
        physics steps taken.
    max_rel_error
        the largest error [-] of what `measure` names.
    measure
        what max_rel_error and tolerance measure.
    tolerance
        its tolerance [-].
    tolerance_basis
        why the tolerance is what it is.
    passed
        the run's `passed`.
    verdict
        the run's Verdict (None with passed None).
    wall_time_s
        wall time of the simulation [s].
    checks
        the scenario's checks.
    note
        why a run is not validated (its verdict and reason), or what a study noted (None: nothing).
    answer
        the scenario's question and the run's answer (`Result.answer`; None where the scene states none):
        `springlab validate` prints the answer, one line per scenario.
    """

    scene: str
    scenario: str
    integrator: str
    dt: float
    steps: int
    max_rel_error: float
    measure: str
    tolerance: float
    tolerance_basis: str
    passed: bool | None
    verdict: Verdict | None
    wall_time_s: float
    checks: tuple[Check, ...]
    note: str | None = None
    answer: Answer | None = None

    @classmethod
    def of(cls, result: Result) -> ValidationRow:
        """The row of a run that has an exact reference (compared columns or checks).

        Parameters
        ----------
        result
            the run.
        """
        if result.errors:
            worst = max(e.max_rel for e in result.errors.values())
            assert result.tolerance is not None, "compared columns always have a tolerance"
            tolerance, basis, measure = result.tolerance, result.tolerance_basis, "trajectory max_rel"
        else:
            # no compared columns: the row shows the check closest to (or furthest past) its tolerance
            tightest = max(result.checks, key=lambda c: c.error / c.tolerance if c.tolerance > 0 else math.inf)
            worst, tolerance = tightest.error, float(tightest.tolerance)
            basis = f"{tightest.name}: {tightest.basis}"
            measure = f"{tightest.name} {'rel' if tightest.reference != 0 else 'abs'}"
        note = None
        if result.model_limits:
            note = f"{result.verdict}: " + "; ".join(result.model_limits)
        elif result.estimate_range is not None and not result.estimate_range.inside:
            note = f"{result.verdict}: {result.estimate_range.reason()}"
        if result.grid_notes:
            note = "; ".join([*([note] if note else []), *result.grid_notes])
        return cls(
            scene=result.scene,
            scenario=result.scenario,
            integrator=result.integrator,
            dt=result.dt,
            steps=result.steps,
            max_rel_error=worst,
            measure=measure,
            tolerance=tolerance,
            tolerance_basis=basis,
            passed=result.passed,
            verdict=result.verdict,
            wall_time_s=result.wall_time_s,
            checks=result.checks,
            note=note,
            answer=result.answer,
        )

    def _shown(self) -> display.Summary:
        """The row as a notebook shows it: verdict, setting, error against tolerance."""
        return display.Summary(
            "ValidationRow",
            f"{self.scene} / {self.scenario}",
            None if self.verdict is None else str(self.verdict),
            self.passed,
            self.note
            or f"{self.measure} {display.number(self.max_rel_error)} against tolerance {display.number(self.tolerance)}",
            (
                display.Fact("integrator", self.integrator),
                display.Fact("dt", self.dt, "s"),
                display.Fact("steps", self.steps),
                display.Fact(self.measure, self.max_rel_error),
                display.Fact("tolerance", self.tolerance),
                display.Fact("wall time", self.wall_time_s, "s"),
            ),
        )

    def to_dict(self) -> dict[str, Any]:
        """The row as `springlab validate --json` prints it; `note` only where there is one."""
        row = {
            "scene": self.scene,
            "scenario": self.scenario,
            "integrator": self.integrator,
            "dt": self.dt,
            "steps": self.steps,
            "max_rel_error": self.max_rel_error,
            "measure": self.measure,
            "tolerance": self.tolerance,
            "tolerance_basis": self.tolerance_basis,
            "passed": self.passed,
            "verdict": None if self.verdict is None else self.verdict.value,
            "wall_time_s": self.wall_time_s,
            "checks": [check.to_dict() for check in self.checks],
        }
        if self.note is not None:
            row["note"] = self.note
        if self.answer is not None:
            row.update(self.answer.to_dict())
        return json_ready(row)
