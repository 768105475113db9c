"""`springlab tradeoff`: error against cost of every integrator and timestep; the cheapest setting for --tol (a scene:
against its exact solution; a model file: against a converged run of the same model)."""

from __future__ import annotations

import argparse

from springlab import outputs
from springlab.cli import model_text, options
from springlab.cli import text as cli_text
from springlab.errors import BadInputError, ExitCode
from springlab.sim import model_files
from springlab.studies import tradeoff

NAME = "tradeoff"
HELP = "error vs cost of every integrator and timestep; cheapest setting for --tol"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    options.scene_arguments(parser, model_files=True)
    parser.add_argument(
        "--keyframe", metavar="NAME|INDEX", help="a model file: where every run starts (default: first keyframe)"
    )
    parser.add_argument(
        "--integrators", metavar="A,B", help="a model file: the integrators to sweep (default: all five)"
    )
    parser.add_argument(
        "--dt", metavar="LIST", help="a model file: the timesteps 'a,b,c' [s] (default: from 4x its own down)"
    )
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
    if model_files.is_model_file(args.scene):
        return _model_file(args)
    given = [f"--{name}" for name in ("keyframe", "integrators", "dt") if getattr(args, name) is not None]
    if given:
        raise BadInputError(f"{given[0]} applies to a model file (MODEL.xml), not to the scene {args.scene!r}")
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
        outputs.write(result, args.output)
    if args.json:
        options.print_json(result.to_dict())
    else:
        cli_text.print_tradeoff(result, args.output)
    pick = result.recommendation
    return ExitCode.FAILED if pick is not None and not pick.found else ExitCode.OK


def _model_file(args: argparse.Namespace) -> int:
    """`tradeoff MODEL.xml`: every integrator and timestep against a converged run of the same model."""
    from springlab.studies.model_tradeoff import model_tradeoff

    options.refuse_scene_options(args, "scenario", "set")
    options.check_output(args)
    with options.executor(args) as executor:
        result = model_tradeoff(
            args.scene,
            keyframe=args.keyframe,
            tol=args.tol,
            duration=args.duration,
            integrators=options.names(args.integrators),
            dts=options.numbers("--dt", args.dt) if args.dt else None,
            executor=executor,
        )
    if args.output:
        outputs.write(result, args.output)
    if args.json:
        options.print_json(result.to_dict())
    else:
        model_text.print_model_tradeoff(result, args.output)
    pick = result.recommendation
    return ExitCode.FAILED if pick is not None and not pick.found else ExitCode.OK
