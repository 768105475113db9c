"""What dry friction holds in a model file, and one run of the hold (springlab.studies.friction_hold's runs).

* `find_hold`: the held bodies (named, or found: free bodies in a frictional contact at the operating point,
  else bodies whose own joints have frictionloss), what holds them, their sizes and the settings that act on
  that friction (`hold_settings`), as a `HoldPlan` of plain data;
* `configure`: a copy of the model with swept settings applied;
* `run_hold` / `track`: one run from the operating point, controls held, and each held body through it (slip,
  creep velocity, when it leaves the grip); `coulomb_margin`: how much more friction could carry.
"""

from __future__ import annotations

import copy
import dataclasses
import time as _time
from collections.abc import Mapping, Sequence

import mujoco
import numpy as np

from springlab.errors import BadInputError
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.operating_point import OperatingPoint, operating_point
from springlab.scenes.capabilities.friction import CONTACT_FRICTION, JOINT_FRICTION, SolverSetting
from springlab.sim.simulate import Trajectory, simulate

#: the hold [s] when none is given
DEFAULT_HOLD_S = 10.0
#: the slip is read this often [s] (a forward pass of positions and collisions per sample: a few per cent of a
#: run's steps)
SAMPLE_S = 0.01
#: the Coulomb margin is read this far into the hold (or at the middle of the time the body is held) [s]
MARGIN_AT_S = 1.0

_ELLIPTIC = int(mujoco.mjtCone.mjCONE_ELLIPTIC)
_PYRAMIDAL = int(mujoco.mjtCone.mjCONE_PYRAMIDAL)
_FREE = int(mujoco.mjtJoint.mjJNT_FREE)


@dataclasses.dataclass(frozen=True)
class HoldPlan:
    """What a run of the hold needs, as plain data (it travels to dask workers).

    Attributes
    ----------
    qpos, qvel, act, ctrl
        the operating point: where every run starts; its controls are held [SI, actuator units].
    bodies
        the held bodies' ids.
    body_geoms
        per held body, its geoms' ids.
    holder_geoms
        per held body, the geoms of the bodies touching it at the operating point (empty: a joint's
        frictionloss holds it; it cannot leave a grip).
    sizes
        per held body, its size [m] (the length scale of tol).
    geoms
        the geoms whose solref and solimp the contact settings set (the held bodies' and those touching them).
    pairs
        explicit contact pairs among them.
    dofs
        the held bodies' degrees of freedom with frictionloss.
    baseline
        setting -> the model's own value.
    hold_s
        the hold [s].
    """

    qpos: tuple[float, ...]
    qvel: tuple[float, ...]
    act: tuple[float, ...]
    ctrl: tuple[float, ...]
    bodies: tuple[int, ...]
    body_geoms: tuple[tuple[int, ...], ...]
    holder_geoms: tuple[tuple[int, ...], ...]
    sizes: tuple[float, ...]
    geoms: tuple[int, ...]
    pairs: tuple[int, ...]
    dofs: tuple[int, ...]
    baseline: tuple[tuple[str, float], ...]
    hold_s: float


def body_size(model: mujoco.MjModel, body: int) -> float:
    """The largest extent [m] of the bounding boxes of the body's colliding geoms (all its geoms if none
    collides), in the body's frame: 0.04 m for a 40 mm cube."""
    geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == body]
    colliding = [g for g in geoms if model.geom_contype[g] or model.geom_conaffinity[g]]
    corners = []
    for g in colliding or geoms:
        center, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
        rotation = np.zeros(9)
        mujoco.mju_quat2Mat(rotation, model.geom_quat[g])
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
        local = center + signs * half
        corners.append(local @ rotation.reshape(3, 3).T + model.geom_pos[g])
    if not corners:
        return 0.0
    points = np.concatenate(corners)
    return float(np.max(points.max(axis=0) - points.min(axis=0)))


