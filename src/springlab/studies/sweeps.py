"""A parameter sweep of any scene: a grid (or random samples) of parameters, every configuration one run.

`springlab sweep car road_bump --vary damping=1000:8000:8 --vary speed=2:20:10`
runs every combination, batched, and reports per configuration its
parameters, the scenario's quantities (what `springlab run` puts in
summary.json), the errors against the exact solution where there is one, and
whether it passed. A configuration that blows up is a row marked `diverged`,
not a failed sweep.

How it runs: the configurations are cut into chunks of `CHUNK_CONFIGURATIONS`;
each chunk is one threaded `mujoco.rollout` call (`batch.run_rollout`,
bit-identical per run to `springlab run`, which steps with the same function) on the executor (springlab.studies.executor:
locally, or on dask workers that rebuild each model from the scene's MJCF and
the row's parameters). Rows come back in configuration order, so the sweep is
the same bit for bit wherever it ran.
"""

from __future__ import annotations

import dataclasses
import math
import time as _time
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab import display, scenes, tables
from springlab.answer import Answer
from springlab.errors import BadInputError, DivergedError, UnknownNameError
from springlab.files import Output, json_ready, rows_text
from springlab.runs.compare import Verdict
from springlab.runs.run import Result, evaluate, prepare
from springlab.scenes.base import Case
from springlab.scenes.declarations import keyword_parameters
from springlab.sim.batch import run_rollout
from springlab.sim.simulate import check_timing, integrator_id

from . import answers
from .executor import Executor, chunked, resolve

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure

#: configurations per chunk (one batched MuJoCo call each): seconds of work, not milliseconds
CHUNK_CONFIGURATIONS = 64
#: most configurations one sweep may hold
MAX_CONFIGURATIONS = 10_000_000
#: one axis of `sweep(vary=...)`: (low, high, n) or (low, high, n, "log"), n None with `samples`
AxisSpec = tuple[float, float, int | None] | tuple[float, float, int | None, str]
#: the options renamed in issue 32, old keyword -> new
RENAMED = {"seed": "sample_seed"}


@dataclasses.dataclass(frozen=True)
class Axis:
    """One varied parameter: `count` values from `low` to `high` [parameter's unit], even or log-spaced."""

    name: str
    low: float
    high: float
    count: int | None
    log: bool = False

    def values(self) -> np.ndarray:
        """The grid values (count of them), ends included."""
        assert self.count is not None, "only an axis with N (NAME=LOW:HIGH:N) has grid values"
        if self.count == 1:
            return np.array([self.low])
        if self.log:
            return np.geomspace(self.low, self.high, self.count)
        return np.linspace(self.low, self.high, self.count)

    def sample(self, unit: np.ndarray) -> np.ndarray:
        """Map uniform [0, 1) numbers onto the range (log-uniform for a log axis)."""
        if self.log:
            return np.exp(math.log(self.low) + unit * (math.log(self.high) - math.log(self.low)))
        return self.low + unit * (self.high - self.low)

    def to_dict(self) -> dict[str, Any]:
        """sweep --json's `vary` entry: name, low, high, count (None with --samples), log."""
        return {"name": self.name, "low": self.low, "high": self.high, "count": self.count, "log": self.log}


def make_axis(name: str, low: float, high: float, count: int | None, log: bool = False) -> Axis:
    """A checked Axis: finite ends, N a whole number >= 1 (or None: sampled), a log range above zero."""
    if not (math.isfinite(low) and math.isfinite(high)):
        raise BadInputError(f"--vary {name}: LOW and HIGH must be finite numbers, got {low!r}, {high!r}")
    if count is not None and (isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1):
        raise BadInputError(f"--vary {name}: N must be an integer >= 1, got {count!r}")
    if log and (low <= 0 or high <= 0):
        raise BadInputError(f"--vary {name}: a log range needs LOW > 0 and HIGH > 0, got {low:g}:{high:g}")
    if count is not None and count > 1 and low == high:
        raise BadInputError(f"--vary {name}: LOW equals HIGH; use N = 1 or --set {name}={low:g}")
    return Axis(name, float(low), float(high), None if count is None else int(count), log)


