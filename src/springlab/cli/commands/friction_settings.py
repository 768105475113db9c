"""`springlab friction-settings`: MuJoCo's friction settings against exact dry friction."""

from __future__ import annotations

import argparse

from springlab import scenes
from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import ExitCode
from springlab.sim.simulate import INTEGRATORS

NAME = "friction-settings"
HELP = "MuJoCo's friction settings vs exact dry friction: model error, error vs cost, the cheapest for --tol"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    frictional = ", ".join(name for name, scene in scenes.SCENES.items() if scene.dry_friction is not None)
    parser.add_argument("scene", help=f"a scene with exact dry-friction cases: {frictional}")
    parser.add_argument("scenarios", nargs="*", help="its cases to sweep (default: all)")
    parser.add_argument(
        "--tol", type=float, metavar="TOL", help="pick the cheapest setting meeting this relative error"
    )
    parser.add_argument("--integrators", metavar="A,B", help=f"integrators to sweep (default: {','.join(INTEGRATORS)})")
    parser.add_argument("--dt", metavar="LIST", help="timesteps to sweep, e.g. 0.002,0.001 [s] (default: the scene's)")
    options.set_argument(parser, help="a parameter that is not swept (repeatable)")
    options.executor_arguments(parser)
    parser.add_argument(
        "--output", metavar="DIR", help="write friction_settings.json, friction_settings.csv, friction_settings.png"
    )
    parser.add_argument("--json", action="store_true", help="print friction_settings.json")


def main(args: argparse.Namespace) -> int:
    from springlab.plots import friction_settings as friction_chart  # matplotlib only for this command
    from springlab.studies import friction_settings

    options.check_output(args)
    integrators = options.names(args.integrators)
    dts = options.numbers("--dt", args.dt) if args.dt else None
    with options.executor(args) as executor:
        study = friction_settings.friction_settings(
            args.scene,
            args.scenarios or None,
            tol=args.tol,
            integrators=integrators,
            dts=dts,
            executor=executor,
            **options.parse_sets(args.set),
        )
    if args.output:
        friction_chart.write(study, args.output)
    if args.json:
        options.print_json(study.to_dict())
    else:
        cli_text.print_friction_settings(study, args.output)
    return ExitCode.FAILED if any(c.pick is not None and not c.pick.found for c in study.cases) else ExitCode.OK
