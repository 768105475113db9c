"""The Erasmus bridge's fix: a damper between a stay and the deck. Which damper, and what does it buy?

For a 300 m stay with its damper 6 m from the deck: the damper that gives mode 1 the most damping (the
cable's transcendental equation, and the engineer's rule sqrt(T m) L / (pi a) beside it), a free decay run
in MuJoCo at three dampers (too soft, the best, too stiff: a stiff damper pins the cable and damps nothing),
and what the best one does to the RMS deflection in a random wind (exact, with and without it).

Run: python scenarios/stay_cable_damper.py
"""

import springlab

best = springlab.run("stay_cable", "damper", duration=4.0, n_elements=49).quantities
optimum = best["optimal_damper_n_s_m_continuum"]
print(
    f"best damper at 6 m: {optimum / 1e3:.1f} kN s/m (rule: {best['optimal_damper_n_s_m_universal'] / 1e3:.1f}),"
    f" giving mode 1 a damping ratio of {best['max_damping_ratio_continuum']:.3%}"
    f" (rule a / 2L: {best['max_damping_ratio_universal']:.3%})"
)
for factor in (0.1, 1.0, 10.0):
    # RK4 at 0.25 ms: the stiffest damper holds its node with a decay rate c / (m dx) of 7800 1/s
    run = springlab.run(
        "stay_cable", "damper", duration=4.0, dt=2.5e-4, n_elements=49, damper_coefficient=factor * optimum
    )
    q = run.quantities
    print(
        f"  c = {factor * optimum / 1e3:7.1f} kN s/m: MuJoCo measures zeta_1 = {q['mode_1_damping_ratio']:.4%}"
        f" (exact {q['mode_1_damping_ratio_exact']:.4%}, cable {q['mode_1_damping_ratio_continuum']:.4%});"
        f" checks passed: {run.passed}"
    )
wind = springlab.run("stay_cable", "wind", duration=60.0, n_elements=49, damper_coefficient=optimum).quantities
print(
    f"in the wind: {wind['rms_displacement_m_exact'] * 1e3:.1f} mm RMS at mid-span with it,"
    f" {wind['rms_displacement_m_no_damper'] * 1e3:.1f} mm without: {wind['rms_reduction_factor']:.2f} times less"
)
