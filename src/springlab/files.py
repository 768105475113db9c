"""Writing files atomically: text, CSV at full precision and JSON with null for inf and nan.

Every file is written to a temporary name in its target folder and renamed
into place, so an interrupted or failed write never leaves a partial file.
`Output` is how a result declares one file it writes (springlab.outputs.write writes them all);
`write_all` writes a set of files all or nothing.
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import io
import json
import math
import os
import pathlib
import secrets
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from .errors import BadInputError


def prepare_directory(directory: str | os.PathLike) -> pathlib.Path:
    """Create `directory` (and parents) or raise BadInputError saying why it cannot be."""
    path = pathlib.Path(directory)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise BadInputError(f"cannot create output directory {str(path)!r}: {error.strerror or error}") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise BadInputError(f"output directory {str(path)!r} is not writable")
    return path


def check_directory(directory: str | os.PathLike) -> pathlib.Path:
    """Raise BadInputError unless a file can be written in `directory`; leave nothing behind.

    For commands that compute for seconds before they write: a bad --output
    fails at once. It tries for real (creates the missing folders and a probe
    file, then removes them), so permissions, read-only mounts and /proc answer
    as they will when the results are written.
    """
    path = pathlib.Path(directory)
    if path.exists() and not path.is_dir():
        raise BadInputError(f"output directory {str(path)!r} exists and is not a directory")
    missing = []
    for folder in [path, *path.parents]:
        if folder.exists():
            break
        missing.append(folder)
    try:
        for folder in reversed(missing):
            folder.mkdir()
        os.unlink(temporary_beside(path / "probe"))
    except OSError as error:
        raise BadInputError(f"cannot write into output directory {str(path)!r}: {error.strerror or error}") from None
    finally:
        for folder in missing:
            with contextlib.suppress(OSError):
                folder.rmdir()
    return path


def temporary_beside(target: pathlib.Path) -> pathlib.Path:
    """Create a hidden, unique, empty file next to `target` and return its path.

    Mode 0666 & ~umask, like any new file: tempfile.mkstemp's 0600 would survive
    the final rename and leave the user's results unreadable to others.
    """
    for _ in range(100):
        name = target.parent / f".{target.name}.{secrets.token_hex(4)}.part{target.suffix}"
        try:
            os.close(os.open(name, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
        except FileExistsError:
            continue
        return name
    raise FileExistsError(f"no free temporary file name next to {str(target)!r}")


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike) -> Iterator[pathlib.Path]:
    """Yield a temporary path beside `target`; rename it onto `target` on success, delete it on failure."""
    target = pathlib.Path(target)
    try:
        temporary = temporary_beside(target)
    except OSError as error:
        raise BadInputError(f"cannot write {str(target)!r}: {error.strerror or error}") from None
    try:
        yield temporary
        os.replace(temporary, target)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def json_ready(value: Any) -> Any:
    """Plain JSON types; inf and nan become null, so a key holds a number or null, never a string.

    Where a quantity can be infinite or undefined (a carriage that never settles,
    runs that never separate) the scene reports a boolean flag beside it
    (`settled_for_good`, `separated`) that says why it is null.
    """
    if isinstance(value, Mapping):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def dumps(value: Any) -> str:
    """JSON text of `value` (indented, full float precision)."""
    return json.dumps(json_ready(value), indent=2)


def recorded_rows(n: int, every: int = 1) -> np.ndarray:
    """Indices of the rows `--record-every` keeps out of n: every `every`-th from 0, and always the last."""
    rows = np.arange(0, n, every)
    return rows if rows[-1] == n - 1 else np.append(rows, n - 1)


def number_text(value: float | np.floating) -> str:
    """`value` in the shortest text that reads back (float()) to the same double: `0.1`, not `0.10000000000000001`.

    Python's repr of a float is that shortest round-trip form, and pandas' `to_csv` writes the same; an
    integral value keeps its `.0` (`3.0`, `-0.0`), so a column of floats reads back as floats
    (`pandas.read_csv` would make a column of `3`s integers). `inf`, `-inf` and `nan` as repr writes them.
    """
    return repr(float(value))


def csv_text(columns: Mapping[str, np.ndarray], every: int = 1) -> str:
    """CSV with a header row and every `every`-th row (the last always kept), each number in the shortest
    form that reads back exactly (`number_text`)."""
    names = list(columns)
    n = len(np.asarray(columns[names[0]]))
    rows = recorded_rows(n, every)
    table = np.column_stack([np.asarray(columns[name], float)[rows] for name in names])
    lines = [",".join(names)] + [",".join(map(number_text, row)) for row in table.tolist()]
    return "\n".join(lines) + "\n"


def rows_text(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    """CSV of a header and rows of mixed cells (the csv module's quoting): true/false for booleans, floats in
    their shortest exact form (`number_text`), integers as integers, anything else as its text."""

    def cell(value: Any) -> str:
        if isinstance(value, (bool, np.bool_)):
            return "true" if value else "false"
        if isinstance(value, (float, np.floating)):
            return number_text(value)
        if isinstance(value, (int, np.integer)):
            return str(int(value))
        return str(value)

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    for line in rows:
        writer.writerow([cell(value) for value in line])
    return buffer.getvalue()


def write_text_files(directory: str | os.PathLike, files: Mapping[str, str]) -> list[pathlib.Path]:
    """Write name -> text into `directory`; all files appear, or none of them do."""
    path = prepare_directory(directory)
    written: list[pathlib.Path] = []
    try:
        for name, text in files.items():
            with atomic_path(path / name) as temporary:
                temporary.write_text(text)
            written.append(path / name)
    except BaseException:
        for done in written:
            done.unlink(missing_ok=True)
        raise
    return written


#: the kinds of file a result writes, by suffix: text (JSON, CSV) it gives itself, figures and videos drawn above it
OUTPUT_KINDS = {"json": "text", "csv": "text", "png": "drawn", "mp4": "drawn"}


@dataclasses.dataclass(frozen=True)
class Output:
    """One file a result writes into its folder; springlab.outputs.write writes every file a result declares.

    Attributes
    ----------
    name
        the file name, e.g. 'tradeoff.json'; its suffix is its kind: .json, .csv, .png or .mp4.
    text
        the file's text for .json and .csv; None for .png and .mp4, which the outputs layer draws (the
        results live below the plots and cannot draw themselves).
    """

    name: str
    text: str | None = None

    def __post_init__(self) -> None:
        kind = OUTPUT_KINDS.get(self.kind)
        if kind is None:
            raise ValueError(f"{self.name}: a result writes {', '.join('.' + k for k in OUTPUT_KINDS)} files")
        if (kind == "text") != (self.text is not None):
            raise ValueError(f"{self.name}: a .json or .csv file carries its text, a .png or .mp4 file none")

    @property
    def kind(self) -> str:
        """'json', 'csv', 'png' or 'mp4' (the name's suffix)."""
        return pathlib.PurePath(self.name).suffix.lstrip(".")

    @classmethod
    def json(cls, name: str, value: Any) -> Output:
        """A JSON file of `value` (`dumps`: inf and nan as null), ending in a newline."""
        return cls(name, dumps(value) + "\n")


def write_all(
    directory: str | os.PathLike, writers: Mapping[str, Callable[[pathlib.Path], object]]
) -> list[pathlib.Path]:
    """Write a set of files into `directory`, all or nothing.

    Each writer is called with a temporary path beside its file (hidden, same suffix) and writes the file
    there; only when every one has written are they renamed into place. On any error (a writer's, or a
    rename's) the temporaries and the files already renamed are removed, so no partial set is left.

    Parameters
    ----------
    directory
        the folder (created with its parents; BadInputError if it cannot be).
    writers
        file name -> a function writing that file's content at the path it is given.

    Returns
    -------
    list[pathlib.Path]
        the written files, in the order of `writers`.
    """
    folder = prepare_directory(directory)
    temporaries: dict[pathlib.Path, pathlib.Path] = {}
    renamed: list[pathlib.Path] = []
    try:
        for name, write in writers.items():
            target = folder / name
            try:
                temporaries[target] = temporary_beside(target)
            except OSError as error:
                raise BadInputError(f"cannot write {str(target)!r}: {error.strerror or error}") from None
            write(temporaries[target])
        for target, temporary in temporaries.items():
            os.replace(temporary, target)
            renamed.append(target)
    except BaseException:
        for temporary in temporaries.values():
            temporary.unlink(missing_ok=True)
        for target in renamed:
            target.unlink(missing_ok=True)
        raise
    return list(temporaries)
