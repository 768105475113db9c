"""`springlab validate`: check every exact scenario against its tolerance."""

from __future__ import annotations

import argparse

from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import ExitCode
from springlab.studies import auto

NAME = "validate"
HELP = "check every exact scenario against its tolerance"
#: what to run on a model file instead (this command takes a scene: springlab.cli.main refuses a model file)
MODEL_FILE_INSTEAD = "'springlab run MODEL.xml' (a record, not validated) or 'springlab audit MODEL.xml'"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenes", nargs="*", help="scene names (default: all)")
    parser.add_argument("--integrator", metavar="NAME", help="override the scenes' integrator")
    parser.add_argument("--dt", type=float, metavar="SECONDS", help="override the scenes' timestep [s]")
    parser.add_argument(
        "--tol", type=float, metavar="TOL", help="relative tolerance to hold every run to (needed by --integrator auto)"
    )
    parser.add_argument("--json", action="store_true", help="machine-readable output")


def main(args: argparse.Namespace) -> int:
    rows = auto.validate(args.scenes, integrator=args.integrator, dt=args.dt, tol=args.tol)
    if args.json:
        options.print_json([row.to_dict() for row in rows])
    else:
        cli_text.print_validate(rows)
    return ExitCode.FAILED if any(not r.passed for r in rows) else ExitCode.OK
