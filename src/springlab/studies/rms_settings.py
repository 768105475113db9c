"""What does an accurate RMS under a random load cost? Model size x integrator x timestep x record length.

An RMS estimated from a simulation misses the physical one (the continuum's, under continuous white noise) in
four ways, each computed exactly for a scene that declares a random load (`Scene.random_load`):

* discretization: the size-N model's exact RMS against the continuum's, which is Richardson's extrapolation of the
  declared sizes' exact variances (each a refinement of the last by 2 in spacing, order `order`); the last
  extrapolation's change from the one before is the continuum's own error, reserved out of the tolerance;
* the hold and the integrator: the exact stationary variance of MuJoCo's one-step map at (integrator, dt) under
  the load held over each step, against the continuous model's (springlab.exact.random_vibration);
* the record: the half-width, at `level` confidence, of the pooled RMS of `seeds` independent stationary records
  of the scenario's length (the exact scatter of a record's sample variance, shrinking like 1 / sqrt(seeds)).

Their sum bounds a setting's error at that confidence (the parts' signs differ, so the sum is not counted on to
cancel); its cost is counted work: steps x seeds x model evaluations per step x the size
(springlab.studies.settings). The cheapest setting whose bound meets `tol` is verified by running it: its seeds'
pooled RMS against the continuum's (springlab.studies.random_load), a pass with probability at least `level`.
No run is needed to rank the settings: only the verification simulates.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab import display, tables
from springlab.answer import Answer
from springlab.errors import BadInputError
from springlab.exact import random_vibration as rv
from springlab.files import Output, json_ready
from springlab.scenes.base import Case, Scene
from springlab.scenes.declarations import keyword_parameters, refuse_text
from springlab.sim.simulate import INTEGRATORS, check_timing, integrator_id

from . import answers
from .executor import Executor
from .random_load import declared, records
from .settings import (
    COST_BASIS,
    Recommendation,
    Run,
    RunFields,
    Setting,
    Verification,
    cheapest_verified,
    counted_cost,
    limit_dt,
    pareto_front,
)

if TYPE_CHECKING:
    import pandas

#: the timesteps of each (size, integrator): these fractions of its stability limit on the size's modes
LIMIT_FRACTIONS = (0.9, 0.6, 0.3, 0.15)
#: where an integrator has no limit on the model, the fractions apply to 4 / omega_max
NO_LIMIT_SCALE = 4.0
#: the numbers of independent records the study considers
SEED_COUNTS = (1, 2, 4, 8, 16, 32, 64, 128)
#: the default confidence level of the record's half-width
LEVEL = 0.95
#: verify at most this many candidates (each verification simulates its seeds)
MAX_TRIES = 2


@dataclasses.dataclass(frozen=True)
class RmsRow(RunFields):
    """One setting: the shared row (`run`: its error the bound, its cost the counted work) and its parts.

    Attributes
    ----------
    run
        springlab.studies.settings.Run: the setting's options are the size, the seeds and the record [s].
    size, seeds
        the model's size and the number of records.
    discretization, bias, record
        the three parts of the bound [-] (relative errors of the RMS): size, hold + integrator, record at level.
    """

    run: Run
    size: int
    seeds: int
    discretization: float
    bias: float | None
    record: float | None

    @property
    def error(self) -> float | None:
        """The bound [-]: discretization + bias + record (None: no stationary state at this setting)."""
        return self.run.error

    def to_dict(self) -> dict[str, Any]:
        """The row: size, seeds, integrator, dt [s], record_s [s], steps, discretization, bias, record, error, cost."""
        return {
            "size": self.size,
            "seeds": self.seeds,
            "integrator": self.integrator,
            "dt": self.dt,
            "record_s": dict(self.run.setting.options)["record_s"],
            "steps": self.steps,
            "discretization": self.discretization,
            "bias": self.bias,
            "record": self.record,
            "error": self.error,
            "cost": self.cost,
            "beyond_limit": self.beyond_limit,
        }


@dataclasses.dataclass(frozen=True, repr=False)
class RmsSettings(display.Shown):
    """The settings study's answer: every setting's bound and cost, the front, the verified cheapest.

    Attributes
    ----------
    scene, scenario, description, unit
        names; the RMS in words and its unit.
    size_parameter
        the size's parameter name.
    tol, level
        the relative accuracy [-] asked, and the confidence of the record's part.
    record_s
        one record's length [s].
    sizes, variances
        the sizes whose exact continuous variance [unit^2] the continuum is extrapolated from.
    continuum, continuum_error
        the continuum's variance [unit^2] and the relative error [-] of its RMS (reserved from tol).
    rows
        every setting (RmsRow).
    recommendation
        the cheapest verified setting (springlab.studies.settings.Recommendation).
    """

    scene: str
    scenario: str
    description: str
    unit: str
    size_parameter: str
    tol: float
    level: float
    record_s: float
    sizes: tuple[int, ...]
    variances: tuple[float, ...]
    continuum: float
    continuum_error: float
    rows: tuple[RmsRow, ...]
    recommendation: Recommendation[RmsRow]

    @property
    def front(self) -> list[RmsRow]:
        """The Pareto front of bound vs counted cost."""
        return pareto_front(self.rows)

    @property
    def question(self) -> str:
        """What the study answers."""
        return (
            f"How many {self.size_parameter}, which integrator and timestep, and how many {self.record_s:g} s records"
            f" does {self.description} need to be within {self.tol:.3g} of the continuum's at {self.level:.0%}"
            " confidence?"
        )

    @property
    def question_answer(self) -> Answer:
        """The question and `answer`, with the continuum's RMS and the pick's timestep [s] and bound it quotes."""
        pick = self.recommendation
        numbers: dict[str, float] = {"rms_continuum": math.sqrt(self.continuum)}
        if pick.found and pick.row is not None:
            numbers |= {"dt_s": pick.row.dt, "seeds": pick.row.seeds, "bound": pick.row.error or math.nan}
        return answers.of_words(self.question, self.answer, numbers)

    @property
    def answer(self) -> str:
        """The answer in words, with units."""
        rms = math.sqrt(self.continuum)
        what = self.description.removeprefix("the ")
        head = f"The continuum's {what} is {rms:.4g} {self.unit} (relative error {self.continuum_error:.1g})."
        pick = self.recommendation
        if not pick.found or pick.row is None:
            return f"{head} {pick.text}"
        row = pick.row
        hours = row.seeds * self.record_s / 3600.0
        measured = pick.details.get("pooled_rms")
        return (
            f"{head} Cheapest: {self.size_parameter} = {row.size}, {row.integrator} at dt = {row.dt:.3g} s,"
            f" {row.seeds} records of {self.record_s:g} s ({hours:.3g} h of simulated load): bound {row.error:.2g}"
            f" (discretization {row.discretization:.1g}, hold and integrator {row.bias:.1g}, record {row.record:.2g}"
            f" at {self.level:.0%}); verified: the records' pooled RMS {measured:.4g} {self.unit}, {pick.error:.2g}"
            f" from the continuum's. {pick.text}"
        )

    def _shown(self) -> display.Summary:
        pick = self.recommendation
        verdict = (
            f"{self.size_parameter} {pick.row.size}, {pick.integrator} at dt = {display.number(pick.dt)} s,"
            f" {pick.row.seeds} records"
            if pick.found and pick.row is not None
            else "no setting meets tol"
        )
        return display.Summary(
            "RmsSettings",
            f"{self.scene} / {self.scenario}",
            verdict,
            pick.found,
            self.answer,
            (
                display.Fact("continuum RMS", math.sqrt(self.continuum), self.unit),
                display.Fact("settings", len(self.rows)),
                display.Fact("on the front", len(self.front)),
            ),
            display.table(
                (self.size_parameter, "integrator", "dt [s]", "seeds", "bound [-]", "cost [DOF-evaluations]"),
                [(r.size, r.integrator, r.dt, r.seeds, r.error, r.cost) for r in self.front],
            ),
        )

    def to_dict(self) -> dict[str, Any]:
        """rms_settings.json: question, answer, the continuum, every row, the front, the recommendation."""
        front = {id(r) for r in self.front}
        return json_ready(
            {
                **self.question_answer.to_dict(),
                "scene": self.scene,
                "scenario": self.scenario,
                "size_parameter": self.size_parameter,
                "tolerance": self.tol,
                "level": self.level,
                "record_s": self.record_s,
                "continuum": {
                    "sizes": list(self.sizes),
                    "rms_exact": [math.sqrt(v) for v in self.variances],
                    "rms_continuum": math.sqrt(self.continuum),
                    "error": self.continuum_error,
                },
                "cost_basis": COST_BASIS,
                "rows": [{**r.to_dict(), "pareto": id(r) in front} for r in self.rows],
                "recommendation": self.recommendation.to_dict(),
            }
        )

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab rms --settings --output DIR` writes (springlab.outputs.write): rms_settings.json,
        rms_settings.png."""
        return Output.json("rms_settings.json", self.to_dict()), Output("rms_settings.png")

    def to_pandas(self) -> pandas.DataFrame:
        """One row per setting."""
        return tables.to_pandas(self.to_dict()["rows"])


