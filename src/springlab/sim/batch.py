"""Many simulations at once: `mujoco.batch.Batch` runs of (model, integrator, dt) jobs, and their cost.

`run_batched` runs every job of a list in one `mujoco.batch.Batch`,
bit-identical to `simulate.simulate` per job; `time_run` measures what one job
costs alone.

Wall time. Batched runs share threads, so their wall time is no per-run cost.
The wall time of a configuration is measured by running that configuration
alone, on the calling thread, exactly as `springlab run` steps it (one
`mujoco.rollout` call; best of `repeats`). Runs longer than `TIMING_STEPS`
are timed over their first `TIMING_STEPS` steps and scaled by steps: MuJoCo's
cost per step on a fixed model and integrator does not depend on dt or on the
state. Divide by the duration for the wall time per simulated second.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time as _time
from collections.abc import Callable, Sequence

import mujoco
import numpy as np
from mujoco import batch as _mjbatch
from mujoco import rollout as _rollout

from springlab.errors import BadInputError, DivergedError
from springlab.sim.simulate import Setup

from .simulate import (
    BAD_WARNINGS,
    INTEGRATORS,
    Trajectory,
    check_diverged,
    configured,
    cut_at_stop,
    initial_state,
    integrator_id,
    quiet_mujoco,
    simulate,
)

_STATE = mujoco.mjtState
#: what the batched runner records after every step: time, qpos, qvel, act
RECORD_SPEC = int(_STATE.mjSTATE_TIME | _STATE.mjSTATE_QPOS | _STATE.mjSTATE_QVEL | _STATE.mjSTATE_ACT)
_CTRL = int(_STATE.mjSTATE_CTRL)

#: runs longer than this are timed over their first TIMING_STEPS steps and scaled
TIMING_STEPS = 4000


@dataclasses.dataclass
class Job:
    """One simulation of a batch.

    Attributes
    ----------
    model
        the compiled model; jobs sharing one model object run on it with
        per-simulation timestep and integrator (Batch.expand), jobs with
        different models each run on a copy of theirs (Batch.set_models).
    integrator
        one of INTEGRATORS.
    dt
        timestep [s].
    steps
        number of steps.
    setup
        initial state and controls (control: (nu,) or (steps, nu), held over each step).
    stop
        the scene's stop condition (Scene.stop_condition), applied as `simulate` applies it.
    """

    model: mujoco.MjModel
    integrator: str
    dt: float
    steps: int
    setup: Setup
    stop: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None


def _present(controls: np.ndarray | None) -> np.ndarray:
    """The control series of a job on a model with actuators (which always has one)."""
    assert controls is not None, "a model with actuators runs with a control series"
    return controls


def _controls(job: Job) -> np.ndarray | None:
    """(steps, nu) controls of a job, or None for a model without actuators."""
    nu = job.model.nu
    if not nu:
        return None
    control = np.zeros(nu) if job.setup.control is None else np.asarray(job.setup.control, float)
    return np.broadcast_to(control, (job.steps, nu))


def run_batched(jobs: Sequence[Job], *, nthread: int = 0) -> list[Trajectory | DivergedError]:
    """Run every job in one `mujoco.batch.Batch`; bit-identical to `simulate.simulate` per job.

    Jobs of different lengths share the batch: the runner advances all
    unfinished simulations together, segment by segment, so no simulation
    takes a step it does not need.

    Parameters
    ----------
    jobs
        the simulations.
    nthread
        threads of the batch (0: one per CPU).

    Returns
    -------
    list[Trajectory | DivergedError]
        Per job its Trajectory (t = 0 included; wall_time_s is nan: batched runs
        share threads, see `time_run` for a per-run cost), or the DivergedError
        describing how it blew up (MuJoCo's BADQPOS/BADQVEL/BADQACC warnings, a
        silent reset, non-finite values).
    """
    if not jobs:
        return []
    if any(job.setup.controller is not None for job in jobs):
        return _with_loops_alone(jobs, lambda open_loop: run_batched(open_loop, nthread=nthread))
    for job in jobs:
        integrator_id(job.integrator)
    base = jobs[0].model
    shared = all(job.model is base for job in jobs)
    if not shared and any(
        job.model.nq != base.nq or job.model.nv != base.nv or job.model.na != base.na or job.model.nu != base.nu
        for job in jobs
    ):
        raise BadInputError("batched jobs with different models need the same nq, nv, na and nu")
    with quiet_mujoco():
        batch = _mjbatch.Batch(base, nsim=len(jobs), nthread=nthread)
        if shared:
            batch.expand("opt.timestep")[:] = [job.dt for job in jobs]
            batch.expand("opt.integrator")[:] = [INTEGRATORS[job.integrator] for job in jobs]
        else:
            models = [configured(job.model, job.integrator, job.dt) for job in jobs]
            batch.set_models(models)
        nq, nv, na = base.nq, base.nv, base.na
        starts = []
        scratch: dict[int, mujoco.MjData] = {}  # one MjData per model object, reset for each of its jobs
        for i, job in enumerate(jobs):
            if id(job.model) not in scratch:
                scratch[id(job.model)] = mujoco.MjData(job.model)
            state0 = initial_state(job.model, job.setup.qpos, job.setup.qvel, job.setup.act, scratch[id(job.model)])
            batch.time[i] = 0.0
            batch.qpos[i] = state0[1 : 1 + nq]
            batch.qvel[i] = state0[1 + nq : 1 + nq + nv]
            if na:
                batch.act[i] = state0[1 + nq + nv : 1 + nq + nv + na]
            starts.append(np.concatenate([[0.0], state0[1 : 1 + nq + nv + na]]))
        batch.warning[:] = 0
        controls = [_controls(job) for job in jobs]
        steps = np.array([job.steps for job in jobs])
        records: list[list[np.ndarray]] = [[] for _ in jobs]
        done = 0
        for end in np.unique(steps):
            ids = np.flatnonzero(steps >= end).astype(np.int32)
            count = int(end - done)
            control = None
            if base.nu:
                control = np.stack([_present(controls[i])[done:end] for i in ids])
            out = batch.rollout(count, control=control, record=[RECORD_SPEC], ids=ids)[RECORD_SPEC]
            for row, job_index in enumerate(ids):
                records[job_index].append(out[row])
            done = int(end)
        warnings = np.array(batch.warning)
    results: list[Trajectory | DivergedError] = []
    for i, job in enumerate(jobs):
        states = np.concatenate([starts[i][None], *records[i]])
        trajectory = Trajectory(
            time=states[:, 0],
            qpos=states[:, 1 : 1 + nq],
            qvel=states[:, 1 + nq : 1 + nq + nv],
            act=states[:, 1 + nq + nv :],
            integrator=job.integrator,
            dt=job.dt,
            wall_time_s=math.nan,
        )
        fired = [name for name, w in zip(("BADQPOS", "BADQVEL", "BADQACC"), BAD_WARNINGS) if warnings[i, w, 1] > 0]
        if job.stop is not None:
            trajectory, stopped = cut_at_stop(trajectory, job.stop)
            if stopped:
                fired = []  # as simulate: warnings may come from steps after the event
        try:
            check_diverged(trajectory, job.dt, ["unstable"] if fired else [])
        except DivergedError as error:
            why = f"; MuJoCo flagged {'/'.join(fired)} (NaN or |value| > 1e10, then reset)" if fired else ""
            results.append(DivergedError(f"{error}{why}"))
            continue
        results.append(trajectory)
    return results


def _alone(job: Job) -> Trajectory | DivergedError:
    """One job through `simulate` (a controller in the loop: MuJoCo steps it from Python, it cannot be batched)."""
    setup = job.setup
    try:
        return simulate(
            job.model,
            integrator=job.integrator,
            dt=job.dt,
            duration=job.steps * job.dt,
            qpos=setup.qpos,
            qvel=setup.qvel,
            act=setup.act,
            stop=job.stop,
            controller=setup.controller,
        )
    except DivergedError as error:
        return error


def _with_loops_alone(
    jobs: Sequence[Job], batched: Callable[[list[Job]], list[Trajectory | DivergedError]]
) -> list[Trajectory | DivergedError]:
    """The jobs' results in their order: the closed-loop ones each run alone, the others by `batched`."""
    open_loop = [job for job in jobs if job.setup.controller is None]
    results = iter(batched(open_loop) if open_loop else [])
    return [next(results) if job.setup.controller is None else _alone(job) for job in jobs]