def _frictional(model: mujoco.MjModel, data: mujoco.MjData, index: int) -> bool:
    contact = data.contact[index]
    return int(contact.dim) >= 3 and float(contact.friction[0]) > 0  # touching: active, or within its margin


def _touching(model: mujoco.MjModel, data: mujoco.MjData) -> dict[int, set[int]]:
    """body -> the geoms of other bodies in a frictional contact with it, at the state in `data`."""
    out: dict[int, set[int]] = {}
    for i in range(data.ncon):
        if not _frictional(model, data, i):
            continue
        a, b = (int(g) for g in data.contact[i].geom)
        out.setdefault(int(model.geom_bodyid[a]), set()).add(b)
        out.setdefault(int(model.geom_bodyid[b]), set()).add(a)
    return out


def _body_names(model: mujoco.MjModel) -> list[str]:
    return [model.body(b).name or str(b) for b in range(1, model.nbody)]


def _friction_dofs(model: mujoco.MjModel, body: int) -> list[int]:
    return [d for d in range(model.nv) if model.dof_bodyid[d] == body and model.dof_frictionloss[d] > 0]


def _chosen_bodies(
    model: mujoco.MjModel, label: str, point: OperatingPoint, touching: Mapping[int, set[int]], names: Sequence[str]
) -> list[int]:
    """The held bodies: those named, or found (module docstring); BadInputError where none is held."""
    if names:
        known = _body_names(model)
        chosen = []
        for name in names:
            body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            if body <= 0:
                shown = ", ".join(known[:12]) + (" ..." if len(known) > 12 else "")
                raise BadInputError(f"--body {name!r}: no such body in {label}; valid: {shown}")
            if model.body_dofnum[body] == 0:
                raise BadInputError(f"--body {name!r} has no joint of its own in {label}: it cannot slip")
            if body not in touching and not _friction_dofs(model, body):
                raise BadInputError(
                    f"--body {name!r}: no dry friction holds it at {point.label} (no frictional contact, no"
                    " frictionloss on its joints)"
                )
            chosen.append(body)
        return list(dict.fromkeys(chosen))
    free = [
        b
        for b in range(1, model.nbody)
        if b in touching and any(model.jnt_type[j] == _FREE for j in range(model.njnt) if model.jnt_bodyid[j] == b)
    ]
    if free:
        return free
    joints = [b for b in range(1, model.nbody) if _friction_dofs(model, b)]
    if joints:
        return joints
    if not touching:
        raise BadInputError(
            f"no dry friction in {label} at {point.label}: no contact with friction and no joint frictionloss;"
            " friction-settings studies a body that dry friction holds"
        )
    names_touching = ", ".join(model.body(b).name or str(b) for b in sorted(touching) if b > 0)
    raise BadInputError(
        f"no free body is held by friction in {label} at {point.label}; name the held body with --body"
        f" (bodies in frictional contact: {names_touching})"
    )


def _common(values: np.ndarray) -> float | None:
    """The one value all rows share (None: they differ, or there are none)."""
    if values.size == 0 or not np.all(values == values.flat[0]):
        return None
    return float(values.flat[0])


