"""What the printer head's control figures show, computed here (scene layer) and drawn by springlab.plots.control.

* `shaper_curves`: each shaper's exact residual vibration V over +-30 % of belt-frequency error (the shaper as
  applied on the step grid, designed at the nominal belt), with MuJoCo's points: the shaped move run on belts
  detuned by the error, its residual envelope at the command's end over the unshaped move's on the same belt
  (both MuJoCo's, from the state at each command's end).
* `step_responses`: the sampled loop's 1 mm step on each encoder, MuJoCo's encoder at the samples beside the
  exact sampled loop's (springlab.exact.sampled_loop.step_response of the belt plant read from the model).
* `side_by_side`: the unshaped and a shaped move filmed in one model (two printer heads, one above the other,
  by MjSpec attach), each carriage's and motor's deviation from its centre of mass drawn `exaggeration` times
  larger, so the belt's ringing (micrometres) shows on a 25 mm move.
Frequencies [Hz], times [s], positions [m].
"""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np

from springlab.exact import sampled_loop, shaping

from .control import belt_plant, output_row
from .moves import belt_damping_ratio, belt_omega
from .scene import SCENE

__all__ = ["ShaperCurve", "SideBySide", "StepResponse", "shaper_curves", "side_by_side", "step_responses"]

#: the frequency errors at which MuJoCo runs the shaped moves for the curves' points [-]
CURVE_POINTS = (-0.3, -0.2, -0.1, -0.05, 0.0, 0.05, 0.1, 0.2, 0.3)
#: the second copy's offset below the first [m] (the carriage is 5 cm tall with its cartridge)
_OFFSET = 0.09


@dataclasses.dataclass(frozen=True)
class ShaperCurve:
    """One shaper's robustness: V [-] over frequency errors [-], exact and MuJoCo's.

    Attributes
    ----------
    name
        The shaper ("zv", "mzv", "zvd", "ei").
    errors, vibration
        The exact curve: true belt frequency f_s (1 + error), V of the applied shaper there.
    point_errors, point_vibration
        MuJoCo's: the shaped move's residual envelope over the unshaped move's, on belts detuned by the errors.
    duration_s
        The time the applied shaper adds [s].
    """

    name: str
    errors: np.ndarray
    vibration: np.ndarray
    point_errors: np.ndarray
    point_vibration: np.ndarray
    duration_s: float


def _envelope_at_end(case_params: dict[str, float], scenario: str, end_time: float, dt: float) -> float:
    """MuJoCo's ring-down envelope [m] of the carriage at `end_time` [s] (the command's end): from the state there."""
    case = SCENE.case(scenario, case_params)
    run = case.simulate(SCENE.integrator, dt, end_time)
    (q_c, v_c), (q_m, v_m) = case.joint_columns(run)["carriage"], case.joint_columns(run)["motor"]
    p = case.params
    m_c, m_m, k = p["carriage_mass"], p["motor_mass"], p["belt_stiffness"]
    omega = float(belt_omega(k, m_c, m_m))
    zeta = belt_damping_ratio(p["belt_damping"], k, m_c, m_m)
    stretch, rate = q_m[-1] - q_c[-1], v_m[-1] - v_c[-1]
    omega_d = omega * math.sqrt(1 - zeta * zeta)
    return m_m / (m_c + m_m) * math.hypot(stretch, (rate + zeta * omega * stretch) / omega_d)


def shaper_curves(dt: float = SCENE.dt, points: tuple[float, ...] = CURVE_POINTS) -> list[ShaperCurve]:
    """The shapers' exact curves and MuJoCo's points at the defaults (module docstring)."""
    nominal = SCENE.case("move_zv").params
    design = {k: nominal[k] for k in ("shaper_frequency_hz", "shaper_damping_ratio")}
    zeta = design["shaper_damping_ratio"]
    errors = np.linspace(-0.3, 0.3, 241)
    curves = []
    for name in shaping.SHAPERS:
        applied = shaping.on_grid(shaping.make_shaper(name, design["shaper_frequency_hz"], zeta), dt)
        exact = applied.vibration(design["shaper_frequency_hz"] * (1 + errors), zeta)
        measured = []
        for error in points:
            # the belt detuned, its damping ratio kept: stiffness x (1 + e)^2, damping x (1 + e)
            belt = {
                "belt_stiffness": nominal["belt_stiffness"] * (1 + error) ** 2,
                "belt_damping": nominal["belt_damping"] * (1 + error),
            }
            move = SCENE.case("move", belt)
            n, _ = SCENE.move_profile(move.params, dt)
            unshaped = _envelope_at_end(belt, "move", 2 * n * dt, dt)
            shaped = _envelope_at_end(belt | design, f"move_{name}", 2 * n * dt + applied.duration, dt)
            measured.append(shaped / unshaped)
        curves.append(ShaperCurve(name, errors, exact, np.array(points), np.array(measured), applied.duration))
    return curves


