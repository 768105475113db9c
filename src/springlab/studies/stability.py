"""Where each integrator stops being trustworthy: stability boundaries, step maps and energy.

On m x'' + d x' + k x = 0 (the scene that declares itself the textbook's one-mode
mass-spring-damper, `Scene.oscillator`, as a unit oscillator; springlab.studies.extremes
.build_oscillator): the measured omega*dt at which each integrator's response starts to grow,
per damping ratio, against the theory in `exact.limits.stability_limit`
(`measure_boundaries`: `Boundary` rows); the per-step amplification factor of MuJoCo's
one-step map over a (zeta, omega*dt) grid (`amplification_map`: an `AmplificationMap`); and the
undamped energy of every integrator against its exact discrete-map formula
(`energy_histories`: `EnergyHistories`). `stability_report` adds the extremes table
(springlab.studies.extremes) and returns a `StabilityReport`, whose `to_dict()` is
`springlab stability`'s JSON.

The MuJoCo step maps on the 1-DOF oscillator (omega = sqrt(k/m), zeta =
d/(2 sqrt(k m)), y = omega*dt, measured in tests/studies/test_stability.py):

* euler, implicit, implicitfast: identical; semi-implicit (symplectic) Euler
  with implicit joint damping, v' = (v - dt k/m x)/(1 + 2 zeta y),
  x' = x + dt v'. Stable while y < 2 zeta + 2 sqrt(zeta^2 + 1). Undamped it
  conserves I = v^2 + omega^2 x^2 - dt omega^2 x v exactly, so the energy
  stays between I/(2(1 + y/2)) and I/(2(1 - y/2)) [per unit mass].
* rk4: the classical map R(dt A), R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24;
  undamped the energy is multiplied by |R(iy)|^2 = 1 - y^6/72 + y^8/576
  every step.
* discrete: backward Euler, (m + dt d + dt^2 k) a = -k x - d v - dt k v,
  v' = v + dt a, x' = x + dt v'; undamped the energy is multiplied by
  1/(1 + y^2) every step. Never unstable.
"""

from __future__ import annotations

import dataclasses
import math
import time as _time
from collections.abc import Iterable, Mapping, Sequence
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from mujoco import batch as _mjbatch

from springlab import display, tables
from springlab.answer import Answer
from springlab.errors import BadInputError, DivergedError
from springlab.exact.limits import stability_limit
from springlab.files import Output
from springlab.sim.batch import RECORD_SPEC, run_batched
from springlab.sim.simulate import BAD_WARNINGS, INTEGRATORS, integrator_id, quiet_mujoco

from . import answers
from .executor import Executor, resolve
from .extremes import (
    ACCURACY,
    EXTREME_CASES,
    FULL_EXTREME_CASES,
    VERIFY_STEPS,
    ExtremeRun,
    build_oscillator,
    extremes_table,
)

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure

#: damping ratios of the default boundary measurement (the contract needs 0, 0.1, 1, 10)
STABILITY_ZETAS = (0.0, 0.1, 0.5, 1.0, 2.0, 10.0)
#: with --full
FULL_STABILITY_ZETAS = (0.0, 0.01, 0.05, 0.1, 0.2, 0.5, 0.8, 1.0, 1.5, 2.0, 5.0, 10.0, 30.0, 100.0)
#: steps per growth test; growth test: max |z| over the second half > GROWTH_FACTOR x over the first half
GROWTH_STEPS = 1000
GROWTH_FACTOR = 2.0
#: boundary search: omega*dt from SEARCH_START, doubling up to SEARCH_STOP, then bisection to this ratio
SEARCH_START = 0.05
SEARCH_STOP = 1.0e4
SEARCH_PRECISION = 1.0e-4
#: measured boundaries must be within this relative distance of the theory
BOUNDARY_TOLERANCE = 0.02


def _read_only(array: np.ndarray) -> np.ndarray:
    """`array` as a float array that cannot be written through (results are immutable)."""
    out = np.array(array, float)
    out.flags.writeable = False
    return out


