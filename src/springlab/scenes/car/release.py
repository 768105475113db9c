"""car's 1-DOF scenarios, push_release and damped_release (the textbook problem; module car's docstring).

m x'' + d x' + k (x - springref) = -m g,   springref = clearance + m g / k
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.exact import analytic, events, linear
from springlab.scenes.base import Case, PhaseField, Reference
from springlab.sim.simulate import Setup, Trajectory

from .parts import Variant, gravity


def damping_from_ratio(params: dict[str, float], explicit: set[str]) -> dict[str, float]:
    """damping [N s/m] = 2 zeta sqrt(k m), unless damping itself was given (then zeta follows)."""
    if "damping" in explicit and "damping_ratio" in explicit:
        raise ParameterError("set either damping [N s/m] or damping_ratio [-], not both")
    k, m = params["stiffness"], params["mass"]
    if "damping" in explicit:
        return {"damping_ratio": params["damping"] / (2.0 * math.sqrt(k * m))}
    return {"damping": 2.0 * params["damping_ratio"] * math.sqrt(k * m)}


def one_dof(model: mujoco.MjModel) -> tuple[float, float, float, float, float]:
    """(m [kg], k [N/m], d [N s/m], springref [m], g [m/s^2]) of the 1-DOF car, read back."""
    heave = model.joint("heave")
    return (
        float(model.body("car").mass[0]),
        float(heave.stiffness[0]),
        float(model.dof_damping[heave.dofadr[0]]),
        float(model.qpos_spring[heave.qposadr[0]]),
        gravity(model),
    )


class Release(Variant):
    """Pushed down by the passers-by's weight and released: undamped, or with dampers (`damped`)."""

    def __init__(self, damped: bool):
        self.damped = damped
        self.relevant = (
            ("mass", "stiffness", "damping", "damping_ratio", "clearance", "push_mass")
            if damped
            else ("mass", "stiffness", "damping", "clearance", "push_mass")
        )

    def check_consistency(self, params: dict[str, float], g: float) -> None:
        m, k, d, clearance, push = (params[n] for n in ("mass", "stiffness", "damping", "clearance", "push_mass"))
        sag = push * g / k
        if sag >= clearance:
            raise ParameterError(
                f"push_mass = {push:g} kg pushes the car bottom {sag:.4g} m down, through the ground"
                f" (clearance {clearance:g} m); valid: push_mass < {k * clearance / g:.6g} kg"
            )
        # highest point after release: x_s + sag (undamped), less the first overshoot's decay (damped)
        zeta = d / (2.0 * math.sqrt(k * m))
        overshoot = math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta * zeta)) if zeta < 1.0 else 0.0
        if sag * overshoot > m * g / k:
            raise ParameterError(
                f"push_mass = {push:g} kg makes the car rebound {sag * overshoot:.4g} m above its rest height,"
                f" off its springs (they are compressed only {m * g / k:.4g} m by its weight);"
                f" valid: push_mass <= {m / overshoot:.6g} kg"
            )

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], g: float) -> None:
        heave = spec.joint("heave")
        m, k = params["mass"], params["stiffness"]
        heave.stiffness = [k, 0.0, 0.0]
        heave.damping = [params["damping"], 0.0, 0.0]
        heave.springref = params["clearance"] + m * g / k  # static equilibrium at the clearance

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        model, params = case.model, case.params
        qpos = model.qpos0.copy()
        m, k, d, springref, g = one_dof(model)
        qpos[model.joint("heave").qposadr[0]] = springref - (m + params["push_mass"]) * g / k  # pushed down
        return Setup(qpos=qpos, qvel=np.zeros(model.nv))

    def reference(self, case: Case, time: np.ndarray, dt: float) -> Reference:
        model, params = case.model, case.params
        m, k, d, springref, g = one_dof(model)
        rest = springref - m * g / k
        x0 = springref - (m + params["push_mass"]) * g / k
        x, v = analytic.free_response(time, m, k, d, x0 - rest, 0.0)
        # z = (x, v, 1): the spring's preload and gravity as a constant generator state
        system = linear.generator_system([[m]], [[d]], [[k]], forcing=[[k * rest]], generator=[[0.0]])
        states = np.column_stack([x + rest, v, np.ones_like(time)])
        return Reference(
            pos={"heave": x + rest}, vel={"heave": v}, system=system, states=states, rows={"heave": (0, 1)}
        )

    def modes(self, case: Case) -> list[tuple[float, float]]:
        model = case.model
        m, k, d, _, _ = one_dof(model)
        return [(math.sqrt(k / m), analytic.damping_ratio(m, k, d))]

    def phase_field(self, case: Case) -> PhaseField | None:
        model = case.model
        m, k, d, springref, g = one_dof(model)
        rest = springref - m * g / k
        return lambda x, v: (v, -(k * (x - rest) + d * v) / m)

    def equilibria(self, case: Case) -> list[dict]:
        model = case.model
        m, k, d, springref, g = one_dof(model)
        return [{"x": springref - m * g / k, "stable": True}]

    def quantities(self, case: Case, trajectory: Trajectory) -> dict:
        model, params = case.model, case.params
        m, k, d, springref, g = one_dof(model)
        rest = springref - m * g / k
        sag = params["push_mass"] * g / k
        omega = math.sqrt(k / m)
        heave = model.joint("heave")
        x = trajectory.qpos[:, heave.qposadr[0]]
        v = trajectory.qvel[:, heave.dofadr[0]]
        out: dict = {
            "static_sag_m": sag,
            "height_before_release_m": rest - sag,
            "equilibrium_height_m": rest,
            "amplitude_m": -sag,
            "omega_rad_s": omega,
            "period_s": 2 * math.pi / omega,
            "sag_under_own_weight_m": m * g / k,
        }
        if d == 0.0:
            # the phase plane (x, v): an ellipse centred at (x_s, 0), semi-axes |A| and omega |A|
            out["phase_ellipse_height_semi_axis_m"] = sag
            out["phase_ellipse_velocity_semi_axis_m_s"] = omega * sag
        out["max_height_m"] = float(np.max(x))
        out["max_speed_m_s"] = float(np.max(np.abs(v)))
        if self.damped or d > 0.0:
            zeta = analytic.damping_ratio(m, k, d)
            out["damping_ratio"] = zeta
            out["regime"] = analytic.regime(m, k, d)
            if 0.0 < zeta < 1.0:
                omega_d = analytic.damped_frequency(m, k, d)
                out["omega_d_rad_s"] = omega_d
                out["damped_period_s"] = 2 * math.pi / omega_d
                out["logarithmic_decrement"] = 2 * math.pi * zeta / math.sqrt(1 - zeta * zeta)
                peaks = events.extrema(trajectory.time, x - rest, v)
                # well above the integration error; successive same-sign extrema are one damped period apart
                peaks = peaks[np.abs(peaks[:, 1]) > 1e-3 * np.max(np.abs(peaks[:, 1]), initial=0.0)]
                if len(peaks) >= 3:
                    out["logarithmic_decrement_measured"] = float(np.mean(np.log(peaks[:-2, 1] / peaks[2:, 1])))
                    out["measured_extrema"] = int(len(peaks))
            if zeta > 0:
                out["decay_time_constant_s"] = 1.0 / (zeta * omega)
        return out
