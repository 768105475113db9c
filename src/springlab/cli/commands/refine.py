"""`springlab refine`: how much model a question needs (model size x integrator x timestep)."""

from __future__ import annotations

import argparse

from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import BadInputError, ExitCode
from springlab.sim.simulate import INTEGRATORS

NAME = "refine"
HELP = "how much model a question needs: model size x integrator x timestep, cheapest for --tol"
#: what to run on a model file instead (this command takes a scene: springlab.cli.main refuses a model file)
MODEL_FILE_INSTEAD = "'springlab audit MODEL.xml' or 'springlab tradeoff MODEL.xml'"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="a scene whose model size is a parameter (see docs/cli.md)")
    parser.add_argument("--question", metavar="QUANTITY", help="the quantity to answer (default: the scene's first)")
    parser.add_argument(
        "--tol", type=float, metavar="TOL", help="recommend the cheapest verified setting meeting this relative error"
    )
    parser.add_argument("--sizes", metavar="A,B,C", help="model sizes to sweep (default: the scene's)")
    parser.add_argument("--integrators", metavar="A,B", help=f"integrators to sweep (default: {','.join(INTEGRATORS)})")
    parser.add_argument(
        "--duration", type=float, metavar="SECONDS", help="simulated time [s] (default: the scenario's)"
    )
    options.set_argument(parser)
    options.executor_arguments(parser)
    parser.add_argument("--output", metavar="DIR", help="write DIR/refine.json and DIR/refine.png")
    parser.add_argument("--json", action="store_true", help="print refine.json")


def main(args: argparse.Namespace) -> int:
    """How much model a question needs: model size x integrator x timestep (springlab.studies.refine)."""
    from springlab import outputs  # matplotlib only when this command draws
    from springlab.studies import refine

    options.check_output(args)
    sizes = None
    if args.sizes:
        try:
            sizes = [float(s) for s in args.sizes.split(",")]
        except ValueError:
            raise BadInputError(f"--sizes takes whole numbers 'a,b,c', got {args.sizes!r}") from None
    integrators = args.integrators.split(",") if args.integrators else tuple(INTEGRATORS)
    with options.executor(args) as executor:
        result = refine.refine(
            args.scene,
            args.question,
            tol=args.tol,
            sizes=sizes,  # type: ignore[arg-type]  # checked as the size parameter by the study
            integrators=integrators,
            duration=args.duration,
            executor=executor,
            **options.parse_sets(args.set),
        )
    if args.output:
        outputs.write(result, args.output)
    if args.json:
        options.print_json(result.to_dict())
    else:
        cli_text.print_refine(result, args.output)
    pick = result.recommendation
    return ExitCode.FAILED if pick is not None and not pick.found else ExitCode.OK
