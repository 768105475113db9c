"""Accuracy vs cost of any model: every integrator over a timestep grid against a reference, batched.

The runs start from the perturbed operating point and hold the operating point's controls. Each run
is compared with the reference at its own steps (at most MAX_SAMPLES of them, evenly strided) by

  error = max( max_t |q_sim - q_ref|_inf / max_t |q_ref - q_op|_inf,  max_t |v_sim - v_ref|_inf / max_t |v_ref|_inf )

(positions differenced in the tangent space; a scale of 0 counts the error absolutely): for a 1-DOF
model the max relative error over the position and velocity columns that `springlab tradeoff` reports.

The reference: when the model is linear along the motion (its linearization, re-taken at
LINEARITY_PROBES states of the motion, differs from the one at the operating point by less than
`linearity_tolerance`), the exact solution of the (affine) linearization, expm, at any time;
otherwise RK4 at h, h/2, ... until the Richardson estimate of its error, diff / (2^p - 1) with p the
order observed over the last three levels (clamped to [1, 4]: contact-rich models lose RK4's
order), is at most REFERENCE_FRACTION x tol. h = spacing / (2 lcm(m_i)) for the grid's timesteps
spacing / m_i, so every step of every grid run is a reference step: the default grid takes its m_i
from SMOOTH (2^a and 3 x 2^a), whose lcm stays at twice the largest.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from fractions import Fraction

import mujoco
import numpy as np

from springlab.errors import BadInputError, DivergedError
from springlab.exact.linearize import Linearization
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.operating_point import OperatingPoint
from springlab.sim.batch import Job, run_batched, time_run
from springlab.sim.simulate import MAX_STEPS, Setup, Trajectory

from .limits import Limit

#: default grid: this many timesteps ...
GRID_POINTS = 12
#: ... over this many decades below the largest
GRID_DECADES = 3.0
#: the default grid's largest timestep: this multiple of the largest confirmed limit (runs beyond show the blow-up)
GRID_TOP_OVER_LIMIT = 1.2
#: the default grid's finest timestep takes at most this many steps over the duration (never exit 2 for the grid)
GRID_MAX_STEPS = 100_000
#: the divisors m of the default grid's timesteps top / m: their lcm is at most 2x the largest
SMOOTH = sorted({2**a * b for a in range(16) for b in (1, 3)})
#: the duration holds at least this many of the largest timestep
MIN_CHECKPOINTS = 10
#: each run is compared at most at this many of its steps
MAX_SAMPLES = 2000
#: the reference's own estimated error must be at most this fraction of tol
REFERENCE_FRACTION = 0.01
#: most steps of one reference run
REFERENCE_MAX_STEPS = 50_000
#: states along the motion where the linearization is re-taken to test linearity
LINEARITY_PROBES = 4
#: runs a list of jobs, as batch.run_batched (springlab.studies.audit.ship.Runner: locally or on dask workers)
RunJobs = Callable[[Sequence[Job]], list[Trajectory | DivergedError]]

#: steps of the timing run behind each integrator's cost per step
TIMING_STEPS = 1000
#: ... or as many more as take at least this long [s]
TIMING_MIN_S = 0.02
#: ... up to this many
TIMING_MAX_STEPS = 64 * TIMING_STEPS
#: the cost per step is the best of this many runs of that length
TIMING_REPEATS = 5
#: a run shorter than TIMING_MIN_S sets the next length: this margin over the length its speed calls for
TIMING_MARGIN = 1.25


def checkpoint_spacing(dts: list[float], duration: float) -> float:
    """The smallest common multiple [s] of the timesteps (as decimals): every run has a step there.

    Raises
    ------
    BadInputError
        fewer than MIN_CHECKPOINTS such multiples fit in the duration.
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


def reference_step(dts: list[float], spacing: float) -> float:
    """h = spacing / (2 lcm(spacing / dt_i)) [s]: every step of every run at dts is a multiple of h."""
    return spacing / (2 * math.lcm(*(max(1, round(spacing / dt)) for dt in dts)))


