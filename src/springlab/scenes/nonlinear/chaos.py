"""forced_duffing's chaos: the separation of twin runs, refined until converged, and Benettin's
estimate of the largest Lyapunov exponent (module nonlinear's docstring).

Functions of the scene (`springlab.scenes.nonlinear.scene.Nonlinear`), which re-runs itself at other
settings and initial states.
"""

from __future__ import annotations

import math
from typing import Protocol

import mujoco
import numpy as np

from springlab.exact import events
from springlab.scenes.base import Case
from springlab.sim.simulate import ORDERS, Trajectory

from .orbits import curvature

#: initial offset of the second forced run [m]
PERTURBATION = 1e-9
#: the separation time is refined (dt halved, at most this many times) until two successive
#: values agree within this relative difference [-]: the headline's three digits
SEPARATION_RTOL, SEPARATION_MAX_HALVINGS = 1e-3, 3
#: Lyapunov exponent by renormalization: transient skipped [s], averaging time [s], renormalization interval [s]
LYAPUNOV_TRANSIENT, LYAPUNOV_TIME, LYAPUNOV_INTERVAL = 10.0, 100.0, 1.0
#: the trajectory counts as accurate while its Richardson error estimate stays below this fraction of
#: the well size [-]
ACCURACY_FRACTION = 0.01


class ChaosScene(Protocol):
    """What these functions use of the nonlinear scene (a Protocol: scenes.nonlinear imports this module)."""

    @property
    def joints(self) -> tuple[str, ...]: ...

    def block(self, model: mujoco.MjModel, trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]: ...

    def well_size(self, case: Case) -> float: ...

    def rerun(
        self,
        case: Case,
        integrator: str,
        dt: float,
        duration: float,
        x0: float | None = None,
        v0: float | None = None,
        state: tuple | None = None,
    ) -> Trajectory: ...


def separation(scene: ChaosScene, case: Case, lead: Trajectory, twin: Trajectory) -> tuple[float, float]:
    """(time [s] the pair's positions first lie the well size apart, finite-time Lyapunov exponent [1/s]).

    The crossing of |x_twin - x| = well is located by cubic Hermite interpolation of the gap with its
    rate (springlab.exact.events, O(dt^4)). The exponent is the gap's mean growth rate up to then,
    ln(well / PERTURBATION) / t. (inf, nan): never that far apart.
    """
    x, v = scene.block(case.model, lead)
    x2, v2 = scene.block(case.model, twin)
    n = min(len(x), len(x2))
    well = scene.well_size(case)
    t_sep = events.first_crossing(lead.time[:n], x2[:n] - x[:n], v2[:n] - v[:n], well)
    if not math.isfinite(t_sep):
        return math.inf, math.nan
    return float(t_sep), math.log(well / PERTURBATION) / float(t_sep)