@dataclasses.dataclass(frozen=True)
class SweepRow:
    """One configuration of a sweep and what its run gave.

    Attributes
    ----------
    values
        varied parameter -> its value here [its unit].
    parameters
        every parameter of the run (SI).
    quantities
        the scenario's scalar quantities (numbers, bools, strings; what `springlab run` reports).
    errors
        compared column -> max_rel [-] against the exact solution (empty without one).
    passed
        the run's `passed` (None: no reference; False for a diverged or invalid configuration).
    diverged
        the run blew up.
    detail
        why the row did not pass, in one line: why it diverged, "invalid: ..." for a configuration
        the scenario cannot start from (e.g. a bump that lifts the car), or for a run that failed
        the reason of its verdict (see `failure_detail`: which column or check, its error against
        its tolerance, the scene's physical cause such as the tire leaving the road); "" for a
        run that passed.
    """

    values: dict[str, float]
    parameters: dict[str, float]
    quantities: dict[str, Any]
    errors: dict[str, float]
    passed: bool | None
    diverged: bool
    detail: str

    @property
    def invalid(self) -> bool:
        """Whether the scenario could not start from this configuration."""
        return self.detail.startswith("invalid")

    def to_dict(self) -> dict[str, Any]:
        """sweep --json's row: values, parameters, quantities, errors, passed, diverged, detail."""
        return {
            "values": dict(self.values),
            "parameters": dict(self.parameters),
            "quantities": dict(self.quantities),
            "errors": dict(self.errors),
            "passed": self.passed,
            "diverged": self.diverged,
            "detail": self.detail,
        }


