"""Chapter 5.7's printer head, with control: how fast can it be positioned by a bang-bang move, an input shaper
or a feedback loop? (issue 35's answer table)

For the default inkjet carriage and an illustrative 3D-printer toolhead axis (a 50 Hz belt, zeta 0.1): the
time until the carriage stays within +-10 um of a target one inch away, for the minimum-time bang-bang move,
the quietest bang-bang move, each input shaper on the minimum-time move and the sampled PD loop on each
encoder; each a MuJoCo run beside its exact value. Prints the answer in words, then (--json) the table.

Run: python scenarios/printer_positioning_table.py [--preset inkjet|printer_frame|all] [--json]
"""

import argparse
import json

from springlab.scenes.printer_head.answers import PRESETS, positioning_table

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--preset", choices=[*PRESETS, "all"], default="all")
parser.add_argument("--json", action="store_true", help="print the tables as JSON after the sentences")
args = parser.parse_args()

tables = [positioning_table(name) for name in (PRESETS if args.preset == "all" else [args.preset])]
for table in tables:
    print(table.question)
    for sentence in table.sentences():
        print("  " + sentence)
if args.json:
    print(json.dumps([table.to_dict() for table in tables], indent=2))
