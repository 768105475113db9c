"""Fig. 5.2's question: how does friction at the bit influence the rotation of a kilometre-long drill rod?

The top drive spins up to 60 rpm in 2 s; the bit, held by dry friction, sticks while the string winds up,
breaks free when the string's torque reaches the friction torque, overshoots the top drive and slows to a
near stop again: stick-slip. For three friction torques: the wind-up, the breakaway time (MuJoCo, the
32-element model solved exactly, the continuous rod), the bit's peak speed and when it nearly stops again.

Run: python scenarios/drill_string_bit_friction.py
"""

import springlab

for friction in (5e3, 1e4, 1.5e4):
    result = springlab.run("drill_string", "breakaway", bit_friction_torque=friction, duration=6.0)
    q = result.quantities
    print(
        f"T_f = {friction / 1e3:4.1f} kN m: winds up {q['windup_turns']:.2f} turns (static estimate"
        f" {q['windup_turns_static']:.2f}), breaks free at {q['breakaway_time_s']:.4f} s (exact"
        f" {q['breakaway_time_s_exact']:.4f} s, rod {q['breakaway_time_s_continuum']:.4f} s), peaks at"
        f" {q['peak_bit_speed_rpm']:.0f} rpm ({q['peak_speed_ratio']:.2f} x the top drive), nearly stops again at"
        f" {q['restick_time_s']:.3f} s; checks passed: {result.passed}"
    )