@dataclasses.dataclass(frozen=True, repr=False)
class Sweep(display.Shown):
    """A finished sweep; one row per configuration, in order (the last axis fastest on a grid).

    `to_dict()` is what `springlab sweep --json` prints, `to_pandas()` is sweep.csv as a DataFrame.

    Attributes
    ----------
    scene, scenario, integrator
        names run.
    dt
        timestep [s].
    duration
        simulated time [s].
    axes
        the varied parameters.
    samples
        random points drawn (None: the full grid).
    values
        varied parameter -> (n,) values [its unit] (read-only arrays).
    rows
        one SweepRow per configuration.
    wall_time_s
        wall time of the whole sweep [s].
    executor
        where it ran ('local', '2 local dask workers', ...).
    chunks
        batched calls made.
    """

    scene: str
    scenario: str
    integrator: str
    dt: float
    duration: float
    axes: tuple[Axis, ...]
    samples: int | None
    values: dict[str, np.ndarray] = dataclasses.field(repr=False)
    rows: tuple[SweepRow, ...] = dataclasses.field(repr=False)
    wall_time_s: float
    executor: str
    chunks: int

    def __post_init__(self) -> None:
        values = {}
        for name, column in self.values.items():
            column = np.asarray(column).view()
            column.setflags(write=False)
            values[name] = column
        object.__setattr__(self, "values", values)

    @property
    def size(self) -> int:
        """Number of configurations."""
        return len(self.rows)

    @property
    def diverged(self) -> int:
        """Number of configurations whose run blew up."""
        return sum(bool(r.diverged) for r in self.rows)

    @property
    def invalid(self) -> int:
        """Number of configurations the scenario cannot start from."""
        return sum(r.invalid for r in self.rows)

    @property
    def passed(self) -> int:
        """Number of configurations whose run passed."""
        return sum(r.passed is True for r in self.rows)

    @property
    def failed(self) -> int:
        """Number of configurations whose run failed (diverged and invalid ones included)."""
        return sum(r.passed is False for r in self.rows)

    @property
    def configurations_per_s(self) -> float | None:
        """Configurations run per second of wall time [1/s] (None: no time measured)."""
        return self.size / self.wall_time_s if self.wall_time_s > 0 else None

    def quantity_names(self) -> list[str]:
        """Scalar numeric quantities of the scenario, in summary.json order."""
        names: list[str] = []
        for row in self.rows:
            for name, value in row.quantities.items():
                if name not in names and _is_number(value):
                    names.append(name)
        return names

    @property
    def headline(self) -> str | None:
        """The quantity the sweep answers by default: the scenario's last numeric quantity that every
        configuration that ran has (its headline result, e.g. max_displacement_m), else the first error column
        ('<col>_max_rel'); None when nothing ran."""
        ran = [row for row in self.rows if row.quantities]
        names = [n for n in self.quantity_names() if all(n in row.quantities for row in ran)]
        if names:
            return names[-1]
        errors = [c for row in self.rows for c in row.errors]
        return f"{errors[0]}_max_rel" if errors else None

    @property
    def question_answer(self) -> Answer:
        """The question and its answer: the counts and the headline's range over the passed configurations."""
        say = answers.Quoter()
        varied = ", ".join(a.name for a in self.axes)
        name = self.headline
        question = (
            f"How does {name or 'the result'} of {self.scene} / {self.scenario} vary with {varied} over {self.size}"
            f" configurations ({self.integrator}, dt = {answers.written(self.dt, '~s')}), and which pass their check?"
        )
        counts = (
            f"{say('passed', self.passed, spec='d')} of {say('configurations', self.size, spec='d')} configurations"
            f" passed, {say('failed', self.failed, spec='d')} failed, {say('diverged', self.diverged, spec='d')} diverged"
            + (f", {say('invalid', self.invalid, spec='d')} invalid" if self.invalid else "")
        )
        if name is None:
            return say.answer(question, f"{counts}.")
        values = self.column(name)
        shown = np.array([row.passed is True for row in self.rows]) & np.isfinite(values)
        if not shown.any():
            return say.answer(question, f"{counts}; no passed configuration has a value of {name}.")
        where = np.flatnonzero(shown)
        low, high = int(where[np.argmin(values[shown])]), int(where[np.argmax(values[shown])])
        unit = "" if name.endswith("_max_rel") else answers.unit_of(name)
        if answers.written(float(values[low]), unit) == answers.written(float(values[high]), unit):
            return say.answer(
                question, f"{counts}. {name} is {say(name, float(values[low]), unit)} in every passed one."
            )
        return say.answer(
            question,
            f"{counts}. Over the passed ones {name} ranges from {say(f'{name}_min', float(values[low]), unit)}"
            f" ({self._where(say, low, 'min')}) to {say(f'{name}_max', float(values[high]), unit)}"
            f" ({self._where(say, high, 'max')}).",
        )

    @property
    def question(self) -> str:
        """What the sweep asks, in words (`question_answer`)."""
        return self.question_answer.question

    @property
    def answer(self) -> str:
        """The answer in words with units (`question_answer`)."""
        return self.question_answer.answer

    def _where(self, say: answers.Quoter, index: int, end: str) -> str:
        """'damping = 0.5 N s/m, stiffness = 200 N/m': the varied values of configuration `index`, with units,
        quoted as '<name>_at_<end>'."""
        known = scenes.SCENES.get(self.scene)
        units = {name: p.unit for name, p in known.parameters.items()} if known else {}
        words = []
        for name in self.values:
            value = float(self.values[name][index])
            unit, after = answers.unit_words(units.get(name, "-"))
            words.append(f"{name} = {say(f'{name}_at_{end}', value, unit)}{after}")
        return ", ".join(words)

    def column(self, name: str) -> np.ndarray:
        """(n,) values of a varied parameter, a quantity, or an error column ('<col>_max_rel') [their units]."""
        if name in self.values:
            return self.values[name]
        out = np.full(self.size, np.nan)
        for i, row in enumerate(self.rows):
            if name.endswith("_max_rel") and name[: -len("_max_rel")] in row.errors:
                out[i] = row.errors[name[: -len("_max_rel")]]
            elif _is_number(row.quantities.get(name)):
                out[i] = float(row.quantities[name])
        return out

    def _records(self) -> tuple[list[str], list[list[Any]]]:
        """sweep.csv's header and rows, None where a configuration has no value."""
        quantities = []
        for row in self.rows:
            for name, value in row.quantities.items():
                if name not in quantities and (_is_number(value) or isinstance(value, str)):
                    quantities.append(name)
        errors: list[str] = []
        for row in self.rows:
            errors.extend(c for c in row.errors if c not in errors)
        header = list(self.values) + quantities + [f"{c}_max_rel" for c in errors] + ["passed", "diverged", "detail"]
        body = []
        for i, row in enumerate(self.rows):
            line: list[Any] = [self.values[name][i] for name in self.values]
            line += [row.quantities.get(name) for name in quantities]
            line += [row.errors.get(c) for c in errors]
            line += [row.passed, row.diverged, row.detail]
            body.append(line)
        return header, body

    def table(self) -> tuple[list[str], list[list[Any]]]:
        """sweep.csv's header and rows: varied parameters, quantities, errors, passed, diverged, detail
        ("" where a configuration has no value)."""
        header, body = self._records()
        return header, [["" if value is None else value for value in line] for line in body]

    def _shown(self) -> display.Summary:
        """The sweep as a notebook shows it: counts first, then the setting, then the rows (truncated)."""
        bad = self.failed + self.diverged + self.invalid
        header, body = self.table()
        keep = [i for i, name in enumerate(header) if name != "detail"][:9]
        return display.Summary(
            "Sweep",
            f"{self.scene} / {self.scenario}",
            f"{self.passed} of {self.size} passed",
            bad == 0,
            f"{self.failed} failed, {self.diverged} diverged, {self.invalid} invalid",
            (
                display.Fact("varied", ", ".join(a.name for a in self.axes)),
                display.Fact("integrator", self.integrator),
                display.Fact("dt", self.dt, "s"),
                display.Fact("duration", self.duration, "s"),
                display.Fact("wall time", self.wall_time_s, "s"),
                display.Fact("configurations per second", self.configurations_per_s, "1/s"),
            ),
            display.table([header[i] for i in keep], [[line[i] for i in keep] for line in body]),
        )

    def plot(self, quantity: str | None = None) -> Figure:
        """A quantity over the varied parameters (`springlab.plots.sweep.sweep_figure`; `quantity=None`: the scenario's last).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self, quantity=quantity)

    def to_dict(self) -> dict[str, Any]:
        """What `springlab sweep --json` prints: setting, axes, counts, timings and every row (plain JSON values)."""
        return json_ready(
            {
                **self.question_answer.to_dict(),
                "scene": self.scene,
                "scenario": self.scenario,
                "integrator": self.integrator,
                "dt": self.dt,
                "duration": self.duration,
                "vary": [a.to_dict() for a in self.axes],
                "samples": self.samples,
                "configurations": self.size,
                "diverged": self.diverged,
                "invalid": self.invalid,
                "passed": self.passed,
                "failed": self.failed,
                "chunks": self.chunks,
                "executor": self.executor,
                "wall_time_s": self.wall_time_s,
                "configurations_per_s": self.configurations_per_s,
                "rows": [row.to_dict() for row in self.rows],
            }
        )

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab sweep --output DIR` writes (springlab.outputs.write): sweep.csv (header, then one
        row per configuration, numbers in their shortest exact form) and sweep.png (its quantity given to the writer)."""
        return Output("sweep.csv", rows_text(*self.table())), Output("sweep.png")

    def to_pandas(self) -> pandas.DataFrame:
        """sweep.csv as a DataFrame, one row per configuration: varied parameters, quantities,
        `<column>_max_rel` errors, passed, diverged, detail (None/NaN where a configuration has no value;
        needs pandas)."""
        header, body = self._records()
        return tables.to_pandas([dict(zip(header, line)) for line in body])


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def configurations(axes: Sequence[Axis], samples: int | None = None, sample_seed: int = 0) -> dict[str, np.ndarray]:
    """Varied parameter -> (n,) values: the full grid (last axis fastest), or `samples` random points.

    Random points are uniform in each range (log-uniform on a log axis) from numpy's
    PCG64 seeded with `sample_seed`, so a sampled sweep is reproducible.
    """
    if samples is not None:
        if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 1:
            raise BadInputError(f"--samples must be an integer >= 1, got {samples!r}")
        unit = np.random.default_rng(sample_seed).random((int(samples), len(axes)))
        return {axis.name: axis.sample(unit[:, j]) for j, axis in enumerate(axes)}
    missing = [a.name for a in axes if a.count is None]
    if missing:
        raise BadInputError(f"--vary {missing[0]} needs N (NAME=LOW:HIGH:N) unless --samples is given")
    counts = [a.count for a in axes if a.count is not None]  # all of them: checked just above
    total = math.prod(counts)
    if total > MAX_CONFIGURATIONS:
        raise BadInputError(f"the grid has {total} configurations, more than {MAX_CONFIGURATIONS}; use --samples")
    mesh = np.meshgrid(*[a.values() for a in axes], indexing="ij")
    return {a.name: m.ravel() for a, m in zip(axes, mesh)}


