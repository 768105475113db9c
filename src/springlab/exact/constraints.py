"""What holds a model at a state: active constraints, contacts and dry friction (MuJoCo's constraint rows).

* `active_constraints(model, data)`: the named elements active after a forward pass.
* `ConstraintState` / `summarize_constraints`: what is active at one state, or along a run (their union).
* `watch(model, start, duration)`: a fine run from a state, stepped here to collect what becomes active along it.

`springlab.exact.model_at_point.ModelAtPoint.constraints` is what constrains a model at its operating point.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from typing import Any

import mujoco
import numpy as np

from springlab.sim.simulate import BAD_WARNINGS, Setup, integrator_id, quiet_mujoco

_CNSTR = mujoco.mjtConstraint
#: constraint row types by what they are, for people (contacts are counted per contact, not per row)
CONSTRAINT_KINDS = {
    int(_CNSTR.mjCNSTR_EQUALITY): "equality",
    int(_CNSTR.mjCNSTR_FRICTION_DOF): "dry friction",
    int(_CNSTR.mjCNSTR_FRICTION_TENDON): "dry friction",
    int(_CNSTR.mjCNSTR_LIMIT_JOINT): "joint limit",
    int(_CNSTR.mjCNSTR_LIMIT_TENDON): "tendon limit",
    int(_CNSTR.mjCNSTR_CONTACT_FRICTIONLESS): "contact",
    int(_CNSTR.mjCNSTR_CONTACT_PYRAMIDAL): "contact",
    int(_CNSTR.mjCNSTR_CONTACT_ELLIPTIC): "contact",
}
_FRICTIONAL_CONTACTS = (int(_CNSTR.mjCNSTR_CONTACT_PYRAMIDAL), int(_CNSTR.mjCNSTR_CONTACT_ELLIPTIC))


@dataclasses.dataclass(frozen=True)
class ConstraintState:
    """What constrains a model at one state (or along a run: the union over its steps).

    Attributes
    ----------
    elements
        every active constraint, e.g. "joint limit 'hip'", "contact 'foot'/'floor'", "equality 'weld'",
        "dry friction: joint 'x' (frictionloss)" (sorted; a run: every one active at some step).
    counts
        kind -> number of active elements ("contact", "joint limit", "tendon limit", "equality",
        "dry friction").
    dry_friction
        the elements whose force is dry (Coulomb) friction: joint and tendon frictionloss, and contacts
        with friction (condim >= 3): sticking and slipping are no linear dynamics.
    max_abs_qvel
        max |qvel| [m/s or rad/s] (a run: over its steps).
    max_abs_qacc
        max |qacc| [m/s^2 or rad/s^2] (a run: over its steps).
    """

    elements: tuple[str, ...]
    counts: dict[str, int]
    dry_friction: tuple[str, ...]
    max_abs_qvel: float
    max_abs_qacc: float

    @property
    def smooth(self) -> bool:
        """No constraint, contact or dry friction is active: the dynamics is one smooth function there."""
        return not self.elements

    def drift(self, duration: float) -> float:
        """How far the state moves by itself over `duration` [s], |qvel| T + |qacc| T^2 / 2 [m or rad]."""
        return self.max_abs_qvel * duration + 0.5 * self.max_abs_qacc * duration**2

    def describe(self) -> str:
        """'3 contacts, 4 joint limits (with dry friction)' or 'nothing active', for people."""
        if not self.elements:
            return "no constraint, contact or dry friction active"
        plural = {"contact": "contacts", "joint limit": "joint limits", "tendon limit": "tendon limits"}
        plural["equality"] = "equality constraints"
        parts = [f"{n} {kind if n == 1 else plural[kind]}" for kind, n in self.counts.items() if kind != "dry friction"]
        if self.dry_friction:
            parts.append(f"dry friction ({len(self.dry_friction)})")
        return ", ".join(parts)

    def to_dict(self) -> dict[str, Any]:
        """{"elements", "counts", "dry_friction", "max_abs_qvel", "max_abs_qacc"}."""
        return {
            "elements": list(self.elements),
            "counts": dict(self.counts),
            "dry_friction": list(self.dry_friction),
            "max_abs_qvel": self.max_abs_qvel,
            "max_abs_qacc": self.max_abs_qacc,
        }


def _name(model: mujoco.MjModel, kind: str, index: int) -> str:
    getter = {"joint": model.joint, "tendon": model.tendon, "equality": model.eq, "geom": model.geom}[kind]
    element = getter(int(index))
    if element.name:
        return element.name
    if kind == "geom":
        body = model.body(int(model.geom_bodyid[index]))
        return f"{body.name or 'body ' + str(body.id)} geom {index}"
    return str(index)


def active_constraints(
    model: mujoco.MjModel, data: mujoco.MjData, labels: dict[tuple[int, ...], tuple[str, str | None]] | None = None
) -> tuple[set[str], set[str]]:
    """(active elements, the dry-friction ones among them) after a forward pass in `data`
    (names as `ConstraintState.elements`).

    `labels`: the names of what a row constrains (its type and element, a contact's geoms), kept between
    the calls along one run (`watch`), which meets the same contacts and limits at many steps."""
    memo: dict[tuple[int, ...], tuple[str, str | None]] = {} if labels is None else labels
    elements: set[str] = set()
    dry: set[str] = set()
    nefc = data.nefc
    geoms = data.contact.geom
    # the rows of one contact (its friction directions) or one element share a type and id: named once
    for kind_id, index in set(zip(data.efc_type[:nefc].tolist(), data.efc_id[:nefc].tolist())):
        kind = CONSTRAINT_KINDS.get(kind_id, "constraint")
        key = (kind_id, *geoms[index].tolist()) if kind == "contact" else (kind_id, index)
        if key not in memo:
            memo[key] = _label(model, kind_id, kind, key[1:])
        label, friction = memo[key]
        elements.add(label)
        if friction is not None:
            dry.add(friction)
    return elements, dry


def _label(model: mujoco.MjModel, kind_id: int, kind: str, element: tuple[int, ...]) -> tuple[str, str | None]:
    """The name of a constraint row's element (`ConstraintState.elements`), and its dry-friction name (None: not
    dry friction); `element`: a contact's two geoms, else the row's id."""
    if kind == "contact":
        a, b = (_name(model, "geom", g) for g in element)
        friction = f"dry friction: contact {a!r}/{b!r}" if kind_id in _FRICTIONAL_CONTACTS else None
        return f"contact {a!r}/{b!r}", friction
    (index,) = element
    if kind_id == int(_CNSTR.mjCNSTR_FRICTION_DOF):
        label = f"dry friction: joint {_name(model, 'joint', int(model.dof_jntid[index]))!r} (frictionloss)"
        return label, label
    if kind_id == int(_CNSTR.mjCNSTR_FRICTION_TENDON):
        label = f"dry friction: tendon {_name(model, 'tendon', index)!r} (frictionloss)"
        return label, label
    if kind == "joint limit":
        return f"joint limit {_name(model, 'joint', index)!r}", None
    if kind == "tendon limit":
        return f"tendon limit {_name(model, 'tendon', index)!r}", None
    return f"equality {_name(model, 'equality', index)!r}", None


def summarize_constraints(elements: set[str], dry: set[str], qvel: float, qacc: float) -> ConstraintState:
    """A ConstraintState from the names `active_constraints` collected (at one state or along a run)."""
    counts: dict[str, int] = {}
    for label in sorted(elements):
        kind = "dry friction" if label.startswith("dry friction") else label.split(" '")[0]
        counts[kind] = counts.get(kind, 0) + 1
    return ConstraintState(tuple(sorted(elements)), counts, tuple(sorted(dry)), float(qvel), float(qacc))


@dataclasses.dataclass(frozen=True)
class Watch:
    """A fine run from a start: its peak speed and every constraint active along it (`watch`).

    Attributes
    ----------
    peak_speed
        max |qvel| over the run [m/s or rad/s].
    along
        the union of the constraints active at its steps (`ConstraintState`).
    dt
        its timestep [s] (RK4).
    diverged
        whether it blew up (its figures then cover the steps before).
    """

    peak_speed: float
    along: ConstraintState
    dt: float
    diverged: bool


#: the fine watch run's timestep: the model's own / WATCH_REFINE (again, if that blows up)
WATCH_REFINE = 4
_BAD = list(BAD_WARNINGS)


def watch(model: mujoco.MjModel, start: Setup, duration: float) -> Watch:
    """RK4 at the model's own timestep / WATCH_REFINE from `start` for `duration` [s], stepped here to
    read the constraints active at every step (contacts that begin, limits that engage)."""
    work = copy.copy(model)
    work.opt.integrator = integrator_id("rk4")
    dt = float(model.opt.timestep) / WATCH_REFINE
    for _ in range(2):
        work.opt.timestep = dt
        data = mujoco.MjData(work)
        elements: set[str] = set()
        dry: set[str] = set()
        peak_v = peak_a = 0.0
        diverged = False
        with quiet_mujoco():
            mujoco.mj_resetData(work, data)
            data.qpos[:] = start.qpos if start.qpos is not None else work.qpos0
            if start.qvel is not None:
                data.qvel[:] = start.qvel
            if start.act is not None and work.na:
                data.act[:] = start.act
            if start.control is not None and work.nu:
                data.ctrl[:] = np.atleast_2d(start.control)[0]
            labels: dict[tuple[int, ...], tuple[str, str | None]] = {}
            # views into `data`, read after every step (the loop is in Python: keep each step's reads few)
            qacc, qvel, warnings = data.qacc, data.qvel, data.warning.number
            for _ in range(max(1, round(duration / dt))):
                mujoco.mj_step(work, data)  # leaves the constraints and qacc of the state it started from
                if data.nefc:
                    found, friction = active_constraints(work, data, labels)
                    elements |= found
                    dry |= friction
                peak_a = max(peak_a, float(np.abs(qacc).max(initial=0.0)))
                speed = float(np.abs(qvel).max(initial=0.0))
                if not math.isfinite(speed) or warnings[_BAD].any():
                    diverged = True
                    break
                peak_v = max(peak_v, speed)
        if not diverged:
            break
        dt /= WATCH_REFINE
    return Watch(peak_v, summarize_constraints(elements, dry, peak_v, peak_a), dt, diverged)
