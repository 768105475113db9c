"""What the `springlab` commands share: the parser class, the common options, and their parsing.

Only the command line parses strings ("mass=2", "0.002,0.001"); the library takes typed values.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

from springlab import files
from springlab.errors import BadInputError, ExitCode
from springlab.runs.compare import Verdict
from springlab.runs.run import Result
from springlab.sim.simulate import INTEGRATORS
from springlab.studies import auto
from springlab.studies.executor import CONNECT_TIMEOUT_S, Executor


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors and exit code 2."""

    def error(self, message: str) -> NoReturn:  # noqa: D401 - argparse hook
        raise BadInputError(f"{message} (see '{self.prog} --help')")

    def parse_known_args(  # type: ignore[override]  # argparse's overloads; one signature here
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        # a command's own parser takes options and positionals in any order
        # (`run slider --set x0=0.05 harmonic`); argparse's intermixed parsing calls
        # back into this method, hence the guard
        if self._subparsers is not None or getattr(self, "_intermixing", False):
            return super().parse_known_args(args, namespace)
        self._intermixing = True
        try:
            return self.parse_known_intermixed_args(args, namespace)
        finally:
            self._intermixing = False


# -- parsing the strings -----------------------------------------------------------


def parse_sets(pairs: Sequence[str]) -> dict[str, Any]:
    """['mass=2', ...] -> {'mass': 2.0}; the names and ranges are checked by the scene.

    The library takes numbers; a VALUE that is not one stays text, which the scene refuses naming the
    parameter's valid range (`mass must be a number > 0 kg, got 'abc'`).
    """
    out: dict[str, Any] = {}
    for pair in pairs or ():
        name, sep, value = pair.partition("=")
        if not sep or not name.strip():
            raise BadInputError(f"--set takes NAME=VALUE, got {pair!r}")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            out[name.strip()] = value.strip()
    return out


def numbers(option: str, text: str) -> list[float]:
    """'a,b,c' -> [a, b, c] (floats), or BadInputError naming the option."""
    try:
        return [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise BadInputError(f"{option} takes numbers separated by commas, e.g. 0.002,0.001; got {text!r}") from None


def names(text: str | None) -> list[str] | None:
    """'a,b' -> ['a', 'b'] (None: the option was not given, or given empty)."""
    return [name.strip() for name in text.split(",")] if text else None


def print_json(value: Any) -> None:
    """Print a result's dict as the JSON its file holds."""
    print(files.dumps(value))


# -- options several commands share -------------------------------------------------


def scene_arguments(parser: argparse.ArgumentParser, *, model_files: bool = False) -> None:
    """SCENE [SCENARIO] [--set NAME=VALUE]... (`model_files`: SCENE may also be a model file MODEL.xml)."""
    parser.add_argument(
        "scene",
        help="scene name (see 'springlab list') or a model file MODEL.xml"
        if model_files
        else "scene name (see 'springlab list')",
    )
    parser.add_argument("scenario", nargs="?", help="scenario name (default: the scene's first)")
    set_argument(parser)


def set_argument(parser: argparse.ArgumentParser, help: str = "override a parameter, SI units (repeatable)") -> None:
    """--set NAME=VALUE (repeatable)."""
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help=help)


def timing_arguments(parser: argparse.ArgumentParser) -> None:
    """--integrator, --dt, --duration and --tol of one run."""
    parser.add_argument(
        "--integrator",
        choices=None,
        metavar="NAME",
        help=f"one of {', '.join(INTEGRATORS)} (default: the scene's validated one), or auto:"
        " the cheapest setting that meets --tol (see 'springlab tradeoff')",
    )
    parser.add_argument("--dt", type=float, metavar="SECONDS", help="timestep [s]")
    parser.add_argument("--duration", type=float, metavar="SECONDS", help="simulated time [s]")
    parser.add_argument(
        "--tol",
        type=float,
        metavar="TOL",
        help="relative tolerance to hold the run to (default: the integrator's predicted error)",
    )


def refuse_scene_options(args: argparse.Namespace, *names: str) -> None:
    """A scene's options given with a model file are bad input, said in one line (`names`: attributes of
    `args`, e.g. 'scenario', 'set', 'tol')."""
    for name in names:
        if getattr(args, name, None):
            option = name if name == "scenario" else f"--{name.replace('_', '-')}"
            raise BadInputError(f"{option} applies to a scene, not to a model file ({args.scene})")


def executor_arguments(parser: argparse.ArgumentParser) -> None:
    """--workers N | --scheduler ADDRESS, and --verbose."""
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--workers", type=int, metavar="N", help="run the chunks on a local dask cluster of N worker processes"
    )
    where.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run the chunks on a running dask scheduler, e.g. tcp://10.0.0.5:8786"
        f" (unreachable for {CONNECT_TIMEOUT_S:g} s: exit 2)",
    )
    parser.add_argument(
        "--verbose",
        action="store_true",
        help="with --workers/--scheduler: let dask.distributed's own log lines through to stderr",
    )


def executor(args: argparse.Namespace, nthread: int = 0) -> Executor:
    """Where a study's chunks run: locally (default, on `nthread` threads), --workers N or --scheduler ADDRESS."""
    return Executor(
        workers=args.workers,
        scheduler=args.scheduler,
        progress=False if args.json else None,
        nthread=nthread,
        quiet=not args.verbose,
    )


def check_output(args: argparse.Namespace) -> None:
    """An unwritable --output DIR is bad input before seconds of computing, not after."""
    if args.output:
        files.check_directory(args.output)


# -- one run, as run, render, plot and view make it -----------------------------------------


def run(args: argparse.Namespace) -> Result:
    """springlab.run from the scene, timing and --set arguments that run, render and plot share (a scene's run:
    a model file was refused before, springlab.cli.main)."""
    result = auto.run(
        args.scene,
        args.scenario,
        integrator=args.integrator,
        dt=args.dt,
        duration=args.duration,
        tol=args.tol,
        **parse_sets(args.set),
    )
    if not isinstance(result, Result):  # a model file reached a command that takes a scene
        raise BadInputError(f"{args.scene} is a model file; this command takes a scene (see 'springlab list')")
    return result


def report_model_limits(result: Result) -> None:
    """One stderr line per place the run left the range its scene's equations describe."""
    for limit in result.model_limits:
        print(f"springlab: {result.scene} {result.scenario} is not validated: {limit}", file=sys.stderr)


def verdict(result: Result) -> int:
    """Exit code of a run whose outputs were written: 1 when outside its tolerance or its model's range."""
    report_model_limits(result)
    if result.model_limits:
        return ExitCode.FAILED
    if result.passed is False:
        if result.verdict is Verdict.NOT_VALIDATED and result.estimate_range is not None:
            why = f"not validated ({result.estimate_range.reason()})"
        elif result.tolerance is not None:
            why = f"outside its tolerance (max error above {result.tolerance:.2e})"
        else:  # held to its checks alone
            why = f"outside its tolerance ({result.message})"
        print(f"  note: {result.scene}/{result.scenario} is {why}; see 'springlab run'", file=sys.stderr)
        return ExitCode.FAILED
    return ExitCode.OK
