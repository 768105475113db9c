"""`springlab run`: simulate one scenario and compare it with its exact solution, or record a model file's run."""

from __future__ import annotations

import argparse

from springlab import outputs
from springlab.cli import model_text, options
from springlab.cli import text as cli_text
from springlab.errors import BadInputError, ExitCode
from springlab.sim import model_files

NAME = "run"
HELP = "simulate one scenario and compare it with its exact solution (or run MODEL.xml: not validated)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    options.scene_arguments(parser, model_files=True)
    options.timing_arguments(parser)
    parser.add_argument(
        "--keyframe",
        metavar="NAME|INDEX",
        help="a model file: where the run starts (default: first keyframe, else qpos0)",
    )
    parser.add_argument("--output", metavar="DIR", help="write DIR/trajectory.csv and DIR/summary.json")
    parser.add_argument("--record-every", type=int, default=1, metavar="N", help="keep every N-th step in the CSV")
    parser.add_argument("--json", action="store_true", help="print summary.json")


def main(args: argparse.Namespace) -> int:
    if args.record_every < 1:
        raise BadInputError(f"--record-every must be an integer >= 1, got {args.record_every}")
    if model_files.is_model_file(args.scene):
        return _model_file(args)
    if args.keyframe is not None:
        raise BadInputError(f"--keyframe applies to a model file (MODEL.xml), not to the scene {args.scene!r}")
    result = options.run(args)
    if args.output:
        outputs.write(result, args.output, every=args.record_every)
    if args.json:
        options.print_json(result.to_dict())
    else:
        cli_text.print_run(result, args.output)
    options.report_model_limits(result)
    return ExitCode.FAILED if result.passed is False else ExitCode.OK


def _model_file(args: argparse.Namespace) -> int:
    """`run MODEL.xml`: the model's motion from its keyframe, written and shown, never validated (exit 0)."""
    from springlab.runs.model_run import run_model

    options.refuse_scene_options(args, "scenario", "set", "tol")
    options.check_output(args)
    run = run_model(args.scene, keyframe=args.keyframe, integrator=args.integrator, dt=args.dt, duration=args.duration)
    if args.output:
        outputs.write(run, args.output, every=args.record_every)
    if args.json:
        options.print_json(run.to_dict())
    else:
        model_text.print_model_run(run, args.output)
    return ExitCode.OK
