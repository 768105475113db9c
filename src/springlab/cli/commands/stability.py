"""`springlab stability`: stability boundaries against theory, the extremes table, undamped energy."""

from __future__ import annotations

import argparse

from springlab import outputs
from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import ExitCode
from springlab.studies import stability

NAME = "stability"
HELP = "stability boundaries vs theory, extremes table, undamped energy"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--full",
        action="store_true",
        help="more damping ratios and extreme cases, advice verified by running it (slower)",
    )
    options.executor_arguments(parser)
    parser.add_argument("--output", metavar="DIR", help="write DIR/stability.json, stability.png and energy.png")
    parser.add_argument("--json", action="store_true", help="print stability.json")


def main(args: argparse.Namespace) -> int:
    options.check_output(args)
    with options.executor(args) as executor:
        report = stability.stability_report(full=args.full, executor=executor)
        amplification = stability.amplification_map(executor=executor) if args.output else None
    if args.output:
        assert amplification is not None  # computed above whenever there is an output folder
        outputs.write(report, args.output, amplification=amplification)
    if args.json:
        options.print_json(report.to_dict())
    else:
        cli_text.print_stability(report, args.output)
    return ExitCode.OK if report.passed else ExitCode.FAILED
