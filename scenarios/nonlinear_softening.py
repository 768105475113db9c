"""Chapter 5.5, Fig. 5.20: a spring that weakens with stretch, F = k1 x + k3 x^3 with k3 < 0.

Several equilibria (a stable one at 0, unstable ones where the spring force vanishes again),
bounded motion inside the separatrix, escape outside it.
Run: python scenarios/nonlinear_softening.py
"""

import springlab

inside = springlab.run("nonlinear", "softening")
q = inside.quantities
p = inside.parameters
print(
    f"spring: k1 = {p['k1']:g} N/m, k3 = {p['k3']:g} N/m^3, m = {p['mass']:g} kg;"
    f" force peaks at {q['peak_spring_force_N']:.4g} N at x = {q['peak_force_stretch_m']:.4g} m"
)
for x, kind in zip(q["equilibria_m"], q["equilibrium_kinds"]):
    print(f"  equilibrium x = {x:+.4g} m: {kind}")
print(
    f"separatrix energy (saddles) {q['separatrix_energy_J']:.4g} J, barrier {q['barrier_height_J']:.4g} J above the rest state"
)
print(
    f"released at x0 = {p['x0']:g} m: E = {q['energy_J']:.6g} J < separatrix -> {q['motion']}, period"
    f" {q['period_simulated_s']:.10g} s simulated vs {q['period_quadrature_s']:.10g} s from the energy integral;"
    f" linear theory 2 pi / omega = {6.283185307179586 / q['omega_at_0_m_rad_s']:.6g} s"
)
print(f"  energy drift {q['energy_drift_relative']:.1e} of the kinetic energy")

outside = springlab.run("nonlinear", "softening_escape")
q = outside.quantities
print(
    f"launched at v0 = {outside.parameters['v0']:g} m/s: E = {q['energy_J']:.6g} J > separatrix -> escapes;"
    f" |x| reaches {q['escape_radius_m']:g} m (3 saddle distances) after {q['escape_time_s']:.10g} s"
    f" (energy integral: {q['escape_time_quadrature_s']:.10g} s); the run stops there"
)
print("validated:", inside.passed and outside.passed)
