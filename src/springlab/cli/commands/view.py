"""`springlab view`: watch a scene's validated run (or any MJCF) live in MuJoCo's interactive viewer."""

from __future__ import annotations

import argparse

from springlab.cli import options
from springlab.errors import ExitCode

NAME = "view"
HELP = "watch a scene's validated run (or any MJCF) live in MuJoCo's interactive viewer"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", metavar="SCENE|MODEL.xml", help="scene name (see 'springlab list') or an MJCF file")
    parser.add_argument("scenario", nargs="?", help="scenario name (default: the scene's first)")
    options.set_argument(parser)
    options.timing_arguments(parser)
    parser.add_argument(
        "--slow-motion",
        type=float,
        default=1.0,
        metavar="FACTOR",
        help="run FACTOR times slower (default 1: real time)",
    )
    parser.add_argument(
        "--exaggerate",
        type=float,
        metavar="FACTOR",
        help="draw displacements FACTOR times larger around their mean, as 'render' does (default: render's)",
    )
    parser.add_argument(
        "--close-after", type=float, metavar="SECONDS", help="close the window after SECONDS of wall time"
    )


def main(args: argparse.Namespace) -> int:
    """Watch a scene's validated run (or any MJCF) live in MuJoCo's interactive viewer (springlab.cli.view)."""
    from springlab.cli import view  # GLFW only for the command that opens a window

    result = view.command(args, options.run)
    return ExitCode.OK if result is None else options.verdict(result)