@dataclasses.dataclass(frozen=True)
class SweepChunk:
    """A chunk of a sweep: plain data, the worker rebuilds every model from the scene's MJCF.

    Attributes
    ----------
    scene
        the scene's name.
    scenario
        the scenario's name.
    integrator
        MuJoCo's integrator name.
    dt
        timestep [s].
    duration
        simulated time of every run [s].
    configurations
        each configuration's parameter overrides, (name, value) pairs, SI.
    """

    scene: str
    scenario: str
    integrator: str
    dt: float
    duration: float
    configurations: tuple[tuple[tuple[str, Any], ...], ...]


def run_chunk(payload: SweepChunk, nthread: int = 0) -> list[dict[str, Any]]:
    """Run one chunk of a sweep as one batched MuJoCo call; the sweep's rows for it.

    A module-level function of plain data, so dask ships it to workers: the
    payload names the scene, scenario and setting and lists each configuration's
    parameter overrides; every model is rebuilt here from the scene's MJCF.

    Parameters
    ----------
    payload
        the chunk.
    nthread
        batch threads (0: one per CPU).
    """
    scene = scenes.get(payload.scene)
    chosen = scene.scenario(payload.scenario)
    dt, duration, integrator = payload.dt, payload.duration, payload.integrator
    steps = check_timing(dt, duration)
    prepared, jobs, rows = [], [], []
    for overrides in payload.configurations:
        params = scene.resolve(chosen, dict(overrides))
        row: dict[str, Any] = {
            "parameters": params,
            "quantities": {},
            "errors": {},
            "passed": None,
            "diverged": False,
            "detail": "",
        }
        rows.append(row)
        # built here, not taken from Case.compiled's shared cases: the rollout below writes into the model
        case = Case(scene, chosen, params, scene.build(params, chosen))
        try:
            job = case.job(integrator, dt, steps)
        except BadInputError as error:  # e.g. a bump that lifts the car off its springs: a row, not a failed sweep
            row.update(passed=False, detail=f"invalid: {error}")
            continue
        prepared.append((row, case))
        jobs.append(job)
    # each case is this chunk's own: the rollout sets its model's integrator and timestep in place
    for (row, case), outcome in zip(prepared, run_rollout(jobs, nthread=nthread, private_models=True)):
        try:
            if isinstance(outcome, DivergedError):
                raise outcome
            result = evaluate(case, outcome)
        except DivergedError as error:
            row.update(passed=False, diverged=True, detail=str(error))
        else:
            row["quantities"] = _scalars(result.quantities)
            row["errors"] = {column: e.max_rel for column, e in result.errors.items()}
            row["passed"] = result.passed
            row["detail"] = failure_detail(result)
    return rows


