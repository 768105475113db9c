"""Where the MJCF files are (inside the installed package, or models/ of a checkout), and a user's model file.

* `directory()` / `path(scene)`: the shipped scenes' MJCF files.
* `is_model_file(text)`: whether a command's argument names a model file rather than a scene.
* `load(path)`: a user's MJCF (or URDF MuJoCo loads) compiled, or one clear BadInputError; every command and
  study that takes a model file loads it here.
"""

from __future__ import annotations

import functools
import os
import pathlib

import mujoco

from springlab.errors import BadInputError

from .simulate import quiet_mujoco

_PACKAGE = pathlib.Path(__file__).resolve().parents[1]  # src/springlab/sim/model_files.py -> springlab/
_PACKAGED = _PACKAGE / "models"
_CHECKOUT = _PACKAGE.parents[1] / "models"

#: file name endings that make an argument a model file even where no such file exists (it is then reported
#: missing, not looked up as a scene)
MODEL_SUFFIXES = (".xml", ".mjcf", ".urdf")


@functools.cache  # a stat per call added up: every run and every sweep configuration asks
def directory() -> pathlib.Path:
    """The folder holding the scene MJCF files."""
    # a wheel carries springlab/models; an editable install reads the checkout's models/
    return _PACKAGED if _PACKAGED.is_dir() else _CHECKOUT


def path(scene: str) -> pathlib.Path:
    """Path of the MJCF file of `scene` (models/<scene>.xml)."""
    return directory() / f"{scene}.xml"


def is_model_file(text: str | os.PathLike[str]) -> bool:
    """Whether `text` names a model file: an existing file, or a name ending in one of MODEL_SUFFIXES."""
    name = os.fspath(text)
    return name.lower().endswith(MODEL_SUFFIXES) or pathlib.Path(name).is_file()


def load(file: str | os.PathLike[str]) -> mujoco.MjModel:
    """The model file at `file` (MJCF, or URDF MuJoCo loads), compiled with MuJoCo's warnings kept quiet.

    Raises
    ------
    BadInputError
        no such file, or MuJoCo cannot compile it (its message, on one line).
    """
    text = os.fspath(file)
    if not pathlib.Path(text).is_file():
        raise BadInputError(f"no such model file {text!r}")
    try:
        with quiet_mujoco():
            return mujoco.MjModel.from_xml_path(text)
    except Exception as error:  # MuJoCo raises ValueError with its compiler's message
        message = " ".join(str(error).split())
        raise BadInputError(f"cannot load {text!r}: {message}") from None
