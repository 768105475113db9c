"""Framing: the camera is placed from the motion's extent, so moving bodies stay in view at a readable size.

A scene's MJCF camera gives the direction and the lens (field of view); where
it stands is computed for each run from what moves (:func:`frame_camera`):

1. **Fit the whole motion.** The bounding-box corners of every moving geom at
   every frame, the anchors of the drawn springs and the geoms of non-world
   bodies that do not move (the car's wheels in its 1-DOF scenarios) are
   projected into the camera. The camera moves in its image plane and along
   its axis, in *or* out, until they fill the central ``FRAME_MARGIN`` of the
   view: a 25 mm printer move is filmed close up, a 5 m release from far.
2. **Follow when the whole motion is too big.** If fitting everything leaves
   the largest moving geom smaller than ``READABLE_FRACTION`` of the view's
   width (the slider's exercise: a 0.1 m block over 5 m), the camera instead
   keeps the zoom at which that geom spans ``FOLLOW_FRACTION`` of the width
   (or wider, so that any single frame's moving geoms fit) and pans lazily: it stays put while the bodies are inside the view and slides
   just enough to keep them there when they would leave. Vibrations do not
   shake the picture; long travels are followed.

Tracking cameras (mode other than fixed, or attached to a moving body) and
MuJoCo's free camera are left alone. The caller's model is never changed: the
result is a shallow copy with its own camera position and far plane.
"""

from __future__ import annotations

import copy
import math

import mujoco
import numpy as np

__all__ = ["FRAME_MARGIN", "READABLE_FRACTION", "frame_camera", "framed_model"]

#: fraction of the view the framed points may fill [-]
FRAME_MARGIN = 0.88
#: smallest share of the view width the largest moving geom may get before the camera follows [-]
READABLE_FRACTION = 0.12
#: share of the view width the largest moving geom gets when the camera follows [-]
FOLLOW_FRACTION = 0.3

_CORNERS = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], dtype=float)


def _moving_geoms(model: mujoco.MjModel) -> np.ndarray:
    """Ids of the geoms on bodies that can move (not welded to the world)."""
    return np.flatnonzero(model.body_weldid[model.geom_bodyid] != 0)


def _context_geoms(model: mujoco.MjModel) -> np.ndarray:
    """Geoms of bodies welded to the world that are not the world body itself (e.g. welded wheels)."""
    body = model.geom_bodyid
    return np.flatnonzero((model.body_weldid[body] == 0) & (body != 0))


def _world_points(model, data, geoms) -> np.ndarray:
    """(g * 8, 3) world positions [m] of the geoms' bounding-box corners."""
    aabb = model.geom_aabb[geoms]  # local centre (3) and half sizes (3)
    local = aabb[:, None, :3] + _CORNERS[None] * aabb[:, None, 3:]  # (g, 8, 3)
    rot = data.geom_xmat[geoms].reshape(-1, 3, 3)
    return (data.geom_xpos[geoms][:, None] + np.einsum("gij,gcj->gci", rot, local)).reshape(-1, 3)


