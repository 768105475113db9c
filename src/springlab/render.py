"""Off-screen video rendering of recorded MuJoCo trajectories.

The entry point is :func:`render_video`: it replays a recorded trajectory
(``time``, ``qpos``) through MuJoCo's classic OpenGL renderer without a
display and writes an H.264 ``.mp4`` (plays in browsers) or a ``.gif``.

Design notes
------------
* **GL backend.** Headless machines have no X server, so :func:`ensure_gl_backend`
  selects EGL (``MUJOCO_GL=egl``) unless the user chose a backend. With Mesa
  this renders on the CPU (llvmpipe); no GPU is needed. The module calls it at
  import time, before importing :mod:`mujoco`. If :mod:`mujoco` was imported
  earlier with a different setting, the GL context class is still picked from
  the environment at render time (``mujoco.egl.GLContext`` for ``egl``), so the
  import order does not matter.
* **One GL context per video.** A single GL context, ``MjrContext`` and
  ``MjvScene`` are created per call and reused for every frame. Shadows,
  reflections, skybox, haze and fog are switched off (they cost extra render
  passes on a CPU rasteriser); tendons (the visible spring) stay on.
* **Readable picture.** MuJoCo clears to black; a flat white backdrop quad is
  added to the scene behind everything, so the background is light and the
  model's own colours contrast with it. Time (``t = 1.23 s``) and the optional
  label are drawn with Pillow (antialiased TrueType DejaVu Sans from
  matplotlib, Unicode-capable, e.g. Greek letters) in dark text on a
  translucent white box.
* **Everything moving stays in the picture.** A scene's MJCF camera frames
  its usual motion; when a run carries a body out of a fixed camera's view
  (:func:`framed_model`), a copy of the model gets that camera backed off
  along its own axis, same direction and lens, just enough to hold every
  moving geom at every frame. The caller's model is never changed.
* **Frames follow the clock, not the integrator.** Frames are sampled at
  :func:`frame_times` (``k / fps``) by linear interpolation of the recorded
  states (:func:`sample_states`), so video time equals simulation time no
  matter what the physics time step was.
* **Overlap.** Frames are handed to a writer thread through a bounded queue; the
  thread feeds ``imageio_ffmpeg.write_frames`` (libx264, ``yuv420p``, preset
  ``veryfast``), and ffmpeg encodes in its own process while the next frames
  are rendered, so both cores are busy.
* **All or nothing.** Output goes to a hidden temporary file in the target
  directory, renamed over ``output`` only on success; on any failure
  (including a raising ``panel`` callback or Ctrl-C) the temporary file is
  removed.
"""

from __future__ import annotations

import math
import os


def ensure_gl_backend() -> None:
    """Select the EGL OpenGL backend for MuJoCo unless the user chose one.

    Sets ``MUJOCO_GL=egl`` when ``MUJOCO_GL`` is unset or empty; an existing
    value (``egl``, ``osmesa``, ``glfw``, ...) is respected. Call it before
    importing :mod:`mujoco` or creating any renderer. (This module calls it on
    import.)
    """
    if not os.environ.get("MUJOCO_GL", "").strip():
        os.environ["MUJOCO_GL"] = "egl"


ensure_gl_backend()  # must run before `import mujoco` picks its GL backend

import copy  # noqa: E402
import importlib.util  # noqa: E402
import queue  # noqa: E402
import sys  # noqa: E402
import threading  # noqa: E402
import time as _time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from fractions import Fraction  # noqa: E402
from pathlib import Path  # noqa: E402

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from . import outputs  # noqa: E402
from .errors import BadInputError  # noqa: E402  (a ValueError; the CLI maps it to exit 2)

__all__ = ["ensure_gl_backend", "frame_times", "sample_states", "render_video", "check_video_arguments", "framed_model"]

#: Output formats render_video can write, by file extension.
SUPPORTED_EXTENSIONS = (".mp4", ".gif")

#: Largest width/height accepted (GL renderbuffers are limited; video players too).
MAX_SIZE = 8192

#: H.264 settings: fast preset, visually clean quality for flat-shaded scenes.
X264_PRESET = "veryfast"
X264_CRF = 20

#: GIF frame delays are stored in 1/100 s; players clamp delays below 2/100 s.
GIF_MAX_FPS = 50

