"""`springlab audit` on models nobody here wrote: the MJCF files shipped in dm_control's suite.

Robots (`ROBOTS`): the audit reports the constraints, contacts and dry friction MuJoCo has at the operating
point, every limit it reports is confirmed by runs made here or labelled unconfirmed, the own setting is
called unstable only if a run of it blows up, every degree of freedom is moved, and the recommendation meets
tol against an independent reference (with that reference's own error added: resting contacts cost RK4 its
order).

Each audits without error, and its recommended setting meets the tolerance against an independent
reference computed here: MuJoCo's RK4 at a timestep far below the audit's, run with mujoco.rollout
(not springlab's runner), itself checked converged (its distance to the run at twice its timestep is
at most a tenth of tol), and the error measured here at (up to 500 of) the recommended run's
steps with mj_differentiatePos. The reference's step: about half of each case's `reference` step, which
keeps omega_max h <= 0.02 on the model's fastest mode (RK4's error, (omega h)^4 / 120 per radian, is then
~1e-9: far inside tol / 10) where the motion is smooth, and is 2e-5 s where contacts take RK4's order
away; the convergence check measures what the step gives, so a step too coarse fails it, never passes. Durations: the humanoid and the cheetah first touch the floor at 0.22 s and
0.13 s; the cheetah's run includes its landing, the humanoid's stops before (a falling humanoid's
contacts are chaotic: no RK4 reference converges in reasonable time, which `springlab audit` reports).
"""

from __future__ import annotations

import pathlib

import dm_control  # a test-only dependency (the `test` extra)
import mujoco
import numpy as np
import pytest
from mujoco import rollout

from helpers.audit import audit_coarsest, check_limits_honest
from springlab.sim.simulate import INTEGRATORS

SUITE = pathlib.Path(dm_control.__file__).parent / "suite"
_FULL = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)

#: the reference step where contacts take RK4's order away (the cheetah's landing, a robot lying on the floor) [s]
CONTACT_REFERENCE = 2e-5

CASES = {
    # model: (duration [s], tol [-], reference step [s], swept grid (helpers/audit.py: audit_coarsest)): the smooth
    # ones' fastest modes are 4.6 (pendulum), 3.9 (cartpole) and 7.2 rad/s (acrobot), so omega_max h <= 0.004 at
    # h ~ 5e-4 s (module docstring), and their picks are rk4 at 0.1 or 0.05 s, 10 or 20 steps: 3 or 4 timesteps of
    # the 12 can cost as little; the cheetah's 4 finest timesteps, 2.3e-4 to 2.9e-5 s, were half its sweep's CPU
    "pendulum": (1.0, 1e-3, 1e-3, (0.1, 3)),
    "cartpole": (1.0, 1e-3, 1e-3, (0.1, 3)),
    "acrobot": (1.0, 1e-3, 1e-3, (0.1, 4)),
    "cheetah": (0.3, 2e-2, CONTACT_REFERENCE, (0.03, 8)),
    # the humanoid: in ROBOTS below, lying on the floor (issue 25), where its contacts are the hard case
}


def _states(model, integrator, dt, duration, start, times):
    """qpos, qvel at `times` [s] (multiples of dt) of a run from `start`, by mujoco.rollout."""
    work = model.__copy__()
    work.opt.integrator = INTEGRATORS[integrator]
    work.opt.timestep = dt
    data = mujoco.MjData(work)
    data.qpos[:], data.qvel[:] = start.qpos, start.qvel
    if start.act is not None:
        data.act[:] = start.act
    state0 = np.empty(mujoco.mj_stateSize(work, _FULL))
    mujoco.mj_getState(work, data, state0, _FULL)
    steps = round(duration / dt)
    control = np.tile(start.control, (1, steps, 1)) if work.nu else None
    states, _ = rollout.rollout(work, data, state0[None], control, nstep=steps)
    states = np.concatenate([state0[None], states[0]])
    rows = np.round(np.asarray(times) / dt).astype(int)
    return states[rows, 1 : 1 + work.nq], states[rows, 1 + work.nq : 1 + work.nq + work.nv]


