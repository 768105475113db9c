"""The columns of a record as people have them: a lab's CSV export or arrays in memory, with their units.

A CSV file is read in two passes over its head and one over its body:

* the head (its first 64 KiB) says how the file is laid out: comment lines
  (`#`) before the header are skipped, the separator is the one of comma,
  semicolon or tab that splits the header into several names and the first
  rows into as many fields, a decimal comma is recognised in a semicolon- or
  tab-separated file, and a row of units right under the header is taken as
  such (no cell of it a number);
* the body is streamed in blocks of 4 MiB: each block's rows are counted field
  by field (numpy over its bytes, so a ragged row is refused with its line
  number) and parsed by `numpy.loadtxt` (numpy's C reader), only the two columns
  the fit uses kept. Memory stays bounded by a block plus the two columns
  (16 bytes per row); a block with an empty or `NA` cell is parsed again row by
  row to skip those cells as missing, or to name the line of a cell that is text.

Units come from the column names (`elapsed_ms`, `disp_mm`, `x [mm]`, `t (s)`)
or a units row. `units` resolves them against what each column holds: a unit of
the right kind is applied and said so, anything else (an unknown unit, a length
on a time column, the name and the units row disagreeing) is a one-line warning
and no factor; an explicit factor (`--scale`, `--time-scale`) always wins.

Arrays in memory (a mapping of column name -> array, or a pandas DataFrame,
whose named index counts as a column) go through the same choice of columns and
units; pandas is not needed to read them (a DataFrame is read through its
`columns` and `to_numpy`).
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import os
import re
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from springlab import progress
from springlab.errors import BadInputError

#: bytes of the head read to learn the layout [B]
HEAD = 1 << 16
#: bytes per block of the body [B]: bounded memory, and numpy's reader at full speed
BLOCK = 1 << 22
#: files at least this large show a progress bar on a terminal [B]
PROGRESS_FROM = 4 * BLOCK
#: data rows of the head that must agree with the header on the separator
SAMPLE_ROWS = 20
#: separators looked for, in order of preference where several fit, and how the messages name them
SEPARATORS = {",": "comma", ";": "semicolon", "\t": "tab"}
#: cell texts that mark a missing value, besides an empty cell and NaN
MISSING = ("", "nan", "na", "n/a", "null", "none", "-")

#: what each role of a column measures
QUANTITY = {"time": "time", "pos": "length", "vel": "velocity", "acc": "acceleration"}
#: the SI unit of each quantity
SI = {"time": "s", "length": "m", "velocity": "m/s", "acceleration": "m/s^2"}
#: units a column may state, in brackets or a units row: symbol -> (quantity, SI units per unit)
UNITS: dict[str, tuple[str, float]] = {
    "s": ("time", 1.0),
    "sec": ("time", 1.0),
    "ms": ("time", 1e-3),
    "us": ("time", 1e-6),
    "µs": ("time", 1e-6),
    "μs": ("time", 1e-6),
    "ns": ("time", 1e-9),
    "min": ("time", 60.0),
    "h": ("time", 3600.0),
    "m": ("length", 1.0),
    "cm": ("length", 1e-2),
    "mm": ("length", 1e-3),
    "um": ("length", 1e-6),
    "µm": ("length", 1e-6),
    "μm": ("length", 1e-6),
    "nm": ("length", 1e-9),
    "in": ("length", 0.0254),
    "m/s": ("velocity", 1.0),
    "cm/s": ("velocity", 1e-2),
    "mm/s": ("velocity", 1e-3),
    "um/s": ("velocity", 1e-6),
    "µm/s": ("velocity", 1e-6),
    "m/s^2": ("acceleration", 1.0),
    "m/s2": ("acceleration", 1.0),
    "m/s²": ("acceleration", 1.0),
    "mm/s^2": ("acceleration", 1e-3),
    "mm/s2": ("acceleration", 1e-3),
    "mm/s²": ("acceleration", 1e-3),
    "g": ("acceleration", 9.80665),  # standard gravity, as accelerometers report
}
#: units a name's `_suffix` states: short and unmistakable only (not `_min` (minimum?), `_g` (grams?), `_in`)
SUFFIX_UNITS = ("s", "ms", "us", "µs", "μs", "m", "cm", "mm", "um", "µm", "μm")
_BRACKETS = re.compile(r"^(?P<base>.*?)\s*(?:\[(?P<square>[^\[\]]*)\]|\((?P<round>[^()]*)\))\s*$")
_DECIMAL_COMMA = re.compile(r"^\s*[+-]?(\d+,\d*|,\d+)([eE][+-]?\d+)?\s*$")


def split_unit(name: str) -> tuple[str, str | None]:
    """A column name's base and the unit it states: 'x [mm]' -> ('x', 'mm'), 'elapsed_ms' -> ('elapsed', 'ms').

    A bracketed unit (`[..]` or `(..)` at the end) is split off whatever it says; a `_suffix` only when it is
    one of SUFFIX_UNITS. No unit: (name, None).
    """
    name = name.strip()
    match = _BRACKETS.match(name)
    if match and match.group("base"):
        unit = match.group("square") if match.group("square") is not None else match.group("round")
        return match.group("base").strip(), unit.strip()
    base, sep, suffix = name.rpartition("_")
    if sep and base and suffix in SUFFIX_UNITS:
        return base, suffix
    return name, None


def _unit_of(text: str) -> str:
    """A unit's text as UNITS spells it: brackets and spaces dropped ('[mm]' -> 'mm', 'm / s' -> 'm/s')."""
    text = text.strip().strip("[]()").strip()
    text = text.replace(" ", "").replace("·", "").replace("**", "^")
    return text


