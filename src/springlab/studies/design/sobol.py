"""Which printer-head properties matter, by variance: Sobol first-order and total indices (SALib).

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

The inputs: carriage mass, belt stiffness, belt damping ratio, drive force and
move length, each log-uniform over default x span^[-1, 1] (the design study's
spans; the move from a quarter to four times the default inch). The sampled
variables are the exponents u in [-1, 1], so each property is log-uniform;
Sobol indices are properties of that input distribution, stated with them.
The output is the positioning time T [s] of the bang-bang move plus settling
(springlab.studies.design.study.simulate_moves, run in chunks on the executor, so a cluster
gives the same indices bit for bit).
"""

from __future__ import annotations

import dataclasses
import math
import time as _time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from springlab.errors import BadInputError
from springlab.studies.design import study as design
from springlab.studies.executor import Executor, chunked, resolve

#: the varied properties, in order, with units
PARAMETERS: Mapping[str, str] = {
    "carriage_mass": "kg",
    "belt_stiffness": "N/m",
    "damping_ratio": "-",
    "drive_force": "N",
    "move_distance": "m",
}
#: each spans default x span^[-1, 1] (the design study's spans; a quarter inch to four inches of move)
SPANS: Mapping[str, float] = {**design.SPANS, "move_distance": 4.0}
#: base samples N of the default study: N (D + 2) = 16384 x 7 = 114,688 simulations
DEFAULT_BASE_SAMPLES = 16384
#: confidence level of the bootstrap intervals, and the resamples drawn
CONFIDENCE = 0.95
RESAMPLES = 100
#: configurations per chunk (one batched MuJoCo call each)
CHUNK_CONFIGURATIONS = design.CHUNK_CONFIGURATIONS


def check_base_samples(n: Any) -> int:
    """N as an int, or BadInputError: the Saltelli scheme needs a power of 2 (Sobol' sequence balance)."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 4 or (int(n) & (int(n) - 1)):
        raise BadInputError(
            f"--sobol N takes a power of 2 >= 4 (base samples of the Sobol' sequence; the study runs N x 7"
            f" simulations), e.g. 1024 or {DEFAULT_BASE_SAMPLES}; got {n!r}"
        )
    return int(n)


def problem(names: list[str]) -> dict[str, Any]:
    """The SALib problem over the exponents u in [-1, 1] of `names`."""
    return {"num_vars": len(names), "names": list(names), "bounds": [[-1.0, 1.0]] * len(names)}


def sample(spec: Mapping[str, Any], base_samples: int, seed: int = 0) -> np.ndarray:
    """(N (D + 2), D) Saltelli sample of `spec` (SALib, scrambled Sobol' sequence seeded with `seed`)."""
    from SALib.sample import sobol as saltelli

    return saltelli.sample(dict(spec), check_base_samples(base_samples), calc_second_order=False, seed=seed)


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
    payload: Mapping[str, Any] | None = None,
    *,
    executor: Executor | None = None,
    chunk_size: int = CHUNK_CONFIGURATIONS,
    description: str = "sobol",
) -> np.ndarray:
    """function({**payload, "rows": chunk}, nthread) over `rows` cut into chunks on the executor; (n,) outputs in order."""
    runner = resolve(executor)
    pieces = chunked(len(rows), chunk_size)
    payloads = [{**(payload or {}), "rows": np.asarray(rows[p.start : p.stop])} for p in pieces]
    parts = runner.map(function, payloads, description=description, sizes=[len(p) for p in pieces], unit="run")
    return np.concatenate(parts) if parts else np.empty(0)


# -- a function with known indices: the check that the pipeline is right ------------------------