@dataclasses.dataclass(frozen=True)
class Boundary:
    """The measured stability boundary of one integrator at one damping ratio (`measure_boundaries`).

    Attributes
    ----------
    integrator
        MuJoCo's integrator name.
    zeta
        damping ratio [-].
    measured_omega_dt
        omega*dt [-] at which the response starts to grow (inf: nothing grew up to SEARCH_STOP).
    theory_omega_dt
        `exact.limits.stability_limit`'s [-] (inf: no limit).
    relative_difference
        |measured - theory| / theory [-] (0 when both are inf).
    within_tolerance
        relative_difference <= BOUNDARY_TOLERANCE.
    """

    integrator: str
    zeta: float
    measured_omega_dt: float
    theory_omega_dt: float
    relative_difference: float
    within_tolerance: bool

    def to_dict(self) -> dict[str, Any]:
        """The row of stability.json's "boundaries": every attribute, in this order."""
        return dataclasses.asdict(self)


class _GrowthTester:
    """Runs the unit oscillator (x0 = 1, v0 = 0) per (integrator, zeta) at given omega*dt, batched,
    and says whether its response grows (GROWTH_FACTOR over GROWTH_STEPS, or MuJoCo flags a blow-up)."""

    def __init__(self, pairs: Sequence[tuple[str, float]], steps: int, nthread: int = 0):
        self.model = build_oscillator(mass=1.0, stiffness=1.0, damping=0.0, x0=1.0, v0=0.0).model
        self.steps = steps
        with quiet_mujoco():
            self.batch = _mjbatch.Batch(self.model, nsim=len(pairs), nthread=nthread)
            self.batch.expand("opt.integrator")[:] = [INTEGRATORS[name] for name, _ in pairs]
            self.batch.expand("dof_damping")[:] = [[2.0 * zeta] for _, zeta in pairs]
            self.timestep = self.batch.expand("opt.timestep")

    def grows(self, ids: np.ndarray, omega_dt: np.ndarray) -> np.ndarray:
        """Per simulation id: does the response grow at omega*dt (== dt [s] here)?"""
        batch, half = self.batch, self.steps // 2
        self.timestep[ids] = omega_dt
        batch.time[ids] = 0.0
        batch.qpos[ids] = 1.0
        batch.qvel[ids] = 0.0
        batch.warning[ids] = 0
        with quiet_mujoco():
            out = batch.rollout(self.steps, record=[RECORD_SPEC], ids=ids)[RECORD_SPEC]
        radius = np.hypot(out[:, :, 1], out[:, :, 2])  # |(omega x, v)| with omega = 1
        early = np.maximum(np.max(radius[:, :half], axis=1), 1.0)
        late = np.max(radius[:, half:], axis=1)
        flagged = np.array(batch.warning)[ids][:, BAD_WARNINGS, 1].sum(axis=1) > 0
        finite = np.isfinite(radius).all(axis=1)
        with np.errstate(invalid="ignore"):
            return flagged | ~finite | ~(late <= GROWTH_FACTOR * early)