@dataclasses.dataclass(frozen=True)
class Columns:
    """A source's column names, the units row if it had one, and how to say where it came from."""

    header: list[str]
    units_row: list[str] | None
    source: str
    notes: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True)
class Layout:
    """How a CSV file is laid out, learnt from its head."""

    columns: Columns
    separator: str
    decimal_comma: bool
    data_offset: int  # [B] where the data rows start
    data_line: int  # line number of the first data row (1-based)
    comments: int  # comment lines before it


# -- the head of a CSV --------------------------------------------------------------------


def _is_number(text: str, decimal_comma: bool = False) -> bool:
    text = text.strip()
    if decimal_comma:
        text = text.replace(",", ".")
    try:
        float(text)
    except ValueError:
        return False
    return True


def _split(line: str, separator: str) -> list[str]:
    """One line's cells (quotes as the csv module reads them), stripped."""
    if '"' not in line:
        return [cell.strip() for cell in line.split(separator)]
    return [cell.strip() for cell in next(csv.reader([line], delimiter=separator))]


def sniff(path: str | os.PathLike) -> Layout:
    """Read the head of a CSV: comments, header, separator, decimal comma, units row.

    Raises
    ------
    BadInputError
        No such file, not text, empty, no header row, one column only.
    """
    source = repr(str(path))
    try:
        with open(path, "rb") as handle:
            head = handle.read(HEAD)
            whole = not handle.read(1)
    except OSError as error:
        raise BadInputError(f"cannot read {source}: {error.strerror or error}") from None
    if b"\0" in head:
        raise BadInputError(f"cannot read {source}: it is not a text file (CSV with a header row and numbers)")
    offset = 3 if head.startswith(b"\xef\xbb\xbf") else 0
    raw_lines = head[offset:].split(b"\n")
    if not whole:
        raw_lines = raw_lines[:-1]  # the last one may be cut
    encoding = "utf-8"
    try:
        b"\n".join(raw_lines).decode(encoding)
    except UnicodeDecodeError:
        encoding = "latin-1"  # a Windows export's 'µm' or '°C': numbers are ASCII either way
    header_text: str | None = None
    header_line = header_start = header_end = 0
    comments: list[tuple[int, str]] = []  # (line number, text)
    rows: list[tuple[int, str, int]] = []  # (line number, text, offset after it)
    for number, raw in enumerate(raw_lines, start=1):
        start, after = offset, offset + len(raw) + 1
        text = raw.decode(encoding).rstrip("\r")
        offset = after
        if not text.strip():
            continue
        if text.lstrip().startswith("#"):
            comments.append((number, text))
            continue
        if header_text is None:
            header_text, header_line, header_start, header_end = text, number, start, after
            continue
        rows.append((number, text, after))
        if len(rows) >= SAMPLE_ROWS:
            break
    if header_text is None:
        raise BadInputError(f"{source} is empty; it needs a header row and data rows")
    separator = _separator(header_text, [text for _, text, _ in rows], source)
    header = _split(header_text, separator)
    decimal_comma = separator != "," and any(
        _DECIMAL_COMMA.match(cell) for _, text, _ in rows for cell in _split(text, separator)
    )
    notes = []
    if separator != ",":
        notes.append(f"{SEPARATORS[separator]}-separated" + (", decimal comma" if decimal_comma else ""))
    units_row = None
    data_offset, data_line = header_end, header_line + 1
    if all(_is_number(cell, decimal_comma) for cell in header):
        # numbers first: the header may be the comment line right above them, as numpy.savetxt writes it
        number, text = comments[-1] if comments else (0, "")
        named = _split(text.lstrip()[1:], separator)
        if not comments or len(named) != len(header) or all(_is_number(cell, decimal_comma) for cell in named):
            raise BadInputError(
                f"{source} has no header row; its first line must name the columns, e.g. time,slider_pos"
            )
        header, data_offset, data_line = named, header_start, header_line
        comments = comments[:-1]
        notes.append(f"header read from comment line {number} (as numpy.savetxt writes it)")
    elif rows:
        number, text, after = rows[0]
        cells = _split(text, separator)
        named = [cell for cell in cells if cell.lower() not in MISSING]
        if named and not any(_is_number(cell, decimal_comma) for cell in cells):
            if len(cells) != len(header):
                raise BadInputError(
                    f"{source} line {number}: {len(cells)} field{'s' * (len(cells) != 1)} under a header of {len(header)};"
                    " valid: every row as many fields as the header"
                )
            units_row = cells
            data_offset, data_line = after, number + 1
            notes.append(f"units row under the header (line {number}): {', '.join(cells)}")
    skipped = sum(1 for number, _ in comments if number < data_line)
    return Layout(
        columns=Columns(header=header, units_row=units_row, source=source, notes=tuple(notes)),
        separator=separator,
        decimal_comma=decimal_comma,
        data_offset=data_offset,
        data_line=data_line,
        comments=skipped,
    )


