"""Friction creep at the audit's operating point, and whether settling longer would bring the model to rest.

A body that Coulomb friction holds (its margin above 1: friction could carry more than the force it carries)
but that MuJoCo lets slide at a steady speed is creeping: MuJoCo's soft-friction model error. A converged run of
the same model creeps just as much, so the sweep's errors (against such a run, or the linearization) cannot see
it, and no integrator or timestep removes it; `springlab friction-settings MODEL.xml` measures it and finds the
settings that stop it. `creep_at` reads both findings off the run of the model's own setting from the operating
point, unperturbed, controls held, over the audit's duration (springlab.exact.point_facts measures it;
springlab.studies.held: what dry friction holds, each body's slip, its Coulomb margin).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import mujoco
import numpy as np

from springlab.errors import BadInputError, DivergedError
from springlab.exact.model_at_point import ModelAtPoint
from springlab.sim.simulate import Trajectory
from springlab.studies.held import coulomb_margin, plan_at, track

#: settling longer "measurably helps" when the motion over the second half of a run from the point is at most
#: this fraction of the motion over its first half (it is dying out)
SETTLING_HELPS = 0.5


@dataclasses.dataclass(frozen=True)
class CreepFinding:
    """A body that dry friction holds but that creeps at the operating point.

    Attributes
    ----------
    body
        its name.
    speed_m_s
        its creep velocity at the model's own setting [m/s] (mean speed over the second half of the run).
    coulomb_margin
        how many times the force friction carries it could carry [-] (above 1: Coulomb friction holds it).
    lost_at_s
        when it left the bodies holding it in the run [s] (None: still held).
    """

    body: str
    speed_m_s: float
    coulomb_margin: float
    lost_at_s: float | None

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "creep" entry: {"body", "speed_m_s", "coulomb_margin", "lost_at_s"}."""
        return dataclasses.asdict(self)


def creep_at(
    at: ModelAtPoint, rest: Trajectory | DivergedError | None, duration: float, drift_limit: float
) -> tuple[tuple[CreepFinding, ...], bool | None]:
    """(the creeping bodies, whether settling longer measurably helps) at the operating point.

    Parameters
    ----------
    at
        the model at its operating point.
    rest
        the run from the point at the model's own setting over the audit's duration (`PointFacts.rest`), or the
        DivergedError it raised.
    duration
        the audit's duration [s] (the hold the plan states).
    drift_limit
        a body creeps when it slips more than this over the run [m] (the audit's rest threshold).

    Returns
    -------
    The findings, and whether the motion of the run's second half is at most SETTLING_HELPS of its first half's
    (`_settling_helps`; None: the run diverged, or was not run).
    """
    if not isinstance(rest, Trajectory):
        return (), None
    model = at.model
    try:
        plan, _, _ = plan_at(at, "the model", hold_s=duration)
    except BadInputError:  # no dry friction holds a body here
        return (), _settling_helps(model, rest)
    findings = []
    for j, body in enumerate(track(model, rest, plan)):
        if body.slip_m <= drift_limit:
            continue
        margin = coulomb_margin(model, rest, plan, j, body.margin_state)
        if margin is not None and margin > 1:
            name = model.body(plan.bodies[j]).name or str(plan.bodies[j])
            findings.append(CreepFinding(name, body.creep_velocity_m_s, margin, body.lost_at_s))
    return tuple(findings), _settling_helps(model, rest)


def _settling_helps(model: mujoco.MjModel, trajectory: Trajectory) -> bool:
    """Whether the run's motion over its second half is at most SETTLING_HELPS of its first half's: per half, the
    largest range (max - min) of any degree of freedom, in the tangent space from the half's first state (an
    oscillation that keeps its amplitude does not help, nor does a steady creep; a decay does)."""
    middle = len(trajectory.time) // 2
    return _range(model, trajectory, middle, len(trajectory.time)) <= SETTLING_HELPS * _range(
        model, trajectory, 0, middle + 1
    )


def _range(model: mujoco.MjModel, trajectory: Trajectory, start: int, stop: int) -> float:
    """Largest range of any degree of freedom over rows start..stop-1 (at most 400 of them) [m or rad]."""
    rows = np.unique(np.linspace(start, stop - 1, min(stop - start, 400)).astype(int))
    moved = np.zeros((len(rows), model.nv))
    for k, row in enumerate(rows):
        mujoco.mj_differentiatePos(model, moved[k], 1.0, trajectory.qpos[start], trajectory.qpos[row])
    return float(np.max(moved.max(axis=0) - moved.min(axis=0), initial=0.0))
