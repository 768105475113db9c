"""Progress bars for long work (renders, sweeps, the demo), shared by every command.

One rule for all of them: a bar (tqdm, with count, rate and ETA) is drawn on
stderr only when stderr is a terminal and the command was not asked for
machine-readable output (``--json``); otherwise nothing is printed, so pipes,
logs and ``--json`` output stay clean.

Usage::

    from springlab import progress

    with progress.bar(total=n_frames, description="rendering", unit="frame", enabled=not args.json) as bar:
        for ...:
            bar.update(1)

A disabled bar is a real ``tqdm`` object with ``disable=True``: ``update`` and
``close`` cost next to nothing, so callers never branch on it.
"""

from __future__ import annotations

import sys
from typing import IO, Any

__all__ = ["bar", "on_terminal"]


def on_terminal(stream: IO[str] | None = None) -> bool:
    """True when ``stream`` (default: the current ``sys.stderr``) is an interactive terminal."""
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream is not None and stream.isatty())
    except (AttributeError, ValueError):  # closed or replaced streams
        return False


def bar(
    total: int | None,
    *,
    description: str,
    unit: str = "it",
    unit_scale: bool = False,
    enabled: bool | None = None,
    stream: IO[str] | None = None,
) -> Any:
    """A tqdm progress bar on ``stream`` (default stderr), or a silent one.

    Parameters
    ----------
    total:
        Number of units of work [count], or None when unknown (no ETA then).
    description:
        Short text before the bar, e.g. ``"rendering"``.
    unit:
        Name of one unit of work, e.g. ``"frame"`` or ``"run"``; the rate is
        shown in units per second.
    unit_scale:
        Show counts with SI prefixes (k, M, G): for bytes, ``unit="B"``.
    enabled:
        False: silent (``--json``, tests). True: draw on ``stream`` even if it
        is not a terminal. None (default): draw only when ``stream`` is a
        terminal.
    stream:
        Where to draw [text stream]; default ``sys.stderr`` at call time.

    Returns
    -------
    A ``tqdm.tqdm`` instance (a context manager; ``update(n)``, ``close()``).
    """
    from tqdm import tqdm  # imported on use: no cost for commands that never draw a bar

    stream = sys.stderr if stream is None else stream
    if enabled is None:
        enabled = on_terminal(stream)
    return tqdm(
        total=total,
        desc=description,
        unit=unit,
        unit_scale=unit_scale,
        file=stream,
        disable=not enabled,
        mininterval=0.1,  # [s] between redraws: cheap next to a frame or a run
        dynamic_ncols=True,
        leave=True,
    )
