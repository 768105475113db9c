"""`springlab friction-settings`: MuJoCo's friction settings against exact dry friction (a scene), or how fast a
body that dry friction holds creeps and which settings stop it (a model file)."""

from __future__ import annotations

import argparse

from springlab import scenes
from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import BadInputError, ExitCode
from springlab.sim import model_files
from springlab.sim.simulate import INTEGRATORS

NAME = "friction-settings"
HELP = (
    "MuJoCo's friction settings vs exact dry friction (a scene), or a held body's creep and the settings that stop"
    " it (MODEL.xml)"
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    frictional = ", ".join(name for name, scene in scenes.SCENES.items() if scene.dry_friction is not None)
    parser.add_argument("scene", help=f"a scene with exact dry-friction cases ({frictional}) or a model file MODEL.xml")
    parser.add_argument("scenarios", nargs="*", help="a scene's cases to sweep (default: all)")
    parser.add_argument(
        "--tol",
        type=float,
        metavar="TOL",
        help="a scene: pick the cheapest setting meeting this relative error; a model file: the slip allowed over"
        " the hold, in body sizes (default 0.025: 1 mm for a 40 mm box)",
    )
    parser.add_argument("--integrators", metavar="A,B", help=f"integrators to sweep (default: {','.join(INTEGRATORS)})")
    parser.add_argument("--dt", metavar="LIST", help="timesteps to sweep, e.g. 0.002,0.001 [s] (default: the scene's)")
    parser.add_argument(
        "--body",
        action="append",
        default=[],
        metavar="NAME",
        help="a model file: a body dry friction holds (repeatable; default: the free bodies in frictional contact)",
    )
    parser.add_argument(
        "--hold", type=float, metavar="SECONDS", help="a model file: how long the body must be held [s] (default 10)"
    )
    parser.add_argument(
        "--keyframe",
        metavar="K",
        help="a model file: where the hold starts, a keyframe name or index (default: the first)",
    )
    options.set_argument(parser, help="a scene's parameter that is not swept (repeatable)")
    options.executor_arguments(parser)
    parser.add_argument(
        "--output", metavar="DIR", help="write friction_settings.json, friction_settings.csv, friction_settings.png"
    )
    parser.add_argument("--json", action="store_true", help="print friction_settings.json")


def main(args: argparse.Namespace) -> int:
    from springlab import outputs  # matplotlib only for this command
    from springlab.studies import friction_hold, friction_settings

    options.check_output(args)
    integrators = options.names(args.integrators)
    dts = options.numbers("--dt", args.dt) if args.dt else None
    model_file = model_files.is_model_file(args.scene)
    _check_arguments(args, model_file)
    with options.executor(args) as executor:
        if model_file:
            study = friction_hold.friction_hold(
                args.scene,
                bodies=args.body,
                hold_s=friction_hold.DEFAULT_HOLD_S if args.hold is None else args.hold,
                keyframe=args.keyframe,
                tol=friction_hold.DEFAULT_TOL if args.tol is None else args.tol,
                integrators=integrators,
                dts=dts,
                executor=executor,
            )
        else:
            study = friction_settings.friction_settings(
                args.scene,
                args.scenarios or None,
                tol=args.tol,
                integrators=integrators,
                dts=dts,
                executor=executor,
                **options.parse_sets(args.set),
            )
    if args.output:
        outputs.write(study, args.output)
    if args.json:
        options.print_json(study.to_dict())
    else:
        cli_text.print_friction_settings(study, args.output)
    return ExitCode.FAILED if any(c.pick is not None and not c.pick.found for c in study.cases) else ExitCode.OK


def _check_arguments(args: argparse.Namespace, model_file: bool) -> None:
    """Options of the other form (a scene's or a model file's) are bad input, said in one line."""
    if model_file:
        given = [name for name, value in (("scenarios", args.scenarios), ("--set", args.set)) if value]
        if given:
            raise BadInputError(f"{given[0]} applies to a scene, not to a model file ({args.scene})")
    else:
        given = [
            name
            for name, value in (("--body", args.body), ("--hold", args.hold), ("--keyframe", args.keyframe))
            if value not in (None, [])
        ]
        if given:
            raise BadInputError(f"{given[0]} applies to a model file (MODEL.xml), not to the scene {args.scene!r}")
