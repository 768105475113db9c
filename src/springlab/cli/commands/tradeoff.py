"""`springlab tradeoff`: error against cost of every integrator and timestep; the cheapest setting for --tol."""

from __future__ import annotations

import argparse

from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import ExitCode
from springlab.plots import charts
from springlab.studies import tradeoff

NAME = "tradeoff"
HELP = "error vs cost of every integrator and timestep; cheapest setting for --tol"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    options.scene_arguments(parser)
    parser.add_argument(
        "--tol", type=float, metavar="TOL", help="recommend the cheapest setting meeting this relative error"
    )
    parser.add_argument(
        "--duration", type=float, metavar="SECONDS", help="simulated time [s] (default: the scenario's)"
    )
    options.executor_arguments(parser)
    parser.add_argument("--output", metavar="DIR", help="write DIR/tradeoff.json and DIR/tradeoff.png")
    parser.add_argument("--json", action="store_true", help="print tradeoff.json")


def main(args: argparse.Namespace) -> int:
    options.check_output(args)
    with options.executor(args) as executor:
        result = tradeoff.tradeoff(
            args.scene,
            args.scenario,
            tol=args.tol,
            duration=args.duration,
            executor=executor,
            **options.parse_sets(args.set),
        )
    if args.output:
        charts.write_tradeoff(result, args.output)
    if args.json:
        options.print_json(result.to_dict())
    else:
        cli_text.print_tradeoff(result, args.output)
    pick = result.recommendation
    return ExitCode.FAILED if pick is not None and not pick.found else ExitCode.OK