def measure_boundaries(
    integrators: Iterable[str] = tuple(INTEGRATORS),
    zetas: Iterable[float] = STABILITY_ZETAS,
    *,
    steps: int = GROWTH_STEPS,
    nthread: int = 0,
) -> list[Boundary]:
    """Measured stability boundary omega*dt [-] per (integrator, zeta) against `exact.limits.stability_limit`.

    On the oscillator scene as a unit oscillator: starting at omega*dt =
    SEARCH_START, doubling until the response grows (GROWTH_FACTOR over
    `steps` steps, or MuJoCo flags a blow-up), then bisecting (geometrically)
    between the last stable and the first growing omega*dt down to a ratio of
    1 + SEARCH_PRECISION. All pairs advance together in one batch.

    Returns
    -------
    list[Boundary]
        One per (integrator, zeta), integrators outermost; measured is inf when
        nothing grew up to SEARCH_STOP.
    """
    pairs = [(name, float(z)) for name in integrators for z in zetas]
    for name, zeta in pairs:
        integrator_id(name)
        if not (math.isfinite(zeta) and zeta >= 0):
            raise BadInputError(f"zeta must be a finite number >= 0, got {zeta!r}")
    tester = _GrowthTester(pairs, steps, nthread)
    n = len(pairs)
    low = np.zeros(n)  # largest omega*dt seen stable
    high = np.full(n, math.inf)  # smallest omega*dt seen growing
    probe = np.full(n, SEARCH_START)
    active = np.ones(n, bool)
    while active.any():
        ids = np.flatnonzero(active).astype(np.int32)
        grows = tester.grows(ids, probe[ids])
        for i, grew in zip(ids.tolist(), grows):
            if grew:
                high[i] = probe[i]
            else:
                low[i] = probe[i]
            if math.isinf(high[i]):
                probe[i] = 2 * low[i]
                active[i] = probe[i] <= SEARCH_STOP
            elif low[i] == 0:
                probe[i] = high[i] / 2
            elif high[i] / low[i] > 1 + SEARCH_PRECISION:
                probe[i] = math.sqrt(low[i] * high[i])
            else:
                active[i] = False
    rows = []
    for i, (name, zeta) in enumerate(pairs):
        measured = math.sqrt(low[i] * high[i]) if math.isfinite(high[i]) else math.inf
        theory = stability_limit(name, zeta)
        if math.isinf(measured) and math.isinf(theory):
            difference = 0.0
        elif math.isinf(measured) or math.isinf(theory):
            difference = math.inf
        else:
            difference = abs(measured - theory) / theory
        rows.append(Boundary(name, zeta, measured, theory, difference, difference <= BOUNDARY_TOLERANCE))
    return rows


@dataclasses.dataclass(frozen=True)
class BoundariesChunk:
    """A chunk of `map_boundaries`: one integrator's boundary searches (plain data, for dask workers).

    Attributes
    ----------
    integrator
        MuJoCo's integrator name.
    zetas
        damping ratios [-] searched.
    steps
        steps per growth test.
    """

    integrator: str
    zetas: tuple[float, ...]
    steps: int


def boundaries_chunk(payload: BoundariesChunk, nthread: int = 0) -> list[Boundary]:
    """measure_boundaries for one integrator (a chunk of the map; plain data in, frozen rows out, for dask workers)."""
    return measure_boundaries([payload.integrator], payload.zetas, steps=payload.steps, nthread=nthread)


def map_boundaries(
    integrators: Iterable[str] = tuple(INTEGRATORS),
    zetas: Iterable[float] = STABILITY_ZETAS,
    *,
    steps: int = GROWTH_STEPS,
    executor: Executor | None = None,
) -> list[Boundary]:
    """measure_boundaries with one chunk per integrator on `executor` (None: locally); the same rows
    in the same order (each pair's search is independent of the others)."""
    zetas = tuple(float(z) for z in zetas)
    payloads = [BoundariesChunk(name, zetas, steps) for name in integrators]
    return [row for part in resolve(executor).map(boundaries_chunk, payloads, description="stability") for row in part]


def one_step_maps(integrator: str, zetas: np.ndarray, omega_dts: np.ndarray, *, nthread: int = 0) -> np.ndarray:
    """MuJoCo's one-step map of the unit oscillator, measured: (len(zetas), len(omega_dts), 2, 2).

    Column j is the state after one step from the unit state e_j = (x, v), so
    z_{n+1} = M z_n exactly for this linear system.
    """
    model = build_oscillator(mass=1.0, stiffness=1.0, damping=0.0, x0=1.0, v0=0.0).model
    zz, hh = np.meshgrid(np.asarray(zetas, float), np.asarray(omega_dts, float), indexing="ij")
    cells = zz.size
    with quiet_mujoco():
        batch = _mjbatch.Batch(model, nsim=2 * cells, nthread=nthread)
        batch.expand("opt.integrator")[:] = INTEGRATORS[integrator]
        batch.expand("dof_damping")[:] = np.repeat(2.0 * zz.ravel(), 2)[:, None]
        batch.expand("opt.timestep")[:] = np.repeat(hh.ravel(), 2)
        batch.qpos[:] = np.tile([[1.0], [0.0]], (cells, 1))
        batch.qvel[:] = np.tile([[0.0], [1.0]], (cells, 1))
        batch.step()
        after = np.column_stack([batch.qpos[:, 0], batch.qvel[:, 0]]).reshape(cells, 2, 2)
    return after.transpose(0, 2, 1).reshape(*zz.shape, 2, 2)


