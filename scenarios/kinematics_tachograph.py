"""Chapter 5.2, 'Tachograph' (Fig. 5.6): a bus's v-t record over 12 s. Determine the displacement
(the area under v(t)) and the acceleration (its slope) as functions of time.

The record used (the figure is not reproduced in the text): the bus pulls away from a stop to
6 m/s in 4 s, cruises for 4 s and brakes to a stop at 12 s.
Run: python scenarios/kinematics_tachograph.py
"""

import springlab

result = springlab.run("kinematics", "tachograph")
q = result.quantities
print(q["velocity_profile"])
print(q["acceleration_profile"])
times = q["knot_times_s"]
for i, (a, dx) in enumerate(zip(q["segment_accelerations_m_s2"], q["segment_displacements_m"])):
    print(f"  {times[i]:g}-{times[i + 1]:g} s: a = {a:+g} m/s^2, displacement {dx:g} m")
print(f"displacement over 12 s = {q['displacement_m']:g} m (MuJoCo: {q['x_end_simulated_m']:.12g} m)")