def chaos(scene: ChaosScene, case: Case, trajectory: Trajectory) -> dict:
    """Sensitivity to initial conditions: a second run from x0 + PERTURBATION, refined until the
    separation time converges (a claim about the physics needs a run converged for it)."""
    model, params = case.model, case.params
    x = scene.block(model, trajectory)[0]
    integrator, duration = trajectory.integrator, float(trajectory.time[-1])
    well = scene.well_size(case)
    out: dict = {"perturbation_m": PERTURBATION, "well_size_m": well}
    # level k: the pair at dt / 2^k; level 0 is this run and its twin
    leads = [trajectory]
    twin = scene.rerun(case, integrator, trajectory.dt, duration, x0=params["x0"] + PERTURBATION)
    found = [separation(scene, case, trajectory, twin)]
    converged = False
    for k in range(1, SEPARATION_MAX_HALVINGS + 1):
        dt_k = trajectory.dt / 2**k
        # the finer pair need not run far past the coarser one's separation
        previous = found[-1][0]
        span = duration if not math.isfinite(previous) else min(duration, 2.0 * previous)
        lead = scene.rerun(case, integrator, dt_k, span)
        twin = scene.rerun(case, integrator, dt_k, span, x0=params["x0"] + PERTURBATION)
        leads.append(lead)
        found.append(separation(scene, case, lead, twin))
        (coarse, _), (fine, _) = found[-2], found[-1]
        if (not math.isfinite(coarse) and not math.isfinite(fine)) or (
            math.isfinite(coarse) and abs(fine - coarse) <= SEPARATION_RTOL * fine
        ):
            converged = True
            break
    t_sep, ftle = found[-1]
    # `separated` false: the pair never separated in the run; separation_time_s and ftle_per_s are then
    # inf (null in JSON), so every key keeps one type
    out["separated"] = bool(math.isfinite(t_sep))
    out["separation_time_s"] = t_sep
    out["ftle_per_s"] = ftle if math.isfinite(t_sep) else math.inf
    out["separation_time_converged"] = converged
    out["separation_time_dt_s"] = trajectory.dt / 2 ** (len(found) - 1)
    out["separation_time_refinement_s"] = [float(t) for t, _ in found]
    out["separation_time_at_run_dt_s"] = float(found[0][0])
    # how long this trajectory itself is right: Richardson estimate from the run at dt/2
    order = ORDERS[integrator]
    xh = scene.block(model, leads[1])[0][::2]
    n = min(len(x), len(xh))
    estimate = 2**order / (2**order - 1) * np.abs(x[:n] - xh[:n])
    wrong = np.flatnonzero(estimate > ACCURACY_FRACTION * well)
    out["accurate_until_s"] = float(trajectory.time[wrong[0]]) if wrong.size else float(trajectory.time[n - 1])
    out["lyapunov_exponent_per_s"], out["lyapunov_standard_error_per_s"] = lyapunov_exponent(
        scene, case, integrator, trajectory.dt
    )
    out["lyapunov_exponent_basis"] = (
        f"estimate: mean log growth of a pair renormalized every {LYAPUNOV_INTERVAL:g} s over"
        f" {LYAPUNOV_TIME:g} s after {LYAPUNOV_TRANSIENT:g} s, at the run's setting; +- is the standard"
        " error of that finite average (statistical, not a bound), and the average is not converged"
        " in its length"
    )
    return out


def lyapunov_exponent(
    scene: ChaosScene,
    case: Case,
    integrator: str,
    dt: float,
    transient: float = LYAPUNOV_TRANSIENT,
    total: float = LYAPUNOV_TIME,
    interval: float = LYAPUNOV_INTERVAL,
) -> tuple[float, float]:
    """Largest Lyapunov exponent [1/s] by Benettin's renormalization, and its standard error [1/s].

    A companion run PERTURBATION away (in the block's (x, v / omega) plane) is pulled back
    to that distance every `interval` [s]; the exponent is the mean log growth per second
    over `total` [s] after `transient` [s]. The standard error treats the segments' growth
    rates as independent, so it is a statistical uncertainty of a finite average, not a bound.
    """
    model = case.model
    m, k1, k3, d = case.physical()
    omega = math.sqrt(abs(float(curvature(scene.well_size(case), k1, k3))) / m) or 1.0
    joint = model.joint(scene.joints[0])
    qpos_adr, dof = joint.qposadr[0], joint.dofadr[0]
    lead = scene.rerun(case, integrator, dt, transient)
    state = (lead.qpos[-1].copy(), lead.qvel[-1].copy())
    twin = (state[0].copy(), state[1].copy())
    twin[0][qpos_adr] += PERTURBATION
    rates: list[float] = []
    segments = max(1, round(total / interval))
    for _ in range(segments):
        lead = scene.rerun(case, integrator, dt, interval, state=state)
        follow = scene.rerun(case, integrator, dt, interval, state=twin)
        state = (lead.qpos[-1].copy(), lead.qvel[-1].copy())
        dx = follow.qpos[-1][qpos_adr] - state[0][qpos_adr]
        dv = follow.qvel[-1][dof] - state[1][dof]
        distance = math.hypot(dx, dv / omega)
        rates.append(math.log(distance / PERTURBATION) / interval)
        # the companion restarts on the same exciter state, PERTURBATION away along the current direction
        twin = (state[0].copy(), state[1].copy())
        twin[0][qpos_adr] += dx * PERTURBATION / distance
        twin[1][dof] += dv * PERTURBATION / distance
    samples = np.array(rates)
    # standard error of the mean rate [1/s]; one segment has no spread to measure
    error = float(np.std(samples, ddof=1) / math.sqrt(len(samples))) if len(samples) > 1 else math.inf
    return float(np.mean(samples)), error
