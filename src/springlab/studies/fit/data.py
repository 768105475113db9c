"""Reading a measured record for `springlab fit`: the CSV, its untidy parts, and where the motion starts.

A record is one time column and one signal of one joint: its position
(`<joint>_pos` [m]), velocity (`<joint>_vel` [m/s]) or acceleration
(`<joint>_acc` [m/s^2], an accelerometer). Column names follow trajectory.csv;
`--map COLUMN=NAME` renames a column of the file to one of those names.

Untidy data is handled, and every step says what it did (`Record.notes`):

* uneven sampling: the model is simulated on its own fine grid and interpolated
  at the recorded times, so any strictly increasing times work;
* rows where the time or the signal is empty or NaN are skipped and counted;
* `scale` multiplies the signal into SI units (e.g. 0.001 for millimetres);
* a record that starts before the release (the signal held still, then let go):
  `start` [s] drops everything before it; without it the fit tests for a held
  part and drops it only when the data show it beyond their noise
  (springlab.studies.fit.release, `cut_at_release`);
* a constant offset, noise and a sensor delay are parameters of the fit, not of the data.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import os
from collections.abc import Mapping, Sequence

import numpy as np

from springlab.errors import BadInputError

#: signal suffixes and the SI unit of each
SIGNALS = {"pos": "m", "vel": "m/s", "acc": "m/s^2"}
#: preferred order when a file holds several signals of the joint
_PREFERENCE = ("pos", "acc", "vel")
#: fewest usable samples a record may have
MIN_SAMPLES = 10


@dataclasses.dataclass(frozen=True, eq=False)  # arrays: compare fields, not results
class Record:
    """A measured signal of one joint, cleaned (immutable: its arrays are read-only views).

    Attributes
    ----------
    time
        (n,) recorded times [s], strictly increasing, only the kept samples.
    values
        (n,) the signal in SI units (after `scale`).
    joint
        The joint it measures.
    signal
        'pos', 'vel' or 'acc'.
    column
        The file's column it came from.
    origin
        Time [s] the model's t = 0 corresponds to (first kept sample, or `start`).
    rows
        Data rows in the file.
    skipped_nan
        Rows skipped because the time or the signal was missing/NaN.
    dropped_before_start
        Samples before the release (or `start`) left out.
    release_detected
        Whether the release was found in the data (not given).
    notes
        One line per thing done to the data.
    """

    time: np.ndarray
    values: np.ndarray
    joint: str
    signal: str
    column: str
    origin: float
    rows: int
    skipped_nan: int = 0
    dropped_before_start: int = 0
    release_detected: bool = False
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for name in ("time", "values"):
            view = np.asarray(getattr(self, name), float).view()
            view.flags.writeable = False
            object.__setattr__(self, name, view)
        object.__setattr__(self, "notes", tuple(self.notes))

    @property
    def name(self) -> str:
        """The signal's trajectory.csv-style name, e.g. 'slider_pos'."""
        return f"{self.joint}_{self.signal}"

    @property
    def unit(self) -> str:
        """SI unit of the signal."""
        return SIGNALS[self.signal]

    @property
    def model_time(self) -> np.ndarray:
        """(n,) times since the origin [s]."""
        return self.time - self.origin


def parse_map(items: Sequence[str] | Mapping[str, str] | None) -> dict[str, str]:
    """`['t=time', 'x=slider_pos']` (or a dict) -> {file column: springlab name}."""
    if items is None:
        return {}
    if isinstance(items, Mapping):
        return {str(k): str(v) for k, v in items.items()}
    mapping = {}
    for item in items:
        column, sep, name = str(item).partition("=")
        if not sep or not column.strip() or not name.strip():
            raise BadInputError(f"--map takes COLUMN=NAME (e.g. t=time, x=slider_pos), got {item!r}")
        mapping[column.strip()] = name.strip()
    return mapping


def _read_rows(path: str | os.PathLike) -> tuple[list[str], list[list[str]]]:
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:
            rows = [row for row in csv.reader(handle) if row and any(cell.strip() for cell in row)]
    except (OSError, UnicodeDecodeError) as error:
        reason = getattr(error, "strerror", None) or str(error)
        raise BadInputError(f"cannot read {str(path)!r}: {reason}") from None
    except csv.Error as error:
        raise BadInputError(f"{str(path)!r} is not a CSV file: {error}") from None
    if not rows:
        raise BadInputError(f"{str(path)!r} is empty; it needs a header row and data rows")
    header = [cell.strip() for cell in rows[0]]
    if all(_is_number(cell) for cell in header):
        raise BadInputError(
            f"{str(path)!r} has no header row; its first line must name the columns, e.g. time,slider_pos"
        )
    return header, rows[1:]


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _number(text: str, row: int, column: str, path) -> float:
    """A cell as a float; '' and 'nan' are NaN (missing), other text is bad input."""
    text = text.strip()
    if text == "" or text.lower() in ("nan", "na", "n/a", "null"):
        return math.nan
    try:
        return float(text)
    except ValueError:
        raise BadInputError(
            f"{str(path)!r} row {row}: column {column!r} holds {text!r}, not a number (empty or NaN marks a missing value)"
        ) from None


