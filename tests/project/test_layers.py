"""The package's folders are its layers, and its import graph runs one way (CONTRIBUTING.md, "Layers").

A module imports only from its own package or the packages of the layers below, nothing imports in a
circle, and no study, run, plot or renderer names a scene: what a scene can do it declares (`Scene`),
and the layers above read the declaration.

The graph is read from the source with `ast`, function-local imports included (an import inside a function is
still a dependency, only a later one), so the check runs without importing springlab.
"""

from __future__ import annotations

import ast
import functools
import pathlib

import pytest

from helpers import source
from helpers.layers import LAYERS, ORDER, layer_of
from helpers.source import PACKAGE

#: the study packages: each answers its own question and none imports another (they share the
#: modules at the root of studies/: the executor, convergence, tradeoff ...)
STUDY_PACKAGES = ("audit", "design", "fit", "frequency")


def modules() -> dict[str, pathlib.Path]:
    """Dotted module name (relative to springlab) -> source file, for every module of the package."""
    return dict(_modules())


@functools.cache
def _modules() -> dict[str, pathlib.Path]:
    # read once per test process: the tests below walk the same tree (the source does not change meanwhile)
    out = {}
    for path in source.source_files():
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
    for node in source.nodes(path):
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
                if candidate in known:  # `from springlab.sim import batch`: a submodule
                    found.add(candidate)
                else:  # `from springlab.scenes.base import Scene`: a name of a module
                    found.add(".".join(target) or "__init__")
    found.discard(module)
    return found


def parsed(path: pathlib.Path) -> ast.Module:
    """The syntax tree of one source file, parsed once per test process (helpers/source.py: the checks only
    read it)."""
    return source.tree(path)


def graph() -> dict[str, set[str]]:
    return {name: set(targets) for name, targets in _graph().items()}


@functools.cache
def _graph() -> dict[str, frozenset[str]]:
    found = modules()
    return {name: frozenset(imports(name, path, set(found))) for name, path in found.items()}


def test_the_import_graph_is_read_from_the_source():
    # the reader itself: it must see the imports this test relies on, or the checks below prove nothing
    edges = graph()
    assert {"sim.simulate", "scenes", "runs.compare"} <= edges["runs.run"]
    assert "runs.run" in edges["studies.tradeoff"] and "sim.batch" in edges["studies.tradeoff"]
    assert "exact.analytic" in edges["scenes.slider.scene"]
    assert "scenes.car.scene" in edges["scenes.car"]  # a scene folder hands on its SCENE
    assert {"studies.auto", "runs.run"} <= edges["__init__"]


def test_every_top_level_package_and_root_module_has_a_layer():
    tops = {path.relative_to(PACKAGE).parts[0].removesuffix(".py") for path in PACKAGE.rglob("*.py")}
    listed = {name for names in LAYERS.values() for name in names}
    assert tops == listed


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


def test_no_study_package_imports_another():
    crossing = []
    for module, targets in graph().items():
        parts = module.split(".")
        if parts[0] != "studies" or len(parts) < 3 or parts[1] not in STUDY_PACKAGES:
            continue
        for target in targets:
            other = target.split(".")
            if other[0] == "studies" and len(other) > 1 and other[1] in STUDY_PACKAGES and other[1] != parts[1]:
                crossing.append(f"{module} imports {target}")
    assert not crossing, "\n".join(crossing)


def _scene_names() -> set[str]:
    scenes = PACKAGE / "scenes"
    found = {p.stem for p in scenes.glob("*.py")} | {p.name for p in scenes.iterdir() if (p / "__init__.py").exists()}
    return found - {"__init__", "base", "capabilities", "checks", "declarations"}


#: imports by name at run time (`importlib.import_module(NAME)`), which the graph above cannot see: each one
#: listed with why, so a new hidden dependency fails here by name. display -> plots.figures runs upward on
#: purpose: a result's `.plot()` finds its drawing in the plots layer only when a figure is asked for, as
#: pandas' `DataFrame.plot` finds its plotting backend.
LAZY_IMPORTS = {("display", "plots.figures"): "a result's .plot() looks up its drawing when asked"}