def default_grid(top: float, points: int = GRID_POINTS, decades: float = GRID_DECADES) -> list[float]:
    """top / m [s] for `points` distinct m of SMOOTH nearest (in log) to a geometric sequence from 1 to
    10^decades, largest dt first."""
    chosen: list[int] = []
    for target in np.geomspace(1.0, 10.0**decades, points):
        free = [m for m in SMOOTH if m not in chosen and (not chosen or m > chosen[-1])]
        chosen.append(min(free, key=lambda m: abs(math.log(m / target))))
    return [top / m for m in chosen]


def grid_for(limits: Mapping[str, Limit], duration: float, own_dt: float) -> list[float]:
    """The default grid [s], largest first: `default_grid` below GRID_TOP_OVER_LIMIT x the largest confirmed
    stability limit (or the largest timestep brute force found bounded where nothing blew up; at most a tenth
    of the duration), its top a divisor of the duration that the model's own timestep divides (`grid_top`),
    over up to GRID_DECADES decades whose finest takes at most GRID_MAX_STEPS steps."""
    confirmed = [lim.confirmed_limit_s for lim in limits.values() if lim.confirmed_limit_s is not None]
    confirmed += [
        lim.runs_bounded_dt_s
        for lim in limits.values()
        if lim.limit_dt_s is None and lim.runs_blew_up_dt_s is None and lim.runs_bounded_dt_s is not None
    ]
    ceiling = min(GRID_TOP_OVER_LIMIT * max(confirmed), duration / 10) if confirmed else duration / 10
    ceiling = max(ceiling, 10 * duration / GRID_MAX_STEPS)  # never a grid too fine to run
    top = grid_top(duration, ceiling, own_dt)
    decades = min(GRID_DECADES, math.log10(top * GRID_MAX_STEPS / duration))
    return default_grid(top, max(2, round(GRID_POINTS * decades / GRID_DECADES)), decades)


def grid_top(duration: float, ceiling: float, own_dt: float) -> float:
    """The default grid's largest timestep [s]: duration / J for the fewest intervals J that keep it at most
    `ceiling` [s], with J dividing duration / own_dt when that is an integer (so the model's own timestep
    divides it and is compared at the same checkpoints)."""
    fewest = max(1, math.ceil(duration / ceiling * (1 - 1e-12)))
    own_steps = duration / own_dt
    if abs(own_steps - round(own_steps)) <= 1e-9 * own_steps and own_dt <= ceiling:
        steps = round(own_steps)
        divisors = [j for j in range(fewest, steps + 1) if steps % j == 0]
        return duration / divisors[0]
    return duration / fewest


def sample_rows(steps: int) -> np.ndarray:
    """The step indices a run of `steps` steps is compared at: all, or every k-th for at most MAX_SAMPLES."""
    stride = max(1, math.ceil(steps / MAX_SAMPLES))
    return np.arange(0, steps + 1, stride)