def load(
    path: str | os.PathLike,
    joints: Sequence[str],
    *,
    mapping: Mapping[str, str] | None = None,
    scale: float = 1.0,
    start: float | None = None,
    signals: Sequence[str] = tuple(SIGNALS),
) -> Record:
    """Read DATA.csv into a Record of the first joint in `joints` that has a signal column.

    Parameters
    ----------
    path
        The CSV file (header row, then numbers).
    joints
        The scene's joints that may be measured, most natural first.
    mapping
        File column -> springlab name ('time', '<joint>_pos', ...).
    scale
        Factor [SI unit per file unit] applied to the signal (not the time).
    start
        Time [s] of the release; samples before it are dropped and the model's t = 0 is there.
    signals
        The signal kinds this scene can fit.

    Raises
    ------
    BadInputError
        No such file, no header, an unknown column, no time or signal column,
        non-monotone time, text in a number cell, too few samples, a non-positive scale.
    """
    if not isinstance(scale, (int, float)) or not math.isfinite(scale) or scale == 0:
        raise BadInputError(f"--scale must be a finite non-zero factor (SI units per file unit), got {scale!r}")
    header, rows = _read_rows(path)
    mapping = dict(mapping or {})
    for column in mapping:
        if column not in header:
            raise BadInputError(
                f"--map names column {column!r}, which {str(path)!r} lacks; its columns: {', '.join(header)}"
            )
    names = [mapping.get(column, column) for column in header]
    if "time" not in names:
        raise BadInputError(
            f"{str(path)!r} has no 'time' column; its columns: {', '.join(header)} (rename one with --map COLUMN=time)"
        )
    candidates = [f"{j}_{s}" for j in joints for s in _PREFERENCE if s in signals]
    chosen = next((name for name in candidates if name in names), None)
    if chosen is None:
        raise BadInputError(
            f"{str(path)!r} has no signal column; expected one of {', '.join(candidates)}"
            f" (its columns: {', '.join(header)}; rename one with --map COLUMN=NAME)"
        )
    t_index, y_index = names.index("time"), names.index(chosen)
    joint, signal = chosen.rsplit("_", 1)
    column = header[y_index]
    time_cells: list[float] = []
    value_cells: list[float] = []
    for number, row in enumerate(rows, start=2):
        cells = row + [""] * (len(header) - len(row))
        time_cells.append(_number(cells[t_index], number, header[t_index], path))
        value_cells.append(_number(cells[y_index], number, column, path))
    time, values = np.array(time_cells, float), np.array(value_cells, float) * scale
    if not (np.all(np.isfinite(time[np.isfinite(time)])) and np.all(np.isfinite(values[np.isfinite(values)]))):
        raise BadInputError(f"{str(path)!r} holds an infinite value; valid: finite numbers")
    keep = np.isfinite(time) & np.isfinite(values)
    time, values = time[keep], values[keep]
    skipped = int(np.count_nonzero(~keep))
    notes = []
    if skipped:
        notes.append(f"skipped {skipped} row(s) with a missing or NaN value")
    if scale != 1.0:
        notes.append(f"signal scaled by {scale:g} into {SIGNALS[signal]}")
    _check_enough(time.size, column, skipped, path)
    steps = np.diff(time)
    if np.any(steps <= 0):
        bad = int(np.flatnonzero(steps <= 0)[0])
        raise BadInputError(
            f"{str(path)!r}: time must increase strictly, but t = {time[bad + 1]:g} s follows"
            f" t = {time[bad]:g} s; valid: one row per sample, in time order"
        )
    if not np.allclose(steps, steps[0], rtol=1e-6, atol=0):
        notes.append(
            f"uneven sampling: intervals {steps.min():.3g} to {steps.max():.3g} s (model interpolated at each sample)"
        )
    record = Record(
        time=time,
        values=values,
        joint=joint,
        signal=signal,
        column=column,
        origin=float(time[0]),
        rows=len(rows),
        skipped_nan=skipped,
        notes=tuple(notes),
    )
    if start is not None:
        return _cut(record, start, path, detected=False)
    return record


def _check_enough(samples: int, column: str, skipped: int, path: str | os.PathLike) -> None:
    if samples < MIN_SAMPLES:
        raise BadInputError(
            f"{str(path)!r} has {samples} usable sample(s) of {column!r}"
            f" ({skipped} skipped as missing/NaN); a fit needs at least {MIN_SAMPLES}"
        )


def cut_at_release(record: Record, start: float) -> Record:
    """The record from a detected release on: samples before `start` [s] dropped (and noted), t = 0 there."""
    return _cut(record, start, record.column, detected=True)


def _cut(record: Record, start: float, path: str | os.PathLike, *, detected: bool) -> Record:
    """The record without the samples before `start` [s], the model's t = 0 there."""
    if not isinstance(start, (int, float)) or not math.isfinite(start):
        raise BadInputError(f"--start must be a finite time in seconds, got {start!r}")
    if start >= record.time[-1]:
        raise BadInputError(
            f"--start {start:g} s is at or after the record's last sample ({record.time[-1]:g} s);"
            f" valid: {record.time[0]:g} to {record.time[-1]:g} s"
        )
    keep = record.time >= start
    dropped = int(np.count_nonzero(~keep))
    how = "release detected" if detected else "start given"
    cut = dataclasses.replace(
        record,
        time=record.time[keep],
        values=record.values[keep],
        origin=float(start),
        dropped_before_start=dropped,
        release_detected=detected,
        notes=(*record.notes, f"{how} at t = {start:.6g} s: {dropped} earlier sample(s) left out"),
    )
    _check_enough(cut.time.size, cut.column, cut.skipped_nan, path)
    return cut


def noise_level(values: np.ndarray) -> float:
    """Robust estimate of white measurement noise [signal units]: MAD of third differences.

    Third differences cancel any smooth motion sampled finely (up to its third
    derivative) and multiply white noise of sigma by sqrt(20).
    """
    if values.size < 8:
        return 0.0
    d3 = np.diff(values, 3)
    return float(1.4826 * np.median(np.abs(d3 - np.median(d3))) / math.sqrt(20.0))