def failure_detail(result: Result) -> str:
    """Why a run did not pass, in one line; "" for a run that passed (or had nothing to pass).

    The verdict's reason (`Result.message`: the columns and checks outside their tolerance with
    error and tolerance, the range of the error estimate, or the scene's own words on where its
    equations stop holding, e.g. a tire leaving the road), prefixed with what kind of failure it is;
    where the reason is not a tolerance, the worst compared column against its tolerance follows,
    so the row says whether the numbers themselves were accurate.

    Parameters
    ----------
    result
        the run of one configuration.

    Returns
    -------
    str
        "outside its tolerance: ...", "outside the scene's model: ...; ..." or "outside the range
        of the error estimate: ...; ...", or "".
    """
    if result.passed is not False:
        return ""
    if result.verdict is Verdict.FAIL:
        return f"outside its tolerance: {result.message}"
    detail = result.message
    tolerances = result.column_tolerances
    if result.errors and tolerances:
        column = max(tolerances, key=lambda c: result.errors[c].max_rel / tolerances[c])
        error, tolerance = result.errors[column].max_rel, tolerances[column]
        relation = "within" if error <= tolerance else "above"
        detail += (
            f"; errors {relation} tolerance (worst {column}: max relative error {error:.3g}"
            f" {'<=' if error <= tolerance else '>'} {tolerance:.3g})"
        )
    return detail


