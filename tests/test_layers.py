"""The package's import graph is one-way: a module imports only from its own layer or the layers below, and
nothing imports in a circle (CONTRIBUTING.md, "Layers").

The graph is read from the source with `ast`, function-local imports included (an import inside a function is
still a dependency, only a later one), so the check runs without importing springlab.
"""

from __future__ import annotations

import ast
import pathlib

import pytest

PACKAGE = pathlib.Path(__file__).resolve().parents[1] / "src" / "springlab"

#: lowest first; a new module adds its name here (scenes/* are physics, render_* are outputs)
LAYERS: dict[str, tuple[str, ...]] = {
    "physics": (
        "errors",
        "progress",
        "model_files",
        "outputs",
        "exciter",
        "simulate",
        "analytic",
        "linear",
        "linearize",
        "polynomials",
        "compare",
        "events",
        "scene",
        "checks",
        "scenes",
    ),
    "one run": ("api",),
    "studies": (
        "batch",
        "tradeoff",
        "stability",
        "extremes",
        "auto",
        "design",
        "design_moves",
        "audit",
        "audit_limits",
        "audit_ship",
        "audit_sweep",
        "fit",
        "fit_data",
        "fit_engine",
        "fit_models",
        "fit_results",
        "fit_starts",
        "sweep",
        "sweeps",
        "executor",
        "sobol",
    ),
    "outputs": (
        "charts",
        "charts_audit",
        "design_chart",
        "fit_chart",
        "plots",
        "plots_style",
        "plots_phase",
        "plots_panel",
        "render",
        "report",
        "media",
        "sweep_plot",
    ),
    "front": ("cli", "cli_text", "demo", "__main__", "__init__"),
}
PREFIXES = {"scenes.": "physics", "render_": "outputs"}
ORDER = list(LAYERS)


def layer_of(module: str) -> str:
    """The layer of `module` (dotted, relative to springlab)."""
    for layer, names in LAYERS.items():
        if module in names:
            return layer
    for prefix, layer in PREFIXES.items():
        if module.startswith(prefix):
            return layer
    raise AssertionError(
        f"springlab.{module} has no layer: add it to LAYERS in tests/test_layers.py (and CONTRIBUTING.md)"
    )


def modules() -> dict[str, pathlib.Path]:
    """Dotted module name (relative to springlab) -> source file, for every module of the package."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        if parts[-1] == "__init__" and len(parts) > 1:
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def imports(module: str, path: pathlib.Path, known: set[str]) -> set[str]:
    """The springlab modules `module` imports anywhere in its source (relative or absolute imports)."""
    if path.name == "__init__.py":  # a package: its relative imports start inside it
        package = [] if module == "__init__" else module.split(".")
    else:
        package = module.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name == "springlab" or alias.name.startswith("springlab."):
                    found.add(alias.name.removeprefix("springlab").lstrip(".") or "__init__")
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)] if node.level > 1 else list(package)
                target = [*base, *(node.module.split(".") if node.module else [])]
            elif node.module and (node.module == "springlab" or node.module.startswith("springlab.")):
                target = node.module.split(".")[1:]
            else:
                continue
            for alias in node.names:
                candidate = ".".join([*target, alias.name])
                if candidate in known:  # `from . import api`: a submodule
                    found.add(candidate)
                else:  # `from .scene import Scene`: a name of a module
                    found.add(".".join(target) or "__init__")
    found.discard(module)
    return found


def graph() -> dict[str, set[str]]:
    found = modules()
    return {name: imports(name, path, set(found)) for name, path in found.items()}


def test_the_import_graph_is_read_from_the_source():
    # the reader itself: it must see the imports this test relies on, or the checks below prove nothing
    edges = graph()
    assert {"simulate", "scene", "compare", "scenes"} <= edges["api"]
    assert "api" in edges["tradeoff"] and "batch" in edges["tradeoff"]
    assert "analytic" in edges["scenes.slider"]
    assert {"auto", "api"} <= edges["__init__"]


def test_every_module_imports_only_from_its_layer_or_below():
    upward = []
    for module, targets in graph().items():
        rank = ORDER.index(layer_of(module))
        for target in sorted(targets):
            if ORDER.index(layer_of(target)) > rank:
                upward.append(f"{module} ({layer_of(module)}) imports {target} ({layer_of(target)})")
    assert not upward, "upward imports:\n" + "\n".join(upward)


def test_the_import_graph_has_no_cycle():
    edges = graph()
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(module: str) -> None:
        state[module] = 1
        path.append(module)
        for target in sorted(edges.get(module, ())):
            if state.get(target) == 1:
                pytest.fail("import cycle: " + " -> ".join([*path[path.index(target) :], target]))
            if target not in state:
                visit(target)
        path.pop()
        state[module] = 2

    for module in sorted(edges):
        if module not in state:
            visit(module)
