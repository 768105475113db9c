"""springlab's exceptions: one base class, each with the CLI exit code it maps to.

A run outside its tolerance is not an exception: it is a result with
summary["passed"] False (exit 1), so its outputs are still written.

Messages are one line that says what was wrong and what is valid, so the CLI can
print them as they are.
"""

from __future__ import annotations

from collections.abc import Iterable


class SpringlabError(Exception):
    """Base class of every error springlab raises on purpose."""

    exit_code = 2


class BadInputError(SpringlabError, ValueError):
    """Usage error, unknown name, non-physical value or unwritable output (exit 2)."""

    exit_code = 2


class UnknownNameError(BadInputError):
    """A scene, scenario, parameter or integrator name that does not exist (exit 2)."""

    def __init__(self, kind: str, name: str, valid: Iterable[str]):
        self.kind, self.name, self.valid = kind, name, sorted(valid)
        super().__init__(f"unknown {kind} {name!r}; valid: {', '.join(self.valid)}")


class ParameterError(BadInputError):
    """A parameter value that is not a finite number in its valid range (exit 2)."""


class DivergedError(SpringlabError):
    """The simulation blew up; nothing is reported or written for it (exit 3)."""

    exit_code = 3


class ClusterError(SpringlabError):
    """The dask cluster a study ran on was lost mid-run (scheduler gone, no workers left, a chunk's
    workers all died); the study stopped and returned nothing (exit 2, like an unreachable scheduler)."""

    exit_code = 2
