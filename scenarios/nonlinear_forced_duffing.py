"""Chapter 5.5: 'the solutions of a non-linear system even behave chaotically'. The double well,
damped and forced sinusoidally (Holmes' Duffing oscillator): two runs whose initial positions
differ by 1e-9 m end up in different wells.

Run: python scenarios/nonlinear_forced_duffing.py
"""

import springlab

result = springlab.run("nonlinear", "forced_duffing")
q = result.quantities
p = result.parameters
print(
    f"m x'' + {p['damping']:g} x' + ({p['k1']:g}) x + {p['k3']:g} x^3 = {p['force_amplitude']:g} N"
    f" sin(2 pi {p['force_frequency']:.6g} Hz t), x(0) = {p['x0']:g} m"
)
print(
    f"a second run from x(0) + {q['perturbation_m']:g} m is {q['well_size_m']:g} m (the well distance) away"
    f" after {q['separation_time_s']:.4g} s (converged: pairs at dt down to {q['separation_time_dt_s']:g} s give"
    f" {', '.join(f'{t:.5g}' for t in q['separation_time_refinement_s'])} s)"
)
print(
    f"finite-time Lyapunov exponent over that time: {q['ftle_per_s']:.3g} 1/s;"
    f" long-time largest Lyapunov exponent (an estimate over 100 s): {q['lyapunov_exponent_per_s']:.3g}"
    f" +- {q['lyapunov_standard_error_per_s']:.2g} 1/s (standard error)"
)
print(
    f"the trajectory itself stays within 1 % of the well distance of the exact one until"
    f" t = {q['accurate_until_s']:.4g} s (Richardson estimate)"
)
check = next(c for c in result.checks if c.name == "observed_order")
print(f"self-convergence: observed order {check.value:.3f} (RK4: 4)")