def lazy_imports(module: str, path: pathlib.Path) -> set[str]:
    """The springlab modules `module` imports by name: `importlib.import_module(X)` with X a string constant or
    a module-level constant holding one (a name built at run time, like the scene discovery's, is no edge)."""
    tree = parsed(path)
    constants = {
        target.id: node.value.value
        for node in tree.body
        if isinstance(node, ast.Assign | ast.AnnAssign) and isinstance(node.value, ast.Constant)
        for target in (node.targets if isinstance(node, ast.Assign) else [node.target])
        if isinstance(target, ast.Name) and isinstance(node.value.value, str)
    }
    found = set()
    for node in source.nodes(path):
        if not (isinstance(node, ast.Call) and node.args):
            continue
        called = node.func
        name = called.attr if isinstance(called, ast.Attribute) else called.id if isinstance(called, ast.Name) else ""
        if name not in ("import_module", "__import__"):
            continue
        argument = node.args[0]
        value = argument.value if isinstance(argument, ast.Constant) else constants.get(getattr(argument, "id", ""))
        if isinstance(value, str) and value.startswith("springlab."):
            found.add(value.removeprefix("springlab."))
    return found


def test_every_import_by_name_is_listed_and_exists():
    known = modules()
    found = {(module, target) for module, path in known.items() for target in lazy_imports(module, path)}
    assert found == set(LAZY_IMPORTS), (
        f"imports by name not in LAZY_IMPORTS (or listed but gone): {found ^ set(LAZY_IMPORTS)}"
    )
    assert all(target in known for _, target in found)


def test_the_import_by_name_reader_sees_display_plot():
    # the reader itself: display.plot imports PLOTTING, a module-level constant, inside a function
    assert lazy_imports("display", PACKAGE / "display.py") == {"plots.figures"}


def test_the_scene_names_this_test_knows_are_the_shipped_models():
    models = PACKAGE.parents[1] / "models"
    assert _scene_names() == {p.stem for p in models.glob("*.xml")}


#: where a string constant names something: compared, passed, stored, keyed, defaulted or returned
NAMING_PARENTS = (
    ast.Compare,
    ast.Call,
    ast.Dict,
    ast.Subscript,
    ast.arguments,
    ast.Tuple,
    ast.List,
    ast.Set,
    ast.Assign,
    ast.AnnAssign,
    ast.Return,
    ast.BoolOp,
)


def test_nothing_outside_the_scenes_names_a_scene():
    """No import of a particular scene and no scene name as a string outside scenes/: a study reads what a
    scene declares. The command line's argument defaults and help are the one exception (front layer)."""
    names = _scene_names()
    found = []
    edges = graph()
    for module, path in modules().items():
        if layer_of(module) in ("scenes", "front"):
            continue
        docstrings = {
            id(node.body[0].value)
            for node in source.nodes(path)
            if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)
            and node.body
            and isinstance(node.body[0], ast.Expr)
            and isinstance(node.body[0].value, ast.Constant)
        }
        for parent in source.nodes(path):
            if not isinstance(parent, NAMING_PARENTS):
                continue  # e.g. the word 'nonlinear' chosen by a conditional expression for a message
            for node in ast.iter_child_nodes(parent):
                if isinstance(node, ast.keyword):
                    node = node.value
                if isinstance(node, ast.Constant) and node.value in names and id(node) not in docstrings:
                    found.append(f"{module}:{node.lineno} names scene {node.value!r}")
        for target in edges[module]:
            parts = target.split(".")
            if parts[0] == "scenes" and len(parts) > 1 and parts[1] in names:
                found.append(f"{module} imports springlab.{target}")
    assert not found, "\n".join(found)
