"""What the words say is what the code is: every module path and file the source and the docs cite exists.

A move that renames a module leaves `springlab.old_name` behind in docstrings and pages; a page that cites a
document outside the repository sends the reader nowhere. Both fail here, so the words cannot drift from the
code (issue 20, "No drift").
"""

from __future__ import annotations

import importlib
import re

import pytest

from helpers.paths import ROOT

PACKAGE = ROOT / "src" / "springlab"
#: where the words are: the package's own source, the pages, and the scripts users copy from
TEXTS = sorted(
    [
        *PACKAGE.rglob("*.py"),
        *(ROOT / "docs").rglob("*.md"),
        ROOT / "README.md",
        ROOT / "CONTRIBUTING.md",
        *(ROOT / "scenarios").glob("*.py"),
        *(ROOT / "benchmarks").glob("*.py"),
        *(ROOT / "tools").glob("*.py"),
    ]
)
DOTTED = re.compile(r"\bspringlab(?:\.[A-Za-z_]\w*)+")
#: repository files cited by path: concrete lower-case names only (models/X.xml, docs/scenes/<name>.md are patterns)
CITED = re.compile(
    r"(?<![\w/.-])((?:tests|docs|models|scenarios|benchmarks|src/springlab)/[a-z0-9_/.-]*[a-z0-9_]\.(?:py|md|xml|csv|png))\b"
    r"|(?<![\w/.-])([A-Z][A-Z_]*\.md)\b"
)


def _resolves(dotted: str) -> bool:
    """Whether `springlab.a.b.c` names a module, or an attribute reached from the longest importable module."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for name in parts[cut:]:
            if not hasattr(obj, name):
                return False
            obj = getattr(obj, name)
        return True
    return False


@pytest.mark.parametrize("path", TEXTS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_dotted_springlab_name_resolves(path):
    text = path.read_text()
    missing = sorted({name for name in DOTTED.findall(text) if not _resolves(name)})
    assert not missing, f"{path.relative_to(ROOT)} names what does not exist: {', '.join(missing)}"


@pytest.mark.parametrize("path", TEXTS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_cited_file_is_in_the_repository(path):
    text = path.read_text()
    cited = {a or b for a, b in CITED.findall(text)}
    missing = sorted(c for c in cited if not (ROOT / c).exists() and not list(ROOT.glob(f"*/{c}")))
    assert not missing, f"{path.relative_to(ROOT)} cites files the repository does not have: {', '.join(missing)}"


def test_the_readers_see_what_they_check():
    # the checks above must find the references they exist for, or they prove nothing
    assert "springlab.run" in DOTTED.findall((ROOT / "docs" / "api.md").read_text())
    assert _resolves("springlab.exact.analytic.free_response") and not _resolves("springlab.analytic_old")
    assert {a or b for a, b in CITED.findall("see CONTRIBUTING.md and tests/project/test_layers.py")} == {
        "CONTRIBUTING.md",
        "tests/project/test_layers.py",
    }
