"""The unit oscillator's contract (springlab.studies.stability, springlab.studies.extremes): the scene that is the
textbook's one-mode mass-spring-damper (`Scene.oscillator`)."""

from __future__ import annotations

import dataclasses

import mujoco


@dataclasses.dataclass(frozen=True)
class OscillatorSpec:
    """A scene that is the textbook's one-mode mass-spring-damper m x'' + d x' + k x = 0 (`Scene.oscillator`).

    springlab.studies.stability and springlab.studies.extremes run it as a unit oscillator and at
    extreme values: they pick the scene that declares this and set its parameters by these names.
    The declaring scene has one degree of freedom in its free scenario, an exact reference for it,
    and joint damping (which MuJoCo's euler, implicit and implicitfast treat implicitly).

    Attributes
    ----------
    mass, stiffness, damping
        names of the scene's parameters m [kg], k [N/m] and d [N s/m].
    x0, v0
        names of its initial position [m] and velocity [m/s] parameters.
    free
        the scenario in which it is released from (x0, v0) without forcing.
    joint
        its one joint: the model's qpos[0] and qvel[0], and the reference's column.
    """

    mass: str
    stiffness: str
    damping: str
    x0: str
    v0: str
    free: str
    joint: str

    def parameters(
        self,
        *,
        mass: float | None = None,
        stiffness: float | None = None,
        damping: float | None = None,
        x0: float | None = None,
        v0: float | None = None,
    ) -> dict[str, float]:
        """The scene's parameter overrides for m [kg], k [N/m], d [N s/m], x0 [m] and v0 [m/s], by its names
        (a value left None is left out: the scene's default holds)."""
        values = {self.mass: mass, self.stiffness: stiffness, self.damping: damping, self.x0: x0, self.v0: v0}
        return {name: value for name, value in values.items() if value is not None}

    def constants(self, model: mujoco.MjModel) -> tuple[float, float, float]:
        """(m [kg], k [N/m], d [N s/m]) read back from the compiled model: the mass of the joint's body, the
        joint's stiffness and its degree of freedom's damping."""
        joint = model.joint(self.joint)
        dof = int(joint.dofadr[0])
        mass = float(model.body_mass[int(model.jnt_bodyid[joint.id])])
        return mass, float(model.jnt_stiffness[joint.id]), float(model.dof_damping[dof])
