"""Dry friction (chapter 5.1's "ever-occurring friction"): when and where does a block on a spring stop,
does friction hold it on an incline, and how far does MuJoCo's regularised friction drift from Coulomb's?

Run: python scenarios/friction_stop_and_creep.py
"""

import springlab

#: MuJoCo's own defaults of the friction settings (the scenarios preset their validated ones)
MUJOCO = {"solref_timeconst": 0.02, "solimp_d0": 0.9, "noslip_iterations": 0}

decay = springlab.run("friction", "coulomb_decay")
q, p = decay.quantities, decay.parameters
print(
    f"block on a {p['stiffness']:g} N/m spring with dry friction F = {p['friction_force']:g} N, released at"
    f" {p['x0']:g} m: the amplitude falls by 2F/k = {q['amplitude_drop_per_half_cycle_m']:g} m every half cycle"
)
print(
    f"  exact: {q['half_cycles_exact']} half cycles, stops at t = {q['stop_time_s_exact']:.6g} s,"
    f" x = {q['stop_position_m_exact']:.6g} m (inside the stick zone +-{q['stick_zone_m']:g} m)"
)
print(
    f"  MuJoCo at its validated setting: {q['half_cycles']} half cycles, stop at {q['stop_time_s']:.6g} s,"
    f" x = {q['stop_position_m']:.6g} m; error {decay.max_rel_error:.2g}: {decay.verdict}"
)
default = springlab.run("friction", "coulomb_decay", **MUJOCO)
q = default.quantities
print(
    f"  MuJoCo at its defaults: stop at {q['stop_time_s']:.6g} s, x = {q['stop_position_m']:.6g} m, then creeps"
    f" at {q['creep_velocity_m_s'] * 1e3:.3g} mm/s; error {default.max_rel_error:.2g}: {default.verdict}"
)

hold = springlab.run("friction", "incline_hold", **MUJOCO, impratio=1, elliptic_cone=0)
q, p = hold.quantities, hold.parameters
print(
    f"box on a {p['incline_deg']:g} deg incline, mu = {p['mu']:g} (friction angle {q['friction_angle_deg']:.3g} deg):"
    f" exactly no motion; MuJoCo's defaults creep at {q['creep_velocity_m_s'] * 1e3:.3g} mm/s"
    f" ({q['crept_distance_m'] * 1e3:.3g} mm in {hold.duration:g} s)"
)
held = springlab.run("friction", "incline_hold")
print(f"  at its validated setting: {held.quantities['creep_velocity_m_s'] * 1e6:.3g} um/s: {held.verdict}")
