"""`springlab interactive`: a scenario as a web page running MuJoCo in the browser, with sliders."""

from __future__ import annotations

import argparse

from springlab.cli import options
from springlab.errors import ExitCode

NAME = "interactive"
HELP = "a scenario as a web page running MuJoCo in the browser, with sliders"
#: what to run on a model file instead (this command takes a scene: springlab.cli.main refuses a model file)
MODEL_FILE_INSTEAD = "'springlab view MODEL.xml'"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="a scene that runs in the browser (slider)")
    parser.add_argument(
        "scenario", nargs="?", help="one of its scenarios that run in the browser (default: all of them)"
    )
    parser.add_argument("--output", required=True, metavar="DIR", help="folder for SCENE-SCENARIO.html and its scripts")
    parser.add_argument("--json", action="store_true", help="print what was written as JSON")


def main(args: argparse.Namespace) -> int:
    """Write the scenario's interactive page (MuJoCo's WebAssembly build, sliders, exact solution, verdict)."""
    from springlab.render import interactive

    pages = interactive.write_interactive(args.scene, args.scenario, args.output)
    if args.json:
        options.print_json([page.to_dict() for page in pages])
    else:
        others = f" and {len(pages) - 1} more scenarios beside it" if len(pages) > 1 else ""
        print(
            f"wrote {pages[0].path}{others} ({pages[0].size_bytes / 1e6:.1f} MB with MuJoCo"
            f" {interactive.MUJOCO_JS_MUJOCO} as WebAssembly); open it from disk or a web server"
        )
    return ExitCode.OK
