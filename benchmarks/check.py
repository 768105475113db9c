"""Fail when a benchmark's ratio is over its budget: `python benchmarks/check.py [results.json]`.

Reads the table `make bench` wrote (benchmarks/results.json: rows with `name`, `ratio`, `budget`), prints
every row over its budget, and exits 1 if there is one (0 otherwise, 2 for a file it cannot read). A
benchmark, not a timed test: the suite tests this checker on a made-up table, never on timings.
"""

from __future__ import annotations

import json
import math
import pathlib
import sys

DEFAULT = pathlib.Path(__file__).resolve().parent / "results.json"


def over_budget(table: dict) -> list[str]:
    """One line per row whose ratio is over its budget (a ratio that is no number counts as over)."""
    lines = []
    for row in table["rows"]:
        ratio, budget = float(row["ratio"]), float(row["budget"])
        if not (math.isfinite(ratio) and ratio <= budget):
            lines.append(f"{row['name']}: ratio {ratio:.3g} over its budget {budget:.3g} ({row.get('floor', '')})")
    return lines


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    path = pathlib.Path(args[0]) if args else DEFAULT
    try:
        table = json.loads(path.read_text())
        lines = over_budget(table)
    except (OSError, ValueError, KeyError, TypeError) as error:
        print(f"check: cannot read {path}: {error}", file=sys.stderr)
        return 2
    for line in lines:
        print(line)
    print(f"{len(table['rows']) - len(lines)} of {len(table['rows'])} rows within budget")
    return 1 if lines else 0


if __name__ == "__main__":
    sys.exit(main())