def ishigami_chunk(payload: Mapping[str, Any], nthread: int = 0) -> np.ndarray:
    """Ishigami function sin x1 + a sin^2 x2 + b x3^4 sin x1 of payload["rows"] (n, 3), x in [-pi, pi]^3."""
    x = np.asarray(payload["rows"], float)
    a, b = payload["a"], payload["b"]
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami(
    base_samples: int, *, a: float = 7.0, b: float = 0.1, seed: int = 0, executor: Executor | None = None
) -> dict[str, dict[str, float]]:
    """Sobol indices of the Ishigami function through the same sampling, executor and analysis."""
    spec = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": [[-math.pi, math.pi]] * 3}
    rows = sample(spec, base_samples, seed)
    output = evaluate(ishigami_chunk, rows, {"a": a, "b": b}, executor=executor, chunk_size=4096)
    return analyze(spec, output, seed)


# -- the printer head ---------------------------------------------------------------------------


def printer_head_chunk(payload: Mapping[str, Any], nthread: int = 0) -> np.ndarray:
    """Positioning time [s] of each row of exponents u (n, D) in payload["rows"] (one batched call)."""
    values = properties(payload["base"], payload["names"], payload["rows"])
    runs = design.simulate_moves(payload["base"], values, omega_dt=payload["omega_dt"], nthread=nthread)
    return runs["positioning_time_s"]


def defaults(base: Mapping[str, float]) -> dict[str, float]:
    """The properties' default values at `base` (damping ratio from the belt damping)."""
    return {**design.default_properties(base), "move_distance": base["move_distance"]}


def properties(base: Mapping[str, float], names: list[str], exponents: np.ndarray) -> dict[str, np.ndarray]:
    """Property -> (n,) values default x span^u for exponent rows u (n, D); unsampled ones at default."""
    centre = defaults(base)
    exponents = np.asarray(exponents, float)
    values = {name: np.full(len(exponents), centre[name]) for name in design.PROPERTIES}
    for j, name in enumerate(names):
        values[name] = centre[name] * SPANS[name] ** exponents[:, j]
    return values


