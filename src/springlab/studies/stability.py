"""Where each integrator stops being trustworthy: stability boundaries, step maps and energy.

On m x'' + d x' + k x = 0 (the slider scene's model as a unit oscillator):
the measured omega*dt at which each integrator's response starts to grow, per
damping ratio, against the theory in `simulate.stability_limit`
(`measure_boundaries`); the per-step amplification factor of MuJoCo's
one-step map over a (zeta, omega*dt) grid (`amplification_map`); and the
undamped energy of every integrator against its exact discrete-map formula
(`energy_histories`). `stability_report` adds the extremes table
(springlab.studies.extremes) and is `springlab stability`'s JSON.

The MuJoCo step maps on the 1-DOF slider (omega = sqrt(k/m), zeta =
d/(2 sqrt(k m)), y = omega*dt, measured in tests/test_stability.py):

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

import math
import time as _time
from collections.abc import Iterable, Sequence
from typing import Any

import mujoco
import numpy as np
from mujoco import batch as _mjbatch

from springlab import scenes
from springlab.errors import BadInputError, DivergedError
from springlab.exact.limits import stability_limit
from springlab.scenes.base import Scenario, Scene
from springlab.scenes.slider import Slider
from springlab.sim.batch import RECORD_SPEC, Job, run_batched
from springlab.sim.simulate import BAD_WARNINGS, INTEGRATORS, integrator_id, quiet_mujoco

from .executor import Executor, resolve
from .extremes import ACCURACY, EXTREME_CASES, FULL_EXTREME_CASES, VERIFY_STEPS, extremes_table

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


def _oscillator(damping: float = 0.0) -> tuple[mujoco.MjModel, Scene, Scenario, dict[str, float]]:
    """The slider scene's model as a unit oscillator: m = 1 kg, k = 1 N/m (omega = 1 rad/s, omega*dt = dt)."""
    scene = scenes.get("slider")
    chosen = scene.scenario("free")
    params = scene.resolve(chosen, {"mass": 1.0, "stiffness": 1.0, "damping": damping, "x0": 1.0, "v0": 0.0})
    return scene.build(params, chosen), scene, chosen, params


