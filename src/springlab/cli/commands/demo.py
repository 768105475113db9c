"""`springlab demo`: the main job, validate every scene and write everything under the output folder."""

from __future__ import annotations

import argparse
import pathlib
import time

from springlab.cli import text as cli_text
from springlab.cli.signals import Terminated
from springlab.demo import steps as demo
from springlab.errors import ExitCode

NAME = "demo"
HELP = "the main job: validate everything, write out/"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--output", default="out", metavar="DIR", help="output folder (default: out)")


def main(args: argparse.Namespace) -> int:
    """The main job: validate every scene and write everything under the output folder."""
    start = time.perf_counter()
    try:
        state = demo.run_demo(args.output)
    except (KeyboardInterrupt, Terminated) as stop:
        marker = pathlib.Path(args.output) / demo.INCOMPLETE_MARKER
        if marker.exists():
            stop.add_note(f"; {args.output}/ is incomplete (see {marker})")  # main() prints it
        raise
    cli_text.print_demo(state.validation, len(state.artifacts), state.out, time.perf_counter() - start)
    return ExitCode.FAILED if any(not r.passed for r in state.validation) else ExitCode.OK
