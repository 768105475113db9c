"""The scene registry: one module per MJCF file under models/, same name.

Scene modules are discovered, so a new scene is a new module with a module-level
`SCENE` and a models/<name>.xml; nothing else needs editing.
"""

from __future__ import annotations

import importlib
import pkgutil

from ..errors import UnknownNameError
from ..scene import Scene

#: the chapter's order; discovered scenes not listed here follow alphabetically
CATALOGUE_ORDER = ("slider", "car", "printer_head", "kinematics", "nonlinear")


def _discover() -> dict[str, Scene]:
    names = sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))
    names.sort(key=lambda n: (CATALOGUE_ORDER.index(n) if n in CATALOGUE_ORDER else len(CATALOGUE_ORDER), n))
    found = {}
    for name in names:
        module = importlib.import_module(f"{__name__}.{name}")
        found[module.SCENE.name] = module.SCENE
    return found


#: scene name -> Scene, in catalogue order
SCENES: dict[str, Scene] = _discover()


def get(name: str) -> Scene:
    """The scene called `name`; UnknownNameError lists the valid names."""
    try:
        return SCENES[name]
    except KeyError:
        raise UnknownNameError("scene", str(name), SCENES) from None