@dataclasses.dataclass(frozen=True)
class StepResponse:
    """A loop's step response at its samples [s]: MuJoCo's encoder and the exact sampled loop's [m].

    Attributes
    ----------
    encoder
        "motor" or "carriage".
    time, measured, exact
        Sample times [s], MuJoCo's encoder reading [m] and the exact sampled loop's [m].
    reference
        The set point [m].
    gain_margin_db, phase_margin_deg
        The loop's margins [dB], [deg].
    """

    encoder: str
    time: np.ndarray
    measured: np.ndarray
    exact: np.ndarray
    reference: float
    gain_margin_db: float
    phase_margin_deg: float


def step_responses(step: float = 1e-3, duration: float = 0.2) -> list[StepResponse]:
    """Each loop's step of `step` [m] (no path, no feedforward) over `duration` [s], MuJoCo against exact."""
    out = []
    for encoder in ("motor", "carriage"):
        case = SCENE.case(f"feedback_{encoder}", {"planned_move_time": 0.0, "move_distance": step})
        run = case.simulate(SCENE.integrator, SCENE.dt, duration)
        q = case.quantities(run)
        p = case.params
        pid = sampled_loop.Pid(p["kp"], p["kd"], p["ki"], 1 / p["control_rate_hz"])
        per_sample = round(pid.period / SCENE.dt)
        samples = (len(run.time) - 1) // per_sample
        phi, gamma = sampled_loop.zoh(*belt_plant(case.model), pid.period)
        exact, _, _ = sampled_loop.step_response(phi, gamma, output_row(encoder), pid, step, samples)
        measured = case.joint_columns(run)[encoder][0][: samples * per_sample + 1 : per_sample]
        time = run.time[: samples * per_sample + 1 : per_sample]
        out.append(StepResponse(encoder, time, measured, exact, step, q["gain_margin_db"], q["phase_margin_deg"]))
    return out


@dataclasses.dataclass(frozen=True)
class SideBySide:
    """Two moves filmed in one model: the model, the times [s] and the drawn positions (exaggerated), the label.

    Attributes
    ----------
    model
        Two printer heads, the second `_OFFSET` below the first (its names prefixed "shaped_").
    time
        Recording times [s] from 0.
    qpos
        (n, 4) drawn positions [m]: each joint at its centre of mass plus `exaggeration` times its deviation.
    label
        What is drawn, for the frame.
    exaggeration
        The factor on each carriage's and motor's deviation from its centre of mass [-].
    """

    model: mujoco.MjModel
    time: np.ndarray
    qpos: np.ndarray
    label: str
    exaggeration: float


def _two_heads() -> mujoco.MjModel:
    """The printer head and a copy below it, each belt drawn (the copy's drawing renamed to its prefixed sites)."""
    spec, copy = SCENE.model_spec(), SCENE.model_spec()
    frame = spec.worldbody.add_frame(pos=[0.0, 0.0, -_OFFSET])
    spec.attach(copy, prefix="shaped_", frame=frame)
    for text in spec.texts:
        if text.name == "shaped_belt:belt":
            drive, clamp, *style = text.data.split()
            text.name = "belt:shaped_belt"
            text.data = " ".join([f"shaped_{drive}", f"shaped_{clamp}", *style])
    return spec.compile()


def side_by_side(shaper: str = "zv", duration: float = 0.1, exaggeration: float = 200.0) -> SideBySide:
    """The minimum-time move (top) and the same move shaped by `shaper` (bottom), run for `duration` [s]."""
    runs = []
    for scenario in ("move", f"move_{shaper}"):
        case = SCENE.case(scenario)
        run = case.simulate(SCENE.integrator, SCENE.dt, duration)
        columns = case.joint_columns(run)
        q_c, q_m = columns["carriage"][0], columns["motor"][0]
        m_c, m_m = case.params["carriage_mass"], case.params["motor_mass"]
        centre = (m_c * q_c + m_m * q_m) / (m_c + m_m)
        runs.append((run.time, centre + exaggeration * (q_c - centre), centre + exaggeration * (q_m - centre)))
    model = _two_heads()
    qpos = np.zeros((len(runs[0][0]), model.nq))
    for prefix, (_, carriage, motor) in zip(("", "shaped_"), runs):
        qpos[:, model.joint(f"{prefix}carriage").qposadr[0]] = carriage
        qpos[:, model.joint(f"{prefix}motor").qposadr[0]] = motor
    label = f"top: unshaped, bottom: {shaper.upper()}; belt ×{exaggeration:g}"
    return SideBySide(model, runs[0][0], qpos, label, exaggeration)
