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
import time as _time
from collections.abc import Callable, Sequence

import mujoco
import numpy as np
from mujoco import batch as _mjbatch
from mujoco import rollout as _rollout

from .errors import BadInputError, DivergedError
from .scene import Setup
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
        for i, job in enumerate(jobs):
            state0 = initial_state(job.model, job.setup.qpos, job.setup.qvel, job.setup.act)
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


def time_run(job: Job, *, repeats: int = 3, max_steps: int = TIMING_STEPS) -> float:
    """Wall time [s] of one job run alone on the calling thread, as `simulate` steps it.

    Best of `repeats`; a job longer than `max_steps` is timed over its first
    `max_steps` steps and scaled by steps (MuJoCo's cost per step does not
    depend on dt or on the state).
    """
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
