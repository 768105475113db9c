"""springlab's exceptions: one base class, each with the CLI exit code it maps to.

A run outside its tolerance is not an exception: it is a result with
summary["passed"] False (exit 1), so its outputs are still written.

Messages are one line that says what was wrong and what is valid, so the CLI can
print them as they are.
"""

from __future__ import annotations

import enum
import signal
from collections.abc import Iterable


class ExitCode(enum.IntEnum):
    """The `springlab` command's exit codes (docs/cli.md); each exception below carries its own."""

    #: the run or study answered its question (and passed where it is validated)
    OK = 0
    #: a validation fell outside its tolerance (the outputs are still written)
    FAILED = 1
    #: usage, an unknown name, a non-physical value, an unwritable output, a lost cluster
    BAD_INPUT = 2
    #: the simulation diverged (nothing written)
    DIVERGED = 3
    #: the reader of stdout went away (`springlab list | head`): 128 + SIGPIPE, as Unix tools exit
    BROKEN_PIPE = 128 + 13
    #: Ctrl-C: 128 + SIGINT, as shells report a process a signal ended
    INTERRUPTED = 128 + signal.SIGINT
    #: SIGTERM (a timeout, a batch scheduler): 128 + SIGTERM
    TERMINATED = 128 + signal.SIGTERM


class SpringlabError(Exception):
    """Base class of every error springlab raises on purpose."""

    exit_code = ExitCode.BAD_INPUT


class BadInputError(SpringlabError, ValueError):
    """Usage error, unknown name, non-physical value or unwritable output (exit 2)."""

    exit_code = ExitCode.BAD_INPUT


class UnknownNameError(BadInputError):
    """A scene, scenario, parameter or integrator name that does not exist (exit 2)."""

    def __init__(self, kind: str, name: str, valid: Iterable[str]):
        self.kind, self.name, self.valid = kind, name, sorted(valid)
        super().__init__(f"unknown {kind} {name!r}; valid: {', '.join(self.valid)}")


class ParameterError(BadInputError):
    """A parameter value that is not a finite number in its valid range (exit 2)."""


class DivergedError(SpringlabError):
    """The simulation blew up; nothing is reported or written for it (exit 3)."""

    exit_code = ExitCode.DIVERGED


class ClusterError(SpringlabError):
    """The dask cluster a study ran on was lost mid-run (scheduler gone, no workers left, a chunk's
    workers all died); the study stopped and returned nothing (exit 2, like an unreachable scheduler)."""

    exit_code = ExitCode.BAD_INPUT