def _separator(header: str, rows: Sequence[str], source: str) -> str:
    """The separator that splits the header into the most names, preferring one the sample rows agree with."""
    fits = {sep: len(_split(header, sep)) for sep in SEPARATORS}
    candidates = [sep for sep, n in fits.items() if n >= 2]
    if not candidates:
        raise BadInputError(
            f"{source}: its header {header.strip()!r} is one name; a record needs a time and a signal column"
            " separated by a comma, semicolon or tab"
        )
    agreeing = [sep for sep in candidates if all(len(_split(row, sep)) == fits[sep] for row in rows)]
    pool = agreeing or candidates
    return max(pool, key=lambda sep: fits[sep])  # max keeps the first (the preferred) among equals


# -- the body of a CSV --------------------------------------------------------------------


def stream(
    path: str | os.PathLike,
    layout: Layout,
    used: tuple[int, int],
    *,
    show_progress: bool | None = None,
) -> tuple[np.ndarray, np.ndarray, int, int]:
    """The two used columns of a CSV's body, read block by block.

    Parameters
    ----------
    path
        The CSV file.
    layout
        Its layout (`sniff`).
    used
        Indices of the time and the signal column.
    show_progress
        A progress bar on stderr: None draws one on a terminal for a file of PROGRESS_FROM bytes or more.

    Returns
    -------
    time, values, rows, comments
        The raw columns (NaN where a cell is missing), the data rows read, the comment lines among them.

    Raises
    ------
    BadInputError
        A ragged row (with its line number), a cell that is text, an unreadable file.
    """
    source = layout.columns.source
    fields = len(layout.columns.header)
    times: list[np.ndarray] = []
    values: list[np.ndarray] = []
    rows = comments = 0
    size = os.path.getsize(path)
    enabled = show_progress
    if enabled is None and size < PROGRESS_FROM:
        enabled = False
    line = layout.data_line
    name = os.path.basename(str(path))
    with (
        open(path, "rb") as handle,
        progress.bar(total=size, description=f"reading {name}", unit="B", unit_scale=True, enabled=enabled) as bar,
    ):
        handle.seek(layout.data_offset)
        bar.update(layout.data_offset)
        carry = b""
        while True:
            chunk = handle.read(BLOCK)
            buffer = carry + chunk
            if chunk:
                cut = buffer.rfind(b"\n") + 1
                if cut == 0:  # one line longer than a block: read on
                    carry = buffer
                    bar.update(len(chunk))
                    continue
                block, carry = buffer[:cut], buffer[cut:]
            else:
                block, carry = buffer, b""
            if block:
                t, y, n, c = _block(block, line, layout, used, fields, source)
                times.append(t)
                values.append(y)
                rows, comments = rows + n, comments + c
                line += block.count(b"\n")
            bar.update(len(chunk))
            if not chunk:
                break
    time = np.concatenate(times) if times else np.empty(0)
    signal = np.concatenate(values) if values else np.empty(0)
    return time, signal, rows, comments


