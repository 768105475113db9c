"""The package keeps one docstring style (numpy) and types its public API (CONTRIBUTING.md, "Style").

Read from the source with `ast`, like tests/project/test_layers.py, so the check runs without importing springlab.
mypy (`make lint`) checks that the annotations are right; this checks that the public ones exist.
"""

from __future__ import annotations

import ast
import pathlib
import re

from helpers import source
from helpers.layers import LAYERS
from helpers.paths import ROOT

PACKAGE = ROOT / "src" / "springlab"

#: CONTRIBUTING.md's size limits ("Style"): a module a reader can hold, a function that fits on two screens
MAX_MODULE_LINES = 750
MAX_FUNCTION_LINES = 120

GOOGLE_SECTION = re.compile(r"^\s*(Args|Arguments|Returns|Yields|Raises|Attributes|Keyword Args):\s*$", re.M)


def _sources() -> tuple[tuple[str, pathlib.Path], ...]:
    """Every module of the package (its trees parsed once per test process, helpers/source.py): no module is
    exempt."""
    return tuple((p.relative_to(PACKAGE).as_posix(), p) for p in source.source_files())


def _docstrings(path: pathlib.Path):
    for node in source.nodes(path):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            doc = ast.get_docstring(node, clean=False)
            if doc:
                yield getattr(node, "lineno", 1), doc


def _public_functions(body: list[ast.stmt], public: bool = True):
    """Module-level functions and methods of public classes whose names do not start with '_'."""
    for node in body:
        if isinstance(node, ast.ClassDef):
            yield from _public_functions(node.body, public and not node.name.startswith("_"))
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and public and not node.name.startswith("_"):
            yield node


def test_docstrings_use_numpy_sections_only():
    found = [
        f"{name}:{line}: {match.group(1)}:"
        for name, path in _sources()
        for line, doc in _docstrings(path)
        for match in GOOGLE_SECTION.finditer(doc)
    ]
    assert not found, "Google-style sections; write Parameters / Returns / Raises with dashes:\n" + "\n".join(found)


def test_public_functions_have_type_hints():
    missing = []
    for name, path in _sources():
        for node in _public_functions(source.tree(path).body):
            args = node.args
            params = [a for a in [*args.posonlyargs, *args.args, *args.kwonlyargs] if a.arg not in ("self", "cls")]
            params += [a for a in (args.vararg, args.kwarg) if a is not None]
            bare = [a.arg for a in params if a.annotation is None]
            if node.returns is None and node.name != "__init__":
                bare.append("return")
            if bare:
                missing.append(f"{name}:{node.lineno} {node.name}: {', '.join(bare)}")
    assert not missing, "public functions without type hints:\n" + "\n".join(missing)


def test_contributing_lists_the_layers_of_test_layers():
    text = (PACKAGE.parents[1] / "CONTRIBUTING.md").read_text()
    table = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 3 and cells[0] in LAYERS:
            table[cells[0]] = tuple(re.findall(r"`([\w.]+)`", cells[1]))
    assert table == LAYERS


def test_contributing_shows_the_package_tree_as_it_is():
    text = (PACKAGE.parents[1] / "CONTRIBUTING.md").read_text()
    block = text.split("```\nsrc/springlab/\n", 1)[1].split("```", 1)[0]
    shown, folders = set(), []
    for line in block.splitlines():
        depth = (len(line) - len(line.lstrip())) // 2  # two spaces a level under src/springlab/
        words = line.split()
        if words and words[0].endswith("/"):
            folders[depth - 1 :] = [words[0].rstrip("/")]
            words = words[1:]
        else:
            folders = folders[: depth - 1]
        shown.update("/".join([*folders, w]) for w in words)
    actual = {p.relative_to(PACKAGE).as_posix() for p in PACKAGE.rglob("*.py")}
    assert shown == actual, f"missing from CONTRIBUTING.md: {sorted(actual - shown)}; gone: {sorted(shown - actual)}"


def test_no_module_over_750_lines():
    sizes = {p.relative_to(PACKAGE).as_posix(): len(p.read_text().splitlines()) for p in PACKAGE.rglob("*.py")}
    over = [f"{name}: {lines} lines" for name, lines in sorted(sizes.items()) if lines > MAX_MODULE_LINES]
    assert not over, f"modules over {MAX_MODULE_LINES} lines (split them along their seams):\n" + "\n".join(over)


def test_no_function_over_120_lines():
    over = [
        f"{name}:{node.lineno} {node.name}: {node.end_lineno - node.lineno + 1} lines"
        for name, path in _sources()
        for node in source.nodes(path)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and node.end_lineno is not None
        and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES
    ]
    assert not over, (
        f"functions over {MAX_FUNCTION_LINES} lines (decorators aside; move a step into a helper):\n" + "\n".join(over)
    )