def _tangent_distance(model: mujoco.MjModel, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a - b|_inf per row of two qpos arrays, differenced in the tangent space."""
    if model.nq == model.nv:  # hinges and slides only: qpos is the tangent coordinate
        return np.max(np.abs(a - b), axis=1, initial=0.0)
    dq = np.zeros((len(a), model.nv))  # MuJoCo differences each row (quaternions), numpy takes every max at once
    for i in range(len(a)):
        mujoco.mj_differentiatePos(model, dq[i], 1.0, b[i], a[i])
    return np.max(np.abs(dq), axis=1, initial=0.0)


@dataclasses.dataclass(frozen=True)
class Sampled:
    """A reference at a run's sampled steps (`Reference.sampled`).

    Attributes
    ----------
    rows
        the run's step indices where the reference has a state.
    qpos, qvel
        the reference's states there [m or rad, m/s or rad/s], one row per index.
    scale_q
        max |q_ref - q_op|_inf over them, in the tangent space [m or rad].
    scale_v
        max |v_ref|_inf over them [m/s or rad/s].
    """

    rows: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    scale_q: float
    scale_v: float


class Reference:
    """The reference motion: `states(dt, rows)` gives (qpos, qvel, kept) at times rows * dt [s].

    Attributes
    ----------
    kind
        what it is, for people.
    error_estimate
        its own estimated error [-] (0 for the exact solution).
    dt
        its timestep [s] (None for the exact solution).
    """

    kind = ""
    error_estimate = 0.0
    dt: float | None = None
    #: the last `sampled` answer, kept for the next run of the same dt and steps (another integrator's)
    _last: tuple[tuple[int, float, int], ModelAtPoint, Sampled] | None = None

    def states(self, dt: float, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        raise NotImplementedError

    def sampled(self, at: ModelAtPoint, dt: float, steps: int) -> Sampled:
        """The reference where `run_error` compares a run of `steps` steps of `dt` [s] (`sample_rows`), with
        its scales about the point of `at`; the last answer is kept, so the runs of every integrator at one dt,
        compared in turn, share one."""
        key = (id(at), dt, steps)
        if self._last is not None and self._last[0] == key:
            return self._last[2]
        rows = sample_rows(steps)
        ref_q, ref_v, kept = self.states(dt, rows)
        rows = rows[kept]
        if len(rows) < 2:
            found = Sampled(rows, ref_q, ref_v, 0.0, 0.0)
        else:
            origin = np.broadcast_to(at.point.qpos, ref_q.shape)
            scale_q = float(np.max(_tangent_distance(at.model, ref_q, origin)))
            found = Sampled(rows, ref_q, ref_v, scale_q, float(np.max(np.abs(ref_v), initial=0.0)))
        self._last = (key, at, found)  # `at` held: its id is not reused while the key is kept
        return found


class TrajectoryReference(Reference):
    """A recorded run: states at its own steps; times between them are not kept."""

    def __init__(self, trajectory: Trajectory, kind: str = "", error_estimate: float = 0.0):
        self.trajectory, self.kind, self.error_estimate, self.dt = trajectory, kind, error_estimate, trajectory.dt

    def states(self, dt: float, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        index = rows * (dt / self.trajectory.dt)  # self.dt, typed as a float
        nearest = np.round(index).astype(np.int64)
        kept = (np.abs(index - nearest) <= 1e-6) & (nearest < len(self.trajectory.time))  # same time to 1e-6 step
        picked = nearest[kept]
        return self.trajectory.qpos[picked], self.trajectory.qvel[picked], kept


class ExactReference(Reference):
    """The exact solution of the affine linearization dx/dt = f0 + A (x - x_op), at any time.

    f0 = (qvel, qacc, act_dot) at the operating point with the start's held control (zero at an equilibrium
    with no control offset); x in the tangent space. Exact for controls that enter affinely.
    """

    kind = "exact solution of the linearization"

    def __init__(self, at: ModelAtPoint, start: Setup):
        point, linear = at.point, at.linear
        self.nv, n = at.model.nv, linear.A.shape[0]
        self.work = at.continuous
        # the start's held control: its force is in the drift
        held = (
            at.point if start.control is None else dataclasses.replace(at.point, ctrl=np.atleast_2d(start.control)[0])
        )
        drift = ModelAtPoint(at.model, held, at.step).rates
        x0 = np.zeros(n)
        mujoco.mj_differentiatePos(self.work, x0[: self.nv], 1.0, point.qpos, start.qpos)
        x0[self.nv : 2 * self.nv] = start.qvel - point.qvel
        x0[2 * self.nv :] = (start.act if start.act is not None else point.act) - point.act
        self.augmented = np.zeros((n + 1, n + 1))
        self.augmented[:n, :n] = linear.A
        self.augmented[:n, n] = drift
        self.z0 = np.concatenate([x0, [1.0]])
        self.point = point

    def states(self, dt: float, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        from scipy.linalg import expm  # scipy is a dependency; imported here to keep import time low

        stride = int(rows[1] - rows[0]) if len(rows) > 1 else 1  # sample_rows: evenly strided from 0
        step = expm(self.augmented * dt * stride)
        z = self.z0.copy()
        tangent = np.empty((len(rows), len(z) - 1))
        for k in range(len(rows)):
            tangent[k] = z[:-1]
            z = step @ z
        nv = self.nv
        if self.work.nq == nv:
            qpos = self.point.qpos + tangent[:, :nv]
        else:
            qpos = np.empty((len(rows), self.work.nq))
            for k in range(len(rows)):
                qpos[k] = self.point.qpos
                mujoco.mj_integratePos(self.work, qpos[k], tangent[k, :nv], 1.0)
        return qpos, self.point.qvel + tangent[:, nv : 2 * nv], np.ones(len(rows), bool)


def run_error(at: ModelAtPoint, outcome: Trajectory | DivergedError, reference: Reference) -> float | None:
    """A run's error [-] (module docstring) at its sampled steps, None if it diverged."""
    if isinstance(outcome, DivergedError):
        return None
    ref = reference.sampled(at, outcome.dt, len(outcome.time) - 1)
    if len(ref.rows) < 2:
        return None
    qpos, qvel = outcome.qpos[ref.rows], outcome.qvel[ref.rows]
    scale_q, scale_v = ref.scale_q, ref.scale_v
    err_q = float(np.max(_tangent_distance(at.model, qpos, ref.qpos)))
    err_v = float(np.max(np.abs(qvel - ref.qvel), initial=0.0))
    if not (math.isfinite(err_q) and math.isfinite(err_v)):
        return math.inf
    return max(err_q / scale_q if scale_q > 0 else err_q, err_v / scale_v if scale_v > 0 else err_v)


