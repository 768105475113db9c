"""springlab's source as syntax trees, read once per test process and shared by every test that reads the
package's code rather than running it (layers, style, result names, outputs, the API's annotations): five files
each parsed the whole package (0.8 s a parse) and walked it again per check. The trees are only read: no test
changes one."""

from __future__ import annotations

import ast
import functools
import pathlib

from helpers.paths import ROOT

PACKAGE = ROOT / "src" / "springlab"


@functools.cache
def source_files() -> tuple[pathlib.Path, ...]:
    """Every module of the package, sorted by path."""
    return tuple(sorted(PACKAGE.rglob("*.py")))


@functools.cache
def tree(path: pathlib.Path) -> ast.Module:
    """The syntax tree of one source file (`path` under src/springlab)."""
    return ast.parse(path.read_text(), str(path))


@functools.cache
def nodes(path: pathlib.Path) -> tuple[ast.AST, ...]:
    """Every node of `tree(path)`, in `ast.walk`'s order (breadth first)."""
    return tuple(ast.walk(tree(path)))


def trees() -> dict[str, ast.Module]:
    """Path relative to src/springlab (posix) -> syntax tree, for every module of the package."""
    return {path.relative_to(PACKAGE).as_posix(): tree(path) for path in source_files()}
