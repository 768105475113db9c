"""The package's layers (CONTRIBUTING.md, "Layers"), lowest first: read by tests/project/test_layers.py (the
import graph runs one way), tests/project/test_style.py (CONTRIBUTING.md's table agrees) and
tests/results/test_display.py (the drawing a result looks up lives in the plots layer)."""

from __future__ import annotations

#: lowest first: layer -> the packages (folders) and root modules in it; a module may import from its own
#: layer's packages or any layer below. A new top-level package or root module adds its name here and to
#: CONTRIBUTING.md's table (tests/project/test_style.py checks the two agree).
LAYERS: dict[str, tuple[str, ...]] = {
    "foundation": ("answer", "display", "errors", "files", "progress", "tables"),
    "simulation": ("sim",),
    "exact": ("exact",),
    "scenes": ("scenes",),
    "one run": ("runs",),
    "studies": ("studies",),
    "plots": ("plots",),
    "render": ("render",),
    "outputs": ("outputs",),
    "front": ("cli", "demo", "__init__", "__main__"),
}
ORDER = list(LAYERS)


def layer_of(module: str) -> str:
    """The layer of `module` (dotted, relative to springlab): that of its top-level package."""
    top = module.split(".")[0]
    for layer, names in LAYERS.items():
        if top in names:
            return layer
    raise AssertionError(
        f"springlab.{module} is in no layer: add {top!r} to LAYERS in tests/helpers/layers.py (and CONTRIBUTING.md)"
    )
