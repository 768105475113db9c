"""The scene registry: one module or folder per MJCF file under models/, same name.

Scenes are discovered, so a new scene is a new module (`scenes/<name>.py`) or folder
(`scenes/<name>/`, its `__init__` handing on `SCENE`) with a module-level `SCENE` and a
models/<name>.xml; nothing else needs editing. `base` (what every scene provides),
`capabilities` (what a scene declares for the studies) and `checks` (scalar claims) are the
scenes' shared machinery, not scenes.
"""

from __future__ import annotations

import importlib
import pkgutil

from springlab.errors import UnknownNameError

from .base import Scene

#: modules of this package that serve the scenes and are none
MACHINERY = ("base", "capabilities", "checks")
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


#: scene name -> Scene, in catalogue order
SCENES: dict[str, Scene] = _discover()


def get(name: str) -> Scene:
    """The scene called `name`; UnknownNameError lists the valid names."""
    try:
        return SCENES[name]
    except KeyError:
        raise UnknownNameError("scene", str(name), SCENES) from None
