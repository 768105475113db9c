"""Chapter 5.2, 'Analytical determination of acceleration and speed':
x(t) = 0.03 t^3 + 0.2 t^2 + 1.2 t + 3.0 m. Find v(t) and a(t).

A MuJoCo vehicle driven by F = m a(t) from x(0), v(0) reproduces x(t); v(t) and a(t) are its
derivatives. Run: python scenarios/kinematics_polynomial_position.py
"""

import springlab

result = springlab.run("kinematics", "polynomial_position")
q = result.quantities
print(q["position_expression"])
print(q["velocity_expression"], " (dx/dt)")
print(q["acceleration_expression"], " (dv/dt)")
print(
    f"at t = {q['end_time_s']:.3g} s: x = {q['x_end_m']:.6g} m, v = {q['v_end_m_s']:.6g} m/s,"
    f" a = {q['a_end_m_s2']:.6g} m/s^2"
)
print(
    f"MuJoCo:            x = {q['x_end_simulated_m']:.6g} m, v = {q['v_end_simulated_m_s']:.6g} m/s,"
    f" a = {q['a_end_simulated_m_s2']:.6g} m/s^2"
)
worst = result.max_rel_error
print(f"max relative error of the simulated x(t), v(t): {worst:.1e} (tolerance {result.tolerance:.1e})")
