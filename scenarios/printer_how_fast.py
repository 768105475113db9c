"""Chapter 5.7's printer head, first question: How fast can we position the printer head?

One bang-bang move of the default carriage through the scene (validated against the exact 2-DOF
solution), split into the move and the settling, beside the analytic estimate and the
phase-independent worst case 2 sqrt(D M / F) + ln(4 F m_c m_m / (M^2 k band)) / (zeta omega_n).
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

# the worst case over the vibration's phase: residual envelope 4 F m_c m_m / (M^2 k)
m_c, m_m, k, force = p["carriage_mass"], p["motor_mass"], p["belt_stiffness"], p["drive_force"]
total = m_c + m_m
omega, zeta = 2 * math.pi * q["natural_frequency_hz"], q["damping_ratio"]
envelope = 4 * force * m_c * m_m / (total**2 * k)
worst = q["minimum_move_time_s"] + math.log(envelope / p["positioning_band"]) / (zeta * omega)
print(f"worst case over the vibration's phase (envelope {envelope * 1e6:.0f} um): {worst * 1e3:.1f} ms")
