"""A quarter car drives over a half-sine bump (0.08 m high, 4 m long) at 8 and 16 m/s: how hard
is the ride, how far does the suspension travel, and does the tire leave the road?

Run: python scenarios/car_road_bump.py
"""

import springlab

for speed in (8.0, 16.0):
    result = springlab.run("car", "road_bump", speed=speed)
    q = result.quantities
    worst = result.max_rel_error
    print(
        f"{speed:g} m/s ({speed * 3.6:g} km/h), bump crossed in {q['bump_duration_s']:.3f} s:"
        f" peak body acceleration {q['peak_body_acceleration_m_s2']:.3f} m/s^2,"
        f" suspension travel {q['peak_suspension_travel_m'] * 1e3:.2f} mm,"
        f" tire deflection {q['peak_tire_deflection_m'] * 1e3:.2f} mm,"
        f" min tire force {q['min_tire_force_n']:.0f} N of {q['static_tire_force_n']:.0f} N static:"
        f" the tire {'LEAVES' if q['tire_leaves_road'] else 'stays on'} the road"
        f" (max rel error {worst:.1e}, passed {result.passed})"
    )
print(
    f"body bounce {q['body_frequency_hz']:.3f} Hz (zeta {q['body_damping_ratio']:.3f}),"
    f" wheel hop {q['wheel_hop_frequency_hz']:.3f} Hz (zeta {q['wheel_hop_damping_ratio']:.3f})"
)
