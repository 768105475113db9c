"""Where the audit's runs start, what the start moves, and whether the operating point is at rest.

The start: a shipped scene's scenario state where it differs from the operating point; otherwise the operating
point perturbed along every degree of freedom, velocity and control (`start_of`). The excitation: which
degrees of freedom a fine run from the start moves (`excitation`): those it leaves still are verified by no
error. The point: what constrains it and the motion, and its drift over the duration (`point_report`).
"""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np

from springlab.errors import BadInputError, DivergedError
from springlab.exact.constraints import ConstraintState
from springlab.exact.model_at_point import ModelAtPoint
from springlab.sim.simulate import Setup, Trajectory, beyond_mujoco_limits

from .limits import Watch
from .parts import Excitation, PointReport
from .source import Source

#: a degree of freedom "moved" when the fine run from the start changes it by more than this x perturb
MOTION_FRACTION = 1e-2
#: the operating point is "at rest" when its drift, |qvel| T + |qacc| T^2 / 2 over the duration T, stays
#: within this x perturb (the motion the audit itself starts)
REST_FRACTION = 1.0
#: where a start comes from
PERTURBED, SCENARIO_START = "perturbed operating point", "scenario start"


@dataclasses.dataclass(frozen=True)
class Start:
    """Where every run of the audit starts.

    Attributes
    ----------
    setup
        the initial state and held control of every run.
    control_offset
        every actuator's control offset as a fraction of its half range [-] (None: no actuator, or a scene's
        scenario start).
    source
        PERTURBED ("perturbed operating point") or SCENARIO_START ("scenario start").
    """

    setup: Setup
    control_offset: float | None
    source: str

    @property
    def perturbed(self) -> bool:
        """Whether the start is the perturbed operating point (not a scene's scenario start)."""
        return self.source == PERTURBED


def start_of(at: ModelAtPoint, perturb: float, duration: float, source: Source) -> Start:
    """Every run's start (`Start`): a scene's scenario state where it differs from the operating point, else
    the perturbed operating point (`perturbed_start`); either checked against the model's valid range
    (`check_perturbation`)."""
    point = at.point
    start = None
    if source.start is not None and source.start.qpos is not None:
        qvel = np.asarray(source.start.qvel if source.start.qvel is not None else point.qvel, float)
        qpos = np.asarray(source.start.qpos, float)
        if np.any(qpos != point.qpos) or np.any(qvel != point.qvel):  # a scenario driven by inputs alone does not
            start = Start(Setup(qpos, qvel, point.act, point.ctrl), None, SCENARIO_START)  # move here: perturb it
    start = start or perturbed_start(at, perturb, duration)
    check_perturbation(at.model, perturb, start.setup)
    return start


def perturbed_start(at: ModelAtPoint, perturb: float, duration: float) -> Start:
    """The operating point moved by between perturb / 2 and perturb [m or rad] along every degree of freedom,
    given a velocity of between perturb / duration / 2 and perturb / duration [m/s or rad/s] along every one
    (so a model with no position-dependent force moves too), and, for an actuated model, every control offset
    by perturb x its half range (1 where unlimited), held. Signs and sizes are seeded, so audits repeat."""
    model, point = at.model, at.point
    rng = np.random.default_rng(0)

    def pattern(size: int) -> np.ndarray:
        return rng.uniform(0.5, 1.0, size) * rng.choice([-1.0, 1.0], size)

    qpos = point.qpos.copy()
    mujoco.mj_integratePos(model, qpos, perturb * pattern(model.nv), 1.0)
    qvel = point.qvel + perturb / duration * pattern(model.nv)
    ctrl = point.ctrl.copy()
    offset = None
    if model.nu and perturb > 0:
        offset = perturb
        low, high = model.actuator_ctrlrange[:, 0], model.actuator_ctrlrange[:, 1]
        limited = np.asarray(model.actuator_ctrllimited, bool) & (high > low)
        half = np.where(limited, 0.5 * (high - low), 1.0)
        ctrl = ctrl + perturb * half * pattern(model.nu)
        ctrl = np.where(limited, np.clip(ctrl, low, high), ctrl)
    return Start(Setup(qpos, qvel, point.act.copy(), ctrl), offset, PERTURBED)