@dataclasses.dataclass(frozen=True)
class AmplificationMap:
    """The per-step amplification of MuJoCo's measured one-step map over a (zeta, omega*dt) grid (`amplification_map`).

    Attributes
    ----------
    zetas
        damping ratios [-] (n,), read-only.
    omega_dts
        omega*dt [-] (m,), read-only.
    radius
        integrator -> spectral radius [-] (n, m), read-only; > 1: the response grows by that factor per step.
    """

    zetas: np.ndarray
    omega_dts: np.ndarray
    radius: Mapping[str, np.ndarray]

    def to_dict(self) -> dict[str, Any]:
        """{"zetas", "omega_dts", "radius": integrator -> rows} as plain lists (not part of stability.json)."""
        return {
            "zetas": self.zetas.tolist(),
            "omega_dts": self.omega_dts.tolist(),
            "radius": {name: radius.tolist() for name, radius in self.radius.items()},
        }


def amplification_map(
    integrators: Iterable[str] = tuple(INTEGRATORS),
    zetas: np.ndarray | None = None,
    omega_dts: np.ndarray | None = None,
    *,
    executor: Executor | None = None,
) -> AmplificationMap:
    """Spectral radius [-] of MuJoCo's measured one-step map over a (zeta, omega*dt) grid, per integrator.

    > 1 means the response grows by that factor per step (unstable). One chunk per integrator on
    `executor` (None: locally).
    """
    zetas = np.concatenate([[0.0], np.geomspace(1e-2, 100.0, 40)]) if zetas is None else np.asarray(zetas)
    omega_dts = np.geomspace(1e-2, 1e3, 120) if omega_dts is None else np.asarray(omega_dts)
    integrators = list(integrators)
    payloads = [RadiusChunk(name, zetas, omega_dts) for name in integrators]
    radii = resolve(executor).map(radius_chunk, payloads, description="stability map")
    return AmplificationMap(
        _read_only(zetas),
        _read_only(omega_dts),
        MappingProxyType({name: _read_only(radius) for name, radius in zip(integrators, radii)}),
    )


@dataclasses.dataclass(frozen=True, eq=False)  # arrays: compare fields, not results
class RadiusChunk:
    """A chunk of `amplification_map`: one integrator's one-step maps over a grid (plain data, for dask workers).

    Attributes
    ----------
    integrator
        MuJoCo's integrator name.
    zetas
        damping ratios [-] (n,).
    omega_dts
        omega*dt [-] (m,).
    """

    integrator: str
    zetas: np.ndarray
    omega_dts: np.ndarray


def radius_chunk(payload: RadiusChunk, nthread: int = 0) -> np.ndarray:
    """Spectral radius [-] of one integrator's one-step maps over payload's (zetas, omega_dts) grid."""
    maps = one_step_maps(payload.integrator, payload.zetas, payload.omega_dts, nthread=nthread)
    return np.max(np.abs(np.linalg.eigvals(maps)), axis=-1)


# -- the energy ----------------------------------------------------------------

#: the integrators that share MuJoCo's semi-implicit Euler map on these scenes
EULER_FAMILY = ("euler", "implicit", "implicitfast")
#: omega*dt and length of the energy runs
ENERGY_OMEGA_DT = 0.2
ENERGY_PERIODS = 200


