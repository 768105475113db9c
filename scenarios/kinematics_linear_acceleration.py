"""Chapter 5.2, 'Analytical determination of position and velocity':
a(t) = 1.2 t + 3.0 m/s^2, v(0) = 15 m/s, x(0) = 150 m. Find v(t) and x(t).

Run: python scenarios/kinematics_linear_acceleration.py
"""

import springlab

result = springlab.run("kinematics", "linear_acceleration")
q = result.quantities
print(q["acceleration_expression"])
print(q["velocity_expression"], " (v(0) + integral of a)")
print(q["position_expression"], " (x(0) + integral of v)")
print(
    f"at t = {q['end_time_s']:.3g} s: v = {q['v_end_m_s']:.6g} m/s, x = {q['x_end_m']:.6g} m"
    f" (MuJoCo: {q['v_end_simulated_m_s']:.6g} m/s, {q['x_end_simulated_m']:.6g} m)"
)
worst = result.max_rel_error
print(f"max relative error: {worst:.1e}")