def _block(
    block: bytes, line: int, layout: Layout, used: tuple[int, int], fields: int, source: str
) -> tuple[np.ndarray, np.ndarray, int, int]:
    """One block's used columns, its data rows and its comment lines; `line` is its first line's number."""
    b = np.frombuffer(block, np.uint8)
    ends = np.flatnonzero(b == ord("\n"))
    if not ends.size or ends[-1] != b.size - 1:
        ends = np.append(ends, b.size)  # the file's last line without a newline
    starts = np.concatenate(([0], ends[:-1] + 1))
    # fields per line from the separators' positions (sorted, so a line's count is a difference of ranks)
    separators = np.flatnonzero(b == ord(layout.separator))
    if b'"' in block:  # a separator inside quotes is not one
        quotes = np.flatnonzero(b == ord('"'))
        separators = separators[np.searchsorted(quotes, separators) % 2 == 0]
    hashes = np.flatnonzero(b == ord("#"))  # a comment after a row's numbers holds no fields
    stops = ends
    if hashes.size:
        after = np.searchsorted(hashes, starts)
        stops = np.minimum(ends, np.where(after < hashes.size, hashes[np.minimum(after, hashes.size - 1)], b.size))
    per_line = np.searchsorted(separators, stops) - np.searchsorted(separators, starts)
    # blank and comment lines: decided by the first byte, and by the line's text where that is white space
    first = np.append(b, np.uint8(ord("\n")))[starts]
    blank = first == ord("\n")
    comment = first == ord("#")
    for i in np.flatnonzero(np.isin(first, np.frombuffer(b" \t\r", np.uint8))):
        stripped = block[starts[i] : ends[i]].strip()
        blank[i] = not stripped and not (layout.separator == "\t" and b"\t" in block[starts[i] : ends[i]])
        comment[i] = stripped.startswith(b"#")
    data = ~blank & ~comment
    ragged = np.flatnonzero(data & (per_line != fields - 1))
    if ragged.size:
        at = int(ragged[0])
        got = int(per_line[at]) + 1
        if layout.separator == "," and got == 2 * fields:  # each number cut in two at its decimal comma
            raise BadInputError(
                f"{source} line {line + at}: {got} fields under a header of {fields}, as if its numbers had"
                " decimal commas; valid: a decimal comma with semicolons or tabs between the fields"
            )
        raise BadInputError(
            f"{source} line {line + at}: {got} field{'s' * (got != 1)} under a header of {fields};"
            " valid: every row as many fields as the header (an empty cell marks a missing value)"
        )
    rows, comments = int(np.count_nonzero(data)), int(np.count_nonzero(comment))
    if not rows:
        return np.empty(0), np.empty(0), 0, comments
    if layout.decimal_comma:
        block = block.replace(b",", b".")
    text = block.decode("utf-8", errors="replace")
    try:
        table = np.loadtxt(
            io.StringIO(text),
            delimiter=layout.separator,
            comments="#",
            quotechar='"',
            usecols=used,
            ndmin=2,
            dtype=float,
        )
    except ValueError:  # an empty or NA cell, or text: row by row, to skip the first and name the second
        table = _rows(text, line, layout, used, source)
    return table[:, 0], table[:, 1], rows, comments


