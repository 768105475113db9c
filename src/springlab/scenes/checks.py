"""Scalar claims a scene holds a run to when it has no exact trajectory (`Scene.checks`).

Each builder returns a `springlab.scenes.declarations.Check` (measured value, independent reference,
tolerance, basis) for one joint named by the caller, so any scene can use them:

* `linearization_check`: MuJoCo's own acceleration of a joint, finite-differenced at an
  equilibrium, against the closed-form rate sqrt(|V''(x_e)| / m);
* `energy_drift_check`: a conserved energy's drift against a promised bound;
* `richardson_check`: a value measured from the run (a period, an event time) against an
  independent reference, with the run's error estimated from a second run at dt/2;
* `observed_order_check`: self-convergence of runs at dt, dt/2, dt/4 against the integrator's
  order, for runs without any closed-form reference.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from springlab.exact import events

from .declarations import Check

#: safety factor on estimated errors (as in springlab.runs.compare)
SAFETY = 2.0
#: round-off allowance per step, relative (as in springlab.runs.compare)
ROUNDOFF_PER_STEP = 100 * np.finfo(float).eps
#: accepted deviation of the observed from the formal order of convergence [-]: half an order,
#: halfway to the neighbouring orders, so a genuine loss of order (e.g. a held control) fails
CONVERGENCE_ORDER_TOLERANCE = 0.5

_EPS = np.finfo(float).eps


def joint_jacobian(model: mujoco.MjModel, joint: str, x_e: float, step: float) -> np.ndarray:
    """[[0, 1], [da/dx, da/dv]] [1/s^2, 1/s]: MuJoCo's acceleration a = qacc of `joint` linearized at
    (x_e [m or rad], v = 0), every other coordinate at 0 and at rest (e.g. an exciter).

    da/dx: centred differences with steps `step` and step/2, Richardson-combined, which is exact (to
    round-off) for a force polynomial of degree <= 4; da/dv: a centred difference (exact for linear
    damping). The continuous dynamics are differenced: the 'discrete' integrator folds h^2 K into qacc
    itself, so the forward pass runs with RK4's (the model's integrator is restored).
    """
    data = mujoco.MjData(model)
    qpos_adr, dof = model.joint(joint).qposadr[0], model.joint(joint).dofadr[0]

    def acceleration(x, v):
        data.qpos[:] = 0.0
        data.qvel[:] = 0.0
        data.qpos[qpos_adr], data.qvel[dof] = x, v
        mujoco.mj_forward(model, data)
        return float(data.qacc[dof])

    def centred(h):
        return (acceleration(x_e + h, 0.0) - acceleration(x_e - h, 0.0)) / (2 * h)

    integrator = model.opt.integrator
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    try:
        da_dx = events.richardson_extrapolate(centred(step), centred(step / 2), 2)
        velocity_step = 1.0  # [m/s]; the damping force is linear in v
        da_dv = (acceleration(x_e, velocity_step) - acceleration(x_e, -velocity_step)) / (2 * velocity_step)
    finally:
        model.opt.integrator = integrator
    return np.array([[0.0, 1.0], [da_dx, da_dv]])


def linearization_check(
    name: str,
    model: mujoco.MjModel,
    joint: str,
    x_e: float,
    step: float,
    rate_squared: float,
    largest_acceleration: float,
    basis: str,
) -> Check:
    """sqrt(|da/dx|) of `joint` at x_e (joint_jacobian) against sqrt(|rate_squared|) [1/s].

    Tolerance: 2 x the round-off of the Richardson-combined differences, (4 x 2 / h + 2 / h) / 3 =
    10/3 eps |a| / h with |a| `largest_acceleration` at the probes [m/s^2], allowing 10 eps per
    evaluation of MuJoCo's force, relative to |rate_squared| [1/s^2]; a square root halves it.
    """
    jacobian = joint_jacobian(model, joint, x_e, step)
    relative = 10 * (10 / 3) * _EPS * largest_acceleration / step / abs(rate_squared) + 100 * _EPS
    return Check(
        name=name,
        value=math.sqrt(abs(jacobian[1, 0])),
        reference=math.sqrt(abs(rate_squared)),
        tolerance=SAFETY * 0.5 * relative,
        basis=basis,
    )


def energy_drift_check(drift: float, limit: float, basis: str) -> Check:
    """'energy_drift_relative': a measured relative drift [-] of a conserved energy against `limit` [-]."""
    return Check("energy_drift_relative", drift, 0.0, limit, basis)


def richardson_check(
    name: str,
    value: float,
    value_half: float,
    order: int,
    reference: float,
    reference_error: float,
    steps: int,
    basis: str,
) -> Check:
    """A value measured from a run at dt against an independent reference.

    Tolerance (relative): 2 x the Richardson error estimate of `value` from `value_half`, the same
    measured on a run at dt/2 with an integrator of order `order`, + the reference's own error
    estimate, + 100 eps per step of the run.
    """
    estimate = events.richardson_error(value, value_half, order)
    tolerance = (SAFETY * estimate + reference_error) / reference + ROUNDOFF_PER_STEP * steps
    return Check(name, value, reference, tolerance, basis)


def observed_order_check(positions: list[np.ndarray], order: int, window: float) -> Check:
    """'observed_order': log2 |x(dt) - x(dt/2)| / |x(dt/2) - x(dt/4)| against the integrator's order.

    Parameters
    ----------
    positions
        Three series of one coordinate at dt, dt/2, dt/4, sampled at the same times.
    order
        The integrator's formal order.
    window
        The time they span [s] (for the basis line).
    """
    n = min(len(p) for p in positions)
    coarse = float(np.max(np.abs(positions[0][:n] - positions[1][:n])))
    fine = float(np.max(np.abs(positions[1][:n] - positions[2][:n])))
    observed = math.log2(coarse / fine) if fine > 0 and coarse > 0 else math.nan
    return Check(
        "observed_order",
        observed,
        float(order),
        CONVERGENCE_ORDER_TOLERANCE / order,
        f"no closed form: |x(dt) - x(dt/2)| / |x(dt/2) - x(dt/4)| over the first {window:g} s must"
        f" show the integrator's order {order} within +-{CONVERGENCE_ORDER_TOLERANCE:g}",
        certifies_error=False,  # a diagnostic of convergence, not an error of the motion
    )