def _error(model, qpos, qvel, ref_qpos, ref_qvel, origin):
    """max(|dq|_inf / max |q_ref - origin|_inf, |dv|_inf / max |v_ref|_inf) over the checkpoints."""
    dq = np.zeros(model.nv)

    def distance(a, b):
        mujoco.mj_differentiatePos(model, dq, 1.0, b, a)
        return np.max(np.abs(dq))

    err_q = max(distance(a, b) for a, b in zip(qpos, ref_qpos))
    scale_q = max(distance(b, origin) for b in ref_qpos)
    err_v = np.max(np.abs(qvel - ref_qvel))
    return max(err_q / scale_q, err_v / np.max(np.abs(ref_qvel)))


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_dm_control_model_audits_and_its_recommendation_meets_tol(name, untimed):
    duration, tol, reference_step, grid = CASES[name]
    path = SUITE / f"{name}.xml"
    result = audit_coarsest(str(path), grid, tol=tol, duration=duration)
    pick = result.recommendation
    assert pick.verified, result.message
    model = mujoco.MjModel.from_xml_path(str(path))
    steps = round(result.duration / pick.dt)
    times = np.arange(0, steps + 1, max(1, steps // 500)) * pick.dt  # the recommended run's steps
    # RK4 at about half the case's reference step; it and twice it divide the recommended dt
    fine = pick.dt / (2 * max(1, round(pick.dt / reference_step)))
    reference = _states(model, "rk4", fine, result.duration, result.start, times)
    coarser = _states(model, "rk4", 2 * fine, result.duration, result.start, times)
    origin = result.linear.point.qpos
    assert _error(model, *coarser, *reference, origin) <= tol / 10  # the reference itself has converged
    chosen = _states(model, pick.integrator, pick.dt, result.duration, result.start, times)
    assert _error(model, *chosen, *reference, origin) <= tol


#: robot models with contacts, joint limits, dry friction or no position-dependent force (the reacher, as the
#: swimmer): name -> (settle [s], duration [s], tol [-], reference step [s], swept grid (helpers/audit.py:
#: audit_coarsest)); the walker and the humanoid audited lying on the floor. The reacher's fastest mode is 227 rad/s
#: (omega_max h <= 0.012 at h ~ 5e-5 s), the finger's 1510 rad/s (0.015 at ~1e-5 s; module docstring). The
#: humanoid's 2e-5 and 4e-5 s left out took 15360 of the 21130 steps per integrator of its default sweep
ROBOTS = {
    "reacher": (None, 1.0, 1e-3, 1e-4, (1 / 68, 6)),
    "finger": (None, 0.5, 1e-3, 2e-5, (0.05, 11)),
    "walker": (4.0, 0.5, 1e-2, CONTACT_REFERENCE, (0.05, 11)),
    "humanoid": (3.0, 0.2, 1e-2, CONTACT_REFERENCE, (0.02, 10)),
}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(ROBOTS))
def test_robot_audit_reports_its_constraints_and_claims_only_what_runs_confirm(name, untimed):
    settle, duration, tol, reference_step, grid = ROBOTS[name]
    path = SUITE / f"{name}.xml"
    result = audit_coarsest(str(path), grid, settle_s=settle, tol=tol, duration=duration)
    model = mujoco.MjModel.from_xml_path(str(path))
    state = result.point_state
    # constraints are reported where MuJoCo has them, and then the limits come from runs
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = result.linear.point.qpos, result.linear.point.qvel
    mujoco.mj_forward(model, data)
    assert state.at_point.smooth == (data.nefc == 0)
    if not state.linear_map:
        assert all(limit.method == "nonlinear runs" for limit in result.stability.values())
    if np.any(model.dof_frictionloss):
        assert any("frictionloss" in element for element in state.at_point.dry_friction)
    check_limits_honest(result, model)
    # every degree of freedom the model lets move is moved: nothing is "verified" by a model at rest
    assert result.excitation.any_motion and result.excitation.qvel > 0
    pick = result.recommendation
    if pick.integrator is None:
        assert "no swept setting meets tol" in result.message
        return
    steps = round(result.duration / pick.dt)
    times = np.arange(0, steps + 1, max(1, steps // 500)) * pick.dt
    fine = pick.dt / (2 * max(1, round(pick.dt / reference_step)))  # it and twice it divide the recommended dt
    reference = _states(model, "rk4", fine, result.duration, result.start, times)
    coarser = _states(model, "rk4", 2 * fine, result.duration, result.start, times)
    origin = result.linear.point.qpos
    # on a robot resting in contact RK4 loses its order: the difference to twice the step bounds the
    # reference's own error (order >= 1), and the recommendation must meet tol with that error added
    reference_error = _error(model, *coarser, *reference, origin)
    assert reference_error <= tol / 5
    chosen = _states(model, pick.integrator, pick.dt, result.duration, result.start, times)
    assert _error(model, *chosen, *reference, origin) + reference_error <= tol