def check_perturbation(model: mujoco.MjModel, perturb: float, start: Setup) -> None:
    """BadInputError when `perturb` [m or rad] leaves the model's valid range: a rotation of pi or more, more
    than half of a limited joint's range, or a start MuJoCo itself rejects (past 1e10)."""
    rotational = {int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_BALL), int(mujoco.mjtJoint.mjJNT_FREE)}
    if perturb >= math.pi and any(int(t) in rotational for t in model.jnt_type):
        raise BadInputError(
            f"--perturb {perturb:g} rad turns a joint by half a revolution or more; a perturbation must be"
            " small (default 1e-3): use a value below pi"
        )
    for j in range(model.njnt):
        if model.jnt_limited[j] and int(model.jnt_type[j]) in (
            int(mujoco.mjtJoint.mjJNT_HINGE),
            int(mujoco.mjtJoint.mjJNT_SLIDE),
        ):
            span = float(model.jnt_range[j, 1] - model.jnt_range[j, 0])
            if perturb >= span / 2:
                name = model.joint(j).name or str(j)
                raise BadInputError(
                    f"--perturb {perturb:g} is at least half the range of joint {name!r} ({span:g}); use a value below"
                    f" {span / 2:g}"
                )
    bad = beyond_mujoco_limits(model, start.qpos, start.qvel, start.act, start.control)
    if bad is not None:
        raise BadInputError(f"--perturb {perturb:g} gives {bad} at the start, past MuJoCo's limit; use a smaller one")


def drift(point_state: ConstraintState, duration: float) -> float:
    """How far the operating point moves by itself over `duration` [m or rad]: |qvel| T + |qacc| T^2 / 2."""
    return point_state.max_abs_qvel * duration + 0.5 * point_state.max_abs_qacc * duration**2


def excitation(
    model: mujoco.MjModel, start: Start, probe: Trajectory | DivergedError, perturb: float, duration: float
) -> Excitation:
    """How `start` moves the model, and which degrees of freedom the fine run `probe` from it moved: a DOF
    moved when its position changes by more than MOTION_FRACTION x perturb (a scene's start: x 1e-9)."""
    size = perturb if start.perturbed else 0.0
    moved, still = _moved(model, probe, size)
    return Excitation(
        qpos=size, qvel=size / duration, ctrl=start.control_offset, moved=moved, still=still, source=start.source
    )


def _moved(model: mujoco.MjModel, probe: Trajectory | DivergedError, perturb: float) -> tuple[int, tuple[str, ...]]:
    """(degrees of freedom moved, names of those that did not) by the run `probe` (module docstring)."""
    if isinstance(probe, DivergedError):
        return model.nv, ()  # it moved, to the point of blowing up
    rows = np.unique(np.linspace(0, len(probe.time) - 1, min(len(probe.time), 400)).astype(int))
    change = np.zeros(model.nv)
    dq = np.zeros(model.nv)
    origin = probe.qpos[0]
    for row in rows:
        mujoco.mj_differentiatePos(model, dq, 1.0, origin, probe.qpos[row])
        change = np.maximum(change, np.abs(dq))
    threshold = MOTION_FRACTION * max(perturb, 1e-9)
    still = []
    for dof in np.flatnonzero(change <= threshold):
        joint = int(model.dof_jntid[dof])
        name = model.joint(joint).name or f"joint {joint}"
        multi = int(model.jnt_type[joint]) in (int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_BALL))
        still.append(f"{name} (dof {dof})" if multi else name)
    return int(np.count_nonzero(change > threshold)), tuple(still)


def point_report(at: ModelAtPoint, seen: Watch, settle_s: float | None, perturb: float, duration: float) -> PointReport:
    """The operating point's state: what constrains it (`at.constraints`) and the motion from the start
    (`seen`, `limits.watch`), whether it is at rest (its drift within REST_FRACTION x perturb) and whether the
    one-step map is the dynamics (nothing active at either)."""
    at_point = at.constraints
    moves = drift(at_point, duration)
    return PointReport(
        settle_s=settle_s,
        at_point=at_point,
        along_motion=seen.along,
        at_rest=moves <= REST_FRACTION * max(perturb, 1e-12),
        drift_m=moves,
        linear_map=at_point.smooth and seen.along.smooth,
    )
