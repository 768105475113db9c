"""car's pitch_heave: the car as a 2-DOF body, heave and pitch, on front and rear axle springs (module car's docstring).

M q'' + C q' + K q = f0,   q = (heave [m], pitch [rad]),   M = diag(m, I_pitch)
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.exact import analytic
from springlab.exact.linear import generator_system
from springlab.exact.linearize import OperatingPoint, operating_point
from springlab.exact.linearize import linearize as shared_linearize
from springlab.scenes.base import MIN_MASS, MIN_MASS_REASON, Case, Reference
from springlab.sim.simulate import Setup, Trajectory

from .parts import Variant, damped_modes, gravity, refuse_motion, tendon

#: pitch_heave: share of the springs' stiffness at the front axle [-]. Below the
#: front's share of the load (b / (a + b) = 0.56), so the front rides softer
#: than the rear, as most cars do (Olley's flat-ride rule); this couples heave
#: and pitch (kf a != kr b).
FRONT_STIFFNESS_SHARE = 0.45


def pitch_heave_defaults(params: dict[str, float], explicit: set[str]) -> dict[str, float]:
    """Axle springs split from the textbook's four springs; axle dampers at damping_ratio
    of each axle's static load; the push over the front axle."""
    for axle in ("front", "rear"):
        if f"{axle}_damping" in explicit and "damping_ratio" in explicit:
            raise ParameterError(f"set either {axle}_damping [N s/m] or damping_ratio [-], not both")
    a, b, m = params["front_axle_distance"], params["rear_axle_distance"], params["mass"]
    out = {
        "front_stiffness": FRONT_STIFFNESS_SHARE * params["stiffness"],
        "rear_stiffness": (1.0 - FRONT_STIFFNESS_SHARE) * params["stiffness"],
        "push_position": a,
    }
    out.update({k: params[k] for k in ("front_stiffness", "rear_stiffness") if k in explicit})
    zeta = params["damping_ratio"]
    out["front_damping"] = 2.0 * zeta * math.sqrt(out["front_stiffness"] * m * b / (a + b))
    out["rear_damping"] = 2.0 * zeta * math.sqrt(out["rear_stiffness"] * m * a / (a + b))
    return out


class Linear2Dof:
    """pitch_heave's linear equations M q'' + C q' + K q = f0, q = (heave [m], pitch [rad]), read back."""

    def __init__(self, model: mujoco.MjModel):
        m = float(model.body("car").mass[0])
        inertia = float(model.body("car").inertia[1])
        g = gravity(model)
        stiff, damp, rest, arm = [], [], [], []
        for axle in ("front", "rear"):
            t = tendon(model, f"{axle}_suspension")
            stiff.append(t["stiffness"])
            damp.append(t["damping"])
            rest.append(t["rest"])
            arm.append(t["coefficients"]["pitch"])  # d(length)/d(pitch): -a front, +b rear
            if t["coefficients"]["heave"] != 1.0:
                raise ValueError(f"{axle}_suspension must have coefficient 1 on heave")
        self.a, self.b = -arm[0], arm[1]
        jac = np.array([[1.0, arm[0]], [1.0, arm[1]]])  # axle lengths = jac @ q
        self.jacobian = jac
        self.axle_stiffness, self.axle_damping, self.axle_rest = np.array(stiff), np.array(damp), np.array(rest)
        self.mass = np.diag([m, inertia])
        self.stiffness = jac.T @ np.diag(stiff) @ jac
        self.damping = jac.T @ np.diag(damp) @ jac
        # constant generalized force: spring preloads and gravity
        self.preload = jac.T @ (np.array(stiff) * np.array(rest)) + np.array([-m * g, 0.0])
        self.equilibrium = np.linalg.solve(self.stiffness, self.preload)

    @classmethod
    def of(cls, case: Case) -> Linear2Dof:
        """The case's linear equations, read back once per case (its setup, reference, modes and quantities share
        them)."""
        return case.memo("linear_2dof", lambda: cls(case.model))


def push_force(model: mujoco.MjModel, params: dict[str, float]) -> np.ndarray:
    """Generalized force (heave [N], pitch [N m]) of the passers-by's weight pushing down at push_position."""
    force = params["push_mass"] * gravity(model)
    station = params["push_position"]
    return np.array([-force, force * station])  # height there = heave - station * pitch


def axle_force(
    linear: Linear2Dof, axle: int, x: np.ndarray, theta: np.ndarray, vel: Mapping[str, np.ndarray]
) -> np.ndarray:
    """Compressive force [N] of one axle's springs and dampers along a motion."""
    jac = linear.jacobian[axle]
    length = jac[0] * x + jac[1] * theta
    rate = jac[0] * vel["heave"] + jac[1] * vel["pitch"]
    return linear.axle_stiffness[axle] * (linear.axle_rest[axle] - length) - linear.axle_damping[axle] * rate


