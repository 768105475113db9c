"""printer_head's frequency question: what the belt's resonance means for how fast the head can be positioned
(`springlab frequency printer_head`, FrequencySpec.interpret).

The drive force reaches the carriage as the rigid body 1 / (M s^2) plus the belt mode at omega_n (moves.py:
mu s'' + c s' + k s = (m_c / M) F, the carriage at -(m_m / M) s). A bang-bang move of D in time T uses the
force F = 4 M D / T^2; once it is off, an undamped belt rings with the stretch 4 sin^2(omega_n T / 4) F m_c /
(M k), the carriage with (m_m / M) of it:

    residual <= 4 F / (M omega_n^2) = 16 D / (omega_n T)^2,

which is the move's force spectrum read at the resonance: the slower the move against the belt period, the
less of its force is near omega_n. That bound is sharp only for an undamped belt. Damped, the residual is
|1 - e^{s T/2}|^2 a / (omega_n^2 sqrt(1 - zeta^2)) with s the belt's root and a = F / M (springlab.exact.positioning),
which is what these answers use:

* the quietest move: the shortest T beyond which every bang-bang move stays within the band delta after it
  ends, from the exact peak of the damped ring-down (0.0890 s at the scene's defaults; the undamped worst
  case (4 / omega_n) sqrt(D / delta) = 0.1646 s is kept as `quiet_move_time_undamped_s`);
* the minimum-time move at full force, T_min = 2 sqrt(D M / F): positioned when its exact damped ring-down
  leaves the band for good (`minimum_move_positioning_time_s`), and at worst, whatever its phase on the belt,
  T_min + ln(A_worst / delta) / (zeta omega_n) with A_worst = (1 + e^{-zeta omega_n T_min / 2})^2 F /
  (M omega_n^2 sqrt(1 - zeta^2)) (`worst_positioning_time_s`; undamped, 4 F / (M omega_n^2)).

Both read omega_n and zeta from the resonance the frequency response found (its pole). The anti-resonance of
the motor side, sqrt(k / m_c) (the carriage swinging on the belt against a motor that stands still), is what
a controller measuring at the motor cannot see: drive -> motor dips there.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import mujoco
import numpy as np

from springlab.exact import positioning as exact_positioning

from .moves import minimum_move_time, settling_estimate


def quietest_move_time(distance: float, band: float, omega_n: float) -> float:
    """Shortest bang-bang move time T [s] whose UNDAMPED residual bound 16 D / (omega_n T)^2 stays within `band`.

    The undamped worst case only (module docstring); exact.positioning.quietest_move_time is the damped answer.

    Parameters
    ----------
    distance
        move distance D [m].
    band
        positioning band delta (half-width) [m].
    omega_n
        the belt mode's natural frequency [rad/s].

    Returns
    -------
    float
        (4 / omega_n) sqrt(D / delta) [s].
    """
    return 4.0 / omega_n * math.sqrt(distance / band)


def positioning(
    model: mujoco.MjModel,
    params: Mapping[str, float],
    response: Callable[[np.ndarray], np.ndarray],
    resonances: tuple[Mapping[str, Any], ...],
    band: tuple[float, float],
) -> tuple[dict[str, Any], tuple[str, ...]]:
    """How fast the head can be positioned, from the belt's resonance (module docstring; FrequencySpec.interpret).

    Returns
    -------
    tuple
        ({"belt_frequency_hz", "belt_damping_ratio", "belt_period_s", "minimum_move_time_s",
        "minimum_move_positioning_time_s", "worst_residual_m", "worst_settling_time_s", "worst_positioning_time_s",
        "quiet_move_time_s", "quiet_move_belt_periods", "quiet_move_time_undamped_s", "motor_anti_resonance_hz"},
        verdict lines); empty without a resonance.
    """
    belt = [r for r in resonances if r.get("natural_frequency_hz") is not None]
    if not belt:
        return {}, (f"positioning: no belt resonance in the band {band[0]:.4g}-{band[1]:.4g} Hz to read it from",)
    mode = max(belt, key=lambda r: r["magnitude"])
    f_n, zeta = float(mode["natural_frequency_hz"]), float(mode["pole_damping_ratio"])
    omega_n = 2 * math.pi * f_n
    m_c, m_m = float(model.body("carriage").mass[0]), float(model.body("motor").mass[0])
    k = float(model.tendon_stiffness[model.tendon("belt").id])
    total = m_c + m_m
    force, distance, delta = params["drive_force"], params["move_distance"], params["positioning_band"]
    fastest = minimum_move_time(distance, total, force)
    residual = exact_positioning.worst_case_envelope(omega_n, zeta, distance, fastest)  # any phase, damped
    settle = settling_estimate(residual, delta, zeta, omega_n)
    quiet = exact_positioning.quietest_move_time(omega_n, zeta, distance, delta)
    undamped_quiet = quietest_move_time(distance, delta, omega_n)
    exact_fastest = exact_positioning.positioning_time(
        omega_n, zeta, *exact_positioning.bang_bang(distance, fastest), delta
    )
    answers = {
        "belt_frequency_hz": f_n,
        "belt_damping_ratio": zeta,
        "belt_period_s": 1.0 / f_n,
        "minimum_move_time_s": fastest,
        "minimum_move_positioning_time_s": exact_fastest,
        "worst_residual_m": residual,
        "worst_settling_time_s": settle,
        "worst_positioning_time_s": fastest + settle,
        "quiet_move_time_s": quiet,
        "quiet_move_belt_periods": quiet * f_n,
        "quiet_move_time_undamped_s": undamped_quiet,
        "motor_anti_resonance_hz": math.sqrt(k / m_c) / (2 * math.pi),
    }
    lines = (
        f"positioning: the belt mode at {f_n:.4g} Hz (period {1e3 / f_n:.3g} ms, zeta = {zeta:.3g}) rings after a"
        f" bang-bang move of {distance * 1e3:.4g} mm lasting T by |1 - e^(s T/2)|^2 F / (M omega_n^2 sqrt(1 - zeta^2)),"
        " s the damped belt's root",
        f"  at full force ({force:g} N) the move takes {fastest:.4g} s and its damped ring-down is inside"
        f" +-{delta * 1e6:.3g} um for good at {exact_fastest:.4g} s; whatever its phase on the belt it leaves at"
        f" most {residual * 1e6:.3g} um, inside after {settle:.3g} s more: {fastest + settle:.4g} s at worst",
        f"  every bang-bang move of {quiet:.4g} s or longer ({quiet * f_n:.3g} belt periods) rings within"
        f" +-{delta * 1e6:.3g} um (exact damped ring-down; an undamped belt would need"
        f" (4 / omega_n) sqrt(D / band) = {undamped_quiet:.4g} s)",
        f"  a controller measuring at the motor sees the carriage's own frequency sqrt(k / m_c) ="
        f" {answers['motor_anti_resonance_hz']:.4g} Hz as an anti-resonance (drive -> motor)",
    )
    return answers, lines
