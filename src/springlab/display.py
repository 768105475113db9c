"""How a result shows itself: a short `repr` for the terminal, a compact HTML summary for Jupyter
(`_repr_html_`), and `.plot()`, a matplotlib Figure drawn by the plots layer.

Each result class derives from `Shown` and says what matters in one method, `_shown()`, returning a
`Summary`: the verdict first (with its one-line reason), then the figures with their units, then, where
the result holds rows, a small table (the first and last rows of a big one). This module renders that
summary the same way for every result, in text and in HTML, escaping every string (`html.escape`).

`.plot()` is the one call that reaches a layer above the results: the figures are drawn by
`springlab.plots`, which imports the result classes, so the results cannot import it. As pandas'
`DataFrame.plot` finds its plotting backend, `plot` imports the module named by `PLOTTING` when a figure
is asked for (never at import time), and that module's `figure(result)` picks the drawing function by the
result's type. Importing a result never imports matplotlib; tests/results/test_display.py checks that `PLOTTING`
is in the plots layer and draws every result class that has `plot`.
"""

from __future__ import annotations

import dataclasses
import html
import importlib
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: the plots-layer module whose `figure(result, **options)` draws a result: imported when `.plot()` is called
PLOTTING = "springlab.plots.figures"
#: rows a summary's table shows at each end of a longer table
EDGE_ROWS = 5
#: characters of the message shown in the plain repr (the HTML shows all of it)
REPR_MESSAGE = 160
#: the verdict badge's colours: passed, failed, neither (not validated, nothing to validate)
_BADGE = {True: "#1b7f3b", False: "#b3261e", None: "#6b6b6b"}


@dataclasses.dataclass(frozen=True)
class Fact:
    """One figure of a summary: `label`, `value` and its `unit` ('' for none or for [-])."""

    label: str
    value: Any
    unit: str = ""


@dataclasses.dataclass(frozen=True)
class Table:
    """A summary's rows: `columns`, the rows shown (`head`, then `tail` after a gap) and `total` rows."""

    columns: tuple[str, ...]
    head: tuple[tuple[Any, ...], ...]
    tail: tuple[tuple[Any, ...], ...]
    total: int


def table(columns: Sequence[str], rows: Sequence[Sequence[Any]], edge: int = EDGE_ROWS) -> Table:
    """A `Table` of `rows`: all of them up to 2 `edge` + 1, else the first and last `edge`.

    Parameters
    ----------
    columns
        the header (names with units in brackets where they have one).
    rows
        one sequence of values per row.
    edge
        rows kept at each end of a longer table.
    """
    rows = list(rows)
    if len(rows) <= 2 * edge + 1:
        return Table(tuple(columns), tuple(tuple(r) for r in rows), (), len(rows))
    return Table(tuple(columns), tuple(tuple(r) for r in rows[:edge]), tuple(tuple(r) for r in rows[-edge:]), len(rows))


@dataclasses.dataclass(frozen=True)
class Summary:
    """What a result shows: its `kind` (class name) and `title`, the `verdict` with `ok` (True passed,
    False failed, None neither) and its one-line `message`, the `facts`, and an optional `table`."""

    kind: str
    title: str
    verdict: str | None
    ok: bool | None
    message: str
    facts: tuple[Fact, ...] = ()
    table: Table | None = None
    note: str = ""


