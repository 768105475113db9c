"""Where the audited model comes from: an MjModel, a path to an MJCF (or URDF) file, or a shipped scene.

`load(model)` compiles it once and says where it came from (for the text, and for dask workers, which rebuild
it: springlab.studies.audit.ship); a scene also brings its scenario's start and duration.
"""

from __future__ import annotations

import dataclasses
import os
import pathlib

import mujoco

from springlab import scenes
from springlab.errors import BadInputError
from springlab.sim import model_files
from springlab.sim.simulate import Setup


@dataclasses.dataclass(frozen=True)
class Source:
    """A compiled model and where it came from.

    Attributes
    ----------
    label
        for people: the path, "scene 'car' (scenario 'release')" or "<MjModel>".
    model
        the compiled model.
    start
        a shipped scene's scenario start (None: a model file or an MjModel).
    duration
        a shipped scene's scenario duration [s] (None: the audit's default).
    origin
        ("path", file) or ("scene", name): what dask workers rebuild it from (None: an MjModel in memory).
    """

    label: str
    model: mujoco.MjModel
    start: Setup | None = None
    duration: float | None = None
    origin: tuple[str, str] | None = None


def load(model: mujoco.MjModel | str | os.PathLike[str]) -> Source:
    """A compiled model from an MjModel, a path to an MJCF / URDF, or a shipped scene name.

    A scene is built with its default scenario and parameters; its scenario's initial state is the
    sweep's start (as `springlab tradeoff` runs it) and its duration the default.

    Raises
    ------
    BadInputError
        no such file or scene, or MuJoCo cannot compile it (its message, one line).
    """
    if isinstance(model, mujoco.MjModel):
        return Source("<MjModel>", model)
    if not isinstance(model, (str, os.PathLike)):
        raise BadInputError(f"model must be an MjModel, a path to an MJCF file or a scene name, got {model!r}")
    text = os.fspath(model)
    path = pathlib.Path(text)
    if not path.exists() and text in scenes.SCENES:
        case = scenes.case(text)
        chosen, built = case.scenario, case.model
        setup = case.setup(max(1, round(chosen.duration / built.opt.timestep)), built.opt.timestep)
        return Source(f"scene {text!r} (scenario {chosen.name!r})", built, setup, chosen.duration, ("scene", text))
    if not path.is_file():
        raise BadInputError(f"no such model file or scene {text!r}; scenes: {', '.join(sorted(scenes.SCENES))}")
    return Source(text, model_files.load(path), origin=("path", text))
