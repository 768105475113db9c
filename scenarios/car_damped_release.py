"""The same push-and-release with realistic dampers (damping ratio 0.3, Gillespie's 0.2-0.4).

Prints the damping ratio, the damped frequency and the logarithmic decrement,
once from the formula 2 pi zeta / sqrt(1 - zeta^2) and once measured from the
peaks of MuJoCo's simulated motion.

Run: python scenarios/car_damped_release.py
"""

import springlab

result = springlab.run("car", "damped_release")
q = result.quantities
worst = result.max_rel_error
print(
    f"damping ratio zeta = {q['damping_ratio']:.3f}"
    f" (damping {result.parameters['damping']:.1f} N s/m for the four dampers)"
)
print(
    f"omega_n = {q['omega_rad_s']:.4f} rad/s, omega_d = omega_n sqrt(1 - zeta^2) = {q['omega_d_rad_s']:.4f} rad/s"
    f" (damped period {q['damped_period_s']:.4f} s)"
)
print(
    f"logarithmic decrement: formula {q['logarithmic_decrement']:.9f}, measured from"
    f" {q['measured_extrema']} simulated extrema {q['logarithmic_decrement_measured']:.9f}"
)
undamped = q["equilibrium_height_m"] + q["static_sag_m"]
print(
    f"highest point after release {q['max_height_m'] * 1e3:.4f} mm (undamped: {undamped * 1e3:.4f} mm);"
    f" the amplitude falls by e every {q['decay_time_constant_s']:.4f} s"
)
print(
    f"max relative error vs the damped closed form: {worst:.1e}"
    f" (tolerance {result.tolerance:.1e}, passed: {result.passed})"
)
