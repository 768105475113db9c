"""Chapter 5.4, 'Under or overdamped?': d/m = 3, k/m = 2, x(0) = 5 m, v(0) = 0.

1. Is the system over- or underdamped?   2. x(t) = A e^-t + B e^-2t: find A and B.
Run: python scenarios/under_or_overdamped.py
"""

import springlab

result = springlab.run("slider", "exercise")
q = result.quantities
print(f"damping ratio zeta = {q['damping_ratio']:.4f} -> {q['regime']}")
print(f"roots: lambda_1 = {q['lambda_1_per_s']:.6g} 1/s, lambda_2 = {q['lambda_2_per_s']:.6g} 1/s")
print(
    f"x(t) = {q['coefficient_A_m']:.6g} e^({q['lambda_1_per_s']:.3g} t)"
    f" + {q['coefficient_B_m']:.6g} e^({q['lambda_2_per_s']:.3g} t)  [m]"
)
error = result.errors["slider_pos"].max_rel
print(f"MuJoCo ({result.integrator}, dt = {result.dt} s) vs exact: max rel error {error:.2e}")
