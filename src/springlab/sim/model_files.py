"""Where the MJCF files are: inside the installed package, or models/ of a checkout."""

from __future__ import annotations

import functools
import pathlib

_PACKAGE = pathlib.Path(__file__).resolve().parents[1]  # src/springlab/sim/model_files.py -> springlab/
_PACKAGED = _PACKAGE / "models"
_CHECKOUT = _PACKAGE.parents[1] / "models"


@functools.cache  # a stat per call added up: every run and every sweep configuration asks
def directory() -> pathlib.Path:
    """The folder holding the scene MJCF files."""
    # a wheel carries springlab/models; an editable install reads the checkout's models/
    return _PACKAGED if _PACKAGED.is_dir() else _CHECKOUT


def path(scene: str) -> pathlib.Path:
    """Path of the MJCF file of `scene` (models/<scene>.xml)."""
    return directory() / f"{scene}.xml"
