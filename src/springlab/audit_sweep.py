"""Accuracy vs cost of any model: every integrator over a timestep grid against a reference, batched.

The runs start from the perturbed operating point and hold the operating point's controls. They are
compared at checkpoints, the multiples of a spacing every timestep divides (default grid: the
largest timestep divided by integers m, so the checkpoints are the largest timestep's steps), by

  error = max( max_t |q_sim - q_ref|_inf / max_t |q_ref - q_op|_inf,  max_t |v_sim - v_ref|_inf / max_t |v_ref|_inf )

(positions differenced in the tangent space; a scale of 0 counts the error absolutely): for a 1-DOF
model the max relative error over the position and velocity columns that `springlab tradeoff` reports.

The reference: when the model is linear along the motion (its linearization, re-taken at
LINEARITY_PROBES states of the motion, differs from the one at the operating point by less than
`linearity_tolerance`), the exact solution of the (affine) linearization, expm; otherwise RK4 at
ever finer timesteps c/M, c/2M, ... until the Richardson estimate of its error, diff / (2^p - 1)
with p the order observed over the last three levels (clamped to [1, 4]: contact-rich models lose
RK4's order), is at most REFERENCE_FRACTION x tol.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from fractions import Fraction
from typing import Any

import mujoco
import numpy as np

from .batch import Job, run_batched, time_run
from .errors import BadInputError, DivergedError
from .linearize import Linearization, OperatingPoint, linearize
from .scene import Setup
from .simulate import MAX_STEPS, Trajectory, quiet_mujoco

#: default grid: this many timesteps ...
GRID_POINTS = 12
#: ... over this many decades below the largest
GRID_DECADES = 2.5
#: at least this many checkpoints over the duration
MIN_CHECKPOINTS = 10
#: the reference's own estimated error must be at most this fraction of tol
REFERENCE_FRACTION = 0.01
#: most steps of one reference run
REFERENCE_MAX_STEPS = 50_000
#: states along the motion where the linearization is re-taken to test linearity
LINEARITY_PROBES = 4
#: steps of the timing run behind each integrator's cost per step
TIMING_STEPS = 1000


@dataclasses.dataclass
class SweepRun:
    """One (integrator, dt) of the sweep: error [-] vs the reference (None if diverged), wall time [s]."""

    integrator: str
    dt: float
    steps: int
    error: float | None
    wall_time_s: float
    diverged: bool = False

    def row(self) -> dict[str, Any]:
        """{"integrator", "dt", "steps", "wall_time_s", "error", "diverged"}."""
        return dataclasses.asdict(self)


def checkpoint_spacing(dts: list[float], duration: float) -> float:
    """The smallest common multiple [s] of the timesteps (as decimals), which the checkpoints are multiples of.

    Raises:
      BadInputError: fewer than MIN_CHECKPOINTS such multiples fit in the duration.
    """
    fractions = [Fraction(dt).limit_denominator(10**12) for dt in dts]
    numerator = math.lcm(*(f.numerator for f in fractions))
    denominator = math.gcd(*(f.denominator for f in fractions))
    spacing = float(Fraction(numerator, denominator))
    if duration / spacing < MIN_CHECKPOINTS * (1 - 1e-9):
        raise BadInputError(
            f"the timesteps {', '.join(f'{d:g}' for d in dts)} s share only {int(duration / spacing)} common sample"
            f" times in {duration:g} s (need {MIN_CHECKPOINTS}); use timesteps that divide the largest one"
        )
    return spacing


def default_grid(top: float, points: int = GRID_POINTS, decades: float = GRID_DECADES) -> list[float]:
    """top / m [s] for `points` distinct integers m from 1 to about 10^decades, largest dt first."""
    ms = []
    for value in np.geomspace(1.0, 10.0**decades, points):
        ms.append(max(round(value), ms[-1] + 1 if ms else 1))
    return [top / m for m in ms]


def _stride(dt: float, spacing: float) -> int:
    return max(1, round(spacing / dt))


class _Reference:
    """States at the checkpoints k * spacing, k = 0..K: qpos (K+1, nq), qvel (K+1, nv)."""

    def __init__(self, qpos: np.ndarray, qvel: np.ndarray, kind: str, error_estimate: float, dt: float | None):
        self.qpos, self.qvel, self.kind, self.error_estimate, self.dt = qpos, qvel, kind, error_estimate, dt


def _tangent_distance(model: mujoco.MjModel, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a - b|_inf per row of two qpos arrays, differenced in the tangent space."""
    if model.nq == model.nv:  # hinges and slides only: qpos is the tangent coordinate
        return np.max(np.abs(a - b), axis=1, initial=0.0)
    out = np.empty(len(a))
    dq = np.zeros(model.nv)
    for i in range(len(a)):
        mujoco.mj_differentiatePos(model, dq, 1.0, b[i], a[i])
        out[i] = np.max(np.abs(dq), initial=0.0)
    return out


