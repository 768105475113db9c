"""car's frequency questions (`springlab frequency car [SCENARIO]`): the MjSpec edits that give each model its input,
and what the response means for the car.

* damped_release, the chapter's single mass on its suspension, driven by the road: the spring and the damper
  both run from the body to a road plate (a fixed tendon heave - road), so the road's motion y drives both,
      m x'' = k (y - x) + c (y' - x') (+ the preload that carries m g),
  and the body's motion per road motion is the transmissibility T = (c s + k) / (m s^2 + c s + k) exactly,
  whatever moves the road. The road plate is a body 1e12 times heavier than the car, gravity-compensated, on a
  vertical slide joint, pushed by the actuator `road_acceleration` with gear equal to its mass: its control is
  the road's acceleration [m/s^2] (a shaker under the wheels; the car's reaction changes it by m / M_road
  = 1e-12 relative). X''/Y'' = X/Y = T, so the default response, the body's acceleration `heave:acc` (comfort),
  reads the transmissibility itself. |T| < 1, the suspension isolates, above sqrt(2) omega_n whatever the
  damping: |T|^2 - 1 = m omega^2 (2 k - m omega^2) / ((k - m omega^2)^2 + (c omega)^2).
* pitch_heave: the passers-by's push as a sine, the actuator `push` (an upward force [N] at push_position, a
  fixed tendon heave - push_position pitch), to the body's pitch: both modes of the pitch plane, each named
  by its node (heave-dominated, "bounce": the node outside the wheelbase; pitch-dominated: inside). At the
  default damping (zeta 0.3 per axle) the two modes, 4.7 and 5.9 Hz, make one merged peak; lighter dampers
  (damping_ratio 0.05) show both.
* road_bump: the quarter car's road height as a control (road_bump.road_as_control).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import mujoco
import numpy as np

from springlab.exact import analytic

from .parts import damped_modes
from .pitch_heave import Linear2Dof, undamped_modes

#: the road plate's mass per car mass [-]: its motion follows the commanded acceleration to 1e-12 relative
ROAD_MASS_RATIO = 1e12
#: points of the log grid on which the isolation crossing is bracketed before brentq refines it
CROSSING_POINTS = 2000


def road_under_the_car(spec: mujoco.MjSpec, params: Mapping[str, float]) -> None:
    """damped_release's single mass with the road under its spring and damper (module docstring).

    The heave joint's spring and damper move to the fixed tendon `suspension` = heave - road (same stiffness,
    damping and rest length, so the static equilibrium stays at the clearance with the road at 0); the road is
    a gravity-compensated slide joint of mass ROAD_MASS_RATIO x the car's, driven by `road_acceleration`
    (gear = its mass: the control is the road's acceleration [m/s^2]).

    Parameters
    ----------
    spec
        damped_release's (or push_release's) spec after the scene's edits.
    params
        the scene's parameters (SI).
    """
    heave = spec.joint("heave")
    stiffness, damping, rest = float(heave.stiffness[0]), float(heave.damping[0]), float(heave.springref)
    heave.stiffness = [0.0, 0.0, 0.0]
    heave.damping = [0.0, 0.0, 0.0]
    mass = ROAD_MASS_RATIO * params["mass"]
    road = spec.worldbody.add_body(name="road", pos=[0.0, 0.0, 0.0])
    road.mass = mass
    road.inertia = [1.0, 1.0, 1.0]
    road.explicitinertial = True
    road.gravcomp = 1.0  # the plate is held against gravity: only the commanded acceleration moves it
    road.add_joint(name="road", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0.0, 0.0, 1.0])
    suspension = spec.add_tendon(
        name="suspension", stiffness=[stiffness, 0.0, 0.0], damping=[damping, 0.0, 0.0], springlength=[rest, rest]
    )
    suspension.wrap_joint("heave", 1.0)
    suspension.wrap_joint("road", -1.0)
    spec.add_actuator(
        name="road_acceleration",
        trntype=mujoco.mjtTrn.mjTRN_JOINT,
        target="road",
        gear=[mass, 0.0, 0.0, 0.0, 0.0, 0.0],
        ctrllimited=0,
    )


def single_mass(model: mujoco.MjModel) -> tuple[float, float, float]:
    """(m [kg], k [N/m], c [N s/m]) of the road-driven single mass, read back from the model."""
    tendon = model.tendon("suspension").id
    return (
        float(model.body("car").mass[0]),
        float(model.tendon_stiffness[tendon]),
        float(model.tendon_damping[tendon]),
    )


def last_crossing(
    response: Callable[[np.ndarray], np.ndarray], band: tuple[float, float], level: float = 1.0
) -> float | None:
    """The highest frequency [Hz] in the band where |H| falls through `level` (brentq on a log-grid bracket), or
    None where it does not."""
    from scipy.optimize import brentq

    grid = np.geomspace(band[0], band[1], CROSSING_POINTS)
    above = np.abs(response(grid)) >= level
    falls = np.nonzero(above[:-1] & ~above[1:])[0]
    if falls.size == 0:
        return None
    i = int(falls[-1])
    return float(
        brentq(
            lambda f: float(np.abs(response(np.array([f])))[0]) - level,
            grid[i],
            grid[i + 1],
            xtol=1e-14 * grid[i],
            rtol=4 * float(np.finfo(float).eps),
        )
    )


def isolation(
    model: mujoco.MjModel,
    params: Mapping[str, float],
    response: Callable[[np.ndarray], np.ndarray],
    resonances: tuple[Mapping[str, Any], ...],
    band: tuple[float, float],
) -> tuple[dict[str, Any], tuple[str, ...]]:
    """Where the single-mass suspension starts to isolate: |T| falls below 1 (FrequencySpec.interpret).

    Returns
    -------
    tuple
        ({"natural_frequency_hz", "damping_ratio", "isolation_frequency_hz" (from the model's response; None:
        not inside the band), "isolation_frequency_closed_form_hz" (sqrt(2) f_n)}, verdict lines).
    """
    m, k, c = single_mass(model)
    f_n = math.sqrt(k / m) / (2 * math.pi)
    zeta = c / (2 * math.sqrt(k * m))
    found = last_crossing(response, band)
    answers = {
        "natural_frequency_hz": f_n,
        "damping_ratio": zeta,
        "isolation_frequency_hz": found,
        "isolation_frequency_closed_form_hz": math.sqrt(2.0) * f_n,
    }
    where = (
        f"above {found:.4g} Hz"
        if found is not None
        else f"only above {math.sqrt(2.0) * f_n:.4g} Hz, outside the band {band[0]:.4g}-{band[1]:.4g} Hz"
    )
    lines = (
        f"isolation: the suspension passes less than the road's motion (|T| < 1) {where}; closed form √2 f_n ="
        f" {math.sqrt(2.0) * f_n:.4g} Hz (f_n = {f_n:.4g} Hz), whatever the damping (here zeta = {zeta:.3g});"
        " below it the road's motion is amplified",
    )
    return answers, lines


def push_at_the_front(spec: mujoco.MjSpec, params: Mapping[str, float]) -> None:
    """pitch_heave with the passers-by's push as an input: the actuator `push`, an upward force [N] at
    push_position (a fixed tendon heave - push_position pitch: the body's height there, so the force acts on
    heave and, through the lever push_position, on pitch).

    Parameters
    ----------
    spec
        pitch_heave's spec after the scene's edits.
    params
        the scene's parameters (SI).
    """
    station = spec.add_tendon(name="push_station")
    station.wrap_joint("heave", 1.0)
    station.wrap_joint("pitch", -params["push_position"])
    spec.add_actuator(name="push", trntype=mujoco.mjtTrn.mjTRN_TENDON, target="push_station", ctrllimited=0)


def name_modes(
    model: mujoco.MjModel,
    params: Mapping[str, float],
    response: Callable[[np.ndarray], np.ndarray],
    resonances: tuple[Mapping[str, Any], ...],
    band: tuple[float, float],
) -> tuple[dict[str, Any], tuple[str, ...]]:
    """Both pitch-plane modes, named by their node, with the resonance each one makes (FrequencySpec.interpret).

    The modes are the 2 x 2 eigenproblem K phi = omega^2 M phi of the model's own M and K (read back from its
    axle tendons); a mode's node is the station x / theta ahead of the centre of mass that stays still. A node
    outside the wheelbase (ahead of the front axle or behind the rear) makes the mode heave-dominated
    ("bounce"), inside it pitch-dominated. Each resonance belongs to the mode whose undamped frequency is
    nearest its pole's natural frequency.

    Returns
    -------
    tuple
        ({"mode_i_frequency_hz" (undamped), "mode_i_node_m", "mode_i_pitch_per_heave_rad_m", "mode_i_shape",
        "mode_i_natural_frequency_hz" and "mode_i_damping_ratio" (the damped pole's |lambda| / 2 pi and
        -Re(lambda) / |lambda|; None unless both modes ring), "mode_i_resonance_hz" (the peak; None: no peak of
        its own in this response)}, verdict lines).
    """
    linear = Linear2Dof(model)
    modes = undamped_modes(linear.mass, linear.stiffness)
    # the damped modes (the state matrix's oscillatory pairs), in the same ascending order when both ring
    damped = [d for d in damped_modes(analytic.state_matrix(linear.mass, linear.damping, linear.stiffness)) if d[1] < 1]
    damped_of = dict(enumerate(damped)) if len(damped) == len(modes) else {}
    found = [r for r in resonances if r.get("natural_frequency_hz") is not None]
    owner = {
        id(r): min(range(len(modes)), key=lambda i: abs(modes[i][0] / (2 * math.pi) - r["natural_frequency_hz"]))
        for r in found
    }
    answers: dict[str, Any] = {}
    lines = []
    for i, (omega, shape) in enumerate(modes, start=1):
        node = shape[0] / shape[1] if abs(shape[1]) > 1e-12 else math.inf
        inside = -linear.b <= node <= linear.a
        kind = "pitch-dominated" if inside else "heave-dominated (bounce)"
        peaks = [r["frequency_hz"] for r in found if owner[id(r)] == i - 1]
        peak = peaks[0] if peaks else None
        answers.update(
            {
                f"mode_{i}_frequency_hz": omega / (2 * math.pi),
                f"mode_{i}_node_m": float(node),
                f"mode_{i}_pitch_per_heave_rad_m": float(shape[1] / shape[0]) if abs(shape[0]) > 1e-12 else math.inf,
                f"mode_{i}_shape": kind,
                f"mode_{i}_natural_frequency_hz": damped_of[i - 1][0] / (2 * math.pi) if damped_of else None,
                f"mode_{i}_damping_ratio": damped_of[i - 1][1] if damped_of else None,
                f"mode_{i}_resonance_hz": peak,
            }
        )
        side = "ahead of" if node >= 0 else "behind"
        where = "inside" if inside else "outside"
        seen = (
            f"its resonance peaks at {peak:.4g} Hz"
            if peak is not None
            else "no peak of its own in this response (merged with the other mode's or hidden by a zero)"
        )
        if damped_of:
            seen = f"zeta = {damped_of[i - 1][1]:.3g}; " + seen
        lines.append(
            f"mode {i} at {omega / (2 * math.pi):.4g} Hz (undamped): {kind}, node {abs(node):.3g} m {side} the"
            f" centre of mass, {where} the wheelbase (-{linear.b:g} m to {linear.a:g} m); {seen}"
        )
    return answers, tuple(lines)