_BACKGROUND_RGBA = np.array([1.0, 1.0, 1.0, 1.0])  # backdrop colour (white)
_TEXT_RGB = np.array([20.0, 20.0, 28.0])  # near-black text
_TEXT_BOX_ALPHA = 0.78  # translucent white box behind the text
_QUEUE_FRAMES = 8  # bounded render -> encoder queue


# --------------------------------------------------------------------------- time


def frame_times(duration: float, fps: int) -> np.ndarray:
    """Return the frame times [s] of a video of ``duration`` seconds at ``fps``.

    The times are ``0, 1/fps, 2/fps, ...``; there are ``round(duration * fps)``
    of them, so the video lasts exactly as long as the simulated time it shows
    (the last frame is shown from ``(n-1)/fps`` until ``n/fps``).
    """
    fps = _check_fps(fps)
    try:
        duration = float(duration)
    except (TypeError, ValueError):
        raise BadInputError(f"duration must be a number of seconds, got {duration!r}") from None
    if not math.isfinite(duration) or duration < 0:
        raise BadInputError(f"duration must be a finite number of seconds >= 0, got {duration!r}")
    count = int(round(duration * fps))
    return np.arange(count, dtype=float) / fps


def sample_states(time: np.ndarray, qpos: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Linearly interpolate recorded states to the times ``at``.

    Parameters
    ----------
    time:
        Recording times [s], shape ``(n_steps,)``, non-decreasing.
    qpos:
        Recorded positions, shape ``(n_steps, nq)`` (a 1-D array is taken as
        ``nq = 1``).
    at:
        Query times [s], any 1-D array. Times outside ``[time[0], time[-1]]``
        get the first/last recorded state (no extrapolation).

    Returns
    -------
    Array of shape ``(len(at), nq)``. Interpolation is per coordinate, which is
    exact in the sense needed for slide and hinge joints; quaternion
    coordinates come out unnormalised (:func:`render_video` renormalises them).
    """
    t = np.asarray(time, dtype=float)
    q = np.asarray(qpos, dtype=float)
    a = np.asarray(at, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise BadInputError(f"time must be a non-empty 1-D array, got shape {t.shape}")
    if q.ndim == 1:
        q = q[:, None]
    if q.ndim != 2 or q.shape[0] != t.size:
        raise BadInputError(f"qpos must have shape (len(time), nq) = ({t.size}, nq), got {np.shape(qpos)}")
    if a.ndim != 1:
        raise BadInputError(f"at must be a 1-D array of times, got shape {a.shape}")
    if not np.all(np.isfinite(t)):
        raise BadInputError("time contains NaN or infinite values")
    if np.any(np.diff(t) < 0):
        raise BadInputError("time must be increasing (non-decreasing)")
    if np.any(np.isnan(a)):
        raise BadInputError("at contains NaN")

    n = t.size
    if n == 1:
        return np.repeat(q, a.size, axis=0)
    # segment k covers [t[k], t[k+1]]; clamp to the recorded range
    k = np.clip(np.searchsorted(t, a, side="right") - 1, 0, n - 2)
    t0, t1 = t[k], t[k + 1]
    span = t1 - t0
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(span > 0, (a - t0) / np.where(span > 0, span, 1.0), 1.0)
    w = np.clip(w, 0.0, 1.0)[:, None]
    return q[k] * (1.0 - w) + q[k + 1] * w


# ----------------------------------------------------------------- validation


def _check_fps(fps) -> int | float:
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)):
        raise BadInputError(f"fps must be a positive number of frames per second, got {fps!r}")
    if not math.isfinite(fps) or fps <= 0:
        raise BadInputError(f"fps must be > 0, got {fps!r}")
    return fps


def _check_size(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise BadInputError(f"{name} must be an integer number of pixels, got {value!r}")
    value = int(value)
    if not 0 < value <= MAX_SIZE:
        raise BadInputError(f"{name} must be between 1 and {MAX_SIZE} pixels, got {value}")
    return value


def _camera_names(model: mujoco.MjModel) -> list[str]:
    return [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, i) or f"#{i}" for i in range(model.ncam)]


def _resolve_camera(model: mujoco.MjModel, camera) -> int:
    """Camera id; -1 is MuJoCo's default free camera."""
    names = _camera_names(model)
    listing = ", ".join(repr(n) for n in names) if names else "none (use camera=None or -1 for the default free camera)"
    if camera is None:
        return 0 if model.ncam > 0 else -1
    if isinstance(camera, str):
        cam_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
        if cam_id < 0:
            raise BadInputError(f"unknown camera {camera!r}; the model's cameras are: {listing}")
        return cam_id
    if isinstance(camera, (int, np.integer)) and not isinstance(camera, bool):
        if not -1 <= int(camera) < model.ncam:
            raise BadInputError(
                f"camera index {camera} out of range [-1, {model.ncam}); the model's cameras are: {listing}"
            )
        return int(camera)
    raise BadInputError(f"camera must be a name, an index or None, got {camera!r}")


def _output_kind(output) -> tuple[Path, str]:
    try:
        path = Path(os.fspath(output))
    except TypeError:
        raise BadInputError(f"output must be a file path, got {output!r}") from None
    ext = path.suffix.lower()
    if ext not in SUPPORTED_EXTENSIONS:
        raise BadInputError(
            f"unsupported output extension {path.suffix or '(none)'!r} for {str(path)!r}; "
            f"use one of: {', '.join(SUPPORTED_EXTENSIONS)}"
        )
    return path, ext


def check_video_arguments(output, fps, width, height) -> tuple[Path, str, int | float, int, int]:
    """Validate a video request before any work: (path, extension, fps, width, height).

    Raises ``BadInputError`` (a ``ValueError``) for an extension other than
    .mp4/.gif, fps <= 0 (or > 50 for GIF), or a size outside 1..MAX_SIZE px.
    """
    out_path, ext = _output_kind(output)
    fps = _check_fps(fps)
    if ext == ".gif" and fps > GIF_MAX_FPS:
        raise BadInputError(f"GIF supports at most {GIF_MAX_FPS} fps (got {fps}); use .mp4")
    return out_path, ext, fps, _check_size("width", width), _check_size("height", height)


def _normalize_quaternions(model: mujoco.MjModel, q: np.ndarray) -> None:
    """Renormalise free/ball joint quaternions after linear interpolation (in place)."""
    for j in range(model.njnt):
        jtype = model.jnt_type[j]
        adr = model.jnt_qposadr[j]
        if jtype == mujoco.mjtJoint.mjJNT_FREE:
            adr += 3
        elif jtype != mujoco.mjtJoint.mjJNT_BALL:
            continue
        quat = q[:, adr : adr + 4]
        norm = np.linalg.norm(quat, axis=1, keepdims=True)
        np.divide(quat, norm, out=quat, where=norm > 0)


# ------------------------------------------------------------------ framing

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


# ----------------------------------------------------------------- GL renderer


def _gl_context_class():
    """GL context class for the backend selected in MUJOCO_GL *now*.

    ``mujoco.GLContext`` is fixed when :mod:`mujoco` is first imported; if that
    happened before MUJOCO_GL was set, it would be the GLFW context, which
    needs a display. Importing the backend module directly avoids that.
    """
    backend = os.environ.get("MUJOCO_GL", "").strip().lower()
    try:
        if backend == "egl":
            from mujoco.egl import GLContext
        elif backend == "osmesa":
            from mujoco.osmesa import GLContext
        elif backend == "glfw":
            from mujoco.glfw import GLContext
        else:
            GLContext = getattr(mujoco, "GLContext", None)
    except Exception as err:  # ImportError, or PyOpenGL platform errors
        raise RuntimeError(f"cannot load the OpenGL backend MUJOCO_GL={backend!r}: {err}") from err
    if GLContext is None:
        raise RuntimeError(f"no OpenGL context available for MUJOCO_GL={backend!r}")
    return GLContext


#: prefix of the MJCF custom texts that declare a drawn spring
SPRING_PREFIX = "spring:"


def drawn_springs(model: mujoco.MjModel) -> list[tuple[int, int, float, np.ndarray]]:
    """Springs to draw: [(site id, site id, width [m], rgba)] from the model's custom texts.

    A spring that is only a picture (its physics is a joint's stiffness) is declared as
    <custom><text name="spring:NAME" data="SITE1 SITE2 WIDTH R G B A"/></custom>
    rather than as a zero-stiffness tendon, which MuJoCo would compute at every step.
    """
    springs = []
    for i in range(model.ntext):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_TEXT, i) or ""
        if not name.startswith(SPRING_PREFIX):
            continue
        start = model.text_adr[i]
        text = bytes(model.text_data[start : start + model.text_size[i] - 1]).decode()  # drop the NUL
        first, second, width, *rgba = text.split()
        springs.append(
            (
                model.site(first).id,
                model.site(second).id,
                float(width),
                np.array([float(c) for c in rgba], dtype=np.float32),
            )
        )
    return springs


