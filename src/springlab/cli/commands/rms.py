"""`springlab rms`: how much a structure vibrates under a random load, from many seeds, and what an accurate RMS costs."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import BadInputError, ExitCode
from springlab.sim.simulate import INTEGRATORS

if TYPE_CHECKING:
    from springlab.studies.rms_settings import RmsSettings

NAME = "rms"
HELP = "the RMS under a random load: many seeded records against the exact value; --tol: the cheapest accurate setting"
#: what to run on a model file instead (this command takes a scene: springlab.cli.main refuses a model file)
MODEL_FILE_INSTEAD = "'springlab frequency MODEL.xml' (its frequency response)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="a scene with a scenario under a random load (see docs/cli.md)")
    parser.add_argument("--seeds", type=int, default=None, metavar="N", help="records, seeds 0 ... N-1 (default 40)")
    parser.add_argument(
        "--record", type=float, metavar="SECONDS", help="one record's length [s] (default: the scenario's)"
    )
    parser.add_argument("--integrator", choices=list(INTEGRATORS), help="integrator (default: the scenario's)")
    parser.add_argument("--dt", type=float, metavar="SECONDS", help="timestep [s] (default: the scenario's)")
    parser.add_argument(
        "--level",
        type=float,
        default=None,
        metavar="P",
        help="confidence level of the intervals (default 0.99; 0.95 with --tol)",
    )
    parser.add_argument(
        "--tol",
        type=float,
        metavar="TOL",
        help="instead: the cheapest model size, integrator, dt and number of records whose RMS is within TOL of the"
        " continuum's (verified by running them)",
    )
    options.set_argument(parser)
    options.executor_arguments(parser)
    parser.add_argument(
        "--output", metavar="DIR", help="write DIR/rms.json, rms.csv, rms.png (rms_settings.* with --tol)"
    )
    parser.add_argument("--json", action="store_true", help="print the JSON")


def main(args: argparse.Namespace) -> int:
    """The records (springlab.studies.random_load) or, with --tol, the settings (springlab.studies.rms_settings)."""
    from springlab.studies import random_load, rms_settings

    options.check_output(args)
    parameters = options.parse_sets(args.set)
    with options.executor(args) as executor:
        if args.tol is not None:
            for name, value in (("--seeds", args.seeds), ("--integrator", args.integrator), ("--dt", args.dt)):
                if value is not None:
                    raise BadInputError(f"{name} is the study's to choose with --tol; drop it")
            study = rms_settings.rms_settings(
                args.scene,
                tol=args.tol,
                level=rms_settings.LEVEL if args.level is None else args.level,
                record=args.record,
                executor=executor,
                **parameters,
            )
            return _report_settings(study, args)
        result = random_load.ensemble(
            args.scene,
            seeds=random_load.SEEDS if args.seeds is None else args.seeds,
            record=args.record,
            integrator=args.integrator,
            dt=args.dt,
            level=random_load.LEVEL if args.level is None else args.level,
            executor=executor,
            **parameters,
        )
    if args.output:
        from springlab import outputs  # matplotlib only when this command draws

        outputs.write(result, args.output)
    if args.json:
        options.print_json(result.to_dict())
    else:
        cli_text.print_answer(result.question_answer)
        print(
            f"  {len(result.seeds)} records x {result.steps} steps ({result.integrator}, dt = {result.dt:g} s) in"
            f" {result.wall_time_s:.1f} s on {result.executor}; the exact answers in {result.exact_time_s:.1f} s"
        )
        if args.output:
            print(f"  wrote {args.output}/rms.json, rms.csv, rms.png")
    allowed = random_load.allowed_outside(len(result.seeds), result.level)
    return ExitCode.OK if len(result.seeds) - result.inside <= allowed else ExitCode.FAILED


def _report_settings(study: RmsSettings, args: argparse.Namespace) -> int:
    """Write, print and judge the settings study: exit 1 when no setting met tol."""
    if args.output:
        from springlab import outputs  # matplotlib only when this command draws

        outputs.write(study, args.output)
    if args.json:
        options.print_json(study.to_dict())
    else:
        cli_text.print_answer(study.question_answer)
        print(f"  {len(study.rows)} settings, {len(study.front)} on the Pareto front of bound vs counted work")
        if args.output:
            print(f"  wrote {args.output}/rms_settings.json, rms_settings.png")
    return ExitCode.OK if study.recommendation.found else ExitCode.FAILED