def hold_settings(
    model: mujoco.MjModel, geoms: Sequence[int], dofs: Sequence[int], contacts: bool
) -> tuple[tuple[SolverSetting, ...], tuple[str, ...]]:
    """(the settings swept, each with the model's own value as its baseline `mujoco_default`; why any is not).

    impratio (own, 10, 100) and the cone (pyramidal, elliptic) act on contacts; NoSlip (own, 0, 3) on both;
    the time constant of solref (own, own / 4: MuJoCo raises one below 2 dt to 2 dt) and the impedance of solimp
    (d0 = dwidth: own, 0.99) of the held contacts' geoms (or frictionloss dofs), when they share one value.
    """
    acts = (CONTACT_FRICTION,) if contacts else (JOINT_FRICTION,)
    both = (JOINT_FRICTION, CONTACT_FRICTION)
    opt = model.opt
    settings = []
    skipped = []
    if contacts:
        own = float(opt.impratio)
        settings.append(SolverSetting("impratio", tuple(sorted({own, 10.0, 100.0})), own, acts, "impratio [-]"))
        own = float(int(opt.cone) == _ELLIPTIC)
        settings.append(
            SolverSetting(
                "elliptic_cone", (0.0, 1.0), own, acts, "friction cone", names={0.0: "pyramidal", 1.0: "elliptic"}
            )
        )
    own = float(opt.noslip_iterations)
    settings.append(
        SolverSetting("noslip_iterations", tuple(sorted({own, 0.0, 3.0})), own, both, "NoSlip iterations [-]")
    )
    solref = model.geom_solref[list(geoms)] if contacts else model.dof_solref[list(dofs)]
    solimp = model.geom_solimp[list(geoms)] if contacts else model.dof_solimp[list(dofs)]
    timeconst = _common(solref[:, 0]) if len(solref) else None
    if timeconst is not None and timeconst > 0:
        settings.append(
            SolverSetting(
                "solref_timeconst",
                (timeconst, timeconst / 4),
                timeconst,
                both,
                "solref time constant [s]",
                floor_in_dt=2.0,
            )
        )
    else:
        skipped.append("solref: the held contacts do not share one positive time constant")
    impedance = _common(solimp[:, 0]) if len(solimp) else None
    if impedance is not None and impedance < 0.99:
        settings.append(SolverSetting("solimp_d", (impedance, 0.99), impedance, both, "solimp d0 = dwidth [-]"))
    elif impedance is None:
        skipped.append("solimp: the held contacts do not share one impedance")
    return tuple(settings), tuple(skipped)


def find_hold(
    model: mujoco.MjModel,
    label: str,
    *,
    bodies: Sequence[str] = (),
    keyframe: str | int | None = None,
    hold_s: float = DEFAULT_HOLD_S,
) -> tuple[HoldPlan, tuple[SolverSetting, ...], tuple[str, ...], OperatingPoint]:
    """What dry friction holds at the operating point (module docstring): the plan of a run of the hold, the
    settings to sweep, those not swept (why), and the operating point.

    Raises
    ------
    BadInputError
        an unknown keyframe or body, a body without joints or without dry friction, a model without dry friction.
    """
    at = ModelAtPoint(model, operating_point(model, keyframe))
    plan, settings, skipped = plan_at(at, label, bodies=bodies, hold_s=hold_s)
    return plan, settings, skipped, at.point


def plan_at(
    at: ModelAtPoint, label: str, *, bodies: Sequence[str] = (), hold_s: float
) -> tuple[HoldPlan, tuple[SolverSetting, ...], tuple[str, ...]]:
    """`find_hold` at a model at a given operating point (a keyframe, or where the audit let the model settle):
    the plan, the settings to sweep and those not swept (why). What touches what is read from the forward pass
    at the point that `at` keeps (`ModelAtPoint.data`), so a caller that has it computes it once.

    Raises
    ------
    BadInputError
        an unknown body, a body without joints or without dry friction, a model without dry friction there.
    """
    model, point = at.model, at.point
    touching = _touching(model, at.data)
    chosen = _chosen_bodies(model, label, point, touching, bodies)
    body_geoms = tuple(tuple(g for g in range(model.ngeom) if model.geom_bodyid[g] == b) for b in chosen)
    holders = tuple(tuple(sorted(touching.get(b, set()))) for b in chosen)
    geoms = sorted({g for group in (*body_geoms, *holders) for g in group} if any(holders) else set())
    pairs = [p for p in range(model.npair) if {int(model.pair_geom1[p]), int(model.pair_geom2[p])} & set(geoms)]
    dofs = sorted(d for b in chosen for d in _friction_dofs(model, b))
    settings, skipped = hold_settings(model, geoms, dofs, contacts=any(holders))
    plan = HoldPlan(
        qpos=tuple(map(float, point.qpos)),
        qvel=tuple(map(float, point.qvel)),
        act=tuple(map(float, point.act)),
        ctrl=tuple(map(float, point.ctrl)),
        bodies=tuple(chosen),
        body_geoms=body_geoms,
        holder_geoms=holders,
        sizes=tuple(body_size(model, b) for b in chosen),
        geoms=tuple(geoms),
        pairs=tuple(pairs),
        dofs=tuple(dofs),
        baseline=tuple((s.name, s.mujoco_default) for s in settings),
        hold_s=float(hold_s),
    )
    return plan, settings, skipped