def continuum_variance(variances: Sequence[float], order: float) -> tuple[float, float]:
    """(the limit [unit^2], its relative error [-] in the RMS) from variances at spacings halving each time.

    Richardson: v_inf = v_b + (v_b - v_a) / (2^order - 1) from the last two; its error is estimated by the change
    from the extrapolation of the two before (|v_inf - v_inf'| / v_inf, halved for the RMS), or by the last
    correction itself when only two sizes are given.
    """
    if len(variances) < 2:
        raise BadInputError("the continuum needs the exact variance at two sizes at least")
    factor = 2.0**order - 1.0
    values = [float(v) for v in variances]
    last = values[-1] + (values[-1] - values[-2]) / factor
    if len(values) >= 3:
        before = values[-2] + (values[-2] - values[-3]) / factor
        change = abs(last - before)
    else:
        change = abs(last - values[-1])
    return last, 0.5 * change / last


def _rms_error(interval: rv.VarianceInterval) -> float:
    """The interval's largest relative distance [-] of the RMS from sqrt(variance)."""
    low, high = interval.rms_interval()
    centre = math.sqrt(interval.variance)
    return max(high / centre - 1.0, 1.0 - low / centre)


def _timesteps(case: Case, integrator: str, record_s: float) -> list[float]:
    """LIMIT_FRACTIONS of the integrator's stability limit on the case's modes (or of NO_LIMIT_SCALE / omega_max),
    each lowered to divide the record [s] into whole steps (so every row's record is the same length)."""
    modes = case.modes()
    limit = limit_dt(modes, lambda w, z: case.stability_limit(integrator, w, z))
    if limit is None:
        fastest = max((w for w, z in modes if z < 1.0), default=1.0)
        limit = NO_LIMIT_SCALE / fastest
    return [record_s / math.ceil(record_s / (limit * f)) for f in LIMIT_FRACTIONS]


