"""The audit's claims checked on runs made here (mujoco.rollout, not springlab's runner): shared by the audit's
tests on robots written here (tests/studies/audit/test_audit_robots.py) and on dm_control's suite."""

from __future__ import annotations

import importlib
import math

import mujoco
import numpy as np
from mujoco import rollout

from springlab.sim.simulate import INTEGRATORS
from springlab.studies.audit.audit import audit
from springlab.studies.audit.sweep import default_grid, grid_for

_FULL = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)


def rollout_run(model, integrator, dt, steps, qpos, qvel, ctrl=None):
    """(qpos, qvel) at every step of a run, stepped by mujoco.rollout (not springlab's runner); NaN rows after
    MuJoCo flags a blow-up."""
    work = model.__copy__()
    work.opt.integrator, work.opt.timestep = INTEGRATORS[integrator], dt
    data = mujoco.MjData(work)
    data.qpos[:], data.qvel[:] = qpos, qvel
    state0 = np.empty(mujoco.mj_stateSize(work, _FULL))
    mujoco.mj_getState(work, data, state0, _FULL)
    control = np.tile(np.asarray(ctrl, float), (1, steps, 1)) if work.nu else None
    states, _ = rollout.rollout(work, data, state0[None], control, nstep=steps)
    states = np.concatenate([state0[None], states[0]])
    qp, qv = states[:, 1 : 1 + work.nq], states[:, 1 + work.nq : 1 + work.nq + work.nv]
    times = states[:, 0]
    reset = np.flatnonzero(np.diff(times) < 0)  # MuJoCo resets a run it flags: time goes back to 0
    if reset.size:
        qp, qv = qp.copy(), qv.copy()
        qp[reset[0] + 1 :] = np.nan
        qv[reset[0] + 1 :] = np.nan
    return qp, qv


def check_limits_honest(result, model):
    """Every reported limit is confirmed by runs or labelled unconfirmed; a brute-force limit's bracket holds
    in runs made here; the own setting is unstable only if a run of it blows up."""
    for name, limit in result.stability.items():
        data = limit.to_dict()
        if limit.limit_dt_s is None:
            continue
        assert data["confirmed"] in (True, False), name
        if not limit.confirmed:
            assert "UNCONFIRMED" in result.message or name != result.own.integrator
        if limit.method == "nonlinear runs" and limit.confirmed:
            steps = lambda dt: max(2000, math.ceil(result.duration / dt))  # noqa: E731 - the audit's run length
            start = result.start
            below = rollout_run(
                model,
                name,
                limit.runs_bounded_dt_s,
                steps(limit.runs_bounded_dt_s),
                start.qpos,
                start.qvel,
                start.control,
            )
            above = rollout_run(
                model,
                name,
                limit.runs_blew_up_dt_s,
                steps(limit.runs_blew_up_dt_s),
                start.qpos,
                start.qvel,
                start.control,
            )
            assert np.isfinite(below[1]).all(), name
            bounded_speed = np.max(np.abs(below[1]))
            assert not np.isfinite(above[1]).all() or np.max(np.abs(above[1])) > 10 * bounded_speed, name
    own = result.own
    if not own.stable:
        run = rollout_run(
            model,
            own.integrator,
            own.dt,
            max(2000, math.ceil(result.duration / own.dt)),
            result.start.qpos,
            result.start.qvel,
            result.start.control,
        )
        assert not np.isfinite(run[1]).all(), "called unstable, but a run of it stays finite"


def audit_coarsest(model, grid, **options):
    """`audit(model, **options)` sweeping the `n` coarsest timesteps of the audit's default grid, grid = (top [s],
    n) (sweep.default_grid below top, its largest timestep), for a test that reads the recommendation or no sweep.

    The timesteps left out are finer than the recommendation's cheapest rival: asserted here, each costs more
    counted work than the recommendation at every integrator, so none of them is ever the pick and the
    recommendation is the default grid's. The limits, the constraints and the motion do not depend on the
    swept timesteps; the finest ones were most of the sweep's CPU, and of the RK4 reference's below them.
    """
    top, swept = grid
    dts = default_grid(top)[:swept]
    result = audit(model, dts=dts, **options)
    default = grid_for(result.stability, result.duration, result.own.dt)  # the audit's own grid here
    assert dts == default[:swept]
    pick = result.recommendation
    if pick.integrator is not None:
        # the default grid's next timestep (and so every finer one) costs more counted work than the pick at
        # every integrator: steps scale as 1 / dt, each integrator's work per step is fixed
        finest = min(dts)
        cheapest = min(run.cost for run in result.runs if run.setting.dt == finest)
        assert cheapest * finest / default[swept] > pick.row.cost
    return result


def stub_the_timer(monkeypatch) -> None:
    """Make the audit's timer (about 2 s of best-of-3 runs per audit) return one constant [s per step]: it only
    fills the wall times reported beside each run, while the pick ranks counted work (on the real timer:
    test_audit.py's test_the_pick_is_the_cheapest_in_counted_work_and_no_timer_moves_it). For tests that read
    no wall time."""
    module = importlib.import_module("springlab.studies.audit.audit")  # the package's `audit` attribute is the function
    monkeypatch.setattr(module, "cost_per_step", lambda model, start, name, dt: 1e-6)
