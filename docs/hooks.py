"""mkdocs hook: the repository's README.md and CONTRIBUTING.md become pages of the site.

They live beside docs/, not in it, and both they and docs/index.md link across that boundary
(`../README.md`, `docs/api.md`). On GitHub those links resolve as they are; for the site each
is served as a page (readme.md, contributing.md) and every link that crosses is rewritten to the
page it names, so `mkdocs build --strict` validates them like any other link.
"""

from __future__ import annotations

import posixpath
import re
from pathlib import Path

from mkdocs.structure.files import File, Files

#: repository file -> the page it becomes (relative to docs/)
PAGES = {"README.md": "readme.md", "CONTRIBUTING.md": "contributing.md"}
#: [text](target) with a relative target (no scheme)
LINK = re.compile(r"(\]\()(?![a-z][a-z0-9+.-]*:)([^)\s#]+)((?:#[^)\s]*)?\))")


def _rewrite(markdown: str, real: str, virtual: str) -> str:
    """Rewrite the links of a page kept at `real` (in the repository) and served at `virtual` (in docs/).

    A target inside docs/ or one of PAGES is pointed at its page, relative to `virtual`; any other is left
    for mkdocs to validate (and fail on).
    """

    def repoint(match: re.Match) -> str:
        target = posixpath.normpath(posixpath.join(posixpath.dirname(real), match.group(2)))
        if target in PAGES:
            page = PAGES[target]
        elif target.startswith("docs/"):
            page = target.removeprefix("docs/")
        else:
            return match.group(0)
        return match.group(1) + posixpath.relpath(page, posixpath.dirname(virtual) or ".") + match.group(3)

    return LINK.sub(repoint, markdown)


def on_files(files: Files, config) -> Files:
    """Add README.md and CONTRIBUTING.md as pages, their links rewritten."""
    root = Path(config["config_file_path"]).parent
    for source, page in PAGES.items():
        text = _rewrite((root / source).read_text(encoding="utf-8"), source, page)
        files.append(File.generated(config, page, content=text))
    return files


def on_page_markdown(markdown: str, page, config, files: Files) -> str:
    """Point the docs' links to README.md and CONTRIBUTING.md at their pages."""
    if page.file.src_uri in PAGES.values():
        return markdown
    return _rewrite(markdown, "docs/" + page.file.src_uri, page.file.src_uri)