def _to_camera(points: np.ndarray, position: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """(n, 3) rows (right [m], up [m], depth [m]) of world ``points`` seen from a camera at ``position``."""
    rel = (points - position) @ axes  # axes columns: right, up, backward
    return np.column_stack([rel[:, 0], rel[:, 1], -rel[:, 2]])


def _fit(points: np.ndarray, tan_h: float, tan_v: float) -> tuple[float, float, float]:
    """(shift right [m], shift up [m], move back [m]) of the camera that fits ``points`` in the margin.

    Exact for the chosen shift (the middle of the points' span): every point
    then satisfies |right - shift| <= margin tan_h (depth + back), likewise up.
    ``back`` is negative when the camera moves in.
    """
    right, up, depth = points.T
    shift_r = 0.5 * (np.max(right) + np.min(right))
    shift_u = 0.5 * (np.max(up) + np.min(up))
    need = np.maximum(np.abs(right - shift_r) / (FRAME_MARGIN * tan_h), np.abs(up - shift_u) / (FRAME_MARGIN * tan_v))
    return float(shift_r), float(shift_u), float(np.max(need - depth))


def frame_camera(
    model: mujoco.MjModel,
    states: np.ndarray,
    camera_id: int,
    width: int,
    height: int,
    anchors: np.ndarray | None = None,
) -> tuple[mujoco.MjModel, np.ndarray | None]:
    """(model copy with the framed camera, per-frame camera positions (n, 3) [m] or None).

    Parameters
    ----------
    model:
        The model; not modified.
    states:
        ``qpos`` of every frame, shape ``(n, nq)``, as they will be drawn.
    camera_id:
        The camera to frame; only fixed cameras on the world body are moved.
    width, height:
        Size of the view [px] (its aspect ratio matters).
    anchors:
        Optional extra world points [m] to keep in view when the whole motion
        is fitted, shape ``(k, 3)`` (e.g. where a drawn spring is fixed).

    Returns
    -------
    The model (itself when nothing changes) and None when the camera stands
    still, or the per-frame camera positions when it follows the motion.
    """
    if (
        camera_id < 0
        or model.cam_bodyid[camera_id] != 0
        or model.cam_mode[camera_id] != mujoco.mjtCamLight.mjCAMLIGHT_FIXED
    ):
        return model, None
    moving = _moving_geoms(model)
    if moving.size == 0 or len(states) == 0:
        return model, None
    tan_v = math.tan(math.radians(model.cam_fovy[camera_id]) / 2)
    tan_h = tan_v * width / height
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
    position = data.cam_xpos[camera_id].copy()
    axes = data.cam_xmat[camera_id].reshape(3, 3).copy()
    frames = []
    for q in states:
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        frames.append(_to_camera(_world_points(model, data, moving), position, axes))
    context = _context_geoms(model)
    extra = [_to_camera(_world_points(model, data, context), position, axes)] if context.size else []
    if anchors is not None and len(anchors):
        extra.append(_to_camera(np.asarray(anchors, dtype=float).reshape(-1, 3), position, axes))
    everything = np.concatenate(frames + extra)
    shift_r, shift_u, back = _fit(everything, tan_h, tan_v)
    size = float(2.0 * np.max(model.geom_aabb[moving, 3:]))  # largest moving geom [m]
    centre_depth = float(np.median(everything[:, 2])) + back

    framed = copy.copy(model)
    path = None
    if size / (2.0 * tan_h * max(centre_depth, 1e-9)) >= READABLE_FRACTION:
        offsets = np.array([[shift_r, shift_u, back]])
    else:
        # follow: the zoom that fits any one frame, then the laziest pan that keeps each frame inside
        fits = [_fit(points, tan_h, tan_v) for points in frames]
        readable = size / (2.0 * tan_h * FOLLOW_FRACTION) - float(np.median(frames[0][:, 2]))
        back = max(max(f[2] for f in fits), readable)
        offsets = np.empty((len(frames), 3))
        pan = np.array([fits[0][0], fits[0][1]])
        for i, points in enumerate(frames):
            reach_r = FRAME_MARGIN * tan_h * (points[:, 2] + back)
            reach_u = FRAME_MARGIN * tan_v * (points[:, 2] + back)
            low = np.array([np.max(points[:, 0] - reach_r), np.max(points[:, 1] - reach_u)])
            high = np.array([np.min(points[:, 0] + reach_r), np.min(points[:, 1] + reach_u)])
            pan = np.clip(pan, low, np.maximum(low, high))
            offsets[i] = [pan[0], pan[1], back]
        everything = np.concatenate(frames)
    positions = model.cam_pos[camera_id] + offsets @ axes.T  # (n, 3): camera axes -> world
    framed.cam_pos[camera_id] = positions[0]
    # the clipping planes (vis.map.znear/zfar x extent) must still hold everything
    far = float(np.max(everything[:, 2])) + float(np.max(offsets[:, 2]))
    framed.vis.map.zfar = max(float(model.vis.map.zfar), 2.0 * far / max(float(model.stat.extent), 1e-9))
    near = float(np.min(everything[:, 2])) + float(np.min(offsets[:, 2]))
    if near > 0:
        framed.vis.map.znear = min(float(model.vis.map.znear), 0.5 * near / max(float(model.stat.extent), 1e-9))
    if len(offsets) > 1:
        path = positions
    return framed, path


def framed_model(model: mujoco.MjModel, states: np.ndarray, camera_id: int, width: int, height: int) -> mujoco.MjModel:
    """The model with its fixed camera framed on the motion of ``states`` (first frame's place when following).

    See :func:`frame_camera`; kept for callers that film one still camera.
    """
    return frame_camera(model, states, camera_id, width, height)[0]
