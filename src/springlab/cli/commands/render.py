"""`springlab render`: film a scenario off-screen (mp4 H.264 or gif), optionally beside its phase plane."""

from __future__ import annotations

import argparse
import pathlib

from springlab import files
from springlab.cli import options
from springlab.cli import text as cli_text

NAME = "render"
HELP = "film a scenario off-screen: mp4 (H.264) or gif, optionally beside its phase plane"
#: what to run on a model file instead (this command takes a scene: springlab.cli.main refuses a model file)
MODEL_FILE_INSTEAD = "'springlab view MODEL.xml' (MuJoCo's viewer) or 'springlab run MODEL.xml --output DIR'"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    options.scene_arguments(parser)
    options.timing_arguments(parser)
    parser.add_argument(
        "--output", required=True, metavar="FILE", help="FILE.mp4 (H.264, plays in browsers) or FILE.gif"
    )
    parser.add_argument(
        "--fps", type=float, default=30, help="frames per second; video time = simulation time (default 30)"
    )
    parser.add_argument("--width", type=int, default=640, help="width of the 3D view [px] (default 640)")
    parser.add_argument("--height", type=int, default=480, help="height of the 3D view [px] (default 480)")
    parser.add_argument(
        "--composite",
        action="store_true",
        help="add the phase-plane trace drawn as time advances, a height x height panel on the right",
    )
    parser.add_argument(
        "--slow-motion",
        type=float,
        metavar="FACTOR",
        help="play FACTOR times slower (drawing only; default: short runs slowed to >= 90 frames and 6 frames"
        " per period of their fastest mode, e.g. the printer move at 1/50 speed; written on every frame)",
    )
    parser.add_argument(
        "--exaggerate",
        type=float,
        metavar="FACTOR",
        help="draw displacements FACTOR times larger around their mean (drawing only; default: motions below"
        " 1%% of the body's size magnified to about 3%%, e.g. the car x30; written on every frame)",
    )
    parser.add_argument(
        "--antialias",
        action="store_true",
        help="smooth edges by multisampling (about 3x slower per frame on a CPU renderer; default off)",
    )


def main(args: argparse.Namespace) -> int:
    """Simulate a scenario and film it off-screen (mp4 H.264 or gif), optionally with its phase plane."""
    from springlab.render import media
    from springlab.render import video as render  # GL and matplotlib only for the commands that draw

    render.check_video_arguments(args.output, args.fps, args.width, args.height)
    for name, value in (("--slow-motion", args.slow_motion), ("--exaggerate", args.exaggerate)):
        if value is not None:
            render.render_scale.check_factor(name, value)
    result = options.run(args)
    files.prepare_directory(pathlib.Path(args.output).parent)
    info = media.render_run(
        result,
        args.output,
        fps=args.fps,
        width=args.width,
        height=args.height,
        composite=args.composite,
        slow_motion=args.slow_motion,
        exaggerate=args.exaggerate,
        antialias=args.antialias,
    )
    cli_text.print_render(info)
    return options.verdict(result)
