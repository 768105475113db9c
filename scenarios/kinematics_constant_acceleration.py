"""Chapter 5.2, eq. 5.5: uniformly accelerated motion, v = v(0) + a t, x = x(0) + v(0) t + a t^2 / 2.

Run: python scenarios/kinematics_constant_acceleration.py
"""

import springlab

for a in (2.0, -2.0):
    result = springlab.run("kinematics", "constant_acceleration", a0=a)
    q = result.quantities
    print(
        f"a = {a:+g} m/s^2: {q['velocity_expression']};  {q['position_expression']};"
        f"  after {q['end_time_s']:.3g} s: v = {q['v_end_m_s']:.6g} m/s, x = {q['x_end_m']:.6g} m"
    )