def energy_formula(
    integrator: str, omega_dt: float, steps: np.ndarray, x0: float = 1.0, v0: float = 0.0, omega: float = 1.0
) -> dict[str, np.ndarray | float]:
    """The exact energy of each integrator's undamped step map, E_n / E_0 [-].

    euler, implicit, implicitfast (symplectic Euler): I = v^2 + omega^2 x^2 -
    dt omega^2 x v is invariant, so E_n/E_0 lies in [I/(2(1 + y/2)),
    I/(2(1 - y/2))] / E_0 (y = omega*dt, E per unit mass) and reaches both
    ends; returns "low", "high" (for x0 != 0, v0 = 0: 1/(1 + y/2), 1/(1 - y/2)).
    rk4: "ratio" = (1 - y^6/72 + y^8/576)^n. discrete: "ratio" = (1 + y^2)^-n.
    """
    y = omega_dt
    steps = np.asarray(steps, float)
    if integrator in EULER_FAMILY:
        energy0 = 0.5 * (v0**2 + omega**2 * x0**2)
        invariant = v0**2 + omega**2 * x0**2 - y * omega * x0 * v0
        return {"low": invariant / (2 * (1 + y / 2)) / energy0, "high": invariant / (2 * (1 - y / 2)) / energy0}
    if integrator == "rk4":
        return {"ratio": (1 - y**6 / 72 + y**8 / 576) ** steps}
    if integrator == "discrete":
        return {"ratio": (1 + y * y) ** -steps}
    raise BadInputError(f"unknown integrator {integrator!r}; valid: {', '.join(INTEGRATORS)}")


@dataclasses.dataclass(frozen=True)
class EnergyCheck:
    """One integrator's undamped energy against its exact step-map formula (`energy_histories`).

    Attributes
    ----------
    integrator
        MuJoCo's integrator name.
    omega_dt
        y = omega*dt of the run [-].
    steps
        number of steps.
    final_ratio, min_ratio, max_ratio
        E/E0 at the end, its minimum and maximum over the run [-].
    formula
        the exact formula, as text.
    formula_final_ratio
        its E_n/E0 at the end [-] (integrators whose energy changes by a fixed factor per step; else None).
    formula_low, formula_high
        the bounds of E/E0 [-] (the euler family, which keeps an invariant; else None).
    max_relative_deviation
        largest relative deviation from the formula over the run [-] (the euler family: of its invariant).
    """

    integrator: str
    omega_dt: float
    steps: int
    final_ratio: float
    min_ratio: float
    max_ratio: float
    formula: str
    formula_final_ratio: float | None
    formula_low: float | None
    formula_high: float | None
    max_relative_deviation: float

    def to_dict(self) -> dict[str, Any]:
        """The row of stability.json's "energy": the attributes in this order, without the formula's
        values that do not apply (None)."""
        optional = ("formula_final_ratio", "formula_low", "formula_high")
        return {k: v for k, v in dataclasses.asdict(self).items() if not (k in optional and v is None)}


@dataclasses.dataclass(frozen=True)
class EnergyHistories:
    """Energy of every integrator on the undamped oscillator, with each one's exact formula (`energy_histories`).

    Attributes
    ----------
    scene
        the oscillator scene's name (the scene that declares `Scene.oscillator`).
    omega_dt
        y = omega*dt of every run [-].
    periods
        simulated time in natural periods [-].
    time_periods
        time of each step in natural periods [-] (n,), read-only.
    ratio
        integrator -> E_n/E0 [-] (n,), read-only.
    exact
        integrator -> the formula's E_n/E0 [-] (n,), read-only, for the integrators whose energy changes
        by a fixed factor per step (rk4, discrete).
    bounds
        integrator -> (low, high) bounds of E/E0 [-] for those that keep an invariant (the euler family).
    checks
        one `EnergyCheck` per integrator, in MuJoCo's order.
    """

    scene: str
    omega_dt: float
    periods: float
    time_periods: np.ndarray
    ratio: Mapping[str, np.ndarray]
    exact: Mapping[str, np.ndarray]
    bounds: Mapping[str, tuple[float, float]]
    checks: tuple[EnergyCheck, ...]

    def to_dict(self) -> dict[str, Any]:
        """{"scene", "omega_dt", "periods", "time_periods", "ratio", "exact", "bounds", "checks"} as plain
        lists (not part of stability.json, which holds the checks)."""
        return {
            "scene": self.scene,
            "omega_dt": self.omega_dt,
            "periods": self.periods,
            "time_periods": self.time_periods.tolist(),
            "ratio": {name: series.tolist() for name, series in self.ratio.items()},
            "exact": {name: series.tolist() for name, series in self.exact.items()},
            "bounds": {name: list(pair) for name, pair in self.bounds.items()},
            "checks": [check.to_dict() for check in self.checks],
        }


