"""Reading a measured record for `springlab fit`: the file or arrays, their untidy parts, and where the motion starts.

A record is one time column and one signal of one joint: its position
(`<joint>_pos` [m]), velocity (`<joint>_vel` [m/s]) or acceleration
(`<joint>_acc` [m/s^2], an accelerometer). Column names follow trajectory.csv;
`--map COLUMN=NAME` renames a column of the file to one of those names. It comes
from a CSV file (read in bounded memory by springlab.studies.fit.reader), a
mapping of arrays or a pandas DataFrame.

Untidy data is handled, and every step says what it did (`Record.notes`):

* the file's layout: comment lines (`#`), a comma, semicolon or tab between the
  fields, a decimal comma, a units row under the header (springlab.studies.fit.reader);
  a ragged row is refused with its line number;
* units: `scale` and `time_scale` multiply the signal and the time into SI units;
  without them a unit the column states (`elapsed_ms`, `disp_mm`, `x [mm]`,
  `t (s)`, or the units row) is applied and said so, and one that cannot be is a
  warning (a note starting 'warning: ');
* uneven sampling: the model is simulated on its own fine grid and interpolated
  at the recorded times, so any strictly increasing times work;
* rows where the time or the signal is empty or NaN are skipped and counted;
* a record that starts before the release (the signal held still, then let go):
  `start` [s] drops everything before it; without it the fit tests for a held
  part and drops it only when the data show it beyond their noise
  (springlab.studies.fit.release, `cut_at_release`);
* a constant offset, noise and a sensor delay are parameters of the fit, not of the data.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, TypeAlias

import numpy as np
import numpy.typing as npt

from springlab.errors import BadInputError

from . import reader

if TYPE_CHECKING:  # annotations only: a DataFrame is read without importing pandas
    import pandas

#: what a record is read from: a CSV file's path, a mapping of column name -> array, or a pandas DataFrame
DataSource: TypeAlias = "str | os.PathLike[str] | Mapping[str, npt.ArrayLike] | pandas.DataFrame"

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


def load(
    data: DataSource,
    joints: Sequence[str],
    *,
    mapping: Mapping[str, str] | None = None,
    scale: float | None = None,
    time_scale: float | None = None,
    start: float | None = None,
    signals: Sequence[str] = tuple(SIGNALS),
    show_progress: bool | None = None,
) -> Record:
    """Read a record (a CSV file, a mapping of arrays or a DataFrame) of the first joint in `joints` with a signal.

    Parameters
    ----------
    data
        A CSV file's path (header row, then numbers; springlab.studies.fit.reader reads it), a mapping
        of column name -> array ({'time': t, 'slider_pos': x}) or a pandas DataFrame.
    joints
        The scene's joints that may be measured, most natural first.
    mapping
        Column -> springlab name ('time', '<joint>_pos', ...); a column is matched by its whole name or by
        its name without the unit ('x [mm]' by 'x').
    scale
        Factor [SI unit per unit of the data] applied to the signal; None: from the column's stated unit, else 1.
    time_scale
        Factor [s per unit of the data] applied to the time; None: from the column's stated unit, else 1.
    start
        Time [s] (after `time_scale`) of the release; samples before it are dropped and the model's t = 0 is there.
    signals
        The signal kinds this scene can fit.
    show_progress
        A progress bar while a large file is read (None: on a terminal only).

    Raises
    ------
    BadInputError
        No such file, no header, a ragged row, an unknown column, no time or signal column,
        non-monotone time, text in a number cell, too few samples, a zero or non-finite factor.
    """
    _check_factor(scale, "--scale", "SI units per unit of the data, e.g. 0.001 for mm", positive=False)
    _check_factor(time_scale, "--time-scale", "seconds per unit of the data, e.g. 0.001 for ms", positive=True)
    path = data if isinstance(data, (str, os.PathLike)) else None
    if path is not None:
        layout = reader.sniff(path)
        columns = layout.columns
    else:
        columns, arrays = reader.in_memory(data)
    header, source = columns.header, columns.source
    names = _names(header, dict(mapping or {}), source)
    if "time" not in names:
        raise BadInputError(
            f"{source} has no 'time' column; its columns: {', '.join(header)} (rename one with --map COLUMN=time)"
        )
    candidates = [f"{j}_{s}" for j in joints for s in _PREFERENCE if s in signals]
    chosen = next((name for name in candidates if name in names), None)
    if chosen is None:
        raise BadInputError(
            f"{source} has no signal column; expected one of {', '.join(candidates)}"
            f" (its columns: {', '.join(header)}; rename one with --map COLUMN=NAME)"
        )
    t_index, y_index = names.index("time"), names.index(chosen)
    joint, signal = chosen.rsplit("_", 1)
    t_column, column = header[t_index], header[y_index]
    notes = list(columns.notes)
    if path is not None:
        time, values, rows, comments = reader.stream(path, layout, (t_index, y_index), show_progress=show_progress)
        if comments + layout.comments:
            notes.append(f"skipped {comments + layout.comments} comment line(s) starting with #")
    else:
        time, how = reader.as_floats(arrays[t_column], t_column, source)
        values, _ = reader.as_floats(arrays[column], column, source)
        if time.size != values.size:
            raise BadInputError(
                f"{source}: {t_column!r} has {time.size} values and {column!r} {values.size}; valid: one per sample in each"
            )
        rows = time.size
        notes.extend([how] if how else [])
    time, values = _in_units(
        time, values, scale, time_scale, columns.units_row, (t_index, y_index), header, chosen, notes
    )
    time, values, skipped = _finite_samples(time, values, column, source, notes)
    record = Record(
        time=time,
        values=values,
        joint=joint,
        signal=signal,
        column=column,
        origin=float(time[0]),
        rows=rows,
        skipped_nan=skipped,
        notes=tuple(notes),
    )
    if start is not None:
        return _cut(record, start, source, detected=False)
    return record


def _in_units(
    time: np.ndarray,
    values: np.ndarray,
    scale: float | None,
    time_scale: float | None,
    units: Sequence[str] | None,
    indices: tuple[int, int],
    header: Sequence[str],
    chosen: str,
    notes: list[str],
) -> tuple[np.ndarray, np.ndarray]:
    """(time [s], signal [SI]) of `load`'s two columns: an explicit factor, else what the column's name or
    the units row states, else SI; what was applied or doubted is appended to `notes`."""
    t_index, y_index = indices
    t_column, column = header[t_index], header[y_index]
    signal = chosen.rsplit("_", 1)[1]
    # units: an explicit factor, else what the column's name or the units row states, else SI
    t_factor, t_note, t_warning = reader.resolve(
        time_scale,
        reader.stated(t_column, units[t_index] if units else None, "time", "the time"),
        "time",
        t_column,
        "--time-scale",
    )
    y_factor, y_note, y_warning = reader.resolve(
        scale, reader.stated(column, units[y_index] if units else None, signal, chosen), signal, column, "--scale"
    )
    if t_note or y_note:
        notes.append("; ".join(note for note in (t_note, y_note) if note))
    for warning, option in ((t_warning, "--time-scale"), (y_warning, "--scale")):
        if warning:
            notes.append(f"warning: {warning}; give {option} FACTOR if it is not")
    if t_factor != 1.0:
        time = time * t_factor
    if y_factor != 1.0:
        values = values * y_factor
    return time, values


def _finite_samples(
    time: np.ndarray, values: np.ndarray, column: str, source: str, notes: list[str]
) -> tuple[np.ndarray, np.ndarray, int]:
    """(time [s], values, rows skipped) of `load`'s samples: no infinite value, rows with a missing or NaN
    value dropped (noted in `notes`), enough left, time strictly increasing (uneven sampling noted)."""
    if not (np.all(np.isfinite(time[~np.isnan(time)])) and np.all(np.isfinite(values[~np.isnan(values)]))):
        raise BadInputError(f"{source} holds an infinite value; valid: finite numbers")
    keep = np.isfinite(time) & np.isfinite(values)
    skipped = int(keep.size - np.count_nonzero(keep))
    if skipped:
        time, values = time[keep], values[keep]
        notes.append(f"skipped {skipped} row(s) with a missing or NaN value")
    _check_enough(time.size, column, skipped, source)
    steps = np.diff(time)
    if np.any(steps <= 0):
        bad = int(np.flatnonzero(steps <= 0)[0])
        raise BadInputError(
            f"{source}: time must increase strictly, but t = {time[bad + 1]:g} s follows"
            f" t = {time[bad]:g} s; valid: one row per sample, in time order"
        )
    if not np.allclose(steps, steps[0], rtol=1e-6, atol=0):
        notes.append(
            f"uneven sampling: intervals {steps.min():.3g} to {steps.max():.3g} s (model interpolated at each sample)"
        )
    return time, values, skipped


def _check_factor(value: float | None, option: str, meaning: str, *, positive: bool) -> None:
    """A factor is None (from the data's units) or a finite number, non-zero (positive for time)."""
    if value is None:
        return
    bad = not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value)
    if bad or value == 0 or (positive and value < 0):
        kind = "positive" if positive else "non-zero"
        raise BadInputError(f"{option} must be a finite {kind} factor ({meaning}), got {value!r}")