def _scalars(quantities: Mapping[str, Any]) -> dict[str, Any]:
    """The scalar quantities (numbers, bools, strings) as plain Python values."""
    out: dict[str, bool | float | str] = {}
    for name, value in quantities.items():
        if isinstance(value, (bool, np.bool_)):
            out[name] = bool(value)
        elif _is_number(value):
            out[name] = float(value)
        elif isinstance(value, str):
            out[name] = value
    return out


def sweep(
    model: str,
    scenario: str | None = None,
    *,
    vary: Mapping[str, AxisSpec],
    samples: int | None = None,
    sample_seed: int = 0,
    integrator: str | None = None,
    dt: float | None = None,
    duration: float | None = None,
    chunk_size: int = CHUNK_CONFIGURATIONS,
    executor: Executor | None = None,
    **parameters: float,
) -> Sweep:
    """Run a scenario over a grid (or random samples) of parameters, batched; one row per configuration.

    Parameters
    ----------
    model
        scene name (see `springlab list`).
    scenario
        scenario name (None: the scene's default).
    vary
        parameter -> (low, high, n) or (low, high, n, "log") [parameter's unit]; n may be None when
        `samples` is given. (A string, the command line's 'NAME=LOW:HIGH:N[:log]', is a BadInputError.)
    samples
        draw this many random points in the box instead of the full grid.
    sample_seed
        seed of the random points (`seed` before issue 32: a scene's parameter may be named seed).
    integrator, dt, duration
        the setting (None: the scene's validated one, as `springlab run`).
    chunk_size
        configurations per batched call.
    executor
        where the chunks run (None: locally, in this process).
    **parameters
        fixed parameter values (SI), like `--set`.

    Returns
    -------
    Sweep
        The Sweep; rows equal single `springlab.run` calls at the same parameters.

    Raises
    ------
    BadInputError
        unknown names, bad ranges, a configuration with non-physical values, the command line's strings.
    TypeError
        an old keyword spelling (`seed=` where the scene has no parameter seed, `scene=`).
    """
    started = _time.perf_counter()
    scene_obj = scenes.get(model) if isinstance(model, str) else model
    parameters = keyword_parameters("sweep", parameters, declared=scene_obj.parameters, renamed=RENAMED)
    scene_obj, chosen, _ = prepare(scene_obj, scenario, parameters)
    axes = _axes(vary)
    for axis in axes:
        if axis.name not in scene_obj.parameters:
            raise UnknownNameError(f"parameter of {scene_obj.name}", axis.name, scene_obj.parameters)
        if axis.name in parameters:
            raise BadInputError(f"{axis.name} is both varied (--vary) and fixed (--set); choose one")
    if integrator == "auto":
        raise BadInputError("a sweep runs one setting for every configuration; name an integrator, not 'auto'")
    default_integrator, default_dt = scene_obj.setting(chosen)
    integrator = default_integrator if integrator is None else integrator
    integrator_id(integrator)
    dt = default_dt if dt is None else dt
    duration = chosen.duration if duration is None else duration
    check_timing(dt, duration)
    values = configurations(axes, samples, sample_seed)
    count = len(next(iter(values.values())))
    overrides = []
    for i in range(count):
        config = dict(parameters)
        config.update({name: float(values[name][i]) for name in values})
        try:
            scene_obj.resolve(chosen, config)  # bad input is found here, before anything runs
        except BadInputError as error:
            where = ", ".join(f"{name}={values[name][i]:g}" for name in values)
            raise BadInputError(f"configuration {i} ({where}): {error}") from None
        overrides.append(config)
    runner = resolve(executor)
    pieces = chunked(count, chunk_size)
    payloads = [
        SweepChunk(
            scene_obj.name,
            chosen.name,
            integrator,
            float(dt),
            float(duration),
            tuple(tuple(overrides[i].items()) for i in piece),
        )
        for piece in pieces
    ]
    results = runner.map(run_chunk, payloads, description="sweep", sizes=[len(p) for p in pieces], unit="run")
    rows = tuple(
        SweepRow(values={name: float(values[name][i]) for name in values}, **row)
        for i, row in enumerate(r for chunk in results for r in chunk)
    )
    return Sweep(
        scene=scene_obj.name,
        scenario=chosen.name,
        integrator=integrator,
        dt=float(dt),
        duration=float(duration),
        axes=tuple(axes),
        samples=samples,
        values=values,
        rows=rows,
        wall_time_s=_time.perf_counter() - started,
        executor=runner.describe(),
        chunks=len(pieces),
    )


