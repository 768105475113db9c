"""Chapter 5.5: multiple equilibria. Duffing's double well, F = k1 x + k3 x^3 with k1 < 0 < k3:
two stable equilibria +-sqrt(-k1/k3), a saddle at 0, small oscillations at omega = sqrt(-2 k1 / m).

Run: python scenarios/nonlinear_double_well.py
"""

import math

import springlab

result = springlab.run("nonlinear", "double_well")
q = result.quantities
p = result.parameters
print(f"k1 = {p['k1']:g} N/m, k3 = {p['k3']:g} N/m^3, m = {p['mass']:g} kg")
print(f"equilibria_m = {q['equilibria_m']}  ({', '.join(q['equilibrium_kinds'])})")
print(
    f"small-oscillation frequency about +-{q['saddle_or_well_distance_m']:g} m: omega ="
    f" {q['omega_at_+0.1_m_rad_s']:.10g} rad/s = sqrt(-2 k1 / m) = {math.sqrt(-2 * p['k1'] / p['mass']):.10g}"
)
print(
    f"released at {p['x0']:g} m (E = {q['energy_J']:.4g} J below the saddle's {q['separatrix_energy_J']:g} J; barrier {q['barrier_height_J']:.4g} J): stays in"
    f" the right-hand well between {q['turning_points_m'][0]:.6g} and {q['turning_points_m'][1]:.6g} m;"
    f" period {q['period_simulated_s']:.10g} s (energy integral {q['period_quadrature_s']:.10g} s,"
    f" linear theory {2 * math.pi / q['omega_at_+0.1_m_rad_s']:.6g} s)"
)
for check in result.checks:
    print(
        f"  check {check.name}: error {check.error:.1e} <= {check.tolerance:.1e} {'pass' if check.passed else 'FAIL'}"
    )
