"""Watch textbook vibration problems run in MuJoCo, each checked against its exact solution.

The `springlab` command line (argparse; every command calls the library). Each command is one module of
springlab.cli.commands (its options, the parsing of its strings, its call and its text); this module lists
them, builds the parser and maps what comes back to an exit code (springlab.errors.ExitCode: 0 ok; 1 a
validation fell outside its tolerance; 2 bad input; 3 the simulation diverged, nothing written; 130
interrupted, Ctrl-C; 143 terminated, SIGTERM). Errors are one line on stderr.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from collections.abc import Sequence
from types import ModuleType

from springlab import __version__
from springlab.cli.commands import (
    audit,
    catalogue,
    demo,
    design,
    fit,
    frequency,
    friction_settings,
    interactive,
    plot,
    refine,
    render,
    rms,
    run,
    stability,
    sweep,
    tradeoff,
    validate,
    view,
)
from springlab.cli.options import Parser
from springlab.cli.signals import Terminated, sigterm_unwinds
from springlab.errors import BadInputError, ExitCode, SpringlabError
from springlab.sim import model_files

#: the commands in the order `springlab --help` lists them; each module has NAME, HELP, add_arguments, main
COMMANDS: tuple[ModuleType, ...] = (
    catalogue,
    run,
    validate,
    render,
    plot,
    tradeoff,
    refine,
    rms,
    stability,
    audit,
    frequency,
    design,
    sweep,
    friction_settings,
    fit,
    view,
    interactive,
    demo,
)


def build_parser() -> argparse.ArgumentParser:
    """The `springlab` parser: one subcommand per module of COMMANDS, its `main` as the `command` default."""
    parser = Parser(
        prog="springlab",
        description=__doc__.splitlines()[0],
        epilog="Start with 'springlab list' and 'springlab run slider'. Exit codes: "
        f"{ExitCode.OK} ok, {ExitCode.FAILED} outside tolerance, {ExitCode.BAD_INPUT} bad input, "
        f"{ExitCode.DIVERGED} diverged, {ExitCode.INTERRUPTED} interrupted, {ExitCode.TERMINATED} terminated.",
    )
    parser.add_argument("--version", action="version", version=f"springlab {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser, metavar="COMMAND")
    for command in COMMANDS:
        command_parser = sub.add_parser(command.NAME, help=command.HELP)
        command.add_arguments(command_parser)
        command_parser.set_defaults(main=command.main, model_file_instead=getattr(command, "MODEL_FILE_INSTEAD", None))
    return parser


def refuse_model_file(args: argparse.Namespace) -> None:
    """A model file given to a command that takes a scene (its module's MODEL_FILE_INSTEAD) is bad input: one
    line naming what to run on a model file instead, before any work."""
    instead = getattr(args, "model_file_instead", None)
    if instead is None:
        return
    given = [getattr(args, "scene", None), *(getattr(args, "scenes", None) or [])]
    model = next((name for name in given if name is not None and model_files.is_model_file(name)), None)
    if model is not None:
        raise BadInputError(f"{args.command} takes a scene, not a model file ({model}); for a model file use {instead}")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `springlab` console script; returns the exit code."""
    try:
        # the terminal gets springlab's one-line answers, never warning text (numpy's overflow
        # warnings at extreme values, library deprecations); the API leaves warnings alone
        with sigterm_unwinds(), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            args = build_parser().parse_args(argv)
            refuse_model_file(args)
            return int(args.main(args))
    except SystemExit as done:  # --help, --version
        return done.code if isinstance(done.code, int) else ExitCode.OK
    except SpringlabError as error:
        print(f"springlab: error: {error}", file=sys.stderr)
        return int(error.exit_code)
    except KeyboardInterrupt as stop:
        print(f"springlab: interrupted{''.join(getattr(stop, '__notes__', ()))}", file=sys.stderr)
        return ExitCode.INTERRUPTED
    except Terminated as stop:
        print(f"springlab: terminated{''.join(getattr(stop, '__notes__', ()))}", file=sys.stderr)
        return ExitCode.TERMINATED
    except BrokenPipeError:
        # the reader went away (`springlab list | head`): stop quietly, as Unix tools do;
        # point stdout at devnull so the interpreter's final flush cannot raise again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return ExitCode.BROKEN_PIPE


if __name__ == "__main__":
    sys.exit(main())
