"""The scene registry: one module or folder per MJCF file under models/, same name.

Scenes are discovered, so a new scene is a new module (`scenes/<name>.py`) or folder
(`scenes/<name>/`, its `__init__` handing on `SCENE`) with a module-level `SCENE` and a
models/<name>.xml; nothing else needs editing. `base` (what every scene provides),
`declarations` (parameters, scenarios, references, checks as plain data), `capabilities` (what
a scene declares for the studies) and `checks` (scalar claims) are the scenes' shared machinery,
not scenes.
"""

from __future__ import annotations

import importlib
import pkgutil
import types
from collections.abc import Iterator, Mapping
from typing import Any

from springlab.errors import UnknownNameError

from .base import Case, Scene

#: modules of this package that serve the scenes and are none
MACHINERY = ("base", "capabilities", "checks", "declarations")
#: the chapter's order; discovered scenes not listed here follow alphabetically
CATALOGUE_ORDER = ("slider", "car", "printer_head", "kinematics", "nonlinear")


def _discover() -> dict[str, Scene]:
    names = sorted(m.name for m in pkgutil.iter_modules(__path__) if m.name not in MACHINERY)
    names.sort(key=lambda n: (CATALOGUE_ORDER.index(n) if n in CATALOGUE_ORDER else len(CATALOGUE_ORDER), n))
    found = {}
    for name in names:
        module = importlib.import_module(f"{__name__}.{name}")
        found[module.SCENE.name] = module.SCENE
    return found


class _Registry(Mapping[str, Scene]):
    """The scenes by name, in catalogue order: read-only, discovered on first use (importing springlab
    imports no scene; the first lookup imports them all, once)."""

    def __init__(self) -> None:
        self._found: Mapping[str, Scene] | None = None

    def _scenes(self) -> Mapping[str, Scene]:
        if self._found is None:
            self._found = types.MappingProxyType(_discover())
        return self._found

    def __getitem__(self, name: str) -> Scene:
        return self._scenes()[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._scenes())

    def __len__(self) -> int:
        return len(self._scenes())

    def __repr__(self) -> str:
        return f"<springlab scenes: {', '.join(self)}>"


#: scene name -> Scene, in catalogue order (read-only; discovered on first use)
SCENES: Mapping[str, Scene] = _Registry()


def get(name: str) -> Scene:
    """The scene called `name`; UnknownNameError lists the valid names."""
    try:
        return SCENES[name]
    except KeyError:
        raise UnknownNameError("scene", str(name), SCENES) from None


def case(scene: str | Scene, scenario: str | None = None, parameters: Mapping[str, Any] | None = None) -> Case:
    """A scene's scenario at these parameters, resolved and compiled once (`Scene.case`).

    Parameters
    ----------
    scene
        a scene or its name.
    scenario
        scenario name (None: the scene's default).
    parameters
        overrides, name -> value (SI).

    Raises
    ------
    UnknownNameError
        a scene, scenario or parameter that does not exist.
    ParameterError
        a value outside its valid range, or a non-physical combination.
    """
    return (get(scene) if isinstance(scene, str) else scene).case(scenario, parameters)