def _axes(vary: Mapping[str, AxisSpec]) -> list[Axis]:
    if not isinstance(vary, Mapping):
        raise BadInputError(
            "vary takes a mapping, parameter -> (low, high, n) or (low, high, n, 'log'), e.g. vary={'damping':"
            f" (0.5, 40.0, 30, 'log')}}, not {vary!r} (the command line's NAME=LOW:HIGH:N[:log] is springlab"
            " sweep --vary's)"
        )
    axes = [typed_axis(name, given) for name, given in vary.items()]
    if not axes:
        raise BadInputError("a sweep needs at least one --vary NAME=LOW:HIGH:N[:log]")
    return axes


def typed_axis(name: str, given: AxisSpec) -> Axis:
    """The checked Axis of `vary[name]`, (low, high, n) or (low, high, n, 'log') [parameter's unit].

    Raises
    ------
    BadInputError
        a string (the command line's LOW:HIGH:N), another shape, strings among the numbers, a bad range.
    """
    form = "takes (low, high, n) or (low, high, n, 'log')"
    if isinstance(given, (str, bytes)):
        raise BadInputError(f"vary[{name!r}] {form}, not the command line's string {given!r}")
    spec: tuple[object, ...] = tuple(given)
    if len(spec) not in (3, 4) or (len(spec) == 4 and spec[3] != "log"):
        raise BadInputError(f"vary[{name!r}] {form}, got {spec!r}")
    low, high, count = spec[:3]
    if any(isinstance(v, (str, bytes)) for v in spec[:3]):
        raise BadInputError(f"vary[{name!r}] takes numbers (low, high, n), not strings: got {spec!r}")
    number = (int, float, np.integer, np.floating)
    if not isinstance(low, number) or not isinstance(high, number):
        raise BadInputError(f"vary[{name!r}] {form} with numbers low and high, got {spec!r}")
    if count is not None and not isinstance(count, (int, np.integer)):
        raise BadInputError(f"--vary {name}: N must be an integer >= 1, got {count!r}")
    return make_axis(name, float(low), float(high), None if count is None else int(count), len(spec) == 4)
