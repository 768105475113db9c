"""`springlab sweep`: a scenario over a grid (or random samples) of parameters, batched; or a model file over its
MJCF options and named attributes."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from springlab import outputs
from springlab.cli import model_text, options
from springlab.cli import text as cli_text
from springlab.errors import BadInputError, ExitCode
from springlab.sim import model_files
from springlab.sim.simulate import INTEGRATORS

if TYPE_CHECKING:
    from springlab.studies.sweeps import AxisSpec

NAME = "sweep"
HELP = "run a scenario (or MODEL.xml: its options, named attributes) over a grid of parameters, batched"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    options.scene_arguments(parser, model_files=True)
    parser.add_argument(
        "--keyframe", metavar="NAME|INDEX", help="a model file: where every run starts (default: first keyframe)"
    )
    parser.add_argument(
        "--vary",
        action="append",
        default=[],
        required=True,
        metavar="NAME=LOW:HIGH:N[:log]",
        help="vary a parameter over N values from LOW to HIGH, SI units (repeatable; :log for log spacing); a model"
        " file: opt.OPTION or KIND.NAME.ATTRIBUTE[INDEX], e.g. opt.impratio, geom.box.friction, opt.integrator=euler,rk4",
    )
    parser.add_argument("--samples", type=int, metavar="N", help="N random points in the box instead of the full grid")
    parser.add_argument("--seed", type=int, default=0, help="seed of the random points (default 0)")
    parser.add_argument("--integrator", metavar="NAME", help=f"one of {', '.join(INTEGRATORS)} (default: the scene's)")
    parser.add_argument("--dt", type=float, metavar="SECONDS", help="timestep [s] (default: the scene's validated one)")
    parser.add_argument(
        "--duration", type=float, metavar="SECONDS", help="simulated time [s] (default: the scenario's)"
    )
    parser.add_argument(
        "--quantity", metavar="NAME", help="what sweep.png shows (default: the scenario's headline quantity)"
    )
    options.executor_arguments(parser)
    parser.add_argument("--output", metavar="DIR", help="write DIR/sweep.csv and DIR/sweep.png")
    parser.add_argument("--json", action="store_true", help="print the sweep (setting, counts, every row) as JSON")


_AXIS_FORM = "--vary takes NAME=LOW:HIGH:N[:log], e.g. damping=0.5:40:30:log"


def parse_axis(text: str) -> tuple[str, AxisSpec]:
    """'NAME=LOW:HIGH:N[:log]' (N may be left out for --samples) -> (NAME, the library's checked axis tuple).

    Raises
    ------
    BadInputError
        the text does not have that form, or the numbers make no range.
    """
    from springlab.studies.sweeps import make_axis

    name, sep, spec = str(text).partition("=")
    if not sep or not name.strip():
        raise BadInputError(f"{_AXIS_FORM}; got {text!r}")
    parts = spec.split(":")
    log = bool(parts) and parts[-1].strip().lower() == "log"
    if log:
        parts = parts[:-1]
    if len(parts) not in (2, 3):
        raise BadInputError(f"{_AXIS_FORM}; got {text!r}")
    try:
        low, high = float(parts[0]), float(parts[1])
        count = int(parts[2]) if len(parts) == 3 else None
    except ValueError:
        raise BadInputError(f"{_AXIS_FORM} (LOW, HIGH numbers, N an integer); got {text!r}") from None
    axis = make_axis(name.strip(), low, high, count, log)
    return axis.name, (axis.low, axis.high, axis.count, "log") if axis.log else (axis.low, axis.high, axis.count)


def _vary(texts: list[str]) -> dict[str, AxisSpec]:
    """--vary's 'NAME=LOW:HIGH:N[:log]' texts -> sweep's typed `vary` mapping (each text checked)."""
    axes = [parse_axis(text) for text in texts]
    names = [name for name, _ in axes]
    if len(set(names)) != len(names):
        raise BadInputError(f"a parameter is varied twice: {', '.join(names)}")
    return dict(axes)


def _model_vary(texts: list[str]) -> dict[str, AxisSpec | tuple[str, ...]]:
    """--vary on a model file -> model_sweep's typed `vary`: 'NAME=LOW:HIGH:N[:log]' an axis tuple,
    'opt.integrator=euler,rk4' and 'opt.cone=pyramidal,elliptic' a tuple of names."""
    from springlab.studies.model_sweep import CHOICES, FORM

    vary: list[tuple[str, AxisSpec | tuple[str, ...]]] = []
    for text in texts:
        name, sep, spec = str(text).partition("=")
        name = name.strip()
        if not sep or not name:
            raise BadInputError(f"--vary takes NAME=LOW:HIGH:N[:log] (a model file: {FORM}); got {text!r}")
        if name.removeprefix("opt.") in CHOICES:
            vary.append((name, tuple(part.strip() for part in spec.split(",") if part.strip())))
        else:
            vary.append(parse_axis(text))
    names = [name for name, _ in vary]
    if len(set(names)) != len(names):
        raise BadInputError(f"a name is varied twice: {', '.join(names)}")
    return dict(vary)


def main(args: argparse.Namespace) -> int:
    from springlab.studies import sweeps

    if model_files.is_model_file(args.scene):
        return _model_file(args)
    if args.keyframe is not None:
        raise BadInputError(f"--keyframe applies to a model file (MODEL.xml), not to the scene {args.scene!r}")
    options.check_output(args)
    with options.executor(args) as executor:
        result = sweeps.sweep(
            args.scene,
            args.scenario,
            vary=_vary(args.vary),
            samples=args.samples,
            sample_seed=args.seed,
            integrator=args.integrator,
            dt=args.dt,
            duration=args.duration,
            executor=executor,
            **options.parse_sets(args.set),
        )
    if args.output:
        outputs.write(result, args.output, quantity=args.quantity)
    if args.json:
        options.print_json(result.to_dict())
        return ExitCode.OK
    cli_text.print_sweep(result, args.quantity, args.output)
    return ExitCode.OK


def _model_file(args: argparse.Namespace) -> int:
    """`sweep MODEL.xml`: its options and named attributes over the grid, each row what `run MODEL.xml` measures."""
    from springlab.studies.model_sweep import default_quantity, model_sweep

    options.refuse_scene_options(args, "scenario", "set")
    options.check_output(args)
    with options.executor(args) as executor:
        result = model_sweep(
            args.scene,
            vary=_model_vary(args.vary),
            keyframe=args.keyframe,
            samples=args.samples,
            sample_seed=args.seed,
            integrator=args.integrator,
            dt=args.dt,
            duration=args.duration,
            executor=executor,
        )
    quantity = args.quantity or default_quantity(result)
    known = [*result.values, *result.quantity_names()]
    if quantity not in known:
        raise BadInputError(f"unknown --quantity {quantity!r}; valid: {', '.join(known)}")
    if args.output:
        outputs.write(result, args.output, quantity=quantity)
    if args.json:
        options.print_json(result.to_dict())
        return ExitCode.OK
    model_text.print_model_sweep(result, quantity, args.output)
    return ExitCode.OK