@dataclasses.dataclass
class SobolStudy:
    """Sobol indices of the printer head's positioning time.

    Attributes
    ----------
    base
        the scene parameters the ranges are centred on (SI).
    names
        the varied properties.
    ranges
        name -> (low, high) [its unit], log-uniform.
    base_samples
        N.
    runs
        N (D + 2) simulations.
    seed
        seed of the sample and of the bootstrap.
    indices
        SALib's S1, S1_conf, ST, ST_conf (name -> value [-]).
    positioning_time_s
        (runs,) output [s].
    unsettled
        how many never settled within design.MAX_DURATION (counted there).
    elasticities
        d ln T / d ln p [-] by least squares over the same runs.
    regression_r2
        R^2 [-] of that fit.
    wall_time_s
        wall time of the simulations [s].
    executor
        where they ran.
    """

    base: dict[str, float]
    names: list[str]
    ranges: dict[str, tuple[float, float]]
    base_samples: int
    runs: int
    seed: int
    indices: dict[str, dict[str, float]]
    positioning_time_s: np.ndarray
    unsettled: int
    elasticities: dict[str, float]
    regression_r2: float
    wall_time_s: float
    executor: str

    def interactions(self) -> dict[str, float]:
        """ST - S1 [-]: the share of variance a property has only through interactions."""
        return {n: self.indices["ST"][n] - self.indices["S1"][n] for n in self.names}

    def ranking(self) -> list[str]:
        """Properties by decreasing total index."""
        return sorted(self.names, key=lambda n: -self.indices["ST"][n])

    def summary(self) -> dict[str, Any]:
        """The `sobol` entry of design.json: parameters, S1, S1_conf, ST, ST_conf, runs (docs/json.md), and more."""
        s1 = self.indices["S1"]
        return {
            "parameters": {
                n: {"unit": PARAMETERS[n], "range": list(self.ranges[n]), "log_uniform": True} for n in self.names
            },
            "S1": s1,
            "S1_conf": self.indices["S1_conf"],
            "ST": self.indices["ST"],
            "ST_conf": self.indices["ST_conf"],
            "runs": self.runs,
            "base_samples": self.base_samples,
            "confidence_level": CONFIDENCE,
            "seed": self.seed,
            "first_order_sum": float(sum(s1.values())),
            "interactions": self.interactions(),
            "ranking": self.ranking(),
            "elasticities": self.elasticities,
            "elasticity_ranking": sorted(self.names, key=lambda n: -abs(self.elasticities[n])),
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


def printer_head(
    base_samples: int = DEFAULT_BASE_SAMPLES,
    *,
    seed: int = 0,
    omega_dt: float = design.OMEGA_DT,
    executor: Executor | None = None,
    chunk_size: int = CHUNK_CONFIGURATIONS,
    **overrides: Any,
) -> SobolStudy:
    """Sobol indices of positioning time over carriage mass, belt stiffness, damping ratio, force and move length.

    Parameters
    ----------
    base_samples
        N, a power of 2; the study runs N x 7 simulations (default 114,688).
    seed
        seed of the scrambled Sobol' sequence and of the bootstrap.
    omega_dt
        omega_n dt [-] of every simulation (RK4), as the design study.
    executor
        where the chunks run (None: locally); the indices are the same bit for bit.
    chunk_size
        simulations per batched call.
    **overrides
        printer_head parameters the ranges are centred on (SI).

    Raises
    ------
    BadInputError
        N not a power of 2, bad parameter values.
    """
    base_samples = check_base_samples(base_samples)
    base = design.base_parameters(overrides)
    names = list(PARAMETERS)
    centre = defaults(base)
    if centre["damping_ratio"] <= 0:
        raise BadInputError("the Sobol study needs belt_damping > 0 (it varies the damping ratio around it)")
    spec = problem(names)
    rows = sample(spec, base_samples, seed)
    start = _time.perf_counter()
    times = evaluate(
        printer_head_chunk,
        rows,
        {"base": dict(base), "names": names, "omega_dt": omega_dt},
        executor=executor,
        chunk_size=chunk_size,
        description="sobol",
    )
    wall = _time.perf_counter() - start
    unsettled = int(np.sum(~np.isfinite(times)))
    # a configuration still moving after MAX_DURATION is censored there: an infinite output has no variance
    censored = np.where(np.isfinite(times), times, design.MAX_DURATION)
    values = properties(base, names, rows)
    elasticities, r2 = _regression({n: values[n] for n in names}, censored)
    return SobolStudy(
        base=base,
        names=names,
        ranges={n: (centre[n] / SPANS[n], centre[n] * SPANS[n]) for n in names},
        base_samples=base_samples,
        runs=len(rows),
        seed=seed,
        indices=analyze(spec, censored, seed),
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


def answer(study: SobolStudy) -> str:
    """Which properties matter, in words, with the study's numbers."""
    s1, st, conf = study.indices["S1"], study.indices["ST"], study.indices["ST_conf"]
    alone = ", ".join(f"{n} {s1[n]:.2f}" for n in study.ranking())
    total = ", ".join(f"{n} {st[n]:.2f}+-{conf[n]:.2f}" for n in study.ranking())
    inter = study.interactions()
    through = [n for n in study.ranking() if inter[n] > max(0.05, study.indices["ST_conf"][n])]
    elastic = sorted(study.names, key=lambda n: -abs(study.elasticities[n]))
    return (
        f"Sobol ({study.runs} runs, {CONFIDENCE:.0%} intervals): alone (S1) {alone}; in total (ST) {total}; "
        f"first-order sum {sum(s1.values()):.2f}. "
        + (f"Through interactions (ST - S1 > 0.05): {', '.join(through)}. " if through else "Interactions are small. ")
        + f"Elasticity ranking from the same runs (R^2 = {study.regression_r2:.2f}): {', '.join(elastic)}"
        + ("; the same order." if elastic == study.ranking() else f"; by variance: {', '.join(study.ranking())}.")
    )
