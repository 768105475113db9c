"""What a picture of a model shows besides its own geoms, shared by the videos and the live viewer.

:func:`stage` arranges a model for being watched over a motion: the rails
stretched over the whole travel (:func:`drawings.covering_guides`), the drawn
springs, dampers, belts and road (:class:`drawings.Drawings`, appended to any
``MjvScene`` each frame: the video's off-screen scene or the live viewer's
``user_scn``) and the fixed camera framed on the motion (:func:`framing.frame_camera`).
:func:`road_bump` is the road a run drives over, as its scene declares it. Drawing only: the
physics model passed in is never changed.
"""

from __future__ import annotations

import mujoco
import numpy as np

from springlab.runs.run import Result

from .drawings import Drawings, RoadBump, covering_guides
from .framing import frame_camera

__all__ = ["stage", "road_bump"]


def stage(
    model: mujoco.MjModel,
    states: np.ndarray,
    camera_id: int,
    width: int,
    height: int,
    road: RoadBump | None = None,
) -> tuple[mujoco.MjModel, Drawings, np.ndarray | None]:
    """(model to draw, its drawings, per-frame camera positions [m] or None) for watching ``states``.

    Parameters
    ----------
    model:
        The model; not modified (the result is a copy wherever something changes).
    states:
        ``qpos`` of every frame as drawn, shape ``(n, nq)``.
    camera_id:
        The camera to frame (-1: MuJoCo's free camera, left alone).
    width, height:
        Size of the view [px] (its aspect ratio frames the camera; its height sets the spring wires' width).
    road:
        Optional :class:`drawings.RoadBump` under a quarter car.

    Returns
    -------
    The model with its rails covering the travel and its camera framed, the :class:`drawings.Drawings`
    to add to every frame (rail marks on when the camera follows), and the camera's positions per
    frame when it follows a long travel (None: it stands still).
    """
    model = covering_guides(model, states)
    drawings = Drawings(model, states, road, height)
    model, camera_path = frame_camera(model, states, camera_id, width, height, anchors=drawings.anchors())
    drawings.rail_marks = camera_path is not None  # a following camera needs marks to show the travel
    return model, drawings, camera_path


def road_bump(result: Result) -> RoadBump | None:
    """The road a run drives over, as its scene declares it for the run's case (`Scene.drawing`; None: none)."""
    return result.case.drawing().road
