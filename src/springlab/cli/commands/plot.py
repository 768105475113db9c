"""`springlab plot`: a scenario's time series, phase plane, family of displacements or zeta family."""

from __future__ import annotations

import argparse

from springlab.cli import options
from springlab.errors import ExitCode

NAME = "plot"
HELP = "plot a scenario: time series, phase plane, family, zeta family"
#: what to run on a model file instead (this command takes a scene: springlab.cli.main refuses a model file)
MODEL_FILE_INSTEAD = "'springlab run MODEL.xml --output DIR' (trajectory.csv)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    options.scene_arguments(parser)
    options.timing_arguments(parser)
    parser.add_argument("--output", required=True, metavar="FILE", help="FILE.png, FILE.svg or FILE.pdf")
    parser.add_argument(
        "--kind",
        default="time",
        choices=("time", "phase", "family", "zeta", "scene"),
        help="time: x(t), v(t) with the exact solution and the error on a log axis (default); "
        "phase: phase plane with vector field, equilibria, separatrices; "
        "scene: the panels the scene declares (e.g. the drill string's speeds, twist and mode shapes); "
        "family: phase trajectories from several initial displacements; "
        "zeta: responses for damping ratios 0 to 2",
    )


def main(args: argparse.Namespace) -> int:
    """Plot a scenario: time series (default), phase plane, family of displacements or zeta family."""
    from springlab.plots import run as plots
    from springlab.studies import families

    plots.check_output(args.output)
    if args.kind == "zeta":
        figure = plots.zeta_family(
            families.run_zeta_family(
                args.scene,
                args.scenario,
                integrator=args.integrator,
                dt=args.dt,
                duration=args.duration,
                **options.parse_sets(args.set),
            )
        )
        verdict: int = ExitCode.OK
    else:
        result = options.run(args)
        if args.kind == "family":
            figure = plots.phase_family(families.run_phase_family(result))
            verdict = ExitCode.OK  # a family is a picture of many runs; the verdict belongs to single runs
        else:
            draw = {"time": plots.time_series, "phase": plots.phase_plane, "scene": plots.scene_figure}[args.kind]
            figure = draw(result)
            verdict = options.verdict(result)
    print(f"wrote {plots.save(figure, args.output)}")
    return verdict