def undamped_modes(mass: np.ndarray, stiffness: np.ndarray) -> list[tuple[float, np.ndarray]]:
    """[(omega [rad/s], unit mode shape (heave, pitch), heave >= 0)] of K phi = omega^2 M phi, ascending."""
    values, vectors = np.linalg.eig(np.linalg.solve(mass, stiffness))
    out = []
    for i in np.argsort(values.real):
        shape = vectors[:, i].real / np.linalg.norm(vectors[:, i].real)
        out.append((math.sqrt(values[i].real), shape if shape[0] >= 0 else -shape))
    return out


def linearize(model: mujoco.MjModel, qpos: np.ndarray) -> dict[str, np.ndarray]:
    """MuJoCo's continuous-time linearization at rest at `qpos` = (heave [m], pitch [rad]): M, C, K (nv x nv).

    springlab.exact.linearize.linearize: centred differences of MuJoCo's inverse dynamics f(q, v, a),
    M = df/da, C = df/dv, K = df/dq; `model` is not modified.
    """
    point = operating_point(model, None)
    full = model.qpos0.copy()
    for name, value in zip(("heave", "pitch"), qpos):
        full[model.joint(name).qposadr[0]] = value
    at_rest = OperatingPoint(qpos=full, qvel=np.zeros(model.nv), act=point.act, ctrl=point.ctrl, label="equilibrium")
    linear = shared_linearize(model, at_rest)
    return {"M": linear.M, "C": linear.C, "K": linear.K}


