"""`springlab audit`: any MJCF's modes, stability limits, error against cost, the cheapest setting for --tol."""

from __future__ import annotations

import argparse
import math

import numpy as np

from springlab import outputs
from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import BadInputError, ExitCode
from springlab.sim.simulate import INTEGRATORS
from springlab.studies.audit.audit import audit as run_audit
from springlab.studies.audit.options import DEFAULT_PERTURB, DEFAULT_TOL

NAME = "audit"
HELP = "any MJCF: modes, stability limits, error vs cost, the cheapest setting for --tol"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", help="path to an MJCF (or URDF) file, or a scene name")
    parser.add_argument(
        "--keyframe", metavar="NAME|INDEX", help="operating point (default: first keyframe, else qpos0)"
    )
    parser.add_argument(
        "--settle",
        type=float,
        metavar="SECONDS",
        help="let the model move this long at its own setting first and audit it where it comes to rest"
        " (a robot standing or lying on the floor; default: audit the keyframe as it is)",
    )
    parser.add_argument(
        "--tol", type=float, default=DEFAULT_TOL, metavar="TOL", help="error tolerance in (0, 1) (default 1e-3)"
    )
    parser.add_argument("--integrators", metavar="A,B", help=f"integrators to sweep (default: {','.join(INTEGRATORS)})")
    parser.add_argument("--dt", metavar="LIST|RANGE", help="timesteps 'a,b,c' or 'LOW:HIGH:N' [s] (default: automatic)")
    parser.add_argument(
        "--duration", type=float, metavar="SECONDS", help="simulated time [s] (default 1; a scene's own)"
    )
    parser.add_argument(
        "--perturb",
        type=float,
        default=DEFAULT_PERTURB,
        metavar="SIZE",
        help="initial perturbation of the operating point [m or rad] (default 1e-3)",
    )
    parser.add_argument("--output", metavar="DIR", help="write DIR/audit.json and DIR/audit.png")
    parser.add_argument("--json", action="store_true", help="print audit.json")
    options.executor_arguments(parser)


def parse_integrators(text: str | None) -> list[str] | None:
    """--integrators 'a,b' -> ['a', 'b'] (None: all five)."""
    if text is None:
        return None
    names = [name.strip() for name in text.split(",") if name.strip()]
    if not names:
        raise BadInputError(f"--integrators needs at least one of {', '.join(INTEGRATORS)}")
    return names


def parse_dts(text: str | None) -> list[float] | None:
    """--dt: seconds 'a,b,c', or a range 'LOW:HIGH:N' (N log-spaced values, each snapped to HIGH / m for an
    integer m so that they share checkpoints); None: the audit's default grid."""
    if text is None:
        return None
    spec = text.strip()
    try:
        if ":" in spec:
            low_text, high_text, count_text = spec.split(":")
            low, high, count = float(low_text), float(high_text), int(count_text)
            if not (0 < low < high and math.isfinite(high) and count >= 2):
                raise ValueError
            values = sorted({high / round(high / v) for v in np.geomspace(low, high, count)}, reverse=True)
        else:
            values = [float(v) for v in spec.split(",") if v.strip()]
    except ValueError:
        raise BadInputError(
            f"--dt must be seconds 'a,b,c' or a range 'LOW:HIGH:N' with 0 < LOW < HIGH, N >= 2; got {text!r}"
        ) from None
    if not values or any(not (math.isfinite(v) and v > 0) for v in values):
        raise BadInputError(f"every dt must be a finite number > 0 s, got {text!r}")
    return values


def main(args: argparse.Namespace) -> int:
    options.check_output(args)
    with options.executor(args) as executor:
        result = run_audit(
            args.model,
            keyframe=args.keyframe,
            settle_s=args.settle,
            tol=args.tol,
            integrators=parse_integrators(args.integrators),
            dts=parse_dts(args.dt),
            duration=args.duration,
            perturb=args.perturb,
            executor=executor,
        )
    if args.output:
        outputs.write(result, args.output)
    if args.json:
        options.print_json(result.to_dict())
    else:
        cli_text.print_audit(result, args.output)
    return ExitCode.OK if result.own_ok else ExitCode.FAILED