def checkpoint_error(model: mujoco.MjModel, point: OperatingPoint, qpos, qvel, reference: _Reference) -> float:
    """The module docstring's error [-] of states at the checkpoints against the reference's."""
    count = min(len(qpos), len(reference.qpos))
    ref_q, ref_v = reference.qpos[:count], reference.qvel[:count]
    scale_q = float(np.max(_tangent_distance(model, ref_q, np.broadcast_to(point.qpos, ref_q.shape))))
    scale_v = float(np.max(np.abs(ref_v), initial=0.0))
    err_q = float(np.max(_tangent_distance(model, qpos[:count], ref_q)))
    err_v = float(np.max(np.abs(qvel[:count] - ref_v), initial=0.0))
    if not (math.isfinite(err_q) and math.isfinite(err_v)):
        return math.inf
    return max(err_q / scale_q if scale_q > 0 else err_q, err_v / scale_v if scale_v > 0 else err_v)


def _at_checkpoints(trajectory: Trajectory, spacing: float, count: int) -> tuple[np.ndarray, np.ndarray]:
    stride = _stride(trajectory.dt, spacing)
    rows = np.arange(count) * stride
    rows = rows[rows < len(trajectory.time)]
    return trajectory.qpos[rows], trajectory.qvel[rows]


def linear_reference(
    model: mujoco.MjModel, linear: Linearization, start: Setup, spacing: float, count: int
) -> _Reference:
    """The exact solution of the affine linearization dx/dt = f0 + A (x - x_op) at the checkpoints.

    f0 = (qvel, qacc, act_dot) at the operating point (zero at an equilibrium); x in the tangent space.
    """
    point = linear.point
    nv, n = model.nv, linear.A.shape[0]
    work = copy.copy(model)
    work.opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)  # the continuous forward pass
    data = mujoco.MjData(work)
    with quiet_mujoco():
        point.load(work, data)
        mujoco.mj_forward(work, data)
    drift = np.concatenate([data.qvel, data.qacc, data.act_dot])
    x0 = np.zeros(n)
    mujoco.mj_differentiatePos(work, x0[:nv], 1.0, point.qpos, start.qpos)
    x0[nv : 2 * nv] = start.qvel - point.qvel
    x0[2 * nv :] = (start.act if start.act is not None else point.act) - point.act
    augmented = np.zeros((n + 1, n + 1))
    augmented[:n, :n] = linear.A
    augmented[:n, n] = drift
    from scipy.linalg import expm  # scipy is a dependency; imported here to keep import time low

    step = expm(augmented * spacing)
    z = np.concatenate([x0, [1.0]])
    states = np.empty((count, n))
    for k in range(count):
        states[k] = z[:n]
        z = step @ z
    qpos = np.empty((count, model.nq))
    for k in range(count):
        qpos[k] = point.qpos
        mujoco.mj_integratePos(work, qpos[k], states[k, :nv], 1.0)
    return _Reference(qpos, point.qvel + states[:, nv : 2 * nv], "exact solution of the linearization", 0.0, None)


def linearity_change(model: mujoco.MjModel, linear: Linearization, trajectory: Trajectory) -> float:
    """max ||A(x(t)) - A(x_op)||_max / ||A(x_op)||_max [-] over LINEARITY_PROBES states of the motion."""
    size = float(np.max(np.abs(linear.A), initial=0.0))
    if size == 0 or not len(trajectory.time):
        return 0.0
    change = 0.0
    last = len(trajectory.time) - 1
    for j in range(1, LINEARITY_PROBES + 1):
        row = round(j * last / LINEARITY_PROBES)
        probe = OperatingPoint(
            trajectory.qpos[row], trajectory.qvel[row], trajectory.act[row], linear.point.ctrl, "along the motion"
        )
        change = max(change, float(np.max(np.abs(linearize(model, probe).A - linear.A))) / size)
    return change


def linearity_tolerance(linear: Linearization, tol: float, duration: float) -> float:
    """Largest relative change of A [-] along the motion for which the linearization's exact solution is a
    reference good to REFERENCE_FRACTION x tol: a relative change e of A shifts frequencies by ~e/2, so the
    motion by ~e |lambda|_max T / 2."""
    rate = max((m.rate_rad_s for m in linear.modes), default=0.0)
    return REFERENCE_FRACTION * tol / max(1.0, rate * duration)