def _rows_of_size(
    case: Case,
    continuum: float,
    integrators: Sequence[str],
    record_s: float,
    seed_counts: Sequence[int],
    level: float,
) -> list[RmsRow]:
    """The rows of one size: every integrator x timestep x number of records of record_s [s]."""
    spec = case.scene.random_load
    assert spec is not None  # the study checked the declaration
    size = int(case.params[spec.size])
    discretization = abs(math.sqrt(spec.continuous(case) / continuum) - 1.0)
    work = float(case.model.nv)
    rows = []
    for integrator in integrators:
        for dt in _timesteps(case, integrator, record_s):
            steps = check_timing(dt, record_s)
            try:
                exact = spec.exact(case, integrator, dt)
            except BadInputError:  # no stationary state: beyond the map's stability limit
                exact = None
            spread = None if exact is None else float(exact.spreads([steps])[0])
            for seeds in seed_counts:
                options = ((spec.size, float(size)), ("seeds", float(seeds)), ("record_s", steps * dt))
                setting = Setting(integrator, dt, options)
                cost = counted_cost(integrator, steps * seeds, work)
                if exact is None or spread is None:
                    run = Run(setting, steps * seeds, None, cost, beyond_limit=True, detail="no stationary state")
                    rows.append(RmsRow(run, size, seeds, discretization, None, None))
                    continue
                bias = abs(math.sqrt(exact.integrator / exact.continuous) - 1.0)
                record = _rms_error(rv.variance_interval(exact.held, spread / math.sqrt(seeds), level))
                run = Run(setting, steps * seeds, discretization + bias + record, cost)
                rows.append(RmsRow(run, size, seeds, discretization, bias, record))
    return rows


