"""`springlab fit`: identify a scene's parameters from a recorded signal (CSV)."""

from __future__ import annotations

import argparse

from springlab import scenes
from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import BadInputError, ExitCode

NAME = "fit"
HELP = "identify a scene's parameters from a recorded signal (CSV)"
#: what to run on a model file instead (this command takes a scene: springlab.cli.main refuses a model file)
MODEL_FILE_INSTEAD = "'springlab sweep MODEL.xml --vary NAME=LOW:HIGH:N'"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    # the scenes that declare a fit (Scene.fit), e.g. "slider, car, printer_head or kinematics"
    fittable = [name for name, scene in scenes.SCENES.items() if scene.fit is not None]
    listed = ", ".join(fittable[:-1]) + " or " + fittable[-1] if len(fittable) > 1 else "".join(fittable)
    parser.add_argument("scene", help=listed)
    parser.add_argument(
        "data", metavar="DATA.csv", help="header row (',', ';' or tab); time [s] and <joint>_pos, _vel or _acc [SI]"
    )
    parser.add_argument(
        "--scenario", metavar="S", help="the scenario the record shows (default: the scene's fit default)"
    )
    parser.add_argument(
        "--map", action="append", default=[], metavar="COLUMN=NAME", help="rename a file column (t=time, x=slider_pos)"
    )
    parser.add_argument(
        "--free", action="append", default=[], metavar="NAME[,NAME...]", help="names to fit (default: the scene's)"
    )
    options.set_argument(parser, help="fix a parameter, SI units (repeatable)")
    parser.add_argument("--start", type=float, metavar="S", help="release time [s]: drop the record before it")
    parser.add_argument(
        "--scale",
        type=float,
        metavar="FACTOR",
        help="SI units per unit of the signal column (mm: 0.001); default: the unit its name states (x_mm, x [mm]), else SI",
    )
    parser.add_argument(
        "--time-scale",
        type=float,
        metavar="FACTOR",
        help="seconds per unit of the time column (ms: 0.001); default: the unit its name states (t_ms, t (ms)), else s",
    )
    parser.add_argument("--degree", type=int, metavar="N", help="kinematics: degree 0-3 of the polynomial")
    parser.add_argument(
        "--starts",
        type=int,
        default=1,
        metavar="N",
        help="independent optimizations, the lowest cost wins (default 1: the linear-algebra start)",
    )
    options.executor_arguments(parser)
    parser.add_argument("--output", metavar="DIR", help="write fit.json, fit.png, trajectory.csv and summary.json")
    parser.add_argument("--json", action="store_true", help="print fit.json")


def _map(items: list[str]) -> dict[str, str]:
    """--map's COLUMN=NAME (repeatable) -> {file column: springlab name}."""
    mapping = {}
    for item in items:
        column, sep, name = str(item).partition("=")
        if not sep or not column.strip() or not name.strip():
            raise BadInputError(f"--map takes COLUMN=NAME (e.g. t=time, x=slider_pos), got {item!r}")
        mapping[column.strip()] = name.strip()
    return mapping


def _free(items: list[str]) -> list[str] | None:
    """--free's NAME[,NAME...] (repeatable) -> the names (None: not given)."""
    if not items:
        return None
    names = [name.strip() for item in items for name in item.split(",") if name.strip()]
    if not names:
        raise BadInputError("--free needs at least one name")
    return names


def main(args: argparse.Namespace) -> int:
    # here, not at the top: mujoco.sysid and scipy load only for fits; `from .fit import`, because
    # springlab.fit (the attribute) is the function once springlab/__init__ has run
    from springlab import outputs
    from springlab.studies.fit.fit import fit

    options.check_output(args)
    with options.executor(args) as executor:
        result = fit(
            args.scene,
            args.data,
            args.scenario,
            map=_map(args.map),
            free=_free(args.free),
            scale=args.scale,
            time_scale=args.time_scale,
            start=args.start,
            degree=args.degree,
            starts=args.starts,
            executor=executor,
            show_progress=False if args.json else None,
            **options.parse_sets(args.set),
        )
    if args.output:
        outputs.write(result, args.output)
    if args.json:
        options.print_json(result.to_dict())
    else:
        cli_text.print_fit(result, args.output)
    return ExitCode.OK if result.converged else ExitCode.FAILED