def number(value: Any) -> str:
    """`value` as a summary shows it: floats to 4 significant digits, None as '-', booleans as yes / no."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float) or hasattr(value, "dtype"):
        value = float(value)
        if math.isnan(value):
            return "nan"
        return f"{value:.4g}"
    if isinstance(value, tuple) and len(value) == 2 and all(isinstance(v, (int, float)) for v in value):
        return f"{number(value[0])} - {number(value[1])}"
    return str(value)


def _fact_text(fact: Fact) -> str:
    text = number(fact.value)
    return f"{fact.label} {text} {fact.unit}".rstrip() if text != "-" or not fact.unit else f"{fact.label} -"


def text(summary: Summary) -> str:
    """The plain repr: `<Kind title: VERDICT>`, the message (cut at REPR_MESSAGE characters) and the
    facts on one line; at most three lines."""
    verdict = summary.verdict if summary.verdict is not None else "no verdict"
    lines = [f"<{summary.kind} {summary.title}: {verdict}>"]
    if summary.message:
        message = summary.message
        lines.append("  " + (message if len(message) <= REPR_MESSAGE else message[: REPR_MESSAGE - 3] + "..."))
    if summary.facts:
        lines.append("  " + ", ".join(_fact_text(f) for f in summary.facts))
    return "\n".join(lines)


def _cell(value: Any) -> str:
    return html.escape(number(value))


def _row(values: Sequence[Any]) -> str:
    """One table row: numbers right-aligned (their digits line up), words left-aligned."""
    cells = []
    for value in values:
        align = "left" if isinstance(value, str) else "right"
        cells.append(f'<td style="padding:1px 8px;text-align:{align};border-bottom:1px solid #eee">{_cell(value)}</td>')
    return "<tr>" + "".join(cells) + "</tr>"


def html_text(summary: Summary) -> str:
    """The HTML summary (`_repr_html_`): the verdict badge and message, the facts, then the table."""
    e = html.escape
    badge = _BADGE[summary.ok]
    verdict = summary.verdict if summary.verdict is not None else "no verdict"
    out = [
        '<div class="springlab-result" style="font-family:system-ui,sans-serif;font-size:13px;'
        'line-height:1.4;max-width:60em">',
        f'<div style="margin-bottom:4px"><b>{e(summary.kind)}</b> <span style="color:#555">'
        f"{e(summary.title)}</span></div>",
        f'<div style="margin-bottom:6px"><span class="springlab-verdict" style="background:{badge};color:#fff;'
        f'padding:1px 7px;border-radius:3px;font-weight:600">{e(verdict)}</span> {e(summary.message)}</div>',
    ]
    if summary.facts:
        out.append('<table class="springlab-facts" style="border-collapse:collapse;margin-bottom:6px">')
        for fact in summary.facts:
            unit = f" {e(fact.unit)}" if fact.unit and fact.value is not None else ""
            out.append(
                f'<tr><th style="text-align:left;font-weight:normal;color:#555;padding:0 12px 0 0">{e(fact.label)}'
                f'</th><td style="text-align:left;padding:0">{_cell(fact.value)}{unit}</td></tr>'
            )
        out.append("</table>")
    if summary.table is not None:
        rows = summary.table
        cell = 'style="padding:1px 8px;text-align:right;border-bottom:1px solid #eee"'
        out.append('<table class="springlab-rows" style="border-collapse:collapse;font-size:12px">')
        out.append("<tr>" + "".join(f"<th {cell}>{e(c)}</th>" for c in rows.columns) + "</tr>")
        out += [_row(row) for row in rows.head]
        if rows.tail:
            hidden = rows.total - len(rows.head) - len(rows.tail)
            out.append(
                f'<tr><td colspan="{len(rows.columns)}" style="padding:1px 8px;color:#777">... {hidden} more rows</td></tr>'
            )
            out += [_row(row) for row in rows.tail]
        out.append("</table>")
        out.append(f'<div style="color:#777;font-size:11px">{rows.total} rows</div>')
    if summary.note:
        out.append(f'<div style="color:#777;font-size:11px">{e(summary.note)}</div>')
    out.append("</div>")
    return "\n".join(out)


def plot(result: Any, **options: Any) -> Figure:
    """The figure of `result`, drawn by the plots layer (`PLOTTING`'s `figure`).

    Parameters
    ----------
    result
        a result with a `plot` method.
    **options
        passed to the drawing function (e.g. `quantity=` of a sweep).

    Returns
    -------
    matplotlib.figure.Figure
        a bare Figure (no pyplot): Jupyter shows it inline, `fig.savefig(...)` writes it.
    """
    return importlib.import_module(PLOTTING).figure(result, **options)


class Shown:
    """The display of a result: `__repr__` and `_repr_html_` from its `_shown()` summary.

    A result dataclass derives from it and passes `repr=False` to `dataclasses.dataclass`, so the
    generated field-by-field repr does not replace this one.
    """

    __slots__ = ()

    def _shown(self) -> Summary:
        raise NotImplementedError

    def __repr__(self) -> str:
        return text(self._shown())

    def _repr_html_(self) -> str:
        """The compact HTML summary Jupyter shows: the verdict first, then the figures with units."""
        return html_text(self._shown())
