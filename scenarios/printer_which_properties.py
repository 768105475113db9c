"""Chapter 5.7's printer head, second question: Which system properties play an important role?

The design study: 7^4 = 2401 configurations of belt stiffness, carriage mass, belt damping ratio and
drive force, each a bang-bang move plus settling in batched MuJoCo (10-20 s on 2 cores), ranked by the
elasticity d ln T / d ln p of positioning time, beside the analytic estimate.

Run: python scenarios/printer_which_properties.py [--levels N]   (N odd, default 7; 3 is a quick look)
"""

import argparse

import springlab

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--levels", type=int, default=7, help="odd grid points per property (default 7: 2401)")
levels = parser.parse_args().levels

study = springlab.design("printer_head", levels=levels, plane_levels=0)  # the dense plane is only for the plot
summary = study.to_dict()
print(study.answer)
print()
print("Elasticity of positioning time d ln T / d ln p (global fit over the grid; local at the default):")
for name in study.ranking:
    print(f"  {name:<15} {study.elasticities[name]:+.3f}   local {study.local_elasticities[name]:+.3f}")
fastest = summary["fastest"]
print(
    f"fastest configuration: {fastest['positioning_time_s'] * 1e3:.1f} ms with "
    + ", ".join(f"{k} {v:.3g}" for k, v in fastest["properties"].items())
)
ratio = summary["estimate_over_simulation"]
print(f"analytic estimate / simulation: median {ratio['median']:.3f}, 5-95 % {ratio['p05']:.3f}-{ratio['p95']:.3f}")
print(f"({study.size} configurations in {study.wall_time_s:.1f} s, {study.size / study.wall_time_s:.0f}/s)")
