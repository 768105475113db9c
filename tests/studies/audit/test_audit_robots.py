"""`springlab audit` on the models robots are made of, written here: joint limits active at the start, an
equality constraint, a keyframe away from equilibrium, a model with no position-dependent force, a damped
pendulum under gravity and a chain coupled by a tendon spring and damper.

The claims: a limit is a limit only when runs confirm it, and a setting is called unstable only when a run of
it blows up; where constraints are active the audit says so and measures the limits by runs; the operating
point is reported (what holds it, whether it is at rest) and `settle_s` brings it to rest; the start moves
every degree of freedom (velocities and controls too), and a model that does not move is "nothing verified";
each prediction is conservative or labelled an estimate. The references are independent: MuJoCo stepped here
(mujoco.rollout; an RK4 reference within tol / 10 of the run at twice its step), closed forms, and a
brute-force bisection of growth written here.

Tolerances: the brute force below bisects to 1e-4 relative on runs of 10 000 steps that count as grown past
10x (a growth of 2.3e-4 per step), so a limit is located to ~3e-4 relative; predictions called exact hold
within 1e-3 of it, and the audit's measured limit (bisected to 1e-4 on the map) within 1e-3.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from helpers.audit import audit_coarsest, check_limits_honest, rollout_run
from springlab.studies.audit.audit import audit
from springlab.studies.audit.sweep import default_grid, grid_for

BRUTE_RELATIVE = 1e-3


def ant_xml() -> str:
    """A torso on four legs above a floor; the keyframe spreads every hip onto its joint limit (30 deg)."""
    legs = ""
    for i, (x, y) in enumerate([(1, 1), (-1, 1), (-1, -1), (1, -1)]):
        legs += (
            f'<body name="leg{i}" pos="{0.2 * x} {0.2 * y} 0">'
            f'<joint name="hip{i}" type="hinge" axis="{-y} {x} 0" range="-30 30" damping="0.5"/>'
            f'<geom type="capsule" fromto="0 0 0 {0.25 * x} {0.25 * y} -0.25" size="0.04" mass="0.3"/></body>'
        )
    spread = " ".join(["0.53"] * 4)  # 30.4 deg: pressed 0.4 deg into the 30 deg limit
    return (
        '<mujoco><option timestep="0.01" integrator="RK4"/><worldbody>'
        '<geom name="floor" type="plane" size="5 5 0.1"/>'
        f'<body name="torso" pos="0 0 0.5"><freejoint/><geom type="sphere" size="0.15" mass="2"/>{legs}</body>'
        f'</worldbody><keyframe><key name="spread" qpos="0 0 0.5 1 0 0 0 {spread}"/></keyframe></mujoco>'
    )


def coupled_xml() -> str:
    """Two damped pendulums whose angles a joint equality constraint ties together."""
    arm = '<geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.02" mass="1"/>'
    return (
        '<mujoco><option timestep="0.002"/><worldbody>'
        f'<body name="a"><joint name="a" type="hinge" axis="0 1 0" damping="0.1"/>{arm}</body>'
        f'<body name="b" pos="0.3 0 0"><joint name="b" type="hinge" axis="0 1 0" damping="0.1"/>{arm}</body>'
        '</worldbody><equality><joint name="tie" joint1="a" joint2="b"/></equality></mujoco>'
    )


def pendulum_xml(damping: float, integrator: str = "Euler", angle: float = 0.0) -> str:
    """A point mass m = 2 kg on a massless rod l = 0.5 m (I = m l^2), joint damping c; keyframe at `angle`."""
    return (
        f'<mujoco><option gravity="0 0 -9.81" integrator="{integrator}" timestep="0.002"/><worldbody><body>'
        f'<joint name="swing" type="hinge" axis="0 1 0" damping="{damping}"/>'
        '<inertial pos="0 0 -0.5" mass="2" diaginertia="1e-9 1e-9 1e-9"/></body></worldbody>'
        f'<keyframe><key name="held" qpos="{angle}"/></keyframe></mujoco>'
    )


def tendon_chain_xml(n: int = 3) -> str:
    """A fixed-free chain of slides (k 100 N/m, m 1 kg) with a tendon spring (300 N/m) and damper (2 N s/m)
    between the first stretch and the last: the damping couples the modes."""
    opening = "".join(
        f'<body name="b{i}"><joint name="j{i}" type="slide" axis="1 0 0" stiffness="100"/>'
        '<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>'
        for i in range(n)
    )
    return (
        f'<mujoco><option gravity="0 0 0"/><worldbody>{opening}{"</body>" * n}</worldbody>'
        '<tendon><fixed stiffness="300" damping="2"><joint joint="j0" coef="1"/>'
        f'<joint joint="j{n - 1}" coef="-1"/></fixed></tendon></mujoco>'
    )


def two_link_xml() -> str:
    """Two damped links in a horizontal plane with motors: no gravity, no spring, no position-dependent force."""
    link = '<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="0.5"/>'
    return (
        '<mujoco><option gravity="0 0 0" timestep="0.01"/><worldbody>'
        f'<body><joint name="shoulder" type="hinge" axis="0 0 1" damping="0.1"/>{link}'
        f'<body pos="0.3 0 0"><joint name="elbow" type="hinge" axis="0 0 1" damping="0.1"/>{link}</body></body>'
        '</worldbody><actuator><motor joint="shoulder" ctrlrange="-1 1" ctrllimited="true"/>'
        '<motor joint="elbow" ctrlrange="-1 1" ctrllimited="true"/></actuator></mujoco>'
    )


def _model(xml: str) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(xml)


def _error(model, run, reference, origin):
    """max(|dq|_inf / max |q_ref - origin|, |dv|_inf / max |v_ref|) over the rows given (tangent space)."""
    dq = np.zeros(model.nv)

    def distance(a, b):
        mujoco.mj_differentiatePos(model, dq, 1.0, b, a)
        return np.max(np.abs(dq))

    (qpos, qvel), (ref_q, ref_v) = run, reference
    err_q = max(distance(a, b) for a, b in zip(qpos, ref_q))
    scale_q = max(distance(b, origin) for b in ref_q)
    return max(err_q / scale_q, np.max(np.abs(qvel - ref_v)) / np.max(np.abs(ref_v)))


#: the RK4 reference's step [s] is about half of this: omega_max h <= 0.005 on the equality model's fastest mode
#: (49 rad/s) and the two-link's (30 rad/s), so its error, (omega h)^4 / 120 per radian, is ~1e-11: far inside
#: tol / 10, which `_reference` checks against the run at twice its step
REFERENCE_STEP = 2e-4


def _reference(model, result, *control):
    """(reference, its distance to RK4 at twice its step) at the recommended run's steps: RK4 at about
    REFERENCE_STEP / 2 [s] from the audit's start (it and twice it divide the recommended dt; for RK4 the
    distance is ~15x the reference's own error)."""
    pick, start = result.recommendation, result.start
    fine = pick.dt / (2 * max(1, round(pick.dt / REFERENCE_STEP)))
    every = round(pick.dt / fine)
    runs = []
    for step, stride in ((fine, every), (2 * fine, every // 2)):
        q, v = rollout_run(model, "rk4", step, round(result.duration / step), start.qpos, start.qvel, *control)
        runs.append((q[::stride], v[::stride]))
    reference, coarser = runs
    return reference, _error(model, coarser, reference, result.linear.point.qpos)


def _grows(model, integrator, dt, steps=10_000, size=1e-6):
    """Brute force, independent of the audit: from the rest state qpos0 moved by `size` in every coordinate,
    does the deviation grow past 10x in `steps` steps (or blow up)?"""
    qpos = model.qpos0 + size
    qvel = np.full(model.nv, size)
    qp, qv = rollout_run(model, integrator, dt, steps, qpos, qvel, np.zeros(model.nu))
    end = max(np.max(np.abs(qp[-1] - model.qpos0)), np.max(np.abs(qv[-1])))
    return not np.isfinite(end) or end > 10 * size


def _brute_limit(model, integrator, guess):
    """The growth boundary [s] by bisection between guess / 2 (bounded) and 2 guess (grown), to 1e-4."""
    low, high = guess / 2, guess * 2
    assert not _grows(model, integrator, low) and _grows(model, integrator, high), integrator
    while high / low > 1 + 1e-4:
        mid = math.sqrt(low * high)
        low, high = (low, mid) if _grows(model, integrator, mid) else (mid, high)
    return math.sqrt(low * high)


# -- constraints active: no false alarm, limits from runs ------------------------------------------------


@pytest.mark.slow
def test_joint_limits_active_at_the_start_are_reported_and_never_a_false_unstable(untimed):
    model = _model(ant_xml())
    # what this test reads is the point, the limits and the own setting, none of which the swept timesteps move:
    # it sweeps the 6 coarsest of the audit's default grid here (asserted), whose 6 finer ones and the RK4
    # reference below them were 3/4 of its CPU
    dts = default_grid(0.05)[:6]
    result = audit(model, duration=0.5, integrators=["rk4", "implicit"], dts=dts)
    assert dts == grid_for(result.stability, result.duration, result.own.dt)[:6]
    state = result.point_state
    assert state.at_point.counts == {"joint limit": 4}
    assert not state.linear_map and "the linear map is not the dynamics" in result.message
    assert all(limit.method == "nonlinear runs" for limit in result.stability.values())
    assert all(limit.prediction in (None, "estimate") for limit in result.stability.values())
    # the false alarm: rk4 at 10 ms from this pose stays bounded (checked here by a run of it)
    qp, qv = rollout_run(model, "rk4", 0.01, 1000, result.start.qpos, result.start.qvel)
    assert np.isfinite(qv).all() and np.max(np.abs(qv)) < 100
    assert result.own.stable and "UNSTABLE" not in result.message
    check_limits_honest(result, model)


@pytest.mark.slow
def test_an_equality_constraint_is_reported_and_the_recommendation_meets_tol_with_motion_excited(untimed):
    model = _model(coupled_xml())
    tol = 1e-3
    # the 6 coarsest timesteps of the default grid: the pick, rk4 at 8.3 ms, has no rival finer (helpers/audit.py)
    result = audit_coarsest(model, (0.05, 6), tol=tol, duration=0.5, integrators=["euler", "rk4"])
    assert result.point_state.at_point.counts == {"equality": 1}
    assert "equality 'tie'" in result.point_state.at_point.elements
    assert not result.point_state.linear_map
    check_limits_honest(result, model)
    assert result.excitation.moved == model.nv and result.excitation.qvel > 0
    pick = result.recommendation
    assert pick.verified
    steps = round(result.duration / pick.dt)
    start = result.start
    reference, converged = _reference(model, result)
    assert converged <= tol / 10
    chosen = rollout_run(model, pick.integrator, pick.dt, steps, start.qpos, start.qvel)
    assert _error(model, chosen, reference, result.linear.point.qpos) <= tol


# -- the operating point ---------------------------------------------------------------------------------


def test_a_keyframe_away_from_equilibrium_is_warned_and_settling_brings_it_to_rest(untimed):
    model = _model(pendulum_xml(damping=0.5, angle=1.0))
    held = audit(model, duration=0.5, integrators=["euler"])
    # held at 1 rad the pendulum accelerates at g sin(1) / l = 16.5 rad/s^2: nowhere near rest
    assert held.point_state.at_point.max_abs_qacc == pytest.approx(9.81 * math.sin(1.0) / 0.5, rel=1e-6)
    assert not held.point_state.at_rest and "not at rest" in held.message
    # damped at c / (2 I) = 0.5 /s, 25 s leave 1 rad * e^-12.5 = 4e-6 rad: at rest at the bottom
    settled = audit(model, duration=0.5, integrators=["euler"], settle_s=25.0)
    assert settled.point_state.at_rest and "not at rest" not in settled.message
    assert settled.point_state.settle_s == 25.0 and "settled for 25 s" in settled.linear.point.label
    assert abs(settled.linear.point.qpos[0]) < 1e-4
    (mode,) = settled.linear.modes
    assert mode.rate_rad_s == pytest.approx(math.sqrt(9.81 / 0.5), rel=1e-6)  # |lambda| = sqrt(K / I) at the bottom


# -- excite what can move --------------------------------------------------------------------------------


def test_a_model_with_no_position_dependent_force_is_excited_and_its_recommendation_meets_tol(untimed):
    model = _model(two_link_xml())
    tol = 1e-3
    # the 6 coarsest timesteps of the default grid: the pick, rk4 at 17 ms, has no rival finer (helpers/audit.py)
    result = audit_coarsest(model, (0.1, 6), tol=tol, duration=1.0, integrators=["euler", "rk4"])
    excitation = result.excitation
    assert excitation.qvel == pytest.approx(1e-3) and excitation.ctrl == pytest.approx(1e-3)
    assert excitation.moved == model.nv and not excitation.still
    start = result.start
    assert np.all(np.abs(start.qvel) >= 0.5e-3) and np.all(np.abs(start.control) >= 0.5e-3)  # each DOF, each motor
    # the vacuous "euler at 100 ms, error 0": with the start moving, a coarse euler run is off
    coarse = [r for r in result.runs if r.integrator == "euler" and r.dt >= 0.05]
    assert coarse and all(r.error > 1e-3 for r in coarse)
    pick = result.recommendation
    assert pick.verified
    reference, converged = _reference(model, result, start.control)
    assert converged <= tol / 10
    chosen = rollout_run(
        model, pick.integrator, pick.dt, round(result.duration / pick.dt), start.qpos, start.qvel, start.control
    )
    assert _error(model, chosen, reference, result.linear.point.qpos) <= tol


def test_a_model_that_does_not_move_verifies_nothing(untimed):
    result = audit(_model(two_link_xml()), perturb=0.0, duration=0.5, integrators=["euler"])
    assert not result.excitation.any_motion and result.excitation.moved == 0
    assert not result.recommendation.verified and result.recommendation.integrator is None
    assert "no motion: nothing was verified" in result.message and "verified by a run" not in result.message


# -- predictions: every explicit force, conservative or an estimate ---------------------------------------


def test_discrete_on_a_damped_pendulum_under_gravity_has_euler_s_limit(untimed):
    # gravity is explicit in discrete (its metric takes springs and damping, not gravity), the joint damping
    # implicit as in euler: omega dt < 2 zeta + 2 sqrt(zeta^2 + 1), omega = sqrt(g / l), zeta = c / (2 I omega)
    c = 0.6
    model = _model(pendulum_xml(damping=c, integrator="discrete"))
    omega = math.sqrt(9.81 / 0.5)
    zeta = c / (2 * 2.0 * 0.5**2 * omega)
    closed = (2 * zeta + 2 * math.hypot(zeta, 1.0)) / omega
    result = audit(model, keyframe="held", duration=1.0, integrators=["discrete", "euler"])
    brute = _brute_limit(model, "discrete", closed)
    assert brute == pytest.approx(closed, rel=BRUTE_RELATIVE)
    for name in ("discrete", "euler"):
        limit = result.stability[name]
        assert limit.prediction == "exact" and limit.limit_dt_predicted_s == pytest.approx(closed, rel=1e-6), name
        assert limit.confirmed and limit.method == "linear map"
        assert limit.limit_dt_s == pytest.approx(brute, rel=BRUTE_RELATIVE), name


@pytest.mark.slow
def test_tendon_chain_predictions_are_conservative_or_marked_estimates_against_brute_force(untimed):
    model = _model(tendon_chain_xml())
    result = audit(model, duration=1.0, integrators=["euler", "implicit", "rk4", "discrete"])
    for name in ("euler", "implicit", "rk4"):
        limit = result.stability[name]
        brute = _brute_limit(model, name, limit.limit_dt_s)
        assert limit.confirmed and limit.limit_dt_s == pytest.approx(brute, rel=BRUTE_RELATIVE), name
        predicted = limit.limit_dt_predicted_s
        if limit.prediction == "exact":
            assert predicted == pytest.approx(brute, rel=BRUTE_RELATIVE), name
        else:
            assert limit.prediction == "estimate", name
        assert predicted <= brute * (1 + 2e-4) or limit.prediction == "estimate", name
    # the tendon damper is explicit in euler and couples the chain's modes: the per-mode form is an estimate
    assert result.stability["euler"].prediction == "estimate"
    assert result.stability["rk4"].prediction == "exact"
    # every force here is a spring or a damper: discrete takes them all implicitly (no limit, and none found)
    assert result.stability["discrete"].limit_dt_predicted_s is None
    assert result.stability["discrete"].limit_dt_s is None
    assert not _grows(model, "discrete", 0.5)
