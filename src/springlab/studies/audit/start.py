"""The audit's start judged: the perturbation it may take, what the start moves, whether the point is at rest.

The start itself (a shipped scene's scenario state where it differs from the operating point, otherwise the
operating point perturbed along every degree of freedom, velocity and control) is made where the other facts at
the point are measured (springlab.exact.point_facts.start_near); `check_perturbation` refuses a perturbation the
model's joints cannot take, before anything is computed. The excitation: which degrees of freedom a fine run
from the start moves (`excitation`): those it leaves still are verified by no error. The point: what constrains
it and the motion, and whether its drift over the duration keeps it from rest (`point_report`, from
`PointFacts`).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from springlab.errors import BadInputError, DivergedError
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.point_facts import PointFacts, Start
from springlab.sim.simulate import Trajectory

from .parts import Excitation, PointReport

#: a degree of freedom "moved" when the fine run from the start changes it by more than this x perturb
MOTION_FRACTION = 1e-2
#: the operating point is "at rest" when its drift, |qvel| T + |qacc| T^2 / 2 over the duration T, stays
#: within this x perturb (the motion the audit itself starts)
REST_FRACTION = 1.0


def check_perturbation(model: mujoco.MjModel, perturb: float) -> None:
    """BadInputError when `perturb` [m or rad] leaves the model's valid range: a rotation of pi or more, or more
    than half of a limited joint's range (checked before anything is computed; a start MuJoCo itself rejects,
    past 1e10, is refused where it is made: springlab.exact.point_facts.start_near)."""
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


def point_report(at: ModelAtPoint, facts: PointFacts, settle_s: float | None, perturb: float) -> PointReport:
    """The operating point's state: what constrains it (`at.constraints`) and the motion from the start
    (`facts.watch`), whether it is at rest (its drift within REST_FRACTION x perturb: `rest_within`) and whether
    the one-step map is the dynamics (nothing active at either)."""
    return PointReport(
        settle_s=settle_s,
        at_point=at.constraints,
        along_motion=facts.watch.along,
        at_rest=facts.drift_m <= rest_within(perturb),
        drift_m=facts.drift_m,
        linear_map=facts.smooth,
    )


def rest_within(perturb: float) -> float:
    """The drift [m or rad] within which the operating point is at rest: REST_FRACTION x perturb (the motion the
    audit itself starts)."""
    return REST_FRACTION * max(perturb, 1e-12)
