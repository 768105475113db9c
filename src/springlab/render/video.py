"""Off-screen video rendering of recorded MuJoCo trajectories.

The entry point is :func:`render_video`: it replays a recorded trajectory
(``time``, ``qpos``) through MuJoCo's classic OpenGL renderer without a
display and writes an H.264 ``.mp4`` (plays in browsers) or a ``.gif``.

The parts live in their own modules:

* :mod:`springlab.render.gl`: the GL backend (``MUJOCO_GL=egl`` unless the
  user chose one, set when a video is rendered, never at import), one GL
  context and ``MjvScene`` per video, the white backdrop.
* :mod:`springlab.render.framing`: the fixed camera backs off so everything
  moving stays in the picture (:func:`framed_model`).
* :mod:`springlab.render.drawings`: springs drawn between their sites.
* :mod:`springlab.render.text`: the time and label drawn on every frame.
* :mod:`springlab.render.sink`: the mp4/gif writers fed from a thread.

Design notes
------------
* **Frames follow the clock, not the integrator.** Frames are sampled at
  :func:`frame_times` (``k / fps``) by linear interpolation of the recorded
  states (:func:`sample_states`), so video time equals simulation time no
  matter what the physics time step was.
* **All or nothing.** Output goes to a hidden temporary file in the target
  directory, renamed over ``output`` only on success; on any failure
  (including a raising ``panel`` callback or Ctrl-C) the temporary file is
  removed.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time as _time
from collections.abc import Callable
from pathlib import Path
from typing import cast

import mujoco
import numpy as np

from springlab import files
from springlab.errors import BadInputError  # a ValueError; the CLI maps it to exit 2
from springlab.progress import bar as progress_bar
from springlab.render import scale as render_scale

from .drawings import SPRING_PREFIX, Drawings, RoadBump, drawn_notes, drawn_springs
from .framing import framed_model
from .gl import OffscreenScene, ensure_gl_backend
from .sink import X264_CRF, X264_PRESET, GifSink, Mp4Sink, WriterThread
from .stage import stage
from .text import TextOverlay

__all__ = [
    "ensure_gl_backend",
    "frame_times",
    "sample_states",
    "render_video",
    "check_video_arguments",
    "framed_model",
    "drawn_springs",
    "SPRING_PREFIX",
    "RoadBump",
    "X264_PRESET",
    "X264_CRF",
]

#: Output formats render_video can write, by file extension.
SUPPORTED_EXTENSIONS = (".mp4", ".gif")

#: Largest width/height accepted (GL renderbuffers are limited; video players too).
MAX_SIZE = 8192

#: GIF frame delays are stored in 1/100 s; players clamp delays below 2/100 s.
GIF_MAX_FPS = 50


# --------------------------------------------------------------------------- time


def frame_times(duration: float, fps: float) -> np.ndarray:
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


def _check_fps(fps: object) -> float:
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)):
        raise BadInputError(f"fps must be a positive number of frames per second, got {fps!r}")
    if not math.isfinite(fps) or fps <= 0:
        raise BadInputError(f"fps must be > 0, got {fps!r}")
    # a numpy scalar passes through unchanged: it acts as a float in every use (arithmetic, formatting)
    return cast(float, fps)


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


def check_video_arguments(
    output: str | os.PathLike[str], fps: object, width: object, height: object
) -> tuple[Path, str, float, int, int]:
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
    fps: float = 30,
    width: int = 640,
    height: int = 480,
    camera: str | int | None = None,
    duration: float | None = None,
    label: str = "",
    progress: bool | None = None,
    panel: Callable[[int, float], np.ndarray] | None = None,
    slow_motion: float = 1.0,
    exaggerate: float | None = 1.0,
    road_bump: RoadBump | None = None,
    antialias: bool = False,
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
        Show a progress bar (frames, rate, ETA) on stderr; ``None`` = only when
        stderr is a terminal (:mod:`springlab.progress`).
    panel:
        Optional ``panel(frame_index, t) -> HxWx3 uint8`` image (RGBA accepted,
        alpha dropped) drawn to the right of the 3D view, e.g. a phase-plane
        plot; ``H`` must equal ``height`` and ``W`` must stay constant. It is
        called once per frame, in order, on the calling thread. The video is
        then ``(width + W) x height``.
    slow_motion:
        Factor S >= 1 [-]: frame k shows simulation time k / (fps S), so the
        video lasts S x ``duration``; "1/S speed" is written on every frame.
    exaggerate:
        Factor E >= 1 [-]: every coordinate is drawn at its mean over the frames
        plus E times its deviation from it (:func:`render_scale.exaggerated`);
        "motion ×E" is written on every frame. Drawing only: the trajectory
        passed in is not changed. ``None``: :func:`render_scale.default_exaggeration`
        of the filmed motion.
    road_bump:
        Optional :class:`drawings.RoadBump`: the road profile drawn under
        a quarter car (its height follows the exaggeration).
    antialias:
        Smooth the edges with the model's multisampling
        (``vis.quality.offsamples``, MuJoCo's default 4); off by default, as
        it makes a frame about 3 times slower on a CPU rasteriser.

    Returns
    -------
    ``{"frames": n, "fps": fps, "width": W, "height": H, "seconds": wall time,
    "path": str, "slow_motion": S, "exaggeration": E}`` with the encoded video
    size ``W x H``.

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
    job = _video_job(
        model, time, qpos, output, fps, width, height, camera, duration, panel, slow_motion, exaggerate, road_bump
    )
    video_w, video_h = _encode(job, label, panel, antialias, progress)
    return job.report(video_w, video_h, _time.perf_counter() - wall_start)


@dataclasses.dataclass(frozen=True, eq=False)
class _VideoJob:
    """A checked video request and what it shows (`_video_job`).

    Attributes
    ----------
    model
        the staged model (`stage`: a copy where it must frame or draw more than the model's own).
    out_path, ext
        the output file and its extension.
    fps, width, height
        frames per second [1/s] and the 3D view's size [px].
    cam_id
        the camera (-1: MuJoCo's free camera).
    at
        simulation time of each frame [s].
    states
        (frames, nq) positions drawn at each frame (exaggerated).
    slow_motion, exaggeration
        the factors [-] written on every frame.
    drawings, camera_path
        what `stage` adds (springs, road) and the camera's path along a long travel (None: fixed).
    """

    model: mujoco.MjModel
    out_path: Path
    ext: str
    fps: float
    width: int
    height: int
    cam_id: int
    at: np.ndarray
    states: np.ndarray
    slow_motion: float = 1.0
    exaggeration: float = 1.0
    drawings: Drawings | None = None
    camera_path: np.ndarray | None = None

    def report(self, video_w: int, video_h: int, seconds: float) -> dict:
        """render_video's answer: the encoded size [px] and the wall time [s]."""
        return {
            "frames": int(self.at.size),
            "fps": self.fps,
            "width": int(video_w),
            "height": int(video_h),
            "seconds": seconds,
            "path": str(self.out_path),
            "slow_motion": self.slow_motion,
            "exaggeration": self.exaggeration,
        }


def _video_job(
    model: mujoco.MjModel,
    time: np.ndarray,
    qpos: np.ndarray,
    output: str | os.PathLike,
    fps: float,
    width: int,
    height: int,
    camera: str | int | None,
    duration: float | None,
    panel: Callable[[int, float], np.ndarray] | None,
    slow_motion: float,
    exaggerate: float | None,
    road_bump: RoadBump | None,
) -> _VideoJob:
    """Every argument checked before touching the file system or GL (BadInputError, TypeError), then the
    frames: their times, the states there (interpolated, quaternions renormalised, exaggerated) and the
    staged model (drawings, a camera that follows)."""
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
    slow_motion = render_scale.check_factor("slow_motion", slow_motion)
    if exaggerate is not None:
        exaggerate = render_scale.check_factor("exaggerate", exaggerate)
    at = frame_times(duration * slow_motion, fps) / slow_motion  # simulation time of each frame [s]
    if at.size == 0:
        raise BadInputError(
            f"duration {duration} s at {fps} fps gives no frames (need duration >= {0.5 / (fps * slow_motion):.3g} s)"
        )
    states = sample_states(t_rec, q_rec, at)  # validates time ordering
    _normalize_quaternions(model, states)
    if exaggerate is None:
        exaggerate = render_scale.default_exaggeration(model, states)
    states = render_scale.exaggerated(model, states, exaggerate)
    if road_bump is not None and exaggerate != 1.0:
        road_bump = dataclasses.replace(road_bump, exaggeration=exaggerate)
    model, drawings, camera_path = stage(model, states, cam_id, width, height, road_bump)
    return _VideoJob(
        model, out_path, ext, fps, width, height, cam_id, at, states, slow_motion, exaggerate, drawings, camera_path
    )


def _encode(
    job: _VideoJob,
    label: str,
    panel: Callable[[int, float], np.ndarray] | None,
    antialias: bool,
    progress: bool | None,
) -> tuple[int, int]:
    """Render every frame of a filmed job and encode them to job.out_path (all or nothing: a temporary file
    beside it, renamed on success, removed on any failure); the encoded size (width, height) [px]."""
    try:
        job.out_path.parent.mkdir(parents=True, exist_ok=True)
        tmp_name = str(files.temporary_beside(job.out_path))
    except OSError as err:
        raise BadInputError(f"cannot write {str(job.out_path)!r}: {err.strerror or err}") from None

    model, at, width, height = job.model, job.at, job.width, job.height
    scene = None
    writer = None
    bar = progress_bar(at.size, description="rendering", unit="frame", enabled=progress)
    try:
        scene = OffscreenScene(model, width, height, job.cam_id, drawings=job.drawings, multisample=antialias)
        data = mujoco.MjData(model)
        text = TextOverlay(
            label,
            height,
            float(at[-1]),
            notes=[*render_scale.labels(job.slow_motion, job.exaggeration), *drawn_notes(model)],
            time_step=1.0 / (job.fps * job.slow_motion),
        )

        first_panel = None
        panel_w = 0
        if panel is not None:
            first_panel = _as_panel_image(panel(0, float(at[0])), 0, height, None)
            panel_w = first_panel.shape[1]
        video_w, video_h = width + panel_w, height
        if job.ext == ".mp4":  # yuv420p needs even sizes: pad by one pixel
            video_w += video_w % 2
            video_h += video_h % 2

        sink: Mp4Sink | GifSink
        if job.ext == ".mp4":
            sink = Mp4Sink(tmp_name, video_w, video_h, job.fps)
        else:
            sink = GifSink(tmp_name, at.size, job.fps)
        writer = WriterThread(sink)

        for i in range(at.size):
            t = float(at[i])
            data.qpos[:] = job.states[i]
            data.time = t
            if job.camera_path is not None:  # a camera that follows a long travel
                model.cam_pos[job.cam_id] = job.camera_path[i]
            mujoco.mj_fwdPosition(model, data)

            frame = np.empty((video_h, video_w, 3), dtype=np.uint8)
            view = frame[:height, :width]
            scene.render(data, view)
            text.draw(view, t)
            if panel is not None:
                assert first_panel is not None  # drawn before the loop whenever there is a panel
                img = first_panel if i == 0 else _as_panel_image(panel(i, t), i, height, panel_w)
                frame[:height, width : width + panel_w] = img
            if video_w > width + panel_w:  # even-size padding: repeat the edge
                frame[:height, -1] = frame[:height, -2]
            if video_h > height:
                frame[-1] = frame[-2]
            writer.put(frame)
            bar.update(1)

        writer.finish()
        writer = None
        os.replace(tmp_name, job.out_path)
    except BaseException:
        if writer is not None:
            writer.abort()
        try:
            os.remove(tmp_name)
        except FileNotFoundError:
            pass
        raise
    finally:
        bar.close()  # ends the bar's line, so a following message starts clean
        if scene is not None:
            scene.close()
    return video_w, video_h
