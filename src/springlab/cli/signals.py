"""SIGTERM as an exception: a timeout or a batch scheduler unwinds a command like Ctrl-C, so the files it was
writing are removed (springlab.files writes atomically)."""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator


class Terminated(BaseException):
    """SIGTERM arrived (a timeout, a batch scheduler): unwinds like Ctrl-C, so partial files are removed."""


def _raise_terminated(signum, frame) -> None:
    raise Terminated


@contextlib.contextmanager
def sigterm_unwinds() -> Iterator[None]:
    """Turn SIGTERM into the Terminated exception for the duration (main thread only; restored after)."""
    try:
        previous = signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
