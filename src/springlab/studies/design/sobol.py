"""Which properties matter, by variance: Sobol first-order and total indices (SALib) of a scene's design
question (`Scene.design`; the printer head's positioning time, for one).

The design study's elasticities come from a log-log fit of positioning time
on the properties (R^2 about 0.5: settling time jumps in half-period steps as
the residual vibration's last peak leaves the band), so they cannot rank a
property whose effect is non-monotone. Variance-based global sensitivity can:

* S1_i, the first-order index: the share of Var(T) explained by property i
  alone (averaging over all the others);
* ST_i, the total index: the share that involves i at all, alone or through
  interactions; ST_i - S1_i is what i does only together with others.

Sampling and estimation are SALib's (Saltelli's scheme on a scrambled Sobol'
sequence, `SALib.sample.sobol`; Jansen/Saltelli estimators with bootstrap
confidence intervals, `SALib.analyze.sobol`), not hand-written. With D inputs
and N base samples the study runs N (D + 2) simulations (second-order indices
off: they would need N (2 D + 2)).

The inputs are the ones the scene's declaration names for the Sobol study (`DesignSpec.sobol`; the
printer head's: carriage mass, belt stiffness, belt damping ratio, drive force and move length), each
log-uniform over default x span^[-1, 1] (the declared spans; the printer head's move from a quarter to
four times the default inch). The sampled variables are the exponents u in [-1, 1], so each property
is log-uniform; Sobol indices are properties of that input distribution, stated with them. The output
is the positioning time T [s] of the move plus settling (the scene's simulation hook, run in chunks on
the executor by springlab.studies.design.moves, so a cluster gives the same indices bit for bit).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time as _time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab import display, files, tables
from springlab.answer import Answer
from springlab.errors import BadInputError
from springlab.scenes.base import Scene
from springlab.studies import answers
from springlab.studies.executor import Executor, chunked, resolve

from . import moves

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure

#: base samples N of the default study: N (D + 2) = 16384 x 7 = 114,688 simulations of the printer head
DEFAULT_BASE_SAMPLES = 16384
#: confidence level of the bootstrap intervals, and the resamples drawn
CONFIDENCE = 0.95
RESAMPLES = 100
#: configurations per chunk (one batched MuJoCo call each)
CHUNK_CONFIGURATIONS = moves.CHUNK_CONFIGURATIONS


def check_base_samples(n: Any, inputs: int) -> int:
    """N as an int, or BadInputError: the Saltelli scheme needs a power of 2 (Sobol' sequence balance).

    Parameters
    ----------
    n
        the base samples asked for.
    inputs
        D, the varied inputs: the study runs N (D + 2) simulations (the message says how many).

    Raises
    ------
    BadInputError
        `n` is not a power of 2 >= 4.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 4 or (int(n) & (int(n) - 1)):
        raise BadInputError(
            f"--sobol N takes a power of 2 >= 4 (base samples of the Sobol' sequence; the study runs N x {inputs + 2}"
            f" simulations), e.g. 1024 or {DEFAULT_BASE_SAMPLES}; got {n!r}"
        )
    return int(n)


def problem(names: list[str]) -> dict[str, Any]:
    """The SALib problem over the exponents u in [-1, 1] of `names`."""
    return {"num_vars": len(names), "names": list(names), "bounds": [[-1.0, 1.0]] * len(names)}


def sample(spec: Mapping[str, Any], base_samples: int, seed: int = 0) -> np.ndarray:
    """(N (D + 2), D) Saltelli sample of `spec` (SALib, scrambled Sobol' sequence seeded with `seed`)."""
    from SALib.sample import sobol as saltelli

    n = check_base_samples(base_samples, spec["num_vars"])
    return saltelli.sample(dict(spec), n, calc_second_order=False, seed=seed)


def analyze(spec: Mapping[str, Any], output: np.ndarray, seed: int = 0) -> dict[str, dict[str, float]]:
    """SALib's S1, S1_conf, ST, ST_conf (each name -> value [-]) of `output`; CIs at CONFIDENCE by bootstrap."""
    from SALib.analyze import sobol as estimator

    with np.errstate(all="ignore"):
        indices = estimator.analyze(
            dict(spec),
            np.asarray(output, float),
            calc_second_order=False,
            num_resamples=RESAMPLES,
            conf_level=CONFIDENCE,
            print_to_console=False,
            seed=seed + 1,  # SALib draws unseeded bootstrap resamples for seed 0 (`if seed:`)
        )
    return {
        key: {n: float(v) for n, v in zip(spec["names"], indices[key])} for key in ("S1", "S1_conf", "ST", "ST_conf")
    }


def evaluate(
    function: Callable[..., np.ndarray],
    rows: np.ndarray,
    chunk_of: Callable[[np.ndarray], Any],
    *,
    executor: Executor | None = None,
    chunk_size: int = CHUNK_CONFIGURATIONS,
    description: str = "sobol",
) -> np.ndarray:
    """function(chunk_of(part), nthread) over the parts of `rows` cut into chunks on the executor; (n,) outputs
    in order (`chunk_of` makes a part's payload, e.g. IshigamiChunk with its constants bound)."""
    runner = resolve(executor)
    pieces = chunked(len(rows), chunk_size)
    payloads = [chunk_of(np.asarray(rows[p.start : p.stop])) for p in pieces]
    parts = runner.map(function, payloads, description=description, sizes=[len(p) for p in pieces], unit="run")
    return np.concatenate(parts) if parts else np.empty(0)


# -- a function with known indices: the check that the pipeline is right ------------------------


@dataclasses.dataclass(frozen=True, eq=False)  # arrays: compare fields, not results
class IshigamiChunk:
    """A chunk of the Ishigami check: rows (n, 3) of x in [-pi, pi]^3 and the function's constants a, b [-]."""

    rows: np.ndarray
    a: float
    b: float


def ishigami_chunk(payload: IshigamiChunk, nthread: int = 0) -> np.ndarray:
    """Ishigami function sin x1 + a sin^2 x2 + b x3^4 sin x1 of the payload's rows (n, 3), x in [-pi, pi]^3."""
    x = np.asarray(payload.rows, float)
    a, b = payload.a, payload.b
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami(
    base_samples: int, *, a: float = 7.0, b: float = 0.1, seed: int = 0, executor: Executor | None = None
) -> dict[str, dict[str, float]]:
    """Sobol indices of the Ishigami function through the same sampling, executor and analysis."""
    spec = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": [[-math.pi, math.pi]] * 3}
    rows = sample(spec, base_samples, seed)
    output = evaluate(
        ishigami_chunk, rows, functools.partial(IshigamiChunk, a=a, b=b), executor=executor, chunk_size=4096
    )
    return analyze(spec, output, seed)


# -- a scene's design question ------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, eq=False)  # arrays: compare fields, not results
class PositioningChunk:
    """A chunk of a scene's Sobol study: plain data, the worker rebuilds the scene's model.

    Attributes
    ----------
    rows
        (n, D) exponents u [-] of `names`.
    scene
        the scene's name.
    base
        (name, value) pairs: the scene's parameters, SI.
    names
        the D sampled properties.
    spans
        (property, span) pairs [-]: a property is default x span^u.
    omega_dt
        omega_n dt [-] of every simulation.
    """

    rows: np.ndarray
    scene: str
    base: tuple[tuple[str, float], ...]
    names: tuple[str, ...]
    spans: tuple[tuple[str, float], ...]
    omega_dt: float


def positioning_chunk(payload: PositioningChunk, nthread: int = 0) -> np.ndarray:
    """Positioning time [s] of each row of exponents u (n, D) in the payload's rows (one batched call)."""
    _, spec = moves.declaration(payload.scene)
    base = dict(payload.base)
    values = properties(spec.hooks.defaults(base), dict(payload.spans), list(payload.names), payload.rows)
    runs = moves.simulate(payload.scene, base, values, omega_dt=payload.omega_dt, nthread=nthread)
    return runs.positioning_time_s


def properties(
    defaults: Mapping[str, float], spans: Mapping[str, float], names: list[str], exponents: np.ndarray
) -> dict[str, np.ndarray]:
    """Property -> (n,) values default x span^u for exponent rows u (n, D) of `names`; the others at default.

    Parameters
    ----------
    defaults
        every declared property's default [its unit] (the scene's `defaults` hook).
    spans
        property -> span [-] (the declared ones), for the swept properties and `names`.
    names
        the sampled properties, in column order.
    exponents
        (n, D) exponents u in [-1, 1].

    Returns
    -------
    dict[str, np.ndarray]
        the swept properties at their defaults, then each sampled one, (n,) each.
    """
    exponents = np.asarray(exponents, float)
    values = {name: np.full(len(exponents), defaults[name]) for name in spans}
    for j, name in enumerate(names):
        values[name] = defaults[name] * spans[name] ** exponents[:, j]
    return values


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class SobolStudy(display.Shown):
    """Sobol indices of a scene's figure of merit (the positioning time) over its declared inputs.

    Immutable: mappings are read-only views, arrays read-only.

    Attributes
    ----------
    scene
        the scene studied.
    merit
        the figure of merit in words ('positioning time').
    base
        the scene parameters the ranges are centred on (SI).
    names
        the varied properties, in sampling order.
    units
        property -> its unit.
    ranges
        property -> (low, high) [its unit], log-uniform.
    base_samples
        N.
    runs
        N (D + 2) simulations.
    seed
        seed of the sample and of the bootstrap.
    indices
        SALib's S1, S1_conf, ST, ST_conf (property -> value [-]).
    positioning_time_s
        (runs,) output [s], censored at springlab.studies.design.moves.MAX_DURATION.
    unsettled
        how many never settled within MAX_DURATION (counted there).
    elasticities
        d ln T / d ln p [-] by least squares over the same runs.
    regression_r2
        R^2 [-] of that fit.
    wall_time_s
        wall time of the simulations [s].
    executor
        where they ran.
    """

    scene: str
    merit: str
    base: Mapping[str, float]
    names: tuple[str, ...]
    units: Mapping[str, str]
    ranges: Mapping[str, tuple[float, float]]
    base_samples: int
    runs: int
    seed: int
    indices: Mapping[str, Mapping[str, float]]
    positioning_time_s: np.ndarray
    unsettled: int
    elasticities: Mapping[str, float]
    regression_r2: float
    wall_time_s: float
    executor: str

    def __post_init__(self) -> None:
        frozen = {
            "base": moves.frozen_mapping(self.base),
            "names": tuple(self.names),
            "units": moves.frozen_mapping(self.units),
            "ranges": moves.frozen_mapping({n: tuple(r) for n, r in self.ranges.items()}),
            "indices": moves.frozen_mapping({key: moves.frozen_mapping(value) for key, value in self.indices.items()}),
            "elasticities": moves.frozen_mapping(self.elasticities),
            "positioning_time_s": moves.frozen_array(self.positioning_time_s),
        }
        for name, value in frozen.items():
            object.__setattr__(self, name, value)

    @functools.cached_property
    def interactions(self) -> Mapping[str, float]:
        """ST - S1 [-]: the share of variance a property has only through interactions."""
        return moves.frozen_mapping({n: self.indices["ST"][n] - self.indices["S1"][n] for n in self.names})

    @functools.cached_property
    def ranking(self) -> tuple[str, ...]:
        """Properties by decreasing total index."""
        return tuple(sorted(self.names, key=lambda n: -self.indices["ST"][n]))

    @functools.cached_property
    def elasticity_ranking(self) -> tuple[str, ...]:
        """Properties by decreasing |elasticity|: the ranking the design study's log-log fit would make."""
        return tuple(sorted(self.names, key=lambda n: -abs(self.elasticities[n])))

    @property
    def first_order_sum(self) -> float:
        """Sum of the first-order indices [-] (at most 1 up to sampling error; 1 - it: the interactions)."""
        return float(sum(self.indices["S1"].values()))

    @property
    def question(self) -> str:
        """What the Sobol study asks, in words."""
        return f"Which properties drive the variance of the {self.merit}, alone and through their interactions?"

    @property
    def question_answer(self) -> Answer:
        """The question and `answer`, with the first-order and total indices it quotes [-]."""
        s1, st = self.indices["S1"], self.indices["ST"]
        numbers = {f"S1_{n}": s1[n] for n in self.ranking} | {f"ST_{n}": st[n] for n in self.ranking}
        return answers.of_words(self.question, self.answer, {**numbers, "first_order_sum": self.first_order_sum})

    @property
    def answer(self) -> str:
        """Which properties matter, in words, with the study's numbers."""
        s1, st, conf = self.indices["S1"], self.indices["ST"], self.indices["ST_conf"]
        alone = ", ".join(f"{n} {s1[n]:.2f}" for n in self.ranking)
        total = ", ".join(f"{n} {st[n]:.2f} ± {conf[n]:.2f}" for n in self.ranking)
        inter = self.interactions
        through = [n for n in self.ranking if inter[n] > max(0.05, self.indices["ST_conf"][n])]
        elastic = self.elasticity_ranking
        return (
            f"Sobol ({self.runs} runs, {CONFIDENCE:.0%} intervals): alone (S1) {alone}; in total (ST) {total}; "
            f"first-order sum {sum(s1.values()):.2f}. "
            + (
                f"Through interactions (ST - S1 > 0.05): {', '.join(through)}. "
                if through
                else "Interactions are small. "
            )
            + f"Elasticity ranking from the same runs (R^2 = {self.regression_r2:.2f}): {', '.join(elastic)}"
            + ("; the same order." if elastic == self.ranking else f"; by variance: {', '.join(self.ranking)}.")
        )

    def _shown(self) -> display.Summary:
        """The Sobol study as a notebook shows it: the ranking first, then the indices."""
        s1, st = self.indices["S1"], self.indices["ST"]
        return display.Summary(
            "SobolStudy",
            f"{self.scene}: {self.merit}",
            " > ".join(self.ranking),
            None,
            self.answer,
            (
                display.Fact("runs", self.runs),
                display.Fact("first-order sum", self.first_order_sum),
                display.Fact("unsettled", self.unsettled),
                display.Fact("wall time", self.wall_time_s, "s"),
            ),
            display.table(
                ("property", "S1 [-]", "ST [-]", "ST conf [-]"),
                [(n, s1[n], st[n], self.indices["ST_conf"][n]) for n in self.ranking],
            ),
        )

    def plot(self) -> Figure:
        """First-order and total Sobol indices with their intervals, and the elasticities (`springlab.plots.design.sobol_figure`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """The `sobol` entry of design.json and `design --sobol --json`: parameters, S1, S1_conf, ST, ST_conf,
        runs (docs/sweeps.md), and more; JSON-ready (inf and nan as None)."""
        return files.json_ready(
            {
                **self.question_answer.to_dict(),
                "parameters": {
                    n: {"unit": self.units[n], "range": list(self.ranges[n]), "log_uniform": True} for n in self.names
                },
                "S1": dict(self.indices["S1"]),
                "S1_conf": dict(self.indices["S1_conf"]),
                "ST": dict(self.indices["ST"]),
                "ST_conf": dict(self.indices["ST_conf"]),
                "runs": self.runs,
                "base_samples": self.base_samples,
                "confidence_level": CONFIDENCE,
                "seed": self.seed,
                "first_order_sum": self.first_order_sum,
                "interactions": dict(self.interactions),
                "ranking": list(self.ranking),
                "elasticities": dict(self.elasticities),
                "elasticity_ranking": list(self.elasticity_ranking),
                "regression_r2": self.regression_r2,
                "output": "positioning_time_s",
                "positioning_time_s": {
                    "mean": float(np.mean(self.positioning_time_s)),
                    "std": float(np.std(self.positioning_time_s)),
                },
                "unsettled": self.unsettled,
                "wall_time_s": self.wall_time_s,
                "runs_per_s": self.runs / self.wall_time_s if self.wall_time_s > 0 else None,
                "executor": self.executor,
            }
        )

    def to_pandas(self) -> pandas.DataFrame:
        """One row per property, in sampling order, indexed by `property`: unit, low, high [its unit],
        S1, S1_conf, ST, ST_conf, interactions, elasticity [-] (pandas needed)."""
        return tables.to_pandas(
            [
                {
                    "property": n,
                    "unit": self.units[n],
                    "low": self.ranges[n][0],
                    "high": self.ranges[n][1],
                    **{key: self.indices[key][n] for key in ("S1", "S1_conf", "ST", "ST_conf")},
                    "interactions": self.interactions[n],
                    "elasticity": self.elasticities[n],
                }
                for n in self.names
            ],
            index="property",
        )


def run_sobol(
    scene: str | Scene,
    base_samples: int = DEFAULT_BASE_SAMPLES,
    *,
    sobol_seed: int = 0,
    omega_dt: float = moves.OMEGA_DT,
    executor: Executor | None = None,
    chunk_size: int = CHUNK_CONFIGURATIONS,
    **overrides: float,
) -> SobolStudy:
    """Sobol indices of a scene's positioning time over the inputs its design declares (`DesignSpec.sobol`).

    Parameters
    ----------
    scene
        a scene that declares a design question, or its name.
    base_samples
        N, a power of 2; the study runs N (D + 2) simulations (the printer head's default: 114,688).
    sobol_seed
        seed of the scrambled Sobol' sequence and of the bootstrap (`seed` before issue 32: the printer
        head has a parameter seed).
    omega_dt
        omega_n dt [-] of every simulation, as the design study.
    executor
        where the chunks run (None: locally); the indices are the same bit for bit.
    chunk_size
        simulations per batched call.
    **overrides
        scene parameters the ranges are centred on (SI).

    Raises
    ------
    UnknownNameError
        the scene declares no design question, an unknown parameter.
    BadInputError
        N not a power of 2, bad parameter values.
    """
    found, spec = moves.declaration(scene)
    names = list(spec.sobol)
    base_samples = check_base_samples(base_samples, len(names))
    base = moves.base_parameters(found, overrides)
    centre = spec.hooks.defaults(base)
    inputs = tuple(spec.get(n) for n in names)
    moves.spanned(centre, inputs, np.zeros(1), study="Sobol", verb="varies")  # every default > 0
    spans = {p.name: p.span for p in (*spec.properties, *inputs)}
    space = problem(names)
    rows = sample(space, base_samples, sobol_seed)
    start = _time.perf_counter()
    times = evaluate(
        positioning_chunk,
        rows,
        functools.partial(
            PositioningChunk,
            scene=found.name,
            base=tuple(base.items()),
            names=tuple(names),
            spans=tuple(spans.items()),
            omega_dt=omega_dt,
        ),
        executor=executor,
        chunk_size=chunk_size,
        description="sobol",
    )
    wall = _time.perf_counter() - start
    unsettled = int(np.sum(~np.isfinite(times)))
    # a configuration still moving after MAX_DURATION is censored there: an infinite output has no variance
    censored = np.where(np.isfinite(times), times, moves.MAX_DURATION)
    values = properties(centre, spans, names, rows)
    elasticities, r2 = _regression({n: values[n] for n in names}, censored)
    return SobolStudy(
        scene=found.name,
        merit=spec.merit,
        base=base,
        names=tuple(names),
        units={p.name: p.unit for p in inputs},
        ranges={n: (centre[n] / spans[n], centre[n] * spans[n]) for n in names},
        base_samples=base_samples,
        runs=len(rows),
        seed=sobol_seed,
        indices=analyze(space, censored, sobol_seed),
        positioning_time_s=censored,
        unsettled=unsettled,
        elasticities=elasticities,
        regression_r2=r2,
        wall_time_s=wall,
        executor=resolve(executor).describe(),
    )


def _regression(values: Mapping[str, np.ndarray], times: np.ndarray) -> tuple[dict[str, float], float]:
    """Least squares ln T = a + sum e_p ln p: ({p: e_p}, R^2), as the design study's elasticities."""
    names = list(values)
    design_matrix = np.column_stack([np.ones(len(times))] + [np.log(values[n]) for n in names])
    target = np.log(times)
    coefficients, *_ = np.linalg.lstsq(design_matrix, target, rcond=None)
    residual = target - design_matrix @ coefficients
    r2 = 1.0 - float(residual @ residual) / float(np.sum((target - target.mean()) ** 2))
    return {n: float(e) for n, e in zip(names, coefficients[1:])}, r2