class _OffscreenScene:
    """One GL context + MjrContext + MjvScene, reused for every frame."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int, camera_id: int):
        self.model = model
        self.width = width
        self.height = height
        self._gl = None
        self._con = None
        GLContext = _gl_context_class()
        try:
            self._gl = GLContext(width, height)
            self._gl.make_current()
        except Exception as err:
            self.close()
            raise RuntimeError(
                f"could not create an off-screen OpenGL context (MUJOCO_GL={os.environ.get('MUJOCO_GL')!r}): {err}"
            ) from err

        # The offscreen framebuffer size is read from the model when the
        # MjrContext is made. Enlarge it for this context only, then restore the
        # caller's values, so the model passed in is left unchanged.
        vis = model.vis.global_
        saved = (int(vis.offwidth), int(vis.offheight))
        try:
            vis.offwidth = max(saved[0], width)
            vis.offheight = max(saved[1], height)
            self._con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
        except Exception:
            self.close()
            raise
        finally:
            vis.offwidth, vis.offheight = saved
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._con)
        if self._con.currentBuffer != mujoco.mjtFramebuffer.mjFB_OFFSCREEN:
            self.close()
            raise RuntimeError("the OpenGL context has no off-screen framebuffer")

        self.scene = mujoco.MjvScene(model, maxgeom=max(1000, 4 * model.ngeom + 500))
        flags = self.scene.flags
        for flag in (
            mujoco.mjtRndFlag.mjRND_SHADOW,
            mujoco.mjtRndFlag.mjRND_REFLECTION,
            mujoco.mjtRndFlag.mjRND_SKYBOX,
            mujoco.mjtRndFlag.mjRND_HAZE,
            mujoco.mjtRndFlag.mjRND_FOG,
        ):
            flags[flag] = 0
        self.option = mujoco.MjvOption()
        self.option.flags[mujoco.mjtVisFlag.mjVIS_TENDON] = 1  # the spring

        self.camera = mujoco.MjvCamera()
        if camera_id < 0:
            self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
            mujoco.mjv_defaultFreeCamera(model, self.camera)
        else:
            self.camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
            self.camera.fixedcamid = camera_id

        self._springs = drawn_springs(model)
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._pixels = np.empty((height, width, 3), dtype=np.uint8)
        self._eye = np.eye(3)

    def _add_backdrop(self) -> None:
        """Append a flat white quad just inside the far clipping plane."""
        scn = self.scene
        if scn.ngeom >= scn.maxgeom:
            return
        c0, c1 = scn.camera[0], scn.camera[1]
        pos = 0.5 * (np.asarray(c0.pos) + np.asarray(c1.pos))
        fwd = 0.5 * (np.asarray(c0.forward) + np.asarray(c1.forward))
        up = 0.5 * (np.asarray(c0.up) + np.asarray(c1.up))
        fwd /= np.linalg.norm(fwd)
        up -= fwd * (up @ fwd)
        up /= np.linalg.norm(up)
        right = np.cross(fwd, up)
        near, far = float(c0.frustum_near), float(c0.frustum_far)
        dist = 0.95 * far
        half_h = max(abs(c0.frustum_top), abs(c0.frustum_bottom)) + abs(c0.frustum_center)
        if not c0.orthographic:
            half_h *= dist / near
        half = 2.0 * half_h * max(1.0, self.width / self.height)
        mat = np.column_stack([right, up, fwd]).ravel()
        geom = scn.geoms[scn.ngeom]
        mujoco.mjv_initGeom(
            geom,
            mujoco.mjtGeom.mjGEOM_BOX,
            np.array([half, half, 1e-3 * dist]),
            pos + dist * fwd,
            mat,
            _BACKGROUND_RGBA.astype(np.float32),
        )
        geom.emission = 1.0  # rgba * emission = white, whatever the lights
        geom.specular = 0.0
        geom.shininess = 0.0
        geom.reflectance = 0.0
        geom.category = mujoco.mjtCatBit.mjCAT_DECOR
        geom.segid = -1
        scn.ngeom += 1

    def _add_springs(self, data: mujoco.MjData) -> None:
        """Draw each declared spring as a capsule between its two sites (see drawn_springs)."""
        scn = self.scene
        for first, second, width, rgba in self._springs:
            if scn.ngeom >= scn.maxgeom:
                return
            geom = scn.geoms[scn.ngeom]
            mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3), np.eye(3).ravel(), rgba)
            mujoco.mjv_connector(
                geom, mujoco.mjtGeom.mjGEOM_CAPSULE, width, data.site_xpos[first], data.site_xpos[second]
            )
            geom.category = mujoco.mjtCatBit.mjCAT_DECOR
            scn.ngeom += 1

    def render(self, data: mujoco.MjData, out: np.ndarray) -> None:
        """Render ``data`` (kinematics already computed) into ``out`` (H x W x 3)."""
        mujoco.mjv_updateScene(self.model, data, self.option, None, self.camera, mujoco.mjtCatBit.mjCAT_ALL, self.scene)
        self._add_springs(data)
        self._add_backdrop()
        mujoco.mjr_render(self._rect, self.scene, self._con)
        mujoco.mjr_readPixels(self._pixels, None, self._rect, self._con)
        out[...] = self._pixels[::-1]  # OpenGL rows are bottom-up

    def close(self) -> None:
        if self._con is not None:
            if self._gl is not None:
                self._gl.make_current()
            self._con.free()
            self._con = None
        if self._gl is not None:
            self._gl.free()
            self._gl = None


# ---------------------------------------------------------------------- text


def _find_font() -> str | None:
    """Path of matplotlib's DejaVu Sans, found without importing matplotlib."""
    try:
        spec = importlib.util.find_spec("matplotlib")
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    for root in spec.submodule_search_locations:
        path = Path(root, "mpl-data", "fonts", "ttf", "DejaVuSans.ttf")
        if path.is_file():
            return str(path)
    return None