def converged_reference(
    model: mujoco.MjModel,
    point: OperatingPoint,
    start: Setup,
    spacing: float,
    count: int,
    finest_dt: float,
    tol: float,
    *,
    coarse: Trajectory | None = None,
    nthread: int = 0,
) -> _Reference:
    """RK4 refined by halving from below `finest_dt` [s] until its Richardson error estimate is at most
    REFERENCE_FRACTION x tol (module docstring), or REFERENCE_MAX_STEPS; the finest level is returned with
    its estimate (which says whether it converged). `coarse`: an RK4 run at twice the first level's dt
    (the sweep's finest), used as the coarsest level instead of running it again."""
    duration = spacing * (count - 1)
    dt = spacing / (2 * _stride(finest_dt, spacing))
    levels: list[tuple[np.ndarray, np.ndarray]] = []
    estimate, diffs, finest_level = math.inf, [], None
    if coarse is not None and isinstance(coarse, Trajectory) and math.isclose(coarse.dt, 2 * dt):
        levels.append(_at_checkpoints(coarse, spacing, count))  # the sweep's own finest RK4 run
    while True:
        dts = [dt] if levels else [2 * dt, dt]
        steps = [round(duration / d) for d in dts]
        if max(steps) > REFERENCE_MAX_STEPS:
            break
        outcomes = run_batched([Job(model, "rk4", d, s, start) for d, s in zip(dts, steps)], nthread=nthread)
        if any(isinstance(o, DivergedError) for o in outcomes):
            break
        levels.extend(_at_checkpoints(o, spacing, count) for o in outcomes)
        finest_level = dt
        if len(levels) >= 2:
            coarse, fine = levels[-2], levels[-1]
            diffs.append(checkpoint_error(model, point, *coarse, _Reference(*fine, "", 0.0, None)))
            order = 4.0
            if len(diffs) >= 2 and diffs[-1] > 0 and diffs[-2] > 0:
                order = min(max(math.log2(diffs[-2] / diffs[-1]), 1.0), 4.0)
            estimate = diffs[-1] / (2**order - 1)
            target = REFERENCE_FRACTION * tol
            if estimate <= target and len(diffs) >= 2:
                break
            # at the observed order, reaching the target takes (estimate / target)^(1/p) times the steps:
            # past the cap, more levels only cost time (contacts keep RK4 far from its order)
            if len(diffs) >= 2 and max(steps) * (estimate / target) ** (1 / order) > REFERENCE_MAX_STEPS:
                break
        dt /= 2
    if not levels:
        raise BadInputError("the RK4 reference diverged or needs too many steps; use a shorter --duration")
    qpos, qvel = levels[-1]
    return _Reference(qpos, qvel, "RK4, converged (Richardson)", estimate, finest_level)


def sweep_runs(
    model: mujoco.MjModel,
    start: Setup,
    integrators: list[str],
    dts: list[float],
    duration: float,
    *,
    extra: list[tuple[str, float]] = (),
    nthread: int = 0,
) -> dict[tuple[str, float], Trajectory | DivergedError]:
    """Every (integrator, dt) plus `extra` settings, batched: (integrator, dt) -> Trajectory or DivergedError."""
    settings = list(dict.fromkeys([(name, dt) for name in integrators for dt in dts] + list(extra)))
    jobs = []
    for name, dt in settings:
        steps = round(duration / dt)
        if steps > MAX_STEPS:
            raise BadInputError(f"dt = {dt:g} s needs {steps} steps for {duration:g} s (limit {MAX_STEPS})")
        jobs.append(Job(model, name, dt, max(1, steps), start))
    return dict(zip(settings, run_batched(jobs, nthread=nthread)))


def cost_per_step(model: mujoco.MjModel, start: Setup, integrator: str, dt: float) -> float:
    """Wall time of one step [s] of `integrator` on `model`, run alone on the calling thread (best of 3 runs of
    TIMING_STEPS steps, springlab.batch.time_run); a setting's wall time is steps x this (MuJoCo's cost per
    step does not depend on dt; one long timing per integrator is steadier on a loaded machine than many
    short ones)."""
    return time_run(Job(copy.copy(model), integrator, dt, TIMING_STEPS, start), repeats=3) / TIMING_STEPS


def error_of(model, point, outcome, spacing: float, reference: _Reference) -> float | None:
    """A run's checkpoint error [-], None if it diverged."""
    if isinstance(outcome, DivergedError):
        return None
    return checkpoint_error(model, point, *_at_checkpoints(outcome, spacing, len(reference.qpos)), reference)