class _GrowthTester:
    """Runs the unit oscillator (x0 = 1, v0 = 0) per (integrator, zeta) at given omega*dt, batched,
    and says whether its response grows (GROWTH_FACTOR over GROWTH_STEPS, or MuJoCo flags a blow-up)."""

    def __init__(self, pairs: Sequence[tuple[str, float]], steps: int, nthread: int = 0):
        self.model, *_ = _oscillator()
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
) -> list[dict[str, Any]]:
    """Measured stability boundary omega*dt [-] per (integrator, zeta) against `simulate.stability_limit`.

    On the slider scene's model as a unit oscillator: starting at omega*dt =
    SEARCH_START, doubling until the response grows (GROWTH_FACTOR over
    `steps` steps, or MuJoCo flags a blow-up), then bisecting (geometrically)
    between the last stable and the first growing omega*dt down to a ratio of
    1 + SEARCH_PRECISION. All pairs advance together in one batch.

    Returns
    -------
    list[dict[str, Any]]
        Rows {"integrator", "zeta", "measured_omega_dt", "theory_omega_dt",
        "relative_difference", "within_tolerance"}; measured is inf when nothing
        grew up to SEARCH_STOP.
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
        rows.append(
            {
                "integrator": name,
                "zeta": zeta,
                "measured_omega_dt": measured,
                "theory_omega_dt": theory,
                "relative_difference": difference,
                "within_tolerance": difference <= BOUNDARY_TOLERANCE,
            }
        )
    return rows


def boundaries_chunk(payload: dict[str, Any], nthread: int = 0) -> list[dict[str, Any]]:
    """measure_boundaries for one integrator (a chunk of the map; plain data in and out, for dask workers)."""
    return measure_boundaries([payload["integrator"]], payload["zetas"], steps=payload["steps"], nthread=nthread)


def map_boundaries(
    integrators: Iterable[str] = tuple(INTEGRATORS),
    zetas: Iterable[float] = STABILITY_ZETAS,
    *,
    steps: int = GROWTH_STEPS,
    executor: Executor | None = None,
) -> list[dict[str, Any]]:
    """measure_boundaries with one chunk per integrator on `executor` (None: locally); the same rows
    in the same order (each pair's search is independent of the others)."""
    zetas = [float(z) for z in zetas]
    payloads = [{"integrator": name, "zetas": zetas, "steps": steps} for name in integrators]
    return [row for part in resolve(executor).map(boundaries_chunk, payloads, description="stability") for row in part]


def one_step_maps(integrator: str, zetas: np.ndarray, omega_dts: np.ndarray, *, nthread: int = 0) -> np.ndarray:
    """MuJoCo's one-step map of the unit oscillator, measured: (len(zetas), len(omega_dts), 2, 2).

    Column j is the state after one step from the unit state e_j = (x, v), so
    z_{n+1} = M z_n exactly for this linear system.
    """
    model, *_ = _oscillator()
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


def amplification_map(
    integrators: Iterable[str] = tuple(INTEGRATORS),
    zetas: np.ndarray | None = None,
    omega_dts: np.ndarray | None = None,
    *,
    executor: Executor | None = None,
) -> dict[str, Any]:
    """Spectral radius [-] of MuJoCo's measured one-step map over a (zeta, omega*dt) grid, per integrator.

    > 1 means the response grows by that factor per step (unstable). One chunk per integrator on
    `executor` (None: locally). Returns {"zetas", "omega_dts", "radius": integrator -> (len(zetas),
    len(omega_dts))}.
    """
    zetas = np.concatenate([[0.0], np.geomspace(1e-2, 100.0, 40)]) if zetas is None else np.asarray(zetas)
    omega_dts = np.geomspace(1e-2, 1e3, 120) if omega_dts is None else np.asarray(omega_dts)
    integrators = list(integrators)
    payloads = [{"integrator": name, "zetas": zetas, "omega_dts": omega_dts} for name in integrators]
    radii = resolve(executor).map(radius_chunk, payloads, description="stability map")
    return {"zetas": zetas, "omega_dts": omega_dts, "radius": dict(zip(integrators, radii))}


def radius_chunk(payload: dict[str, Any], nthread: int = 0) -> np.ndarray:
    """Spectral radius [-] of one integrator's one-step maps over payload's (zetas, omega_dts) grid."""
    maps = one_step_maps(payload["integrator"], payload["zetas"], payload["omega_dts"], nthread=nthread)
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


def energy_histories(
    omega_dt: float = ENERGY_OMEGA_DT, periods: float = ENERGY_PERIODS, *, nthread: int = 0
) -> dict[str, Any]:
    """Energy of every integrator on the undamped slider (scenario `undamped`) against its formula.

    The energy E = m v^2/2 + k x^2/2 [J] is computed from qpos and qvel
    (MuJoCo's data.energy lags a step). Returns {"omega_dt", "periods",
    "time_periods": (n,), "ratio": integrator -> E_n/E_0 (n,), "rows": per
    integrator a summary with the formula and its largest deviation}.
    """
    scene = scenes.get("slider")
    assert isinstance(scene, Slider)
    chosen = scene.scenario("undamped")
    params = scene.resolve(chosen, {})
    model = scene.build(params, chosen)
    m, k, _ = scene.physical(model)
    omega = math.sqrt(k / m)
    dt = omega_dt / omega
    steps = round(periods * 2 * math.pi / omega_dt)
    setup = scene.setup(model, params, chosen, steps, dt)
    jobs = [Job(model, name, dt, steps, setup) for name in INTEGRATORS]
    outcomes = run_batched(jobs, nthread=nthread)
    x0, v0 = params["x0"], params["v0"]
    energy0 = 0.5 * m * v0**2 + 0.5 * k * x0**2
    n = np.arange(steps + 1)
    ratio, rows = {}, []
    for name, trajectory in zip(INTEGRATORS, outcomes):
        if isinstance(trajectory, DivergedError):
            raise trajectory
        x, v = trajectory.qpos[:, 0], trajectory.qvel[:, 0]
        energy = 0.5 * m * v**2 + 0.5 * k * x**2
        ratio[name] = energy / energy0
        formula = energy_formula(name, omega_dt, n, x0, v0, omega)
        row = {
            "integrator": name,
            "omega_dt": omega_dt,
            "steps": steps,
            "final_ratio": float(ratio[name][-1]),
            "min_ratio": float(ratio[name].min()),
            "max_ratio": float(ratio[name].max()),
        }
        if "ratio" in formula:
            row["formula"] = "(1 - y^6/72 + y^8/576)^n" if name == "rk4" else "(1 + y^2)^-n"
            exact = np.asarray(formula["ratio"])
            row["formula_final_ratio"] = float(exact[-1])
            row["max_relative_deviation"] = float(np.max(np.abs(ratio[name] / exact - 1)))
        else:
            invariant = (v**2 + omega**2 * x**2 - dt * omega**2 * x * v) / (
                v0**2 + omega**2 * x0**2 - dt * omega**2 * x0 * v0
            )
            row["formula"] = "E/E0 in [1/(1 + y/2), 1/(1 - y/2)] (invariant v^2 + w^2 x^2 - dt w^2 x v)"
            row["formula_low"], row["formula_high"] = float(formula["low"]), float(formula["high"])
            row["max_relative_deviation"] = float(np.max(np.abs(invariant - 1)))
        rows.append(row)
    return {
        "omega_dt": omega_dt,
        "periods": periods,
        "time_periods": n * omega_dt / (2 * math.pi),
        "ratio": ratio,
        "rows": rows,
    }


def stability_report(*, full: bool = False, nthread: int = 0, executor: Executor | None = None) -> dict[str, Any]:
    """Boundaries, extremes and energy: `springlab stability`'s JSON (plus the map and energy series).

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
    return {
        "boundaries": boundaries,
        "extremes": extremes,
        "energy": energy["rows"],
        "growth_test": (
            f"response |(omega x, v)| over steps {GROWTH_STEPS // 2}..{GROWTH_STEPS} exceeds"
            f" {GROWTH_FACTOR:g}x its maximum over the first {GROWTH_STEPS // 2}, or MuJoCo flags"
            " a blow-up"
        ),
        "accuracy_threshold": ACCURACY,
        "wall_time_s": _time.perf_counter() - started,
        "_energy_series": energy,
    }


def report_json(report: dict[str, Any]) -> dict[str, Any]:
    """The report without its plot-only series."""
    return {k: v for k, v in report.items() if not k.startswith("_")}