def configure(model: mujoco.MjModel, settings: Mapping[str, float], plan: HoldPlan) -> mujoco.MjModel:
    """A copy of `model` with the settings that differ from the model's own applied (`hold_settings`)."""
    work = copy.copy(model)
    baseline = dict(plan.baseline)
    geoms, pairs, dofs = list(plan.geoms), list(plan.pairs), list(plan.dofs)
    for name, value in settings.items():
        if value == baseline.get(name):
            continue
        if name == "impratio":
            work.opt.impratio = value
        elif name == "elliptic_cone":
            work.opt.cone = _ELLIPTIC if value else _PYRAMIDAL
        elif name == "noslip_iterations":
            work.opt.noslip_iterations = int(value)
        elif name == "solref_timeconst":
            work.geom_solref[geoms, 0] = value
            work.pair_solref[pairs, 0] = value
            work.dof_solref[dofs, 0] = value
        elif name == "solimp_d":
            work.geom_solimp[geoms, :2] = value
            work.pair_solimp[pairs, :2] = value
            work.dof_solimp[dofs, :2] = value
        else:
            raise KeyError(name)
    return work


@dataclasses.dataclass(frozen=True)
class Track:
    """One held body through one run.

    Attributes
    ----------
    slip_m
        max distance of its centre of mass from where the hold started while it was held [m] (a lost body: up to
        the first sample that finds it out of the grip).
    creep_velocity_m_s
        its mean speed over the second half of the time it was held [m/s].
    lost_at_s
        when it first touched none of the bodies that held it [s] (None: held throughout, or held by a joint).
    held_s
        how long it was held [s] (the run's length if it was not lost).
    margin_state
        the row of the run's trajectory where its Coulomb margin is read (MARGIN_AT_S into the hold, while held).
    """

    slip_m: float
    creep_velocity_m_s: float
    lost_at_s: float | None
    held_s: float
    margin_state: int


def track(model: mujoco.MjModel, trajectory: Trajectory, plan: HoldPlan) -> list[Track]:
    """Each held body through a run, read every SAMPLE_S (a forward pass of the positions and collisions)."""
    data = mujoco.MjData(model)
    every = max(1, round(SAMPLE_S / trajectory.dt))
    rows = list(range(0, len(trajectory.time), every))
    if rows[-1] != len(trajectory.time) - 1:
        rows.append(len(trajectory.time) - 1)
    bodies = list(plan.bodies)
    positions = np.empty((len(rows), len(bodies), 3))
    held = np.ones((len(rows), len(bodies)), bool)
    # per held body, every geom's role: 1 its own, 2 a holder's (a contact of a 1 with a 2 holds it)
    roles = np.zeros((len(bodies), model.ngeom), np.int8)
    for j, (mine, theirs) in enumerate(zip(plan.body_geoms, plan.holder_geoms)):
        roles[j, list(mine)] = 1
        roles[j, list(theirs)] = 2
    gripped = [j for j, theirs in enumerate(plan.holder_geoms) if theirs]
    for k, row in enumerate(rows):
        data.qpos[:] = trajectory.qpos[row]
        mujoco.mj_kinematics(model, data)
        positions[k] = data.xipos[bodies]
        if gripped:
            mujoco.mj_collision(model, data)
            pairs = data.contact.geom  # (ncon, 2) geom ids
            for j in gripped:
                role = roles[j][pairs]
                held[k, j] = bool(np.any(role[:, 0] * role[:, 1] == 2))
    times = trajectory.time[rows]
    out = []
    for j in range(len(bodies)):
        slip = np.linalg.norm(positions[:, j] - positions[0, j], axis=1)
        lost = np.flatnonzero(~held[:, j])
        end = int(lost[0]) if lost.size else len(rows) - 1
        half = int(np.searchsorted(times, times[end] / 2))
        span = times[end] - times[half]
        creep = float(np.linalg.norm(positions[end, j] - positions[half, j]) / span) if span > 0 else 0.0
        margin_row = rows[min(int(np.searchsorted(times, min(MARGIN_AT_S, times[end] / 2))), end)]
        out.append(
            Track(
                slip_m=float(slip[: end + 1].max()),  # what it slid while held: once out of the grip it falls
                creep_velocity_m_s=creep,
                lost_at_s=float(times[end]) if lost.size else None,
                held_s=float(times[end]),
                margin_state=int(margin_row),
            )
        )
    return out


