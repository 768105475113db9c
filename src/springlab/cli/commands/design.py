"""`springlab design`: the design study (positioning time over a property sweep, ranked sensitivities)."""

from __future__ import annotations

import argparse

from springlab import scenes
from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import ExitCode

NAME = "design"
HELP = "design study: positioning time over a property sweep, ranked sensitivities"
#: what to run on a model file instead (this command takes a scene: springlab.cli.main refuses a model file)
MODEL_FILE_INSTEAD = "'springlab sweep MODEL.xml --vary NAME=LOW:HIGH:N'"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    declared = ", ".join(name for name, scene in scenes.SCENES.items() if scene.design is not None)
    parser.add_argument("scene", help=f"scene with a design study: {declared}")
    parser.add_argument(
        "--levels",
        type=int,
        default=7,
        metavar="N",
        help="odd number of grid points per property, N^4 configurations (default 7: 2401)",
    )
    parser.add_argument(
        "--plane",
        type=int,
        default=31,
        metavar="N",
        help="odd grid points per axis of the plotted plane over the two most influential properties,"
        " N^2 more configurations (default 31: 961; 0: plot the grid's slice)",
    )
    parser.add_argument("--threads", type=int, default=0, metavar="N", help="batch threads (default 0: one per CPU)")
    options.set_argument(parser, help="start the sweep from another parameter value, SI units (repeatable)")
    parser.add_argument(
        "--sobol",
        type=int,
        nargs="?",
        const=16384,
        metavar="N",
        help="also Sobol indices of carriage mass, belt stiffness, damping ratio, force and move length:"
        " N x 7 runs, N a power of 2 (bare --sobol: 16384, 114,688 runs)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the Sobol sequence and bootstrap (default 0)")
    options.executor_arguments(parser)
    parser.add_argument(
        "--output", metavar="DIR", help="write DIR/design.json, configurations.csv, design.png (and sobol.png)"
    )
    parser.add_argument("--json", action="store_true", help="print design.json")


def main(args: argparse.Namespace) -> int:
    from springlab import outputs  # here, not at the top: mujoco.batch is only needed by this command
    from springlab.studies.design import study as design

    options.check_output(args)
    overrides = options.parse_sets(args.set)
    if args.sobol is not None:
        from springlab.studies.design import sobol

        _, spec = design.declaration(args.scene)
        sobol.check_base_samples(args.sobol, len(spec.sobol))  # bad input before minutes of simulation
    with options.executor(args, nthread=args.threads) as executor:
        study = design.run_study(
            args.scene,
            levels=args.levels,
            plane_levels=args.plane,
            executor=executor,
            omega_dt=design.OMEGA_DT,
            sobol=args.sobol,
            sobol_seed=args.seed,
            **overrides,
        )
    if args.output:
        outputs.write(study, args.output)
    if args.json:
        options.print_json(study.to_dict())
    else:
        cli_text.print_design(study, args.output)
        if study.sobol is not None:
            cli_text.print_sobol(study.sobol, args.output)
    return ExitCode.OK