def energy_histories(
    omega_dt: float = ENERGY_OMEGA_DT, periods: float = ENERGY_PERIODS, *, nthread: int = 0
) -> EnergyHistories:
    """Energy of every integrator on the undamped oscillator against its formula.

    The oscillator scene's free scenario with its damping set to 0 and its other values at their
    defaults. The energy E = m v^2/2 + k x^2/2 [J] is computed from qpos and qvel (MuJoCo's
    data.energy lags a step), with m and k read back from the compiled model.
    """
    oscillator = build_oscillator(damping=0.0)
    case, params, spec = oscillator.case, oscillator.params, oscillator.spec
    m, k, _ = spec.constants(case.model)
    omega = math.sqrt(k / m)
    dt = omega_dt / omega
    steps = round(periods * 2 * math.pi / omega_dt)
    setup = case.setup(steps, dt)
    jobs = [case.job(name, dt, steps, setup=setup) for name in INTEGRATORS]
    outcomes = run_batched(jobs, nthread=nthread)
    x0, v0 = params[spec.x0], params[spec.v0]
    energy0 = 0.5 * m * v0**2 + 0.5 * k * x0**2
    n = np.arange(steps + 1)
    ratio, exact, bounds, checks = {}, {}, {}, []
    for name, trajectory in zip(INTEGRATORS, outcomes):
        if isinstance(trajectory, DivergedError):
            raise trajectory
        x, v = trajectory.qpos[:, 0], trajectory.qvel[:, 0]
        energy = 0.5 * m * v**2 + 0.5 * k * x**2
        ratio[name] = _read_only(energy / energy0)
        formula = energy_formula(name, omega_dt, n, x0, v0, omega)
        row: dict[str, Any] = {"formula_final_ratio": None, "formula_low": None, "formula_high": None}
        if "ratio" in formula:
            row["formula"] = "(1 - y^6/72 + y^8/576)^n" if name == "rk4" else "(1 + y^2)^-n"
            exact[name] = _read_only(np.asarray(formula["ratio"]))
            row["formula_final_ratio"] = float(exact[name][-1])
            row["max_relative_deviation"] = float(np.max(np.abs(ratio[name] / exact[name] - 1)))
        else:
            invariant = (v**2 + omega**2 * x**2 - dt * omega**2 * x * v) / (
                v0**2 + omega**2 * x0**2 - dt * omega**2 * x0 * v0
            )
            row["formula"] = "E/E0 in [1/(1 + y/2), 1/(1 - y/2)] (invariant v^2 + w^2 x^2 - dt w^2 x v)"
            row["formula_low"], row["formula_high"] = float(formula["low"]), float(formula["high"])
            bounds[name] = (row["formula_low"], row["formula_high"])
            row["max_relative_deviation"] = float(np.max(np.abs(invariant - 1)))
        checks.append(
            EnergyCheck(
                integrator=name,
                omega_dt=omega_dt,
                steps=steps,
                final_ratio=float(ratio[name][-1]),
                min_ratio=float(ratio[name].min()),
                max_ratio=float(ratio[name].max()),
                **row,
            )
        )
    return EnergyHistories(
        scene=case.scene.name,
        omega_dt=omega_dt,
        periods=periods,
        time_periods=_read_only(n * omega_dt / (2 * math.pi)),
        ratio=MappingProxyType(ratio),
        exact=MappingProxyType(exact),
        bounds=MappingProxyType(bounds),
        checks=tuple(checks),
    )


