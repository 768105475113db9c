"""Rows of a result as a pandas DataFrame: `to_pandas()` of every result that holds rows.

pandas is optional (`pip install 'springlab[pandas]'`): it is imported here, when a table is
asked for, never at import time.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import pandas


def to_pandas(rows: Sequence[Mapping[str, Any]] | Mapping[str, Any], *, index: str | None = None) -> pandas.DataFrame:
    """A DataFrame of `rows`: a list of records (one dict a row) or a mapping of columns.

    Parameters
    ----------
    rows
        records or columns; values in SI units, as the result's `to_dict()` holds them.
    index
        the column to use as the index (None: a range index).

    Raises
    ------
    ImportError
        pandas is not installed; the message says how to install it.
    """
    try:
        import pandas
    except ImportError:
        raise ImportError("to_pandas() needs pandas: pip install 'springlab[pandas]'") from None
    frame = pandas.DataFrame(rows)
    return frame.set_index(index) if index is not None else frame