def _rows(text: str, line: int, layout: Layout, used: tuple[int, int], source: str) -> np.ndarray:
    """A block parsed row by row: missing cells NaN, text named with its line."""
    header = layout.columns.header
    out = []
    for number, row in enumerate(text.split("\n"), start=line):
        row = row.split("#", 1)[0] if "#" in row else row
        if not row.strip() and not (layout.separator == "\t" and "\t" in row):  # blank, as `_block` counts
            continue
        cells = _split(row.rstrip("\r"), layout.separator)
        out.append([number_of(cells[i], number, header[i], source) for i in used])
    return np.array(out, float).reshape(-1, 2)


def number_of(text: str, line: int, column: str, source: str) -> float:
    """A cell as a float; an empty cell, NaN or NA is NaN (missing), other text is bad input."""
    text = text.strip()
    if text.lower() in MISSING:
        return math.nan
    try:
        return float(text)
    except ValueError:
        raise BadInputError(
            f"{source} line {line}: column {column!r} holds {text!r}, not a number"
            " (an empty cell or NaN marks a missing value)"
        ) from None


# -- arrays in memory ------------------------------------------------------------------------


def in_memory(data: Any) -> tuple[Columns, dict[str, Any]]:
    """A mapping of arrays or a DataFrame (its named index a column too) -> its Columns and name -> column.

    Raises
    ------
    BadInputError
        Anything else.
    """
    if isinstance(data, Mapping):
        items = {str(key): value for key, value in data.items()}
        return Columns(header=list(items), units_row=None, source="the mapping"), items
    if hasattr(data, "columns") and hasattr(data, "index") and hasattr(data, "to_numpy"):  # a DataFrame
        items = {str(key): data[key] for key in data.columns}
        index = getattr(data.index, "name", None)
        if index is not None and str(index) not in items:
            items = {str(index): data.index} | items
        return Columns(header=list(items), units_row=None, source="the DataFrame"), items
    raise BadInputError(
        f"data must be a CSV file's path, a mapping of arrays ({{'time': t, 'slider_pos': x}})"
        f" or a pandas DataFrame; got {type(data).__name__}"
    )


