"""`springlab run`: simulate one scenario and compare it with its exact solution."""

from __future__ import annotations

import argparse

from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import BadInputError, ExitCode
from springlab.runs.run import write_run

NAME = "run"
HELP = "simulate one scenario and compare it with its exact solution"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    options.scene_arguments(parser)
    options.timing_arguments(parser)
    parser.add_argument("--output", metavar="DIR", help="write DIR/trajectory.csv and DIR/summary.json")
    parser.add_argument("--record-every", type=int, default=1, metavar="N", help="keep every N-th step in the CSV")
    parser.add_argument("--json", action="store_true", help="print summary.json")


def main(args: argparse.Namespace) -> int:
    if args.record_every < 1:
        raise BadInputError(f"--record-every must be an integer >= 1, got {args.record_every}")
    result = options.run(args)
    if args.output:
        write_run(args.output, result, every=args.record_every)
    if args.json:
        options.print_json(result.to_dict())
    else:
        cli_text.print_run(result, args.output)
    options.report_model_limits(result)
    return ExitCode.FAILED if result.passed is False else ExitCode.OK