def rms_settings(
    model: str | Scene,
    *,
    tol: float,
    level: float = LEVEL,
    sizes: Sequence[int] | None = None,
    integrators: Sequence[str] = tuple(INTEGRATORS),
    seed_counts: Sequence[int] = SEED_COUNTS,
    record: float | None = None,
    executor: Executor | None = None,
    **parameters: float,
) -> RmsSettings:
    """The cheapest (size, integrator, dt, records) whose RMS is within `tol` of the continuum's, verified.

    Parameters
    ----------
    model
        a scene that declares `random_load`, or its name.
    tol
        the relative accuracy [-] of the RMS, > 0.
    level
        the confidence of the record's part, in (0, 1).
    sizes
        the sizes to consider (default: the declared ones but the last, which only refines the continuum).
    integrators
        MuJoCo integrator names.
    seed_counts
        the numbers of records to consider.
    record
        one record's length [s] (None: the scenario's duration).
    executor
        where the verification's records run (None: locally).
    **parameters
        the scene's parameters, SI (not the size or the seed).

    Raises
    ------
    BadInputError
        no random load, a bad tol, level, size, integrator or record, the size or seed set as a parameter,
        the command line's strings.
    TypeError
        an old keyword spelling (`scene=`) or another study's option.
    """
    parameters = keyword_parameters("rms_settings", parameters)
    refuse_text("sizes", sizes, "a sequence of whole numbers, e.g. sizes=(8, 16)", numbers=True)
    refuse_text("integrators", integrators, "a sequence of names, e.g. integrators=['rk4', 'euler']")
    refuse_text("seed_counts", seed_counts, "a sequence of whole numbers, e.g. seed_counts=(1, 4, 16)", numbers=True)
    found, spec = declared(model)
    if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol > 0):
        raise BadInputError(f"tol must be a finite number > 0 (relative error of the RMS), got {tol!r}")
    if isinstance(level, bool) or not isinstance(level, (int, float)) or not (0.0 < level < 1.0):
        raise BadInputError(f"level must lie in (0, 1), got {level!r}")
    for name in (spec.size, spec.seed):
        if name and name in parameters:
            raise BadInputError(f"the study sets {name} itself; drop --set {name}")
    for name in integrators:
        integrator_id(name)
    if not spec.size or len(spec.sizes) < 2:
        raise BadInputError(f"{found.name}'s random load declares no model sizes to refine")
    chosen = found.scenario(spec.scenario)
    record_s = chosen.duration if record is None else record
    if not (isinstance(record_s, (int, float)) and math.isfinite(record_s) and record_s > 0):
        raise BadInputError(f"record must be a finite number > 0 s, got {record!r}")
    ladder = [found.case(chosen, {**parameters, spec.size: n}) for n in spec.sizes]
    variances = tuple(spec.continuous(c) for c in ladder)
    continuum, continuum_error = continuum_variance(variances, spec.order)
    considered = list(spec.sizes[:-1]) if sizes is None else [int(n) for n in sizes]
    rows: list[RmsRow] = []
    for size in considered:
        case = next((c for c, n in zip(ladder, spec.sizes) if n == size), None)
        case = case or found.case(chosen, {**parameters, spec.size: size})
        rows += _rows_of_size(case, continuum, integrators, float(record_s), seed_counts, level)

    def verify(row: RmsRow) -> Verification:
        params = {**parameters, spec.size: row.size}
        variances_run, wall = records(
            found, chosen.name, params, row.integrator, row.dt, row.steps // row.seeds, range(row.seeds), executor
        )
        pooled = math.sqrt(float(np.mean(variances_run)))
        error = abs(pooled / math.sqrt(continuum) - 1.0)
        return Verification(error <= tol, error, wall, {"pooled_rms": pooled, "seeds": row.seeds})

    pick = cheapest_verified(
        rows,
        tol,
        verify,
        describe=lambda s: _describe(s, spec.size),
        max_tries=MAX_TRIES,
        budget=tol - continuum_error,
        error_words="error against the continuum's RMS",
    )
    return RmsSettings(
        found.name,
        chosen.name,
        spec.description,
        spec.unit,
        spec.size,
        float(tol),
        float(level),
        float(record_s),
        tuple(spec.sizes),
        variances,
        continuum,
        continuum_error,
        tuple(rows),
        pick,
    )


def _describe(setting: Setting, size: str) -> str:
    """'n_elements 99, implicitfast at dt = 0.005 s, 16 records of 600 s'."""
    options = setting.option_values
    return (
        f"{size} {options[size]:g}, {setting.integrator} at dt = {setting.dt:.3g} s, {options['seeds']:g} records"
        f" of {options['record_s']:g} s"
    )
