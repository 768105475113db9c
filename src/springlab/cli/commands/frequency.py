"""`springlab frequency`: the frequency response of any model's linearization, and the band an integrator
reproduces."""

from __future__ import annotations

import argparse

from springlab import outputs
from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import BadInputError, ExitCode
from springlab.sim.simulate import INTEGRATORS
from springlab.studies.frequency import DEFAULT_POINTS
from springlab.studies.frequency import DEFAULT_TOL as FREQUENCY_TOL
from springlab.studies.frequency import frequency as run_frequency

NAME = "frequency"
HELP = "frequency response of any model's linearization, and the band an integrator reproduces"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", help="path to an MJCF file, or a scene name")
    parser.add_argument(
        "scenario", nargs="?", help="a scene's scenario (default: the one its frequency response declares)"
    )
    parser.add_argument(
        "--input", metavar="NAME", help="an actuator (its control) or JOINT:force (a force on the joint)"
    )
    parser.add_argument(
        "--response", metavar="NAME", help="JOINT (position), JOINT:vel, JOINT:acc, or a sensor SENSOR or SENSOR[i]"
    )
    options.set_argument(parser, help="a scene's parameter, SI units (repeatable)")
    parser.add_argument(
        "--band",
        metavar="FMIN:FMAX",
        help="frequency band [Hz] (default: a decade below the slowest mode to 3x the fastest)",
    )
    parser.add_argument(
        "--points", type=int, default=DEFAULT_POINTS, metavar="N", help="log-spaced frequencies (default 200)"
    )
    parser.add_argument(
        "--integrator", metavar="NAME", help=f"one of {', '.join(INTEGRATORS)} (default: the scene's or model's)"
    )
    parser.add_argument("--dt", type=float, metavar="SECONDS", help="timestep [s] (default: the scene's or model's)")
    parser.add_argument(
        "--tol",
        type=float,
        default=FREQUENCY_TOL,
        metavar="TOL",
        help="tolerance on the relative error |H_d / H - 1| in (0, 1) (default 1e-3)",
    )
    parser.add_argument(
        "--sinestream",
        type=int,
        default=0,
        metavar="N",
        help="verify by simulating N sines in MuJoCo over the band and an octave above (default 0: none)",
    )
    parser.add_argument(
        "--amplitude",
        metavar="A1,A2,...",
        help="sinestream input amplitudes in input units (N for a force); several show amplitude dependence",
    )
    parser.add_argument(
        "--sweep",
        choices=("up", "down", "both"),
        help="sweep the band in frequency, each sine from the last one's state (a non-linear model's jump)",
    )
    parser.add_argument("--output", metavar="DIR", help="write DIR/frequency.json, frequency.csv and bode.png")
    parser.add_argument("--json", action="store_true", help="print frequency.json")
    options.executor_arguments(parser)


def parse_band(text: str) -> tuple[float, float]:
    """'FMIN:FMAX' [Hz] -> (fmin, fmax) (checked by springlab.frequency: finite, 0 < fmin < fmax)."""
    parts = str(text).split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        return float(parts[0]), float(parts[1])
    except ValueError:
        raise BadInputError(f"--band must be FMIN:FMAX in Hz (e.g. 0.1:100), got {text!r}") from None


def parse_amplitudes(text: str | None) -> tuple[float, ...] | None:
    """'A1,A2,...' -> floats (checked by springlab.frequency); None: the default amplitude."""
    if text is None:
        return None
    try:
        return tuple(float(part) for part in text.split(","))
    except ValueError:
        raise BadInputError(f"--amplitude takes A1,A2,... in input units (e.g. 0.5,2), got {text!r}") from None


def main(args: argparse.Namespace) -> int:
    options.check_output(args)
    with options.executor(args) as executor:
        result = run_frequency(
            args.model,
            args.scenario,
            input=args.input,
            response=args.response,
            band=None if args.band is None else parse_band(args.band),
            points=args.points,
            integrator=args.integrator,
            dt=args.dt,
            tol=args.tol,
            sines=args.sinestream,
            executor=executor,
            amplitudes=parse_amplitudes(args.amplitude),
            sweep=args.sweep,
            **options.parse_sets(args.set),
        )
    if args.output:
        outputs.write(result, args.output)
    if args.json:
        options.print_json(result.to_dict())
    else:
        cli_text.print_frequency(result, args.output)
    # several amplitudes ask whether the response depends on the amplitude: a non-linear model's departure from
    # its linearization is then the answer, not a failure; a sweep must stay within its harmonic-balance bound
    single = len(result.sinestreams) <= 1
    agrees = (result.sinestream is None or result.sinestream.agrees or not single) and result.sweeps_agree
    return ExitCode.OK if result.covers_band and agrees else ExitCode.FAILED
