"""Chapter 5.7's printer head, first question: How fast can we position the printer head?

One bang-bang move of the default carriage through the scene (validated against the exact 2-DOF
solution), split into the move and the settling, beside the analytic estimate and the
phase-independent worst case 2 sqrt(D M / F) + ln(A_w / band) / (zeta omega_n), A_w the damped belt's largest
ring-down after the move whatever its phase.
The second question is scenarios/printer_which_properties.py.

Run: python scenarios/printer_how_fast.py
"""

import math

import springlab

result = springlab.run("printer_head", "move")
p, q = result.parameters, result.quantities
print(
    f"belt mode {q['natural_frequency_hz']:.1f} Hz, zeta {q['damping_ratio']:.3f} (MuJoCo's linearization"
    f" {q['linearized_natural_frequency_hz']:.1f} Hz, {q['linearized_damping_ratio']:.3f});"
    f" exact-solution check passed: {result.passed}"
)
print(
    f"{q['move_distance_m'] * 1e3:.1f} mm in {q['move_time_s'] * 1e3:.1f} ms of bang-bang move"
    f" (minimum 2 sqrt(D M / F) = {q['minimum_move_time_s'] * 1e3:.2f} ms; each half"
    f" {q['half_move_belt_periods']:.2f} belt periods), residual vibration {q['residual_amplitude_m'] * 1e6:.1f} um,"
    f" inside +-{q['settling_band_m'] * 1e6:.0f} um for good {q['settling_time_s'] * 1e3:.2f} ms later:"
)
print(
    f"positioned in {q['positioning_time_s'] * 1e3:.1f} ms (estimate {q['positioning_time_estimate_s'] * 1e3:.1f} ms)"
)

# the worst case over the vibration's phase: the damped belt's envelope after a move of T = 2 sqrt(D M / F),
# (F / M) (1 + e^(-zeta omega_n T / 2))^2 / (omega_n^2 sqrt(1 - zeta^2)) (undamped: 4 F m_c m_m / (M^2 k))
m_c, m_m, force = p["carriage_mass"], p["motor_mass"], p["drive_force"]
total = m_c + m_m
omega, zeta = 2 * math.pi * q["natural_frequency_hz"], q["damping_ratio"]
shortest = q["minimum_move_time_s"]
envelope = force / total * (1 + math.exp(-zeta * omega * shortest / 2)) ** 2 / (omega**2 * math.sqrt(1 - zeta**2))
worst = shortest + math.log(envelope / p["positioning_band"]) / (zeta * omega)
print(f"worst case over the vibration's phase (envelope {envelope * 1e6:.1f} um): {worst * 1e3:.1f} ms")