def linearity_change(at: ModelAtPoint, trajectory: Trajectory) -> float:
    """max ||A(x(t)) - A(x_op)||_max / ||A(x_op)||_max [-] over LINEARITY_PROBES states of the motion."""
    linear = at.linear
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
        change = max(change, float(np.max(np.abs(ModelAtPoint(at.model, probe, at.step).linear.A - linear.A))) / size)
    return change


def linearity_tolerance(linear: Linearization, tol: float, duration: float) -> float:
    """Largest relative change of A [-] along the motion for which the linearization's exact solution is a
    reference good to REFERENCE_FRACTION x tol: a relative change e of A shifts frequencies by ~e/2, so the
    motion by ~e |lambda|_max T / 2."""
    rate = max((m.rate_rad_s for m in linear.modes), default=0.0)
    return REFERENCE_FRACTION * tol / max(1.0, rate * duration)


def converged_reference(
    at: ModelAtPoint,
    start: Setup,
    step: float,
    duration: float,
    tol: float,
    *,
    coarse: Trajectory | None = None,
    nthread: int = 0,
    run: RunJobs | None = None,
) -> Reference:
    """RK4 at `step`, step/2, ... [s] until its Richardson error estimate is at most REFERENCE_FRACTION x tol
    (module docstring), REFERENCE_MAX_STEPS, or the observed order cannot get there within that cap; the
    finest level is returned with its estimate (which says whether it converged). `coarse`: an RK4 run
    at 2 x step (the sweep's finest), used as the coarsest level instead of running it again. `run`: runs
    the levels' jobs (default: batch.run_batched on `nthread` threads)."""
    run = run or _local(nthread)
    levels: list[Trajectory] = []
    while 2 * round(duration / step) > REFERENCE_MAX_STEPS and 2 * step * MIN_CHECKPOINTS <= duration:
        step *= 2  # too fine for the cap: the finest runs are then compared where their steps meet its steps
    if isinstance(coarse, Trajectory) and math.isclose(coarse.dt, 2 * step):
        levels.append(coarse)
    dt, estimate, diffs = step, math.inf, []
    target = REFERENCE_FRACTION * tol
    ran: dict[float, Trajectory | DivergedError] = {}  # dt [s] -> its run, including the level run ahead
    while True:
        dts = [dt] if levels else [2 * dt, dt]
        steps = [round(duration / d) for d in dts]
        if max(steps) > REFERENCE_MAX_STEPS:
            break
        # an estimate needs two differences, so until three levels the next one always runs: within the cap it
        # runs in the same batch as these (the finest level would otherwise run alone, on one thread)
        ahead = [dt / 2] if len(levels) + len(dts) < 3 and round(duration / (dt / 2)) <= REFERENCE_MAX_STEPS else []
        wanted = [d for d in [*dts, *ahead] if d not in ran]
        if wanted:
            ran.update(zip(wanted, run([Job(at.model, "rk4", d, round(duration / d), start) for d in wanted])))
        outcomes = [ran[d] for d in dts]
        finished = [o for o in outcomes if isinstance(o, Trajectory)]
        if len(finished) < len(outcomes):  # one diverged
            break
        levels.extend(finished)
        if len(levels) >= 2:
            diff = run_error(at, levels[-2], TrajectoryReference(levels[-1]))
            diffs.append(math.inf if diff is None else diff)
            order = 4.0
            if len(diffs) >= 2 and diffs[-1] > 0 and diffs[-2] > 0:
                order = min(max(math.log2(diffs[-2] / diffs[-1]), 1.0), 4.0)
            estimate = diffs[-1] / (2**order - 1)
            if estimate <= target and len(diffs) >= 2:
                break
            # at the observed order, reaching the target takes (estimate / target)^(1/p) times the steps:
            # past the cap, more levels only cost time (contacts keep RK4 far from its order)
            if len(diffs) >= 2 and max(steps) * (estimate / target) ** (1 / order) > REFERENCE_MAX_STEPS:
                break
        dt /= 2
    if len(levels) < 2:
        raise BadInputError(
            "the RK4 reference diverged or needs more than"
            f" {REFERENCE_MAX_STEPS} steps; use a shorter --duration or timesteps that divide the largest one"
        )
    return TrajectoryReference(levels[-1], "RK4, converged (Richardson)", estimate)


