"""Every result serialises one way, with one name: `to_dict()` (issue 20, "Results as objects").

Read from the source with `ast`, like tests/project/test_layers.py and tests/project/test_style.py, over the whole
package: no function or method anywhere in src/springlab is named `as_dict`, `as_json`, `report_json` or `summary`
(a `summary` *property* is data, kept on `Result` for scripts written against `result.summary`); every class
with a `to_dict` is a frozen dataclass; the result classes below have `to_dict`, and those that hold rows
`to_pandas`; pandas is imported only by springlab.tables.
"""

from __future__ import annotations

import ast

from helpers import source
from helpers.source import PACKAGE

#: the old names of serialisation (and of a study's report): gone from the package
OLD_NAMES = {"as_dict", "as_json", "report_json", "summary"}

#: module -> its result classes: each a frozen dataclass with `to_dict()`; a new result joins here
RESULTS = {
    "scenes/declarations.py": {"Check"},
    "runs/compare.py": {"ColumnError", "EstimateRange"},
    "runs/result.py": {"Result", "ValidationRow"},
    "studies/settings.py": {"Setting", "Run", "Recommendation"},
    "studies/tradeoff.py": {"Tradeoff", "TradeoffRun"},
    "studies/sweeps.py": {"Sweep", "SweepRow", "Axis"},
    "studies/families.py": {"Member", "PhaseFamily", "ZetaFamily"},
    "studies/fit/results.py": {"FitResult"},
    "studies/audit/results.py": {"Audit"},
    "studies/audit/parts.py": {
        "OwnSetting",
        "Excitation",
        "PointReport",
        "Linearity",
        "ReferenceUsed",
        "Timings",
    },
    "studies/audit/limits.py": {"Limit", "ConstraintFlag"},
    "studies/stability.py": {"StabilityReport", "Boundary", "EnergyCheck", "EnergyHistories", "AmplificationMap"},
    "studies/extremes.py": {"ExtremeRun"},
    "studies/frequency/results.py": {"FrequencyResponse", "Resonance", "IntegratorBand", "Sinestream", "SweepBranch"},
    "studies/design/study.py": {"Study", "Plane"},
    "studies/design/sobol.py": {"SobolStudy"},
}
#: the result classes that hold rows, which also have `to_pandas()`
ROWS = {
    "Result",
    "Tradeoff",
    "Sweep",
    "PhaseFamily",
    "ZetaFamily",
    "FitResult",
    "Audit",
    "StabilityReport",
    "Study",
    "SobolStudy",
    "FrequencyResponse",
}


def _modules() -> dict[str, ast.Module]:
    # one parse of the package per test process, shared with the other readers of the source (helpers/source.py)
    return source.trees()


def _definitions(body: list[ast.stmt], prefix: str = ""):
    """(qualified name, node) of every function, method and class, at any depth."""
    for node in body:
        if isinstance(node, ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            yield prefix + node.name, node
            yield from _definitions(node.body, f"{prefix}{node.name}.")
        elif isinstance(node, ast.If | ast.Try | ast.With):
            yield from _definitions(node.body, prefix)
            yield from _definitions(getattr(node, "orelse", []), prefix)


def _is_property(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    return any(isinstance(d, ast.Name) and d.id == "property" for d in node.decorator_list)


def _frozen_dataclass(node: ast.ClassDef) -> bool:
    for decorator in node.decorator_list:
        if isinstance(decorator, ast.Call) and ast.unparse(decorator.func) in ("dataclasses.dataclass", "dataclass"):
            if any(
                k.arg == "frozen" and isinstance(k.value, ast.Constant) and k.value.value for k in decorator.keywords
            ):
                return True
    return False


def _methods(node: ast.ClassDef) -> set[str]:
    return {n.name for n in node.body if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)}


def test_no_old_serialisation_names_anywhere_in_the_package():
    found = {
        f"{module}:{name}"
        for module, tree in _modules().items()
        for name, node in _definitions(tree.body)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and node.name in OLD_NAMES
        and not (node.name == "summary" and _is_property(node))
    }
    assert not found, "serialise with to_dict(), nothing else:\n" + "\n".join(sorted(found))


def test_every_class_with_to_dict_is_a_frozen_dataclass():
    mutable = [
        f"{module}:{name}"
        for module, tree in _modules().items()
        for name, node in _definitions(tree.body)
        if isinstance(node, ast.ClassDef) and "to_dict" in _methods(node) and not _frozen_dataclass(node)
    ]
    assert not mutable, "a result is immutable once returned (frozen dataclass):\n" + "\n".join(mutable)


def test_the_result_classes_have_to_dict_and_those_with_rows_to_pandas():
    modules = _modules()
    missing = []
    for module, names in RESULTS.items():
        classes = {n.name: n for n in ast.walk(modules[module]) if isinstance(n, ast.ClassDef)}
        for name in names:
            assert name in classes, f"{module} has no class {name}: update RESULTS"
            methods = _methods(classes[name])
            wanted = {"to_dict"} | ({"to_pandas"} if name in ROWS else set())
            missing += [f"{module}:{name}.{method}" for method in sorted(wanted - methods)]
            if not _frozen_dataclass(classes[name]):
                missing.append(f"{module}:{name} is not a frozen dataclass")
    assert not missing, "\n".join(missing)


def test_pandas_is_imported_only_by_springlab_tables():
    """Outside tables.py, pandas appears only under `if TYPE_CHECKING:` (annotations of to_pandas)."""
    found = []
    for path in source.source_files():
        module = path.relative_to(PACKAGE).as_posix()
        if module == "tables.py":
            continue
        typing_only = {
            id(inner)
            for node in source.nodes(path)
            if isinstance(node, ast.If) and ast.unparse(node.test) in ("TYPE_CHECKING", "typing.TYPE_CHECKING")
            for inner in ast.walk(node)
        }
        for node in source.nodes(path):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            if any(n.split(".")[0] == "pandas" for n in names) and id(node) not in typing_only:
                found.append(f"{module}:{node.lineno}")
    assert not found, "import pandas through springlab.tables.to_pandas:\n" + "\n".join(found)
