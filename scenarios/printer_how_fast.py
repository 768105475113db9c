"""Chapter 5.7's printer head: How fast can we position the printer head? Which system properties
play an important role?

One bang-bang move of the default carriage through the scene (exact 2-DOF solution alongside), then
the design study: 7^4 = 2401 configurations of belt stiffness, carriage mass, belt damping ratio and
drive force through batched MuJoCo (about 10 s on 2 cores), ranked by elasticity.

Run: python scenarios/printer_how_fast.py
"""

import springlab
import springlab.design

result = springlab.run("printer_head", "move")
q = result.summary["quantities"]
print(f"default carriage (belt mode {q['natural_frequency_hz']:.1f} Hz, zeta {q['damping_ratio']:.3f};"
      f" MuJoCo's linearization {q['linearized_natural_frequency_hz']:.1f} Hz, {q['linearized_damping_ratio']:.3f}):"
      f" {q['move_distance_m'] * 1e3:.1f} mm in {q['move_time_s'] * 1e3:.1f} ms of bang-bang move"
      f" (minimum {q['minimum_move_time_s'] * 1e3:.2f} ms), residual vibration {q['residual_amplitude_m'] * 1e6:.1f} um,"
      f" inside +-{q['settling_band_m'] * 1e6:.0f} um for good {q['settling_time_s'] * 1e3:.2f} ms later:"
      f" positioned in {q['positioning_time_s'] * 1e3:.1f} ms (estimate {q['positioning_time_estimate_s'] * 1e3:.1f} ms;"
      f" passed {result.summary['passed']})")

study = springlab.design.run_study("printer_head", plane_levels=0)  # the plane is for the plot
summary = springlab.design.summary(study)
print()
print(springlab.design.answer(study))
print()
print("Elasticity of positioning time d ln T / d ln p (global fit over the grid; local at the default):")
for name in summary["ranking"]:
    print(f"  {name:<15} {summary['elasticities'][name]:+.3f}   local {summary['local_elasticities'][name]:+.3f}")
fastest = summary["fastest"]
print(f"fastest configuration: {fastest['positioning_time_s'] * 1e3:.1f} ms with "
      + ", ".join(f"{k} {v:.3g}" for k, v in fastest["properties"].items()))
print(f"({summary['configurations']} configurations in {summary['wall_time_s']:.1f} s,"
      f" {summary['configurations_per_s']:.0f}/s)")