class _TextOverlay:
    """Dark text on a translucent white box at the top-left of the 3D view."""

    def __init__(self, label: str, view_height: int, max_time: float):
        from PIL import ImageFont

        self.size = max(11, round(view_height / 22))
        path = _find_font()
        try:
            self.font = ImageFont.truetype(path, self.size) if path else ImageFont.load_default(size=self.size)
        except Exception:  # very old Pillow or unreadable font file
            self.font = ImageFont.load_default()
        self.pad = max(3, self.size // 3)
        self.margin = max(2, self.size // 3)
        self.line_h = int(round(self.size * 1.25))
        self.label = " ".join(str(label).split())  # one line, no control chars
        self._digits = len(f"{max(max_time, 0.0):.2f}")

    def time_text(self, t: float) -> str:
        return f"t = {t:{self._digits}.2f} s"

    def draw(self, view: np.ndarray, t: float) -> None:
        from PIL import Image, ImageDraw

        lines = [s for s in (self.label, self.time_text(t)) if s]
        widths = [int(math.ceil(self.font.getlength(s))) for s in lines]
        box_w = min(view.shape[1] - self.margin, max(widths) + 2 * self.pad)
        box_h = min(view.shape[0] - self.margin, len(lines) * self.line_h + 2 * self.pad)
        if box_w <= 0 or box_h <= 0:
            return
        mask = Image.new("L", (box_w, box_h), 0)
        draw = ImageDraw.Draw(mask)
        for i, s in enumerate(lines):
            draw.text((self.pad, self.pad + i * self.line_h), s, fill=255, font=self.font)
        alpha = np.asarray(mask, dtype=np.float32)[..., None] * (1.0 / 255.0)
        y, x = self.margin, self.margin
        region = view[y : y + box_h, x : x + box_w].astype(np.float32)
        region = region * (1.0 - _TEXT_BOX_ALPHA) + 255.0 * _TEXT_BOX_ALPHA
        region = region * (1.0 - alpha) + _TEXT_RGB * alpha
        view[y : y + box_h, x : x + box_w] = np.clip(region + 0.5, 0, 255).astype(np.uint8)


# ---------------------------------------------------------------------- sinks


class _Mp4Sink:
    """H.264 / yuv420p through imageio-ffmpeg (ffmpeg runs in its own process)."""

    def __init__(self, path: str, width: int, height: int, fps):
        import imageio_ffmpeg

        self._path = path
        self._gen = imageio_ffmpeg.write_frames(
            path,
            (width, height),
            pix_fmt_in="rgb24",
            pix_fmt_out="yuv420p",
            fps=Fraction(fps).limit_denominator(100000),
            codec="libx264",
            quality=None,
            macro_block_size=1,  # sizes are made even by the caller
            ffmpeg_log_level="error",
            output_params=["-preset", X264_PRESET, "-crf", str(X264_CRF), "-movflags", "+faststart", "-f", "mp4"],
        )
        self._gen.send(None)  # starts ffmpeg

    def write(self, frame: np.ndarray) -> None:
        self._gen.send(frame)

    def close(self) -> None:
        self._gen.close()  # closes ffmpeg's stdin and waits for it to finish
        if not os.path.isfile(self._path) or os.path.getsize(self._path) == 0:
            raise RuntimeError("ffmpeg produced no output (see its messages above)")

    def abort(self) -> None:
        self._gen.close()


class _GifSink:
    """GIF through imageio's pillow plugin; frame delays keep video time = sim time."""

    def __init__(self, path: str, n_frames: int, fps):
        import imageio.v3 as iio

        # Delays are whole centiseconds; distribute rounding so that frame k
        # starts at round(100 k / fps) cs, i.e. the clock never drifts.
        starts = np.round(np.arange(n_frames + 1) * (100.0 / fps)).astype(int)
        self._durations = [int(d) * 10 for d in np.diff(starts)]  # ms
        self._file = open(path, "wb")
        try:
            self._writer = iio.imopen(self._file, "w", plugin="pillow", extension=".gif")
        except Exception:
            self._file.close()
            raise

    def write(self, frame: np.ndarray) -> None:
        self._writer.write(frame, is_batch=False, duration=self._durations, loop=0)

    def close(self) -> None:
        try:
            self._writer.close()
        finally:
            self._file.close()

    def abort(self) -> None:
        self._writer.images_to_write = []  # drop frames, write nothing
        self.close()


class _WriterThread:
    """Feeds frames to a sink on a worker thread through a bounded queue.

    Only the worker thread touches the sink after construction, so sink calls
    never run concurrently. Errors in the worker are re-raised in the caller.
    """

    _STOP = object()

    def __init__(self, sink, maxsize: int = _QUEUE_FRAMES):
        self._sink = sink
        self._queue: queue.Queue = queue.Queue(maxsize)
        self._error: BaseException | None = None
        self._abort = threading.Event()
        self._done = False
        self._thread = threading.Thread(target=self._run, name="springlab-video-writer", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            while True:
                item = self._queue.get()
                if item is self._STOP or self._abort.is_set():
                    break
                self._sink.write(item)
            if self._abort.is_set():
                self._sink.abort()
            else:
                self._sink.close()
        except BaseException as err:  # noqa: BLE001 - handed to the caller
            self._error = err
            try:
                self._sink.abort()
            except BaseException:  # noqa: BLE001
                pass

    def _check(self) -> None:
        if self._error is not None:
            raise RuntimeError(f"video encoding failed: {self._error}") from self._error

    def _put(self, item) -> None:
        while True:
            self._check()
            if not self._thread.is_alive():
                raise RuntimeError("video encoder thread stopped unexpectedly")
            try:
                self._queue.put(item, timeout=0.2)
                return
            except queue.Full:
                continue

    def put(self, frame: np.ndarray) -> None:
        self._put(frame)

    def finish(self) -> None:
        """Flush all frames, close the sink (finishes the file), raise on error."""
        self._put(self._STOP)
        self._thread.join()
        self._done = True
        self._check()

    def abort(self) -> None:
        """Stop as soon as possible, discarding queued frames."""
        if self._done:
            return
        self._abort.set()
        try:
            while True:
                self._queue.get_nowait()
        except queue.Empty:
            pass
        try:
            self._queue.put_nowait(self._STOP)
        except queue.Full:  # pragma: no cover - queue was just drained
            pass
        self._thread.join(timeout=30)
        self._done = True


# ------------------------------------------------------------------- progress


class _Progress:
    def __init__(self, total: int, enabled: bool, stream=None):
        self.total = total
        self.enabled = enabled and total > 0
        self.stream = stream if stream is not None else sys.stderr
        self.start = _time.perf_counter()
        self._last = 0.0

    def update(self, done: int) -> None:
        if not self.enabled:
            return
        now = _time.perf_counter()
        if done < self.total and now - self._last < 0.1:
            return
        self._last = now
        frac = done / self.total
        bar = "#" * int(30 * frac)
        rate = done / max(now - self.start, 1e-9)
        self.stream.write(f"\rrendering [{bar:<30}] {done}/{self.total} frames {rate:5.1f} fps")
        if done >= self.total:
            self.stream.write("\n")
            self._last = 0.0  # finished: nothing left to terminate
        self.stream.flush()

    def interrupted(self) -> None:
        """End a partly drawn bar with a newline so error messages start clean."""
        if self.enabled and self._last:
            try:
                self.stream.write("\n")
                self.stream.flush()
            except Exception:  # noqa: BLE001
                pass


def _stderr_is_terminal() -> bool:
    try:
        return bool(sys.stderr is not None and sys.stderr.isatty())
    except (AttributeError, ValueError):
        return False


# ----------------------------------------------------------------- main entry


def _as_panel_image(img, index: int, height: int, width: int | None) -> np.ndarray:
    arr = np.asarray(img)
    if arr.ndim != 3 or arr.shape[2] not in (3, 4) or arr.dtype != np.uint8:
        raise BadInputError(
            f"panel({index}, t) must return an HxWx3 (or HxWx4) uint8 image, got shape {arr.shape} dtype {arr.dtype}"
        )
    if arr.shape[0] != height:
        raise BadInputError(f"panel({index}, t) returned height {arr.shape[0]}, expected the video height {height}")
    if width is not None and arr.shape[1] != width:
        raise BadInputError(
            f"panel({index}, t) returned width {arr.shape[1]}, but the first panel image had width {width}"
        )
    return arr[:, :, :3]


def render_video(
    model: mujoco.MjModel,
    time: np.ndarray,
    qpos: np.ndarray,
    output: str | os.PathLike,
    *,
    fps: int = 30,
    width: int = 640,
    height: int = 480,
    camera: str | int | None = None,
    duration: float | None = None,
    label: str = "",
    progress: bool | None = None,
    panel: Callable[[int, float], np.ndarray] | None = None,
) -> dict:
    """Render a recorded trajectory to a video file.

    Parameters
    ----------
    model:
        The MuJoCo model the trajectory belongs to. It is not modified: if
        ``width``/``height`` exceed the model's offscreen buffer
        (``model.vis.global_.offwidth/offheight``), the buffer is enlarged only
        while this call's GL context is created, then the values are restored.
    time, qpos:
        Recording times [s] (increasing, starting at 0) and positions,
        shape ``(n_steps,)`` and ``(n_steps, model.nq)``.
    output:
        ``*.mp4`` (H.264, yuv420p, ``+faststart``: plays in browsers) or
        ``*.gif``. Missing parent directories are created.
    fps:
        Frames per second of the video (<= 50 for GIF).
    width, height:
        Size of the 3D view in pixels. For mp4, odd sizes are padded by one
        pixel to even (a yuv420p requirement); the returned size is the encoded
        one.
    camera:
        Camera name or index from the model, ``-1`` for MuJoCo's free camera,
        or ``None``: the model's first camera if it has one, else the free camera.
        A fixed camera on the world body backs off if the motion would leave
        its view (see :func:`framed_model`).
    duration:
        Seconds of simulation to show (default ``time[-1]``). Frames are
        sampled at ``frame_times(duration, fps)`` by linear interpolation of the
        recording, not one per physics step; so video time equals simulation
        time.
    label:
        Optional text drawn above the simulation time on every frame.
    progress:
        Show a progress bar on stderr; ``None`` = only when stderr is a terminal.
    panel:
        Optional ``panel(frame_index, t) -> HxWx3 uint8`` image (RGBA accepted,
        alpha dropped) drawn to the right of the 3D view, e.g. a phase-plane
        plot; ``H`` must equal ``height`` and ``W`` must stay constant. It is
        called once per frame, in order, on the calling thread. The video is
        then ``(width + W) x height``.

    Returns
    -------
    ``{"frames": n, "fps": fps, "width": W, "height": H, "seconds": wall time,
    "path": str}`` with the encoded video size ``W x H``.

    Raises
    ------
    BadInputError (a ValueError)
        For bad arguments (non-positive fps or size, unknown camera, unsupported
        extension, mismatched ``time``/``qpos``, bad panel images, ...).
    RuntimeError
        If no off-screen OpenGL context can be created or encoding fails.

    The video is written to a temporary file next to ``output`` and renamed on
    success; on any error no partial file is left behind.
    """
    wall_start = _time.perf_counter()

    # ---- validate everything before touching the file system or GL
    if not isinstance(model, mujoco.MjModel):
        raise TypeError(f"model must be a mujoco.MjModel, got {type(model).__name__}")
    out_path, ext, fps, width, height = check_video_arguments(output, fps, width, height)
    cam_id = _resolve_camera(model, camera)
    if panel is not None and not callable(panel):
        raise TypeError(f"panel must be callable(frame_index, t) or None, got {panel!r}")

    t_rec = np.asarray(time, dtype=float)
    q_rec = np.asarray(qpos, dtype=float)
    if t_rec.ndim != 1 or t_rec.size == 0:
        raise BadInputError(f"time must be a non-empty 1-D array, got shape {t_rec.shape}")
    if q_rec.ndim == 1 and model.nq == 1:
        q_rec = q_rec[:, None]
    if q_rec.shape != (t_rec.size, model.nq):
        raise BadInputError(
            f"qpos must have shape (len(time), model.nq) = ({t_rec.size}, {model.nq}), got {q_rec.shape}"
        )
    if not np.all(np.isfinite(q_rec)):
        raise BadInputError("qpos contains NaN or infinite values")
    if duration is None:
        duration = float(t_rec[-1])
    try:
        duration = float(duration)
    except (TypeError, ValueError):
        raise BadInputError(f"duration must be a number of seconds, got {duration!r}") from None
    if not math.isfinite(duration) or duration <= 0:
        raise BadInputError(
            f"duration must be > 0 s, got {duration!r}"
            + (" (time[-1]; pass duration= or a longer recording)" if duration == t_rec[-1] else "")
        )
    at = frame_times(duration, fps)
    n_frames = at.size
    if n_frames == 0:
        raise BadInputError(f"duration {duration} s at {fps} fps gives no frames (need duration >= {0.5 / fps:.3g} s)")
    states = sample_states(t_rec, q_rec, at)  # validates time ordering
    _normalize_quaternions(model, states)
    model = framed_model(model, states, cam_id, width, height)
    if progress is None:
        progress = _stderr_is_terminal()

    try:
        out_path.parent.mkdir(parents=True, exist_ok=True)
        tmp_name = str(outputs.temporary_beside(out_path))
    except OSError as err:
        raise BadInputError(f"cannot write {str(out_path)!r}: {err.strerror or err}") from None

    scene = None
    writer = None
    bar = _Progress(n_frames, bool(progress))
    try:
        scene = _OffscreenScene(model, width, height, cam_id)
        data = mujoco.MjData(model)
        text = _TextOverlay(label, height, float(at[-1]))

        first_panel = None
        panel_w = 0
        if panel is not None:
            first_panel = _as_panel_image(panel(0, float(at[0])), 0, height, None)
            panel_w = first_panel.shape[1]
        video_w, video_h = width + panel_w, height
        if ext == ".mp4":  # yuv420p needs even sizes: pad by one pixel
            video_w += video_w % 2
            video_h += video_h % 2

        if ext == ".mp4":
            sink = _Mp4Sink(tmp_name, video_w, video_h, fps)
        else:
            sink = _GifSink(tmp_name, n_frames, fps)
        writer = _WriterThread(sink)

        for i in range(n_frames):
            t = float(at[i])
            data.qpos[:] = states[i]
            data.time = t
            mujoco.mj_fwdPosition(model, data)

            frame = np.empty((video_h, video_w, 3), dtype=np.uint8)
            view = frame[:height, :width]
            scene.render(data, view)
            text.draw(view, t)
            if panel is not None:
                img = first_panel if i == 0 else _as_panel_image(panel(i, t), i, height, panel_w)
                frame[:height, width : width + panel_w] = img
            if video_w > width + panel_w:  # even-size padding: repeat the edge
                frame[:height, -1] = frame[:height, -2]
            if video_h > height:
                frame[-1] = frame[-2]
            writer.put(frame)
            bar.update(i + 1)

        writer.finish()
        writer = None
        os.replace(tmp_name, out_path)
    except BaseException:
        if writer is not None:
            writer.abort()
        bar.interrupted()
        try:
            os.remove(tmp_name)
        except FileNotFoundError:
            pass
        raise
    finally:
        if scene is not None:
            scene.close()

    return {
        "frames": int(n_frames),
        "fps": fps,
        "width": int(video_w),
        "height": int(video_h),
        "seconds": _time.perf_counter() - wall_start,
        "path": str(out_path),
    }
