"""How much does it vibrate under a random load? Many seeded records against the exact stationary RMS.

For a scene that declares a scenario under a seeded stationary random load (`Scene.random_load`, a
springlab.scenes.capabilities.random_load.RandomLoadSpec) the study runs `seeds` records of the scenario at one setting, each
started from the exact stationary distribution with its own load (seed k's load is the same whichever batch,
worker or order runs it), and measures each record's sample variance of the declared output. It reports, beside
them, the exact variance three ways (continuous time: the physical answer; under the held load MuJoCo applies;
MuJoCo's own one-step map), the scatter one record's estimate has (exact, from the record's autocovariance) and
the interval at `level` it falls in: a correct simulation leaves a record outside with probability 1 - level,
so the count inside is a test that can fail.

The records run in chunks of `SEEDS_PER_CHUNK` seeds, each chunk one batched `mujoco.rollout` over the seeds
(threads split the seeds), stepped in blocks of `BLOCK_STEPS` steps from the last state, so memory stays
bounded for records of millions of steps and only the running sum of y^2 is kept. Chunks go through
springlab.studies.executor (locally, `--workers N`, `--scheduler ADDRESS`): a chunk is a pure function of its
payload (scene, parameters, setting, seeds), so the numbers are identical whichever runs them.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time as _time
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
from mujoco import rollout as _rollout

from springlab import display, scenes, tables
from springlab.answer import Answer
from springlab.errors import BadInputError, DivergedError
from springlab.exact import random_vibration as rv
from springlab.files import Output, csv_text, json_ready
from springlab.scenes.base import Scene
from springlab.scenes.capabilities.random_load import RandomLoadSpec
from springlab.scenes.declarations import keyword_parameters, refuse_text
from springlab.sim.simulate import check_timing, configured, initial_state, integrator_id, quiet_mujoco

from . import answers
from .executor import Executor, chunked, resolve

if TYPE_CHECKING:
    import pandas

#: seeds per chunk (one batched rollout; the executor's unit of work)
SEEDS_PER_CHUNK = 4
#: steps per rollout call within a chunk (memory: seeds x BLOCK_STEPS x the state's size x 8 bytes)
BLOCK_STEPS = 2000
#: the default confidence level of a record's interval: 40 records of a correct simulation leave more than 2
#: outside with probability 1 - P(Binomial(40, 0.01) <= 2) = 0.8 % (a 95 % level: 32 %)
LEVEL = 0.99
#: the default number of seeds
SEEDS = 40

_FULL = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)


def declared(scene: str | Scene) -> tuple[Scene, RandomLoadSpec]:
    """(scene, its RandomLoadSpec), or BadInputError naming the scenes that declare one."""
    found = scenes.get(scene) if isinstance(scene, str) else scene
    if found.random_load is None:
        names = [s.name for s in scenes.SCENES.values() if s.random_load is not None]
        raise BadInputError(
            f"{found.name} has no scenario under a random load; scenes with one: {', '.join(names) or 'none'}"
        )
    return found, found.random_load


@dataclasses.dataclass(frozen=True)
class SeedsChunk:
    """A chunk's payload: plain data (the worker rebuilds the model from the scene's MJCF).

    Attributes
    ----------
    scene, scenario
        names.
    parameters
        (name, value) pairs, SI: the overrides of the case (the seed is set per record).
    integrator
        MuJoCo integrator name.
    dt
        timestep [s].
    steps
        steps per record.
    seeds
        the seeds of this chunk's records.
    """

    scene: str
    scenario: str
    parameters: tuple[tuple[str, float], ...]
    integrator: str
    dt: float
    steps: int
    seeds: tuple[int, ...]


def run_seeds(payload: SeedsChunk, nthread: int = 0) -> list[float]:
    """The sample variance (1/K) sum_{k=1..K} y_k^2 of each seed's record [unit^2], one batched rollout.

    Raises
    ------
    DivergedError
        a record blew up (MuJoCo reset it, or it went non-finite).
    """
    scene, spec = declared(payload.scene)
    case = scene.case(payload.scenario, dict(payload.parameters))
    row = spec.output(case)
    model = configured(case.model, payload.integrator, payload.dt)
    count, steps = len(payload.seeds), payload.steps
    setups = [spec.setup(case, steps, payload.dt, seed) for seed in payload.seeds]
    state = np.stack([initial_state(model, s.qpos, s.qvel, s.act) for s in setups])
    controls = np.stack([np.broadcast_to(np.asarray(s.control, float), (steps, model.nu)) for s in setups])
    threads = max(1, min(count, (os.cpu_count() or 1) if nthread == 0 else nthread))
    datas = [mujoco.MjData(model) for _ in range(threads)]
    models = [model] * count
    span = slice(1, 1 + model.nq + model.nv)
    sums = np.zeros(count)
    block = np.empty((count, min(BLOCK_STEPS, steps), state.shape[1]))
    done = 0
    with quiet_mujoco() as messages:
        while done < steps:
            size = min(BLOCK_STEPS, steps - done)
            out = block if size == block.shape[1] else np.empty((count, size, state.shape[1]))
            _rollout.rollout(
                models,
                datas,
                state,
                np.ascontiguousarray(controls[:, done : done + size]),
                nstep=size,
                state=out,
                skip_checks=True,
            )
            times = np.concatenate([state[:, :1], out[:, :, 0]], axis=1)
            if not (np.all(np.isfinite(out)) and np.all(np.diff(times, axis=1) > 0)):
                raise DivergedError(
                    f"a record diverged ({payload.integrator}, dt = {payload.dt:g} s): MuJoCo reset it or it went"
                    " non-finite; use a smaller dt"
                )
            y = out[:, :, span] @ row
            sums += np.einsum("ij,ij->i", y, y)
            state = out[:, -1].copy()
            done += size
    if any("unstable" in m.lower() for m in messages):
        raise DivergedError(f"a record diverged ({payload.integrator}, dt = {payload.dt:g} s): {messages[0].strip()}")
    return list(sums / steps)


@dataclasses.dataclass(frozen=True, repr=False)
class Ensemble(display.Shown):
    """Many seeded records of a random-load scenario against the exact stationary variance.

    Attributes
    ----------
    scene, scenario
        names.
    description, quantity, unit
        the RMS in words, its quantity name and unit (the scene's declaration).
    parameters
        the case's parameters, SI (the seed is each record's).
    integrator, dt
        the setting [s].
    steps
        steps per record.
    seeds
        the records' seeds.
    variances
        each record's sample variance [unit^2].
    continuous, held, integrated
        the exact variance [unit^2]: continuous time, under the held load, of MuJoCo's one-step map.
    spread
        the standard deviation [unit^2] of one record's sample variance (exact).
    level
        the confidence level of the intervals.
    wall_time_s
        the records' wall time [s] (the executor's, the exact answers excluded).
    exact_time_s
        the exact answers' time [s].
    executor
        where the records ran.
    """

    scene: str
    scenario: str
    description: str
    quantity: str
    unit: str
    parameters: dict[str, float]
    integrator: str
    dt: float
    steps: int
    seeds: tuple[int, ...]
    variances: tuple[float, ...]
    continuous: float
    held: float
    integrated: float
    spread: float
    level: float
    wall_time_s: float
    exact_time_s: float
    executor: str

    @property
    def record_s(self) -> float:
        """One record's length [s]."""
        return self.steps * self.dt

    @property
    def rms(self) -> np.ndarray:
        """Each record's RMS [unit]."""
        return np.sqrt(np.asarray(self.variances))

    @property
    def interval(self) -> rv.VarianceInterval:
        """Where one record's sample variance falls at `level`, around the exact held variance."""
        return rv.variance_interval(self.held, self.spread, self.level)

    @property
    def inside(self) -> int:
        """How many records' variances lie inside `interval`."""
        interval = self.interval
        return sum(interval.contains(v) for v in self.variances)

    @property
    def mean_variance(self) -> float:
        """The records' mean sample variance [unit^2]: the pooled estimate."""
        return float(np.mean(self.variances))

    @property
    def mean_interval(self) -> rv.VarianceInterval:
        """Where the mean of len(seeds) independent records falls at `level` (spread / sqrt(seeds))."""
        return rv.variance_interval(self.held, self.spread / math.sqrt(len(self.seeds)), self.level)

    @property
    def expected_outside(self) -> float:
        """The number of records a correct simulation leaves outside, on average: (1 - level) seeds."""
        return (1.0 - self.level) * len(self.seeds)

    @property
    def question(self) -> str:
        """What the study answers, in words."""
        return f"How large is {self.description} under the random load, and do {len(self.seeds)} seeded records agree?"

    @property
    def question_answer(self) -> Answer:
        """The question and `answer`, with the RMS values it quotes (in the response's unit)."""
        return answers.of_words(
            self.question,
            self.answer,
            {
                "rms_exact": math.sqrt(self.continuous),
                "rms_held": math.sqrt(self.held),
                "rms_integrated": math.sqrt(self.integrated),
                "rms_pooled": math.sqrt(self.mean_variance),
                "inside": self.inside,
            },
        )

    @property
    def answer(self) -> str:
        """The answer in words, with units."""
        low, high = self.interval.rms_interval()
        mean_low, mean_high = self.mean_interval.rms_interval()
        pooled = math.sqrt(self.mean_variance)
        return (
            f"{self.description[:1].upper()}{self.description[1:]} is {math.sqrt(self.continuous):.4g} {self.unit} exactly"
            f" ({math.sqrt(self.held):.4g} {self.unit} under the load held over {self.dt:g} s steps,"
            f" {math.sqrt(self.integrated):.4g} {self.unit} for {self.integrator}'s own map). {self.inside} of"
            f" {len(self.seeds)} records of {self.record_s:g} s fall inside their {self.level:.0%} interval"
            f" {low:.4g} to {high:.4g} {self.unit} (a correct simulation leaves {self.expected_outside:.2g} outside on"
            f" average); pooled, they give {pooled:.4g} {self.unit} ({self.level:.0%} interval for the pool"
            f" {mean_low:.4g} to {mean_high:.4g} {self.unit})."
        )

    def _shown(self) -> display.Summary:
        return display.Summary(
            "Ensemble",
            f"{self.scene} / {self.scenario}",
            f"{self.inside} of {len(self.seeds)} inside",
            self.inside >= len(self.seeds) - allowed_outside(len(self.seeds), self.level),
            self.answer,
            (
                display.Fact("exact RMS (continuous)", math.sqrt(self.continuous), self.unit),
                display.Fact("exact RMS (held)", math.sqrt(self.held), self.unit),
                display.Fact(f"{self.integrator} map's RMS", math.sqrt(self.integrated), self.unit),
                display.Fact("pooled RMS", math.sqrt(self.mean_variance), self.unit),
                display.Fact("record", self.record_s, "s"),
                display.Fact("wall time", self.wall_time_s, "s"),
            ),
            display.table(("seed", f"RMS [{self.unit}]", "inside"), self.rows_shown()),
        )

    def rows_shown(self) -> list[tuple[int, float, bool]]:
        """(seed, RMS [unit], inside its interval) per record."""
        interval = self.interval
        return [(s, math.sqrt(v), interval.contains(v)) for s, v in zip(self.seeds, self.variances)]

    def to_dict(self) -> dict[str, Any]:
        """rms.json: question, answer, the setting, the exact variances, the interval, each record."""
        interval = self.interval
        low, high = interval.rms_interval()
        return json_ready(
            {
                **self.question_answer.to_dict(),
                "scene": self.scene,
                "scenario": self.scenario,
                "quantity": self.quantity,
                "unit": self.unit,
                "parameters": self.parameters,
                "integrator": self.integrator,
                "dt": self.dt,
                "steps": self.steps,
                "record_s": self.record_s,
                "level": self.level,
                "exact": {
                    "rms_continuous": math.sqrt(self.continuous),
                    "rms_held": math.sqrt(self.held),
                    "rms_integrator": math.sqrt(self.integrated),
                    "variance_hold_error": self.held / self.continuous - 1,
                    "variance_integrator_error": self.integrated / self.held - 1,
                    "variance_record_spread": self.spread / self.held,
                    "degrees_of_freedom": interval.degrees_of_freedom,
                },
                "interval": [low, high],
                "inside": self.inside,
                "seeds": len(self.seeds),
                "expected_outside": self.expected_outside,
                "pooled_rms": math.sqrt(self.mean_variance),
                "pooled_interval": list(self.mean_interval.rms_interval()),
                "records": [{"seed": s, "rms": r, "inside": i} for s, r, i in self.rows_shown()],
                "wall_time_s": self.wall_time_s,
                "exact_time_s": self.exact_time_s,
                "executor": self.executor,
            }
        )

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab rms --output DIR` writes (springlab.outputs.write): rms.json, rms.csv (one row
        per record: seed, rms, inside) and rms.png."""
        rows = self.rows_shown()
        columns = {
            "seed": np.array([r[0] for r in rows], float),
            "rms": np.array([r[1] for r in rows]),
            "inside": np.array([float(r[2]) for r in rows]),
        }
        return Output.json("rms.json", self.to_dict()), Output("rms.csv", csv_text(columns)), Output("rms.png")

    def to_pandas(self) -> pandas.DataFrame:
        """One row per record: seed, rms, inside."""
        return tables.to_pandas(self.to_dict()["records"])


def allowed_outside(seeds: int, level: float) -> int:
    """The fewest records outside [-] that a correct simulation exceeds with probability below 1 %: the rule the
    verdict applies (2 of 40 at 99 %: more than 2 outside happens to a correct simulation 0.8 % of the time)."""
    import scipy.stats  # on first use: the command line starts without it

    allowed = 0
    while 1.0 - float(scipy.stats.binom.cdf(allowed, seeds, 1.0 - level)) > 0.01:
        allowed += 1
    return allowed


def records(
    scene: Scene,
    scenario: str,
    parameters: Mapping[str, float],
    integrator: str,
    dt: float,
    steps: int,
    seeds: Sequence[int],
    executor: Executor | None = None,
) -> tuple[list[float], float]:
    """(each seed's sample variance [unit^2], wall time [s]): the records on the executor, chunks of SEEDS_PER_CHUNK."""
    runner = resolve(executor)
    chunks = [
        SeedsChunk(
            scene.name,
            scenario,
            tuple(sorted((k, float(v)) for k, v in parameters.items())),
            integrator,
            float(dt),
            int(steps),
            tuple(int(seeds[i]) for i in part),
        )
        for part in chunked(len(seeds), SEEDS_PER_CHUNK)
    ]
    start = _time.perf_counter()
    try:
        results = runner.map(
            run_seeds, chunks, description="records", sizes=[len(c.seeds) for c in chunks], unit="record"
        )
    finally:
        if executor is None:
            runner.close()
    return [v for chunk in results for v in chunk], _time.perf_counter() - start


def ensemble(
    model: str | Scene,
    scenario: str | None = None,
    *,
    seeds: int | Sequence[int] = SEEDS,
    record: float | None = None,
    integrator: str | None = None,
    dt: float | None = None,
    level: float = LEVEL,
    executor: Executor | None = None,
    **parameters: float,
) -> Ensemble:
    """Records of a random-load scenario, one per seed, against the exact stationary variance (`springlab.rms`).

    Parameters
    ----------
    model
        a scene that declares `random_load`, or its name.
    scenario
        its random-load scenario (None: the declared one).
    seeds
        how many records (seeds 0 ... seeds - 1) or the seeds themselves.
    record
        one record's length [s] (None: the scenario's duration).
    integrator, dt
        the setting (None: the scenario's validated one).
    level
        the confidence level of the intervals, in (0, 1).
    executor
        where the records run (None: locally).
    **parameters
        the scene's parameters, SI (not the seed: each record has its own).

    Raises
    ------
    BadInputError
        no random load, an unknown scenario, a bad setting, seeds or level, a seed set as a parameter.
    DivergedError
        a record blew up.
    TypeError
        an old keyword spelling (`scene=`) or another study's option.
    """
    parameters = keyword_parameters("rms", parameters)
    refuse_text(
        "seeds", seeds, "a count or a sequence of whole numbers, e.g. seeds=40 or seeds=(0, 1, 2)", numbers=True
    )
    found, spec = declared(model)
    chosen = found.scenario(scenario or spec.scenario)
    if chosen.name != spec.scenario:
        raise BadInputError(f"{found.name}'s random load is scenario {spec.scenario!r}, not {chosen.name!r}")
    if spec.seed in parameters:
        raise BadInputError(f"{spec.seed} is each record's own; give --seeds N (records 0 ... N - 1) instead")
    seed_list = _seeds(seeds)
    if isinstance(level, bool) or not isinstance(level, (int, float)) or not (0.0 < level < 1.0):
        raise BadInputError(f"level must lie in (0, 1), got {level!r}")
    default_integrator, default_dt = found.setting(chosen)
    integrator = default_integrator if integrator is None else integrator
    integrator_id(integrator)
    dt = default_dt if dt is None else dt
    steps = check_timing(dt, chosen.duration if record is None else record)
    start = _time.perf_counter()
    case = found.case(chosen, parameters)
    exact = spec.exact(case, integrator, dt)
    spread = float(exact.spreads([steps])[0])
    exact_time = _time.perf_counter() - start
    variances, wall = records(found, chosen.name, parameters, integrator, dt, steps, seed_list, executor)
    return Ensemble(
        found.name,
        chosen.name,
        spec.description,
        spec.quantity,
        spec.unit,
        {k: v for k, v in case.params.items() if k != spec.seed},
        integrator,
        float(dt),
        steps,
        tuple(seed_list),
        tuple(variances),
        exact.continuous,
        exact.held,
        exact.integrator,
        spread,
        float(level),
        wall,
        exact_time,
        resolve(executor).describe() if executor is not None else "local",
    )


def _seeds(seeds: int | Sequence[int]) -> list[int]:
    """The seeds as whole numbers >= 0 (an int n: 0 ... n - 1), or BadInputError."""
    if isinstance(seeds, bool):
        raise BadInputError(f"seeds must be a whole number >= 1 or a list of seeds, got {seeds!r}")
    listed = list(range(seeds)) if isinstance(seeds, int) else list(seeds)
    if not listed or any(isinstance(s, bool) or int(s) != s or s < 0 for s in listed):
        raise BadInputError(f"seeds must be a whole number >= 1 or a list of whole numbers >= 0, got {seeds!r}")
    return [int(s) for s in listed]