# -- the report ----------------------------------------------------------------

#: the tables of a StabilityReport that `to_pandas` gives
StabilityTable = Literal["boundaries", "extremes", "energy"]


@dataclasses.dataclass(frozen=True, repr=False)
class StabilityReport(display.Shown):
    """`springlab stability`: boundaries, extremes and energy (`stability_report`); `to_dict()` is its JSON.

    Attributes
    ----------
    boundaries
        the measured boundary per integrator and damping ratio (`boundary(integrator, zeta)` finds one).
    extremes
        the extremes table, one `ExtremeRun` per run (springlab.studies.extremes).
    energy_histories
        the undamped energy runs and their formulas (`energy` holds their checks).
    growth_test
        what counts as growing, for people.
    accuracy_threshold
        the extremes table's accurate / inaccurate line [-] (max relative error).
    wall_time_s
        wall time of the report [s].
    """

    boundaries: tuple[Boundary, ...]
    extremes: tuple[ExtremeRun, ...]
    energy_histories: EnergyHistories
    growth_test: str
    accuracy_threshold: float
    wall_time_s: float

    @property
    def energy(self) -> tuple[EnergyCheck, ...]:
        """Each integrator's energy against its exact formula (stability.json's "energy")."""
        return self.energy_histories.checks

    @property
    def passed(self) -> bool:
        """Every measured boundary within BOUNDARY_TOLERANCE of its theory (exit 0 of the command; else 1)."""
        return all(b.within_tolerance for b in self.boundaries)

    def boundary(self, integrator: str, zeta: float) -> Boundary:
        """The measured boundary of `integrator` at damping ratio `zeta` [-].

        Raises
        ------
        KeyError
            no boundary was measured there.
        """
        for row in self.boundaries:
            if row.integrator == integrator and row.zeta == zeta:
                return row
        raise KeyError(f"no boundary measured for {integrator!r} at zeta = {zeta:g}")

    @property
    def question_answer(self) -> Answer:
        """The question and its answer: the undamped boundaries and the agreement with theory."""
        say = answers.Quoter()
        question = (
            "At which omega*dt does each of MuJoCo's integrators go unstable on the damped oscillator, and does"
            " the measured boundary agree with the theory?"
        )
        undamped = [b for b in self.boundaries if b.zeta == 0.0 and math.isfinite(b.measured_omega_dt)]
        measured = ", ".join(
            f"{b.integrator} {say(f'{b.integrator}_omega_dt', b.measured_omega_dt, spec='.4g')}" for b in undamped
        )
        never = [b.integrator for b in self.boundaries if b.zeta == 0.0 and not math.isfinite(b.measured_omega_dt)]
        measured += f"; {', '.join(never)} never goes unstable" if never and measured else ""
        within = sum(b.within_tolerance for b in self.boundaries)
        worst = max((b.relative_difference for b in self.boundaries), default=math.nan)
        head = (
            f"Undamped (zeta = 0), the measured limits of omega*dt are {measured}" if measured else "No limit measured"
        )
        agree = "agree" if self.passed else "do not all agree"
        return say.answer(
            question,
            f"{head}. {say('within_tolerance', within, spec='d')} of {say('boundaries', len(self.boundaries), spec='d')}"
            f" measured boundaries {agree} with the theory, the largest relative difference"
            f" {say('largest_relative_difference', worst, spec='.2g')}.",
        )

    @property
    def question(self) -> str:
        """What the report asks, in words (`question_answer`)."""
        return self.question_answer.question

    @property
    def answer(self) -> str:
        """The answer in words (`question_answer`)."""
        return self.question_answer.answer

    def _shown(self) -> display.Summary:
        """The report as a notebook shows it: every boundary within tolerance or not, then the boundaries."""
        worst = max((b.relative_difference for b in self.boundaries), default=None)
        return display.Summary(
            "StabilityReport",
            f"{len(self.boundaries)} boundaries",
            "PASS" if self.passed else "FAIL",
            self.passed,
            f"{sum(b.within_tolerance for b in self.boundaries)} of {len(self.boundaries)} measured boundaries"
            " within tolerance of the theory",
            (
                display.Fact("largest relative difference", worst),
                display.Fact("growth test", self.growth_test),
                display.Fact("wall time", self.wall_time_s, "s"),
            ),
            display.table(
                ("integrator", "zeta [-]", "measured omega dt [-]", "theory omega dt [-]", "rel. difference [-]"),
                [
                    (b.integrator, b.zeta, b.measured_omega_dt, b.theory_omega_dt, b.relative_difference)
                    for b in self.boundaries
                ],
            ),
        )

    def plot(self, amplification: AmplificationMap | None = None) -> Figure:
        """The energy of every integrator against its exact formula (`springlab.plots.charts.energy_figure`), or
        with `amplification` (`amplification_map()`) the stability map with the measured boundaries.

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self, amplification=amplification)

    def to_dict(self) -> dict[str, Any]:
        """stability.json and `springlab stability --json`: {"boundaries", "extremes", "energy", "growth_test",
        "accuracy_threshold", "wall_time_s"} (the energy series and the map are drawn, not stored)."""
        return {
            **self.question_answer.to_dict(),
            "boundaries": [row.to_dict() for row in self.boundaries],
            "extremes": [row.to_dict() for row in self.extremes],
            "energy": [row.to_dict() for row in self.energy],
            "growth_test": self.growth_test,
            "accuracy_threshold": self.accuracy_threshold,
            "wall_time_s": self.wall_time_s,
        }

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab stability --output DIR` writes (springlab.outputs.write): stability.json,
        stability.png (the amplification map, given to the writer) and energy.png."""
        return Output.json("stability.json", self.to_dict()), Output("stability.png"), Output("energy.png")

    def to_pandas(self, table: StabilityTable = "boundaries") -> pandas.DataFrame:
        """One of the report's tables as a DataFrame, a row per entry of `to_dict()[table]` (pandas is optional).

        Parameters
        ----------
        table
            "boundaries" (default: integrator, zeta, measured and theory omega*dt [-], ...), "extremes"
            or "energy".
        """
        if table not in ("boundaries", "extremes", "energy"):
            raise BadInputError(f"unknown table {table!r}; valid: boundaries, extremes, energy")
        return tables.to_pandas(self.to_dict()[table])