def _same_structure(models: Sequence[mujoco.MjModel]) -> bool:
    """Whether one MjData fits every model (same sizes), as threaded `mujoco.rollout` needs."""
    fields = ("nq", "nv", "na", "nu", "nbody", "njnt", "ngeom", "ntendon", "nsensordata", "narena", "nbuffer")
    first = models[0]
    return all(all(getattr(m, f) == getattr(first, f) for f in fields) for m in models)


def run_rollout(
    jobs: Sequence[Job], *, nthread: int = 0, private_models: bool = False
) -> list[Trajectory | DivergedError]:
    """Run jobs of equal length as one threaded `mujoco.rollout` call, one model per job.

    The path `simulate` takes for one run, taken for many at once: bit-identical to
    `simulate.simulate` per job, and as fast as raw rollout on the same models (no Batch
    bookkeeping). Jobs of different lengths or models of different structure fall back to
    `run_batched`. Returns what run_batched returns.

    Parameters
    ----------
    jobs
        the simulations (each model is copied and set to its job's integrator and dt).
    nthread
        threads (0: one per CPU).
    private_models
        every job has its own model, which nobody else reads: set its integrator
        and dt in place instead of copying it (a sweep's chunk builds its models for itself).
    """
    if not jobs:
        return []
    if any(job.setup.controller is not None for job in jobs):
        return _with_loops_alone(jobs, lambda open_loop: run_rollout(open_loop, nthread=nthread))
    steps = {job.steps for job in jobs}
    if private_models and len({id(job.model) for job in jobs}) == len(jobs):
        models = [job.model for job in jobs]
        for job in jobs:
            job.model.opt.integrator = INTEGRATORS[job.integrator]
            job.model.opt.timestep = job.dt
    else:
        models = [configured(job.model, job.integrator, job.dt) for job in jobs]
    if len(steps) != 1 or not _same_structure(models):
        return run_batched(jobs, nthread=nthread)
    count = steps.pop()
    threads = max(1, min((os.cpu_count() or 1) if nthread == 0 else nthread, len(jobs)))
    base = models[0]
    datas = [mujoco.MjData(base) for _ in range(threads)]
    # same structure: one scratch MjData serves every model, as rollout's per-thread datas do
    state0 = np.stack(
        [initial_state(m, j.setup.qpos, j.setup.qvel, j.setup.act, datas[0]) for m, j in zip(models, jobs)]
    )
    controls = None
    if base.nu:
        controls = np.ascontiguousarray(np.stack([_present(_controls(job)) for job in jobs]))
    out = np.empty((len(jobs), count, state0.shape[1]))
    sensors = np.empty((len(jobs), count, base.nsensordata))
    with quiet_mujoco():
        _rollout.rollout(
            models,
            datas,
            state0,
            controls,
            control_spec=_CTRL,
            state=out,
            sensordata=sensors,
            nstep=count,
            skip_checks=True,
        )
    nq, nv, na = base.nq, base.nv, base.na
    results: list[Trajectory | DivergedError] = []
    for i, job in enumerate(jobs):
        states = np.concatenate([state0[i][None], out[i]])
        trajectory = Trajectory(
            time=states[:, 0],
            qpos=states[:, 1 : 1 + nq],
            qvel=states[:, 1 + nq : 1 + nq + nv],
            act=states[:, 1 + nq + nv : 1 + nq + nv + na],
            integrator=job.integrator,
            dt=job.dt,
            wall_time_s=math.nan,
        )
        if job.stop is not None:
            trajectory, _ = cut_at_stop(trajectory, job.stop)
        try:
            # a blow-up shows as MuJoCo's silent reset (time jumping back) or non-finite values
            check_diverged(trajectory, job.dt, [])
        except DivergedError as error:
            results.append(error)
            continue
        results.append(trajectory)
    return results