def _names(header: Sequence[str], mapping: Mapping[str, str], source: str) -> list[str]:
    """Each column's springlab name: mapped by its whole name or its name without the unit, else that name."""
    bases = [reader.split_unit(column)[0] for column in header]
    for key in mapping:
        if key in header:
            continue
        matches = [column for column, base in zip(header, bases) if base == key]
        if not matches:
            raise BadInputError(f"--map names column {key!r}, which {source} lacks; its columns: {', '.join(header)}")
        if len(matches) > 1:
            raise BadInputError(
                f"--map names {key!r}, which could be any of {', '.join(map(repr, matches))}; name one whole"
            )
    return [mapping.get(column, mapping.get(base, base)) for column, base in zip(header, bases)]


def _check_enough(samples: int, column: str, skipped: int, source: str) -> None:
    if samples < MIN_SAMPLES:
        raise BadInputError(
            f"{source} has {samples} usable sample(s) of {column!r}"
            f" ({skipped} skipped as missing/NaN); a fit needs at least {MIN_SAMPLES}"
        )


def cut_at_release(record: Record, start: float) -> Record:
    """The record from a detected release on: samples before `start` [s] dropped (and noted), t = 0 there."""
    return _cut(record, start, record.column, detected=True)


def _cut(record: Record, start: float, path: str, *, detected: bool) -> Record:
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
    # in place (the medians reorder d3, which the MAD does not see): one n-long array, not four
    d3 -= np.median(d3, overwrite_input=True)
    return float(1.4826 * np.median(np.abs(d3, out=d3), overwrite_input=True) / math.sqrt(20.0))
