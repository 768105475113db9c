"""A sinusoidal force that keeps the integrator's order, built in MJCF (no Python callback).

A control held over each step makes a time-varying force first order, even
under RK4. Instead, a very heavy *exciter* body on its own spring oscillates at
the forcing frequency with amplitude E = 1 m, and a fixed tendon spring couples
it to the driven joint: the coupling force on that joint is F0 sin(2 pi f t).
The exciter is integrated by the same integrator as everything else, so the
force is exactly as accurate as the motion (RK4 stays fourth order), and the
model still runs in mujoco.rollout / mujoco.batch.

Two details make it exact to 1e-12:
* the tendon adds its stiffness to the driven joint, so `add` lowers the
  joint's own linear stiffness by the same amount (the joint still sees k);
* the exciter's spring is 1e12 times stiffer than anything it drives
  (`driven_stiffness`), so the driven joint's back-reaction on it is negligible.

The exciter is internal: scenes do not report it as a joint.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

#: exciter amplitude [m]; the force scale lives in the coupling coefficient
AMPLITUDE = 1.0
#: coupling tendon stiffness [N/m], compensated in the driven joint's own stiffness
COUPLING_STIFFNESS = 1.0
#: exciter spring stiffness relative to everything it drives
STIFFNESS_RATIO = 1e12
#: names of the elements `add` creates
JOINT, TENDON = "exciter", "exciter_coupling"


def add(
    spec: mujoco.MjSpec, joint: str, *, force_amplitude: float, force_frequency: float, driven_stiffness: float
) -> None:
    """Add the exciter driving `joint` with F0 sin(2 pi f t) [N].

    Parameters
    ----------
    spec
        the model to edit; `joint` must already have its final stiffness.
    joint
        name of the driven slide joint.
    force_amplitude
        F0 [N].
    force_frequency
        f [Hz], > 0.
    driven_stiffness
        scale of everything the exciter drives [N/m] (spring,
        m omega^2, d omega, ...): the exciter is made 1e12 times stiffer.
    """
    omega = 2 * math.pi * force_frequency
    coef = force_amplitude / (COUPLING_STIFFNESS * AMPLITUDE)
    driven = spec.joint(joint)
    linear, *rest = driven.stiffness
    driven.stiffness = [linear - COUPLING_STIFFNESS, *rest]
    exciter_stiffness = STIFFNESS_RATIO * (driven_stiffness + COUPLING_STIFFNESS * coef**2 + 1.0)
    body = spec.worldbody.add_body(name=JOINT, pos=[0, 0, -1])
    body.mass = exciter_stiffness / omega**2
    body.inertia = [1.0, 1.0, 1.0]
    body.explicitinertial = True
    body.add_joint(
        name=JOINT,
        type=mujoco.mjtJoint.mjJNT_SLIDE,
        axis=[1, 0, 0],
        stiffness=[exciter_stiffness - COUPLING_STIFFNESS * coef**2, 0, 0],
    )
    tendon = spec.add_tendon(name=TENDON, stiffness=[COUPLING_STIFFNESS, 0, 0])
    tendon.wrap_joint(joint, 1.0)
    tendon.wrap_joint(JOINT, coef)


def start(model: mujoco.MjModel, qvel: np.ndarray, force_frequency: float) -> None:
    """Set the exciter's initial velocity in `qvel` so the force starts as +F0 sin(0) (f in [Hz])."""
    # e(t) = -E sin(omega t) makes the coupling force +F0 sin(omega t)
    qvel[model.joint(JOINT).dofadr[0]] = -AMPLITUDE * 2 * math.pi * force_frequency


def coupling_stiffness(model: mujoco.MjModel) -> float:
    """The coupling tendon's stiffness [N/m] added to the driven joint, 0 without an exciter."""
    tendon = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, TENDON)
    return float(model.tendon_stiffness[tendon]) if tendon >= 0 else 0.0
