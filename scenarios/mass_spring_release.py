"""Chapter 5.3: a mass on a spring released from x0 at rest moves as x0 cos(omega t) (eq. 5.9).

Run: python scenarios/mass_spring_release.py
"""

import springlab

result = springlab.run("slider", "undamped", x0=0.1)
q = result.quantities
print(f"omega = sqrt(k/m) = {q['omega_n_rad_s']:.6g} rad/s, period T = {q['period_s']:.6g} s")
x, v = result.pos["slider"], result.vel["slider"]
print(f"max |x| = {abs(x).max():.6g} m, max |v| = {abs(v).max():.6g} m/s (omega x0 = {q['omega_n_rad_s'] * 0.1:.6g})")
print(f"max relative error vs x0 cos(omega t): {result.errors['slider_pos'].max_rel:.2e}")
