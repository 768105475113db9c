"""The API reference (docs/reference/, built by `make docs`) documents every public name.

Cheap by design: the pages' `::: springlab.X` directives are read as text and compared with
`springlab.__all__`; no site is built here (CI builds it with `mkdocs build --strict`).
"""

from __future__ import annotations

import inspect
import pathlib
import re
import typing

import springlab
from helpers.paths import ROOT

REFERENCE = ROOT / "docs" / "reference"
DIRECTIVE = re.compile(r"^:::\s+(springlab(?:\.\w+)+)\s*$", re.M)


def _documented() -> dict[str, pathlib.Path]:
    """Dotted name -> the reference page whose `:::` directive renders it."""
    return {name: page for page in REFERENCE.rglob("*.md") for name in DIRECTIVE.findall(page.read_text())}


def _target(dotted: str) -> object:
    obj: object = springlab
    for part in dotted.split(".")[1:]:
        obj = getattr(obj, part)
    return obj


def test_every_public_name_has_a_reference_entry():
    documented = {name.removeprefix("springlab.") for name in _documented()}
    missing = sorted(set(springlab.__all__) - documented)
    assert not missing, f"in springlab.__all__ but on no page of docs/reference/ (add `::: springlab.X`): {missing}"


def test_every_directive_names_what_exists():
    # griffe resolves the names statically; a renamed object would fail `make docs`, this says so in the suite
    broken = [f"{page.relative_to(ROOT)}: {name}" for name, page in _documented().items() if not _resolves(name)]
    assert not broken, broken


def _resolves(dotted: str) -> bool:
    try:
        _target(dotted)
    except AttributeError:
        return False
    return True


def test_the_results_of_the_public_functions_are_documented():
    # a function's page says what it returns; that class has its own page
    targets = {id(_target(name)) for name in _documented() if _resolves(name)}
    missing = []
    for name in springlab.__all__:
        function = getattr(springlab, name)
        if not inspect.isfunction(function):
            continue
        returned = inspect.signature(function, eval_str=True).return_annotation
        for cls in typing.get_args(returned) or (returned,):
            if inspect.isclass(cls) and cls.__module__.startswith("springlab") and id(cls) not in targets:
                missing.append(f"springlab.{name} -> {cls.__qualname__}")
    assert not missing, f"result classes without a reference page: {missing}"


def test_every_reference_page_is_in_the_navigation():
    nav = (ROOT / "mkdocs.yml").read_text()
    pages = sorted(p.relative_to(ROOT / "docs").as_posix() for p in REFERENCE.rglob("*.md"))
    assert pages and not [p for p in pages if p not in nav]


def test_the_reader_finds_what_it_checks():
    # the directive pattern must match the pages' form, or the checks above pass on nothing
    assert DIRECTIVE.findall("# x\n\n::: springlab.run\n") == ["springlab.run"]
    assert "springlab.Result" in _documented()