def coulomb_margin(model: mujoco.MjModel, trajectory: Trajectory, plan: HoldPlan, j: int, row: int) -> float | None:
    """How many times the force dry friction carries on held body `j` it could carry, at `row` of a run [-]:
    sum of mu N over its held contacts / |sum of their tangential forces| (a joint hold: frictionloss / |its
    friction force|, the least over its dofs). None: friction carries no force there."""
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = trajectory.qpos[row], trajectory.qvel[row]
    if model.na:
        data.act[:] = trajectory.act[row]
    data.ctrl[:] = plan.ctrl
    mujoco.mj_forward(model, data)
    mine, theirs = set(plan.body_geoms[j]), set(plan.holder_geoms[j])
    if theirs:
        capacity, carried = 0.0, np.zeros(3)
        force = np.zeros(6)
        for i in range(data.ncon):
            contact = data.contact[i]
            a, b = (int(g) for g in contact.geom)
            if not ((a in mine and b in theirs) or (b in mine and a in theirs)) or not _frictional(model, data, i):
                continue
            mujoco.mj_contactForce(model, data, i, force)
            frame = np.asarray(contact.frame).reshape(3, 3)
            sign = -1.0 if a in mine else 1.0  # the force acts on geom 2 from geom 1
            capacity += float(contact.friction[0]) * abs(force[0])
            carried += sign * (force[1] * frame[1] + force[2] * frame[2])
        load = float(np.linalg.norm(carried))
        return capacity / load if load > 0 else None
    margins = []
    for row_index in range(data.nefc):
        if int(data.efc_type[row_index]) == int(mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF):
            dof = int(data.efc_id[row_index])
            if dof in plan.dofs and model.dof_bodyid[dof] == plan.bodies[j] and data.efc_force[row_index] != 0:
                margins.append(float(model.dof_frictionloss[dof]) / abs(float(data.efc_force[row_index])))
    return min(margins) if margins else None


def run_hold(
    model: mujoco.MjModel, plan: HoldPlan, integrator: str, dt: float, duration: float
) -> tuple[Trajectory, list[Track], float]:
    """One run of the hold from the operating point, controls held: (its trajectory, each body's track, its CPU
    time [s] on this thread). Raises DivergedError."""
    start = _time.thread_time()
    trajectory = simulate(
        model,
        integrator=integrator,
        dt=dt,
        duration=duration,
        qpos=np.array(plan.qpos),
        qvel=np.array(plan.qvel),
        act=np.array(plan.act),
        control=np.array(plan.ctrl) if model.nu else None,
    )
    cpu = _time.thread_time() - start
    return trajectory, track(model, trajectory, plan), cpu


def slip_over_hold(tracks: Sequence[Track], plan: HoldPlan, duration: float) -> list[float]:
    """Each body's slip over the whole hold [m]: measured where the run covers it or the body was lost, else
    its slip over the run plus its creep velocity over the rest of the hold."""
    rest = max(0.0, plan.hold_s - duration)
    return [t.slip_m if t.lost_at_s is not None else t.slip_m + t.creep_velocity_m_s * rest for t in tracks]
