"""Pieces every car variant shares: gravity and tendons read back from the model, modal data, the refusal
of motions that leave the car's springs or put its bottom through the ground, and the Variant interface.

The car's scenarios differ in their model (1 DOF, pitch and heave, the quarter car), so each scenario
carries its variant (`Scenario.variant`): an object with the hooks below, which `Car` delegates to
instead of dispatching on scenario names.
"""

from __future__ import annotations

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.scenes.base import Case, PhaseField, Reference
from springlab.scenes.capabilities.drawing import Drawing
from springlab.sim.simulate import Setup, Trajectory


class Variant:
    """What one kind of car scenario provides; `Car`'s hooks of the same names delegate here.

    Attributes
    ----------
    relevant
        The parameters the scenario uses, in the order summaries list them.
    """

    relevant: tuple[str, ...] = ()

    def check_consistency(self, params: dict[str, float], g: float) -> None:
        """Raise ParameterError for non-physical combinations decidable from the parameters alone."""

    def check_body_masses(self, params: dict[str, float], mjcf_inertia: tuple[float, float, float]) -> None:
        """Raise ParameterError where a moving body's mass [kg] or inertia [kg m^2] would fall below MuJoCo's
        MIN_MASS (the model would not compile); `mjcf_inertia` is the car body's (roll, pitch, yaw) in the MJCF."""

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], g: float) -> None:
        """MjSpec edits beyond the body's clearance and mass."""

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        """Initial state and controls (qpos0 and rest: the static equilibrium)."""
        raise NotImplementedError

    def reference(self, case: Case, time: np.ndarray, dt: float) -> Reference:
        """The exact solution at `time` [s] of a run with timestep `dt` [s] (Scene.reference)."""
        raise NotImplementedError

    def modes(self, case: Case) -> list[tuple[float, float]]:
        """[(natural frequency [rad/s], damping ratio [-])], for stability advice."""
        raise NotImplementedError

    def quantities(self, case: Case, trajectory: Trajectory) -> dict:
        """Named results, SI, names ending in their unit."""
        raise NotImplementedError

    def phase_field(self, case: Case) -> PhaseField | None:
        """(x, v) -> (x', v') of a one-joint variant, else None."""
        return None

    def equilibria(self, case: Case) -> list[dict]:
        """Equilibria of a one-joint variant: [{"x": position [m], "stable": bool}]."""
        return []

    def model_limits(self, case: Case, trajectory: Trajectory) -> list[str]:
        """Where the run leaves the variant's equations (see Scene.model_limits)."""
        return []

    def drawing(self, case: Case) -> Drawing:
        """What the pictures of a run show beyond the model (see Scene.drawing): nothing by default."""
        return Drawing()


def gravity(model: mujoco.MjModel) -> float:
    """g [m/s^2] from opt.gravity (the car's z axis is vertical)."""
    return -float(model.opt.gravity[2])


def tendon(model: mujoco.MjModel, name: str) -> dict:
    """A fixed tendon read back: stiffness [N/m], damping [N s/m], rest length [m], joint -> coefficient."""
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, name)
    start, count = model.tendon_adr[i], model.tendon_num[i]
    coefficients = {
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, int(model.wrap_objid[w])): float(model.wrap_prm[w])
        for w in range(start, start + count)
    }
    return {
        "stiffness": float(model.tendon_stiffness[i]),
        "damping": float(model.tendon_damping[i]),
        "rest": float(model.tendon_lengthspring[i, 0]),
        "coefficients": coefficients,
    }


def damped_modes(a: np.ndarray) -> list[tuple[float, float]]:
    """[(omega_n [rad/s], zeta [-])] of a state matrix's eigenvalues, ascending.

    An oscillatory pair gives one entry, omega_n = |lambda|, zeta = -Re(lambda) / |lambda|;
    a real root gives (|lambda|, 1), the critically damped bound, for stability advice.
    """
    out = []
    for lam in np.linalg.eigvals(a):
        if lam.imag > 0:
            out.append((abs(lam), -lam.real / abs(lam)))
        elif lam.imag == 0 and lam.real != 0:
            out.append((abs(lam), 1.0))
    return sorted(out)


def refuse_motion(what: str, fix: str, time: np.ndarray, bottoms: dict, springs: dict) -> None:
    """ParameterError if an exact motion puts the car bottom below ground or makes springs pull.

    Parameters
    ----------
    what
        The cause, e.g. 'push_mass = 250 kg at push_position = 1.2 m'.
    fix
        What to do instead.
    time
        (n,) [s].
    bottoms
        Where -> (n,) height of the car bottom there [m].
    springs
        Which -> (n,) compressive force of those springs and dampers [N].
    """
    for where, bottom in bottoms.items():
        if bottom.min() < 0.0:
            i = int(np.argmin(bottom))
            raise ParameterError(
                f"{what} drives the car bottom ({where}) through the ground (height"
                f" {bottom[i]:.4g} m at t = {time[i]:.4g} s); {fix}"
            )
    for axle, force in springs.items():
        if force.min() < 0.0:
            i = int(np.argmin(force))
            raise ParameterError(
                f"{what} lifts the car off its {axle} springs (springs and dampers would"
                f" have to pull {-force[i]:.4g} N at t = {time[i]:.4g} s); {fix}"
            )