def time_run(job: Job, *, repeats: int = 3, max_steps: int = TIMING_STEPS, measured: float | None = None) -> float:
    """Wall time [s] of one job run alone on the calling thread, as `simulate` steps it.

    Best of `repeats`; a job longer than `max_steps` is timed over its first
    `max_steps` steps and scaled by steps (MuJoCo's cost per step does not
    depend on dt or on the state). `measured`, the wall time [s] of the whole job
    already measured the same way (a study's own run of it: `Trajectory.wall_time_s`
    of `simulate` on this thread), counts as one of the repeats: with `repeats` 1 nothing
    is run again.
    """
    if measured is not None:
        if repeats <= 1:
            return measured
        return min(measured, time_run(job, repeats=repeats - 1, max_steps=max_steps))
    if job.setup.controller is not None:
        return _time_alone(job, repeats=repeats, max_steps=max_steps)
    model = configured(job.model, job.integrator, job.dt)  # the job's model is left as it was
    timed = max(1, min(job.steps, max_steps))
    state0 = initial_state(model, job.setup.qpos, job.setup.qvel, job.setup.act)
    controls = None
    if model.nu:
        controls = np.ascontiguousarray(_present(_controls(job))[:timed])[None]
    data = mujoco.MjData(model)
    out = np.empty((1, timed, state0.size))
    sensors = np.empty((1, timed, model.nsensordata))
    best = math.inf
    with quiet_mujoco():
        for _ in range(max(1, repeats)):
            start = _time.perf_counter()
            _rollout.rollout(
                [model],
                [data],
                state0[None],
                controls,
                control_spec=_CTRL,
                state=out,
                sensordata=sensors,
                nstep=timed,
                skip_checks=True,
            )
            best = min(best, _time.perf_counter() - start)
    return best * job.steps / timed


def _time_alone(job: Job, *, repeats: int, max_steps: int) -> float:
    """Wall time [s] of a closed-loop job (`time_run`): its `simulate` stepping, best of `repeats`, scaled by steps."""
    timed = max(1, min(job.steps, max_steps))
    shorter = dataclasses.replace(job, steps=timed, stop=None)
    best = math.inf
    for _ in range(max(1, repeats)):
        result = _alone(shorter)
        if isinstance(result, Trajectory):
            best = min(best, result.wall_time_s)
    return best * job.steps / timed
