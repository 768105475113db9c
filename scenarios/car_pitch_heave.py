"""The car as a 2-DOF body (heave + pitch): natural frequencies and mode shapes, and the
motion after the passers-by push down over the front axle and let go.

Frequencies and mode shapes come from MuJoCo's own linearization
(mjd_inverseFD: M, C, K at the static equilibrium) and are checked against the
textbook 2x2 eigenproblem; the motion against the exact linear solution.

Run: python scenarios/car_pitch_heave.py
"""

import math

import springlab

result = springlab.run("car", "pitch_heave")
q = result.quantities
p = result.parameters
print(
    f"a = {p['front_axle_distance']} m, b = {p['rear_axle_distance']} m, I = {p['pitch_inertia']} kg m^2,"
    f" kf = {p['front_stiffness']:.4g} N/m, kr = {p['rear_stiffness']:.4g} N/m"
)
for i, name in ((1, "bounce"), (2, "pitch")):
    node = q[f"mode_{i}_node_m"]
    print(
        f"mode {i} ({name}): {q[f'frequency_{i}_hz']:.4f} Hz"
        f" (analytic {q[f'omega_{i}_analytic_rad_s'] / (2 * math.pi):.4f} Hz),"
        f" {q[f'mode_{i}_pitch_per_heave_rad_m']:+.4f} rad of pitch per m of heave,"
        f" still point {abs(node):.3f} m {'ahead of' if node > 0 else 'behind'} the centre of mass,"
        f" damping ratio {q[f'mode_{i}_damping_ratio']:.3f}"
    )
print(
    f"MuJoCo's linearization vs the hand-written M, C, K: max relative difference {q['linearization_max_rel_diff']:.1e}"
)
print(
    f"push over the front axle: heave {q['initial_heave_offset_m'] * 1e3:+.4f} mm,"
    f" pitch {q['initial_pitch_rad'] * 1e3:+.4f} mrad (nose down)"
)
print(f"max relative error vs the exact linear motion: {result.max_rel_error:.1e} (passed: {result.passed})")