def sweep_runs(
    model: mujoco.MjModel,
    start: Setup,
    integrators: list[str],
    dts: list[float],
    duration: float,
    *,
    extra: Sequence[tuple[str, float]] = (),
    nthread: int = 0,
    run: RunJobs | None = None,
) -> dict[tuple[str, float], Trajectory | DivergedError]:
    """Every (integrator, dt) plus `extra` settings, batched: (integrator, dt) -> Trajectory or DivergedError.

    `run` runs the jobs (default: one batch.run_batched call on `nthread` threads)."""
    run = run or _local(nthread)
    settings = list(dict.fromkeys([(name, dt) for name in integrators for dt in dts] + list(extra)))
    jobs = []
    for name, dt in settings:
        steps = round(duration / dt)
        if steps > MAX_STEPS:
            raise BadInputError(f"dt = {dt:g} s needs {steps} steps for {duration:g} s (limit {MAX_STEPS})")
        jobs.append(Job(model, name, dt, max(1, steps), start))
    return dict(zip(settings, run(jobs)))


def _local(nthread: int) -> RunJobs:
    """batch.run_batched on `nthread` threads (0: one per CPU): the audit's runs in this process."""
    return lambda jobs: run_batched(jobs, nthread=nthread)


def cost_per_step(model: mujoco.MjModel, start: Setup, integrator: str, dt: float) -> float:
    """Wall time of one step [s] of `integrator` on `model`, run alone on the calling thread (springlab.sim.batch
    .time_run): the best of TIMING_REPEATS runs of TIMING_STEPS steps, or of as many as take TIMING_MIN_S (at
    most TIMING_MAX_STEPS); a setting's wall time is steps x this (MuJoCo's cost per step does not depend on dt;
    one long timing per integrator is steadier on a loaded machine than many short ones).

    A run shorter than TIMING_MIN_S is not repeated: its speed sets the next length (TIMING_MARGIN x the
    steps that take TIMING_MIN_S at that speed), and only runs of the final length are repeated.
    """
    steps = TIMING_STEPS
    while True:
        job = Job(model, integrator, dt, steps, start)  # time_run runs a copy: `model` is left as it was
        seconds = time_run(job, repeats=1, max_steps=steps)
        if seconds >= TIMING_MIN_S or steps >= TIMING_MAX_STEPS:
            seconds = min(seconds, time_run(job, repeats=TIMING_REPEATS - 1, max_steps=steps))
            if seconds >= TIMING_MIN_S or steps >= TIMING_MAX_STEPS:
                return seconds / steps
        # too short to time (a repeat came in under, on a loaded machine): longer, at the speed just measured
        wanted = math.ceil(TIMING_MARGIN * steps * TIMING_MIN_S / max(seconds, 1e-12))
        steps = min(max(wanted, steps + 1), TIMING_MAX_STEPS)