class PitchHeave(Variant):
    """Pushed down at push_position (default: over the front axle) and released."""

    relevant = (
        "mass",
        "pitch_inertia",
        "front_axle_distance",
        "rear_axle_distance",
        "front_stiffness",
        "rear_stiffness",
        "front_damping",
        "rear_damping",
        "damping_ratio",
        "clearance",
        "push_mass",
        "push_position",
    )

    def check_body_masses(self, params: dict[str, float], mjcf_inertia: tuple[float, float, float]) -> None:
        """Roll and yaw inertias scale with pitch_inertia (`edit`): the smallest must reach MIN_MASS."""
        lowest = MIN_MASS * mjcf_inertia[1] / min(mjcf_inertia)
        if params["pitch_inertia"] < lowest:
            raise ParameterError(
                f"pitch_inertia must be a finite number >= {lowest:.4g} kg m^2 (roll and yaw inertias scale"
                f" with it; {MIN_MASS_REASON}), got {params['pitch_inertia']!r}"
            )

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], g: float) -> None:
        """The pitch hinge through the CoM and the axle springs as fixed tendons (module docstring)."""
        car, heave = spec.body("car"), spec.joint("heave")
        m, a, b = params["mass"], params["front_axle_distance"], params["rear_axle_distance"]
        heave.stiffness = [0.0, 0.0, 0.0]  # the springs are the axle tendons now
        heave.damping = [0.0, 0.0, 0.0]
        # only the pitch axis turns: roll and yaw inertias follow it in the MJCF's proportion, so
        # MuJoCo's triangle inequality (A + B >= C) holds for any pitch_inertia (identical at the default)
        roll, pitch, yaw = (float(i) for i in car.inertia)
        scale = params["pitch_inertia"] / pitch
        car.inertia = [roll * scale, params["pitch_inertia"], yaw * scale]
        com = list(car.ipos)
        car.add_joint(name="pitch", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 1.0, 0.0], pos=com)
        # the picture follows the parameters: axle sites, hubs and wheels at a and b
        for site, wheel_site, x in (("front_axle", "hub_front", com[0] + a), ("rear_axle", "hub_rear", com[0] - b)):
            spec.site(site).pos = [x, *list(spec.site(site).pos)[1:]]
            spec.site(wheel_site).pos = [x, *list(spec.site(wheel_site).pos)[1:]]
        for side in ("left", "right"):
            for axle, x in (("front", com[0] + a), ("rear", com[0] - b)):
                geom = spec.geom(f"wheel_{axle}_{side}")
                geom.pos = [x, *list(geom.pos)[1:]]
        clearance, length = params["clearance"], a + b
        for axle, k, c, coef, load in (
            ("front", params["front_stiffness"], params["front_damping"], -a, m * g * b / length),
            ("rear", params["rear_stiffness"], params["rear_damping"], b, m * g * a / length),
        ):
            # length = heave + coef * pitch = clearance at rest; preload = the axle's static load
            rest = clearance + load / k
            spring = spec.add_tendon(
                name=f"{axle}_suspension", stiffness=[k, 0.0, 0.0], damping=[c, 0.0, 0.0], springlength=[rest, rest]
            )
            spring.wrap_joint("heave", 1.0)
            spring.wrap_joint("pitch", coef)

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        model, params = case.model, case.params
        qpos = model.qpos0.copy()
        linear = Linear2Dof.of(case)
        q0 = linear.equilibrium + np.linalg.solve(linear.stiffness, push_force(model, params))
        qpos[model.joint("heave").qposadr[0]], qpos[model.joint("pitch").qposadr[0]] = q0
        self._check_motion(case, np.arange(steps + 1) * dt, dt)
        return Setup(qpos=qpos, qvel=np.zeros(model.nv))

    def _check_motion(self, case: Case, time: np.ndarray, dt: float) -> None:
        """ParameterError if the exact motion puts the bottom below ground or makes an axle's springs pull."""
        reference = self.reference(case, time, dt)
        params = case.params
        linear = Linear2Dof.of(case)
        x, theta = reference.pos["heave"], reference.pos["pitch"]
        stations = {"front axle": linear.a, "rear axle": -linear.b, "push position": params["push_position"]}
        refuse_motion(
            f"push_mass = {params['push_mass']:g} kg at push_position = {params['push_position']:g} m",
            "use a smaller push_mass",
            time,
            {where: x - station * theta for where, station in stations.items()},
            {
                "front": axle_force(linear, 0, x, theta, reference.vel),
                "rear": axle_force(linear, 1, x, theta, reference.vel),
            },
        )

    def reference(self, case: Case, time: np.ndarray, dt: float) -> Reference:
        model, params = case.model, case.params
        linear = Linear2Dof.of(case)
        q0 = linear.equilibrium + np.linalg.solve(linear.stiffness, push_force(model, params))
        q, v = analytic.linear_response(
            time, linear.mass, linear.damping, linear.stiffness, q0, np.zeros(2), force=linear.preload
        )
        # z = (q, v, 1): the preloads and gravity as a constant generator state
        system = generator_system(
            linear.mass, linear.damping, linear.stiffness, forcing=linear.preload[:, None], generator=[[0.0]]
        )
        states = np.column_stack([q, v, np.ones_like(time)])
        return Reference(
            pos={"heave": q[:, 0], "pitch": q[:, 1]},
            vel={"heave": v[:, 0], "pitch": v[:, 1]},
            system=system,
            states=states,
            rows={"heave": (0, 2), "pitch": (1, 3)},
        )

    def modes(self, case: Case) -> list[tuple[float, float]]:
        linear = Linear2Dof.of(case)
        return damped_modes(analytic.state_matrix(linear.mass, linear.damping, linear.stiffness))

    def quantities(self, case: Case, trajectory: Trajectory) -> dict:
        model, params = case.model, case.params
        linear = Linear2Dof.of(case)
        measured = linearize(model, linear.equilibrium)
        analytic_modes = undamped_modes(linear.mass, linear.stiffness)
        mujoco_modes = undamped_modes(measured["M"], measured["K"])
        q0 = linear.equilibrium + np.linalg.solve(linear.stiffness, push_force(model, params))
        out: dict = {
            "initial_heave_offset_m": float(q0[0] - linear.equilibrium[0]),
            "initial_pitch_rad": float(q0[1]),
        }
        for i, (omega, shape) in enumerate(mujoco_modes, start=1):
            out[f"omega_{i}_rad_s"] = omega
            out[f"frequency_{i}_hz"] = omega / (2 * math.pi)
            if abs(shape[0]) > 1e-12:
                out[f"mode_{i}_pitch_per_heave_rad_m"] = shape[1] / shape[0]
            if abs(shape[1]) > 1e-12:
                # the station (ahead of the centre of mass) that stays still in this mode: x - s theta = 0
                out[f"mode_{i}_node_m"] = shape[0] / shape[1]
        for i, (omega, _) in enumerate(analytic_modes, start=1):
            out[f"omega_{i}_analytic_rad_s"] = omega
        damped = damped_modes(analytic.state_matrix(measured["M"], measured["C"], measured["K"]))
        # frequency_i_hz above is undamped (K phi = omega^2 M phi); the damping ratio belongs to the damped
        # eigenvalue lambda, whose own natural frequency |lambda| differs once C is not proportional to K
        for i, (omega, zeta) in enumerate(damped, start=1):
            out[f"mode_{i}_damping_ratio"] = zeta
            out[f"mode_{i}_natural_frequency_hz"] = omega / (2 * math.pi)
            out[f"omega_d_{i}_rad_s"] = omega * math.sqrt(max(1 - zeta * zeta, 0.0))
        exact = {"M": linear.mass, "C": linear.damping, "K": linear.stiffness}
        out["linearization_max_rel_diff"] = max(
            float(np.max(np.abs(measured[n] - exact[n])) / np.max(np.abs(exact[n])))
            for n in exact
            if np.max(np.abs(exact[n])) > 0
        )
        heave, pitch = model.joint("heave"), model.joint("pitch")
        out["max_heave_deviation_m"] = float(
            np.max(np.abs(trajectory.qpos[:, heave.qposadr[0]] - linear.equilibrium[0]))
        )
        out["max_pitch_rad"] = float(np.max(np.abs(trajectory.qpos[:, pitch.qposadr[0]])))
        return out