def stability_report(*, full: bool = False, nthread: int = 0, executor: Executor | None = None) -> StabilityReport:
    """Boundaries, extremes and energy: `springlab stability` (its JSON is the report's `to_dict()`).

    full: more damping ratios, more extreme cases, and the advice of every
    extremes case run in full, however many steps it takes (slower: tens of seconds).
    executor: where the boundary searches run, one chunk per integrator (None: locally on `nthread`).
    """
    started = _time.perf_counter()
    executor = Executor(nthread=nthread, progress=False) if executor is None else executor
    boundaries = map_boundaries(zetas=FULL_STABILITY_ZETAS if full else STABILITY_ZETAS, executor=executor)
    extremes = extremes_table(
        FULL_EXTREME_CASES if full else EXTREME_CASES, verify_steps=10**9 if full else VERIFY_STEPS, nthread=nthread
    )
    energy = energy_histories(nthread=nthread)
    return StabilityReport(
        boundaries=tuple(boundaries),
        extremes=tuple(extremes),
        energy_histories=energy,
        growth_test=(
            f"response |(omega x, v)| over steps {GROWTH_STEPS // 2}..{GROWTH_STEPS} exceeds"
            f" {GROWTH_FACTOR:g}x its maximum over the first {GROWTH_STEPS // 2}, or MuJoCo flags"
            " a blow-up"
        ),
        accuracy_threshold=ACCURACY,
        wall_time_s=_time.perf_counter() - started,
    )