def as_floats(value: Any, column: str, source: str) -> tuple[np.ndarray, str]:
    """One column in memory as a float array (NaN where missing) and a note ('' or how times were read).

    Timedeltas become seconds; datetimes seconds since the first of them.
    """
    kind = getattr(getattr(value, "dtype", None), "kind", None)
    if kind is None:
        kind = np.asarray(value).dtype.kind
    note = ""
    try:
        if kind in "mM":
            zone = ""
            if hasattr(value, "dt") and getattr(value.dt, "tz", None) is not None:
                value, zone = value.dt.tz_convert(None), " UTC"  # a Series of aware datetimes
            elif getattr(value, "tz", None) is not None:
                value, zone = value.tz_convert(None), " UTC"  # an aware DatetimeIndex
            raw = np.asarray(value, dtype="datetime64[ns]" if kind == "M" else "timedelta64[ns]")
            missing = np.isnat(raw)
            if kind == "M":
                first = raw[~missing][0] if np.any(~missing) else np.datetime64(0, "ns")
                raw = raw - first
                note = (
                    f"{column!r} read as seconds since its first time, {np.datetime_as_string(first, unit='ms')}{zone}"
                )
            array = raw.astype(np.int64) * 1e-9
            array[missing] = math.nan
        elif hasattr(value, "to_numpy"):
            array = np.asarray(value.to_numpy(dtype=float, na_value=math.nan), float)
        else:
            array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise BadInputError(
            f"column {column!r} of {source} holds something other than numbers; valid: numbers (NaN marks a missing one)"
        ) from None
    if array.ndim != 1:
        raise BadInputError(f"column {column!r} of {source} has shape {array.shape}; valid: one value per sample")
    return array, note


# -- units -----------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Stated:
    """What a column's name and the units row say about its unit, resolved for what it holds."""

    factor: float | None  # [SI per unit], None: nothing usable stated
    unit: str | None  # the unit applied
    warning: str  # '' unless something was stated that cannot be applied


def stated(column: str, units_cell: str | None, role: str, what: str) -> Stated:
    """The unit of `column` (its name, or its cell of the units row), checked against its role.

    Parameters
    ----------
    column
        The column's name in the source.
    units_cell
        Its cell of the units row, or None.
    role
        'time', 'pos', 'vel' or 'acc'.
    what
        How the warning names the column's content, e.g. 'the time' or 'slider_pos'.
    """
    _, named = split_unit(column)
    from_name = _unit_of(named) if named else None
    from_row = _unit_of(units_cell) if units_cell and units_cell.lower() not in MISSING else None
    if from_name and from_row and from_name != from_row:
        if UNITS.get(from_name) != UNITS.get(from_row):
            return Stated(
                None,
                None,
                f"column {column!r}: its name says {from_name!r}, the units row {from_row!r}: no unit applied,"
                f" {what} read as {SI[QUANTITY[role]]}",
            )
    unit = from_name or from_row
    if unit is None:
        return Stated(None, None, "")
    quantity = QUANTITY[role]
    if unit not in UNITS:
        return Stated(
            None,
            None,
            f"column {column!r} is in {unit!r}, a unit springlab does not know: {what} read as {SI[quantity]}",
        )
    kind, factor = UNITS[unit]
    if kind != quantity:
        return Stated(
            None,
            None,
            f"column {column!r} says {unit!r}, a unit of {kind}, but holds {what} (a {quantity}):"
            f" no unit applied, read as {SI[quantity]}",
        )
    return Stated(factor, unit, "")


def resolve(explicit: float | None, state: Stated, role: str, column: str, option: str) -> tuple[float, str, str]:
    """The factor to use [SI per file unit], a note ('' if nothing to say) and a warning ('' if none).

    An explicit factor (`option`, e.g. '--scale') always wins; the note says so when the column stated a unit.
    """
    si = SI[QUANTITY[role]]
    what = "time" if role == "time" else "signal"
    if explicit is not None:
        if state.factor is None:
            return (
                explicit,
                (f"{what} scaled by {explicit:g} into {si} ({option})" if explicit != 1 else ""),
                state.warning,
            )
        if math.isclose(explicit, state.factor, rel_tol=1e-12):
            return (
                explicit,
                f"{what} in {state.unit} ({column!r}): scaled by {explicit:g} into {si} ({option} agrees)",
                "",
            )
        return (
            explicit,
            f"{what} scaled by {explicit:g} into {si}: {option} wins over {column!r}'s {state.unit}"
            f" (x {state.factor:g})",
            "",
        )
    if state.factor is None:
        return 1.0, "", state.warning
    if state.factor == 1.0:
        return 1.0, f"{what} in {state.unit} ({column!r})", ""
    return state.factor, f"{what} in {state.unit} ({column!r}): scaled by {state.factor:g} into {si}", ""
