"""The facts an audit is made of, each a frozen object with its `to_dict()` (its entry in audit.json): the
model's own setting, how the start excites the model, the operating point's state, the linearity verdict's
measure, the reference and the timings. `results.Audit` holds them.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from springlab.exact.constraints import ConstraintState

#: what a run of a setting shows, one word each: "stable" (bounded, below any confirmed limit), and past a
#: confirmed limit "blows up" (MuJoCo flags it or its speed runs away), "spins" (a hinge turns over and keeps
#: turning), "saturates" (it grows, then stops growing: a nonlinear model's amplitude is bounded), "grows" (still
#: growing at the run's end) or "bounded" (the run did not grow within its steps, though runs just above the limit do)
BEHAVIOURS = ("stable", "blows up", "spins", "saturates", "grows", "bounded")


@dataclasses.dataclass(frozen=True)
class OwnSetting:
    """The model's own setting (its integrator and timestep) as the audit found it.

    Attributes
    ----------
    integrator
        the model's integrator.
    dt
        its timestep [s].
    stable
        no run of it blew up: its sweep run over the duration, and (where its timestep is at or above a
        confirmed limit, or the limit comes from runs) a brute-force run at it. Never False from an
        unconfirmed figure.
    error
        its run's error [-] (None: it diverged).
    margin
        its integrator's `limit_dt_s` / dt [-] (None: no limit).
    wall_time_s
        steps x its integrator's measured time per step [s] (reported, never ranked on).
    margin_confirmed
        whether runs confirm the limit behind `margin` (None: no limit).
    cost
        its counted work [DOF-evaluations] (springlab.studies.settings.counted_cost), what the
        recommendation's cost is compared with.
    behaviour
        what a run of it shows, one word (BEHAVIOURS): "stable" below its limit (or with none), else "blows up",
        "spins", "saturates", "grows" or "bounded" (past a confirmed limit, the run did not grow within its steps).
        Only "stable" is stable.
    growth
        how many times its start's deviation from the operating point the run reached [-] (None: not measured,
        or it blew up).
    """

    integrator: str
    dt: float
    stable: bool
    error: float | None
    margin: float | None
    wall_time_s: float
    margin_confirmed: bool | None = None
    cost: float = math.nan
    behaviour: str = "stable"
    growth: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "own_setting": {"integrator", "dt", "stable", "error", "margin", "wall_time_s",
        "margin_confirmed", "cost", "behaviour", "growth"}."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class Excitation:
    """How the audit's start moves the model, and whether the motion reached every degree of freedom.

    Attributes
    ----------
    qpos
        every degree of freedom is moved by between perturb / 2 and perturb [m or rad] (seeded signs).
    qvel
        ... and given a velocity of between qvel / 2 and qvel [m/s or rad/s] (perturb / duration).
    ctrl
        every actuator's control is offset by this fraction of its half range (1 where unlimited) [-]
        and held (None: no actuator, or a scene's scenario start).
    moved
        degrees of freedom the fine run from the start changes by more than MOTION_FRACTION x perturb.
    still
        the names of those it does not (they are not verified by any error).
    source
        "perturbed operating point" or "scenario start".
    """

    qpos: float
    qvel: float
    ctrl: float | None
    moved: int
    still: tuple[str, ...]
    source: str

    @property
    def any_motion(self) -> bool:
        """Whether anything moved at all (else nothing was verified)."""
        return self.moved > 0

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "excitation": {"qpos", "qvel", "ctrl", "moved", "still", "source"}."""
        return {
            "qpos": self.qpos,
            "qvel": self.qvel,
            "ctrl": self.ctrl,
            "moved": self.moved,
            "still": list(self.still),
            "source": self.source,
        }


@dataclasses.dataclass(frozen=True)
class PointReport:
    """The operating point as the audit found it: what constrains it, whether it is at rest, and what
    constrains the motion from the start.

    Attributes
    ----------
    settle_s
        how long the model was left to settle before (None: not settled) [s].
    at_point
        the constraints, contacts and dry friction active at the operating point.
    along_motion
        those active at any step of a fine run from the start (`springlab.exact.constraints.watch`).
    at_rest
        |qvel| T + |qacc| T^2 / 2 (T the duration) within REST_FRACTION x perturb: an equilibrium.
    drift_m
        that drift [m or rad].
    linear_map
        whether MuJoCo's one-step map is the dynamics (nothing of `along_motion` is active), so the
        limits come from it; otherwise they come from nonlinear runs.
    creep
        the bodies dry friction holds (Coulomb margin above 1) that creep at the point
        (springlab.studies.audit.creep.CreepFinding): MuJoCo's soft-friction model error.
    settling_helps
        whether a run from the point moves at most half as much over its second half as over its first, so
        settling longer would bring it closer to rest (None: not measured).
    """

    settle_s: float | None
    at_point: ConstraintState
    along_motion: ConstraintState
    at_rest: bool
    drift_m: float
    linear_map: bool
    creep: tuple[Any, ...] = ()
    settling_helps: bool | None = None

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "operating_point_state": {"settle_s", "at_point", "along_motion", "at_rest",
        "drift_m", "linear_map", "creep", "settling_helps"}."""
        return {
            "settle_s": self.settle_s,
            "at_point": self.at_point.to_dict(),
            "along_motion": self.along_motion.to_dict(),
            "at_rest": self.at_rest,
            "drift_m": self.drift_m,
            "linear_map": self.linear_map,
            "creep": [c.to_dict() for c in self.creep],
            "settling_helps": self.settling_helps,
        }


@dataclasses.dataclass(frozen=True)
class Linearity:
    """How far the linearization moves along the motion: the linear-or-not verdict's measure.

    Attributes
    ----------
    change
        max relative change of A over states of the motion [-] (inf: the probe run diverged).
    tolerance
        the largest change for which the linearization's exact solution is the reference [-].
    """

    change: float
    tolerance: float

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "linearity": {"change", "tolerance"}."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class ReferenceUsed:
    """The reference the sweep's errors are measured against.

    Attributes
    ----------
    kind
        what it is, for people.
    error_estimate
        its own estimated error [-] (0 for the exact solution).
    dt
        its timestep [s] (None for the exact solution).
    converged
        error_estimate within REFERENCE_FRACTION x tol.
    compared_at
        where the runs are compared with it, for people.
    common_time_spacing_s
        the common multiple of the swept timesteps [s]: every run has a step there.
    """

    kind: str
    error_estimate: float
    dt: float | None
    converged: bool
    compared_at: str
    common_time_spacing_s: float

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "reference"."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class Timings:
    """Wall time of each stage of the audit [s]."""

    linearization_and_limits_s: float
    sweep_s: float
    reference_s: float
    total_s: float

    def to_dict(self) -> dict[str, float]:
        """audit.json's "timings_s"."""
        return dataclasses.asdict(self)
