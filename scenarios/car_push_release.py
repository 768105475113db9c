"""Chapter 5.3 "Car suspension": the car pushed down by four passers-by and released.

m = 1000 kg (car + passengers), k = 1e6 N/m (four springs), no damping, the
car bottom 0.10 m above the ground at rest; 250 kg of passers-by push it down
with their weight and let go at t = 0. The three questions:
  1. the extra sag and the height of the car bottom just before release;
  2. x_s, A and omega in x(t) = x_s + A cos(omega t);
  3. the response in the phase plane.

Run: python scenarios/car_push_release.py
"""

import springlab

result = springlab.run("car", "push_release")
q = result.quantities
mm = 1e3

print(
    "1. Extra sag from the push: F/k = 250 kg * 9.81 m/s^2 / 1e6 N/m"
    f" = {q['static_sag_m'] * mm:.4f} mm;"
    f" the car bottom is {q['height_before_release_m'] * mm:.4f} mm above the ground just before release."
)
print(
    f"2. x(t) = x_s + A cos(omega t) with x_s = {q['equilibrium_height_m'] * mm:.4f} mm,"
    f" A = {q['amplitude_m'] * mm:.4f} mm (negative: it starts below x_s),"
    f" omega = sqrt(k/m) = {q['omega_rad_s']:.4f} rad/s (period {q['period_s']:.4f} s)."
)
print(
    f"3. Phase plane (x, v): an ellipse centred at (x_s, 0) = ({q['equilibrium_height_m'] * mm:.1f} mm, 0),"
    f" semi-axes |A| = {q['phase_ellipse_height_semi_axis_m'] * mm:.4f} mm and"
    f" omega |A| = {q['phase_ellipse_velocity_semi_axis_m_s']:.5f} m/s, run clockwise from"
    f" ({q['height_before_release_m'] * mm:.4f} mm, 0)."
)
x, v = result.pos["heave"], result.vel["heave"]
ellipse = ((x - q["equilibrium_height_m"]) / q["phase_ellipse_height_semi_axis_m"]) ** 2 + (
    v / q["phase_ellipse_velocity_semi_axis_m_s"]
) ** 2
print(
    f"MuJoCo's run stays on that ellipse to {abs(ellipse - 1).max():.1e};"
    f" max |x - x_s - A cos(omega t)| = {result.errors['heave_pos'].max_abs:.1e} m"
    f" (tolerance met: {result.passed})."
)
