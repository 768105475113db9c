"""Framing: the fixed camera backs off so everything that moves stays in the picture.

A scene's MJCF camera frames its usual motion; when a run carries a body out
of a fixed camera's view (:func:`framed_model`), a copy of the model gets that
camera backed off along its own axis, same direction and lens, just enough to
hold every moving geom at every frame. The caller's model is never changed.
"""

from __future__ import annotations

import copy
import math

import mujoco
import numpy as np

__all__ = ["framed_model"]

#: fraction of the view the moving parts may fill before the camera backs off
_FRAME_MARGIN = 0.92


def _moving_geoms(model: mujoco.MjModel) -> np.ndarray:
    """Ids of the geoms on bodies that can move (not welded to the world)."""
    return np.flatnonzero(model.body_weldid[model.geom_bodyid] != 0)


_CORNERS = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], dtype=float)


def _camera_points(model, data, cam_id, geoms) -> np.ndarray:
    """(n, 3) rows (right [m], up [m], depth [m]) of the geoms' bounding-box corners in camera axes."""
    aabb = model.geom_aabb[geoms]  # local centre (3) and half sizes (3)
    local = aabb[:, None, :3] + _CORNERS[None] * aabb[:, None, 3:]  # (g, 8, 3)
    rot = data.geom_xmat[geoms].reshape(-1, 3, 3)
    world = data.geom_xpos[geoms][:, None] + np.einsum("gij,gcj->gci", rot, local)
    cam = data.cam_xmat[cam_id].reshape(3, 3)  # columns: right, up, backward
    rel = (world.reshape(-1, 3) - data.cam_xpos[cam_id]) @ cam
    return np.column_stack([rel[:, 0], rel[:, 1], -rel[:, 2]])


def framed_model(model: mujoco.MjModel, states: np.ndarray, camera_id: int, width: int, height: int) -> mujoco.MjModel:
    """The model, or a copy whose fixed camera backs off so every moving part stays in view.

    A scene's MJCF camera frames its usual motion; a parameter choice can carry
    a body out of it (the slider's exercise starts 5 m out). For a fixed camera
    on the world body, the bounding-box corners of every moving geom at every frame
    state (``states``, shape ``(n, nq)``) are projected into the camera; if any
    leaves the central ``_FRAME_MARGIN`` of the view, a copy of the model gets
    the camera shifted in its image plane and pulled back along its axis (same
    direction and field of view, so the look stays the scene's own) just enough
    to hold them all, plus what the original view showed of the static scene.
    Geoms are bounded by their boxes (``geom_aabb``), not spheres, so long
    flat bodies (a car hull) are not over-estimated.
    Tracking cameras and the free camera are left alone. ``model`` is never
    modified.
    """
    if (
        camera_id < 0
        or model.cam_bodyid[camera_id] != 0
        or model.cam_mode[camera_id] != mujoco.mjtCamLight.mjCAMLIGHT_FIXED
    ):
        return model
    moving = _moving_geoms(model)
    if moving.size == 0:
        return model
    tan_v = math.tan(math.radians(model.cam_fovy[camera_id]) / 2)
    tan_h = tan_v * width / height
    data = mujoco.MjData(model)
    points = []
    for q in states:
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        mujoco.mj_camlight(model, data)
        points.append(_camera_points(model, data, camera_id, moving))
    points = np.concatenate(points)

    def inside(p):
        right, up, depth = p.T
        return (
            (np.abs(right) <= _FRAME_MARGIN * tan_h * depth)
            & (np.abs(up) <= _FRAME_MARGIN * tan_v * depth)
            & (depth > 0)
        )

    if np.all(inside(points)):
        return model
    # keep the static scene that was in view (e.g. the wall the spring hangs on)
    static = np.flatnonzero(model.body_weldid[model.geom_bodyid] == 0)
    static = static[model.geom_type[static] != mujoco.mjtGeom.mjGEOM_PLANE]
    if static.size:
        seen = _camera_points(model, data, camera_id, static)
        points = np.concatenate([points, seen[inside(seen)]])
    right, up, depth = points.T
    shift_r = 0.5 * (np.max(right) + np.min(right))
    shift_u = 0.5 * (np.max(up) + np.min(up))
    back = max(
        0.0,
        float(
            np.max(
                np.maximum(
                    np.abs(right - shift_r) / (_FRAME_MARGIN * tan_h), np.abs(up - shift_u) / (_FRAME_MARGIN * tan_v)
                )
                - depth
            )
        ),
    )
    framed = copy.copy(model)
    axes = data.cam_xmat[camera_id].reshape(3, 3)
    framed.cam_pos[camera_id] = model.cam_pos[camera_id] + axes @ np.array([shift_r, shift_u, back])
    # the far clipping plane (vis.map.zfar x extent) must still reach past everything
    far = float(np.max(depth)) + back
    framed.vis.map.zfar = max(float(model.vis.map.zfar), 2.0 * far / max(float(model.stat.extent), 1e-9))
    return framed
