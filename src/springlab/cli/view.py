"""`springlab view`: a scene's validated run, or any MJCF, stepped live in MuJoCo's interactive viewer.

* **What runs.** A scene's scenario first runs exactly as `springlab run` runs it (the scene's
  validated integrator and timestep unless --integrator, --dt or auto say otherwise), so its verdict
  is printed before the window opens. The window then steps the same compiled model from the same
  initial state with the same controls, one `mj_step` per physics step, as `mujoco.rollout` did
  (tests/cli/test_view.py checks the live states against the run's, step by step), and starts again
  where the run ended. A model file runs at the setting its `<option>` declares (or --integrator,
  --dt), from its first keyframe (else `qpos0`), without end.
* **Real time.** Simulated time follows the wall clock (divided by --slow-motion); a model that
  steps slower than that runs as fast as it can, and the closing line says how fast it ran.
* **The same pictures as the videos.** `springlab.render.stage` arranges a copy of the model for
  drawing (rails over the travel, the camera framed on the motion) with the videos' springs,
  dampers, belts and road (`Drawings`), added to the viewer's `user_scn` every frame. The physics
  steps the model that was validated; its state is copied into the drawing copy each frame, small
  motions magnified around the run's mean as the videos magnify them (--exaggerate). The
  scene's fixed camera becomes the viewer's free camera at the same pose (tracking the body when
  the videos' camera follows it), so the mouse can still turn and zoom.
* **No display.** Without DISPLAY or WAYLAND_DISPLAY (Linux), or when GLFW cannot open a window
  with an OpenGL context, one line and exit 2 (`NoDisplayError`), checked before the window is
  launched (mujoco.viewer would otherwise wait forever for a window that never opens). The viewer
  draws through GLFW whatever MUJOCO_GL says (MUJOCO_GL picks the videos' off-screen context): this
  command neither reads nor sets it.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import pathlib
import sys
import threading
import time
import warnings
from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np

from springlab import scenes
from springlab.errors import BadInputError, SpringlabError
from springlab.render import scale as render_scale
from springlab.render.drawings import Drawings, RoadBump
from springlab.render.stage import road_bump, stage
from springlab.runs.run import Result
from springlab.sim.simulate import INTEGRATORS, check_timing, configured, initial_state, quiet_mujoco

__all__ = ["NoDisplayError", "LiveRun", "Viewed", "live_run", "live_model", "check_display", "open_display", "show"]

#: frames the viewer is sent per second [1/s]
FRAME_RATE = 60.0
#: share of a frame the physics may take before the frame is drawn anyway [-] (a slow model stays responsive)
STEP_SHARE = 0.7
#: key that pauses and resumes the run (GLFW key code of the space bar)
PAUSE_KEY = 32
#: most recorded states the camera is framed on (a run's steps are thinned to about this many) [-]
FRAMING_STATES = 2000
#: longest wait for the window's thread to finish closing [s]
CLOSE_TIMEOUT = 10.0
_FULL = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)


class NoDisplayError(SpringlabError):
    """No display to open the viewer on, or GLFW cannot open a window there (exit 2)."""


def check_display() -> None:
    """Raise NoDisplayError where no display server is named (Linux without DISPLAY or WAYLAND_DISPLAY)."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise NoDisplayError(
            "no display to open the viewer on (DISPLAY and WAYLAND_DISPLAY are unset); run it on a desktop,"
            " over 'ssh -X' or under 'xvfb-run', or film the scene off-screen with 'springlab render'"
        )


def open_display() -> tuple[int, int]:
    """Initialise GLFW and open (then close) a hidden window with an OpenGL context: the viewer's window size [px].

    The viewer's window is two thirds of the primary monitor in each direction (MuJoCo's simulate).

    Raises
    ------
    NoDisplayError
        no display named, GLFW missing, or GLFW cannot initialise or open a window on the display.
    """
    check_display()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import glfw
            import mujoco.viewer  # noqa: F401  (its import hands GLFW's library to MuJoCo's simulate)
    except Exception as error:  # ImportError: no glfw package; RuntimeError: no GLFW library
        raise NoDisplayError(f"cannot load GLFW for the viewer: {_one_line(error)}") from None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # GLFW's errors arrive as warnings: they become the message
        try:
            window = None
            if glfw.init():
                glfw.window_hint(glfw.VISIBLE, glfw.FALSE)
                window = glfw.create_window(64, 64, "springlab", None, None)
                glfw.default_window_hints()
        except Exception as error:  # glfw.ERROR_REPORTING = 'raise'
            caught.append(warnings.WarningMessage(error, type(error), "", 0))  # type: ignore[arg-type]
            window = None
    if not window:
        display = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
        why = "; ".join(_glfw_text(w.message) for w in caught) or "no reason given"
        raise NoDisplayError(f"GLFW cannot open an OpenGL window on display {display!r}: {why}")
    glfw.destroy_window(window)
    mode = glfw.get_video_mode(glfw.get_primary_monitor())
    return max(1, 2 * mode.size.width // 3), max(1, 2 * mode.size.height // 3)


def _glfw_text(message: Any) -> str:
    """GLFW's error text without pyglfw's code and bytes repr: "(65544) b'X11: ...'" -> "X11: ..."."""
    text = str(message)
    start, end = text.find("b'"), text.rfind("'")
    return text[start + 2 : end] if 0 <= start < end else text


def _one_line(error: BaseException) -> str:
    return " ".join(str(error).split()) or type(error).__name__


# -- the physics the window shows -----------------------------------------------------------------


@dataclasses.dataclass(eq=False)
class LiveRun:
    """A model at its setting, stepped from a start state with held controls; it starts again after `steps` steps.

    Attributes
    ----------
    model
        the physics model, its integrator and timestep set (`sim.simulate.configured`).
    start
        full physics state at t = 0 (`mjSTATE_FULLPHYSICS`).
    control
        (steps, nu) controls, row k held over step k (as mujoco.rollout holds them), or None.
    steps
        steps before it starts again (None: it runs on).
    """

    model: mujoco.MjModel
    start: np.ndarray
    control: np.ndarray | None = None
    steps: int | None = None
    data: mujoco.MjData = dataclasses.field(init=False)
    #: steps since the last start
    step: int = dataclasses.field(init=False, default=0)
    #: steps taken in all, replays included
    total_steps: int = dataclasses.field(init=False, default=0)
    #: how many times it started again
    replays: int = dataclasses.field(init=False, default=0)

    def __post_init__(self) -> None:
        self.data = mujoco.MjData(self.model)
        self.reset()

    @property
    def elapsed(self) -> float:
        """Simulated time [s] stepped in all, replays included."""
        return self.total_steps * float(self.model.opt.timestep)

    def reset(self) -> None:
        """Back to the start state (t = 0, the first control row)."""
        mujoco.mj_resetData(self.model, self.data)
        mujoco.mj_setState(self.model, self.data, self.start, _FULL)
        self.step = 0

    def advance(self, count: int, deadline: float = math.inf) -> int:
        """Take up to `count` steps, or fewer when time.perf_counter() passes `deadline` [s]; the steps taken."""
        taken = 0
        with quiet_mujoco():  # a warning goes nowhere: the run it replays was checked
            while taken < count:
                if self.steps is not None and self.step >= self.steps:
                    self.reset()
                    self.replays += 1
                if self.control is not None:
                    self.data.ctrl[:] = self.control[self.step]
                mujoco.mj_step(self.model, self.data)
                self.step += 1
                taken += 1
                if taken % 64 == 0 and time.perf_counter() > deadline:
                    break
        self.total_steps += taken
        return taken


def live_run(result: Result, duration: float | None = None) -> LiveRun:
    """The live replay of a run: its model, setting, initial state and controls, `result.steps` steps long.

    Parameters
    ----------
    result
        the run (`springlab.run`).
    duration
        the simulated time [s] the run was asked for (None: its scenario's), which its controls were built for.
    """
    asked = check_timing(result.dt, result.case.scenario.duration if duration is None else duration)
    setup = result.case.setup(asked, result.dt)
    model = configured(result.model, result.integrator, result.dt)
    start = initial_state(model, setup.qpos, setup.qvel, setup.act)
    control = None
    if model.nu:
        rows = np.zeros(model.nu) if setup.control is None else np.asarray(setup.control, float)
        control = np.array(np.broadcast_to(rows, (asked, model.nu)) if rows.ndim == 1 else rows)
    return LiveRun(model, start, control, result.steps)


def live_model(model: mujoco.MjModel, integrator: str | None = None, dt: float | None = None) -> LiveRun:
    """A model file's live run: its own setting (or `integrator`, `dt` [s]), from its first keyframe, without end."""
    name = (
        next(n for n, v in INTEGRATORS.items() if v == int(model.opt.integrator)) if integrator is None else integrator
    )
    work = configured(model, name, float(model.opt.timestep) if dt is None else dt)
    data = mujoco.MjData(work)
    if work.nkey:
        mujoco.mj_resetDataKeyframe(work, data, 0)
    return LiveRun(work, initial_state(work, data.qpos.copy(), data.qvel.copy(), data.act.copy()))


# -- the window --------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Viewed:
    """What one viewer session showed.

    Attributes
    ----------
    wall_s
        time the window was open [s].
    simulated_s
        simulated time stepped [s], replays included.
    frames
        frames sent to the window.
    replays
        times the run started again from its beginning.
    """

    wall_s: float
    simulated_s: float
    frames: int
    replays: int

    @property
    def speed(self) -> float:
        """Simulated seconds per wall second [-] (1: real time)."""
        return self.simulated_s / self.wall_s if self.wall_s > 0 else 0.0


def free_camera(model: mujoco.MjModel, camera_id: int) -> tuple[np.ndarray, float, float, float]:
    """(lookat [m], distance [m], azimuth [deg], elevation [deg]) of a free camera at a fixed camera's pose.

    The point looked at is where the camera's axis passes the moving geoms' centre (the model's centre
    when nothing moves); the free camera's field of view is the model's `vis.global_.fovy`, which the
    caller sets to the camera's.
    """
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
    position = data.cam_xpos[camera_id].copy()
    forward = -data.cam_xmat[camera_id].reshape(3, 3)[:, 2]  # a camera looks along its -z axis
    moving = np.flatnonzero(model.body_weldid[model.geom_bodyid] != 0)
    centre = data.geom_xpos[moving].mean(axis=0) if moving.size else np.asarray(model.stat.center)
    distance = float((centre - position) @ forward)
    if not distance > 0:
        distance = float(model.stat.extent)
    azimuth = math.degrees(math.atan2(forward[1], forward[0]))
    elevation = math.degrees(math.asin(float(np.clip(forward[2], -1.0, 1.0))))
    return position + distance * forward, distance, azimuth, elevation


def _place_camera(camera: mujoco.MjvCamera, model: mujoco.MjModel, camera_id: int, follows: bool) -> None:
    """Point the viewer's camera as the videos' camera points (see the module docstring)."""
    if camera_id < 0:
        return  # MuJoCo's default free camera
    fixed_on_world = (
        model.cam_bodyid[camera_id] == 0 and model.cam_mode[camera_id] == mujoco.mjtCamLight.mjCAMLIGHT_FIXED
    )
    if not fixed_on_world:  # a camera that tracks or rides a body: the viewer uses it as it is
        camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        camera.fixedcamid = camera_id
        return
    lookat, distance, azimuth, elevation = free_camera(model, camera_id)
    camera.lookat[:] = lookat
    camera.distance, camera.azimuth, camera.elevation = distance, azimuth, elevation
    moving = np.flatnonzero(model.body_weldid[model.geom_bodyid] != 0)
    if follows and moving.size:  # the videos' camera pans after the body: the viewer's tracks it
        camera.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        camera.trackbodyid = int(model.body_weldid[model.geom_bodyid[moving[0]]])
    else:
        camera.type = mujoco.mjtCamera.mjCAMERA_FREE


def show(
    live: LiveRun,
    states: np.ndarray,
    *,
    camera_id: int = -1,
    size: tuple[int, int] = (640, 480),
    label: str = "",
    setting: str = "",
    road: RoadBump | None = None,
    slow_motion: float = 1.0,
    exaggerate: float = 1.0,
    close_after: float | None = None,
    opened: Callable[[], None] | None = None,
) -> Viewed:
    """Open MuJoCo's passive viewer on `live` and step it in real time until the window closes.

    Parameters
    ----------
    live
        the physics to step (`live_run`, `live_model`).
    states
        (n, nq) positions of the motion to frame the camera and fix the drawn springs' turns on
        (a run's recorded `qpos`; the start alone for a model file).
    camera_id
        the camera the videos use (-1: MuJoCo's free camera).
    size
        (width, height) of the window [px] (`open_display`).
    label, setting
        what the top-left corner says: the scene and scenario, the integrator and timestep.
    road
        the quarter car's road (`render.stage.road_bump`), or None.
    slow_motion
        factor >= 1 [-] simulated time runs slower than the wall clock.
    exaggerate
        factor >= 1 [-] positions are drawn magnified by around their mean over `states`, as in the
        videos (`render.scale.exaggerated`; drawing only, the physics is stepped as it is).
    close_after
        close the window after this many seconds [s] (None: when the user closes it).
    opened
        called once the window is open (e.g. to print a line).

    Returns
    -------
    Viewed
        how long the window was open, the simulated time stepped, frames and replays.
    """
    import mujoco.viewer

    width, height = size
    centre = np.asarray(states, float).mean(axis=0)
    if road is not None and exaggerate != 1.0:
        road = dataclasses.replace(road, exaggeration=exaggerate)
    drawn = render_scale.exaggerated(live.model, states, exaggerate)
    view_model, drawings, camera_path = stage(live.model, drawn, camera_id, width, height, road)
    if view_model is live.model:
        view_model = _copy(live.model)
    if camera_id >= 0:
        view_model.vis.global_.fovy = float(view_model.cam_fovy[camera_id])  # the free camera gets the lens
    view_data = mujoco.MjData(view_model)
    paused = threading.Event()

    def keys(key: int) -> None:
        if key == PAUSE_KEY:
            paused.clear() if paused.is_set() else paused.set()

    picture = _Picture(view_model, view_data, drawings, exaggerate, centre)
    picture.show(live)
    notes = ", ".join(render_scale.labels(slow_motion, exaggerate)).replace("×", "x")  # MuJoCo's font is ASCII
    frames = 0
    before = set(threading.enumerate())
    try:
        handle = mujoco.viewer.launch_passive(
            view_model, view_data, key_callback=keys, show_left_ui=False, show_right_ui=False
        )
    except RuntimeError as error:  # macOS outside mjpython: "`launch_passive` requires ... `mjpython`"
        raise NoDisplayError(f"cannot open MuJoCo's viewer: {_one_line(error)}") from None
    with handle as viewer:
        with viewer.lock():
            _place_camera(viewer.cam, view_model, camera_id, camera_path is not None)
            viewer.opt.flags[mujoco.mjtVisFlag.mjVIS_TENDON] = 1  # the spring, as in the videos
        if opened is not None:
            opened()
        opened_at = last = time.perf_counter()
        target = 0.0  # simulated time the wall clock asks for [s]
        frame_s = 1.0 / FRAME_RATE
        while viewer.is_running():
            now = time.perf_counter()
            if close_after is not None and now - opened_at >= close_after:
                break
            if not paused.is_set():
                target += (now - last) / slow_motion
                wanted = int(target / float(live.model.opt.timestep)) - live.total_steps
                if wanted > 0:
                    live.advance(wanted, deadline=now + STEP_SHARE * frame_s)
                target = min(target, live.elapsed + frame_s / slow_motion)  # behind: no race to catch up
            last = now
            picture.show(live, viewer.user_scn)
            clock = f"{live.data.time:.3f} s" + (f"  ({notes})" if notes else "")
            viewer.set_texts(
                (
                    mujoco.mjtFontScale.mjFONTSCALE_150,
                    mujoco.mjtGridPos.mjGRID_TOPLEFT,
                    f"{label}\n{setting}\ntime",
                    f"\n\n{clock}" + ("  paused (space)" if paused.is_set() else ""),
                )
            )
            viewer.sync(state_only=True)
            frames += 1
            time.sleep(max(0.0, now + frame_s - time.perf_counter()))
        wall = time.perf_counter() - opened_at
    # the window's thread tears its GL context and window down after close(): wait for it, or the
    # interpreter's exit (atexit glfw.terminate) pulls GLFW away under it and the process crashes
    for thread in set(threading.enumerate()) - before:
        thread.join(timeout=CLOSE_TIMEOUT)
    return Viewed(wall_s=wall, simulated_s=live.elapsed, frames=frames, replays=live.replays)


def _copy(model: mujoco.MjModel) -> mujoco.MjModel:
    import copy

    return copy.copy(model)


@dataclasses.dataclass(eq=False)
class _Picture:
    """The drawing copy of the physics: its model and data, the drawings, the exaggeration and its centre."""

    model: mujoco.MjModel
    data: mujoco.MjData
    drawings: Drawings
    exaggerate: float
    centre: np.ndarray

    def show(self, live: LiveRun, scene: mujoco.MjvScene | None = None) -> None:
        """Copy the physics state into the drawing copy (magnified) and redraw the springs and dampers into `scene`."""
        state = np.empty(mujoco.mj_stateSize(live.model, _FULL))
        mujoco.mj_getState(live.model, live.data, state, _FULL)
        mujoco.mj_setState(self.model, self.data, state, _FULL)
        if self.exaggerate != 1.0:
            self.data.qpos[:] = render_scale.exaggerated(
                self.model, self.data.qpos[None], self.exaggerate, self.centre
            )[0]
        mujoco.mj_kinematics(self.model, self.data)
        if scene is not None:
            scene.ngeom = 0
            self.drawings.add(scene, self.data)


# -- the command -------------------------------------------------------------------------------


def _resolve(target: str) -> tuple[str, mujoco.MjModel | None]:
    """('scene', None) for a scene name, ('model', compiled model) for an MJCF file."""
    path = pathlib.Path(target)
    if not path.exists() and target in scenes.SCENES:
        return "scene", None
    if not path.is_file():
        raise BadInputError(f"no such model file or scene {target!r}; scenes: {', '.join(sorted(scenes.SCENES))}")
    try:
        with quiet_mujoco():
            return "model", mujoco.MjModel.from_xml_path(str(path))
    except Exception as error:  # MuJoCo raises ValueError with its compiler's message
        raise BadInputError(f"cannot load {target!r}: {_one_line(error)}") from None


def _camera_id(model: mujoco.MjModel, name: str | None) -> int:
    """The videos' camera: the scene's named one, else the model's first, else -1 (free)."""
    if name is not None:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, name)
    return 0 if model.ncam else -1


def command(args: argparse.Namespace, run: Callable[[argparse.Namespace], Result]) -> Result | None:
    """`springlab view`: check the names, the display, run the scenario (`run`), open the window; the run or None.

    Parameters
    ----------
    args
        the parsed command line (scene, scenario, --set, --integrator, --dt, --duration, --tol,
        --slow-motion, --close-after).
    run
        the command line's `springlab run` (the same run, the same setting).
    """
    kind, model = _resolve(args.scene)
    render_scale.check_factor("--slow-motion", args.slow_motion)
    if args.exaggerate is not None:
        render_scale.check_factor("--exaggerate", args.exaggerate)
    if args.close_after is not None and not (math.isfinite(args.close_after) and args.close_after > 0):
        raise BadInputError(f"--close-after must be a number of seconds > 0, got {args.close_after!r}")
    if kind == "scene":
        scene = scenes.get(args.scene)
        scene.scenario(args.scenario)  # an unknown scenario fails here, before the display is looked at
    else:
        extra = [
            name
            for name, given in (
                ("a scenario", args.scenario),
                ("--set", args.set),
                ("--duration", args.duration),
                ("--tol", args.tol),
            )
            if given
        ]
        if extra or args.integrator == "auto":
            raise BadInputError(
                f"{', '.join(extra) or 'integrator auto'} goes with a scene name; a model file runs at its own"
                " setting (valid: --integrator NAME, --dt SECONDS)"
            )
        if args.integrator is not None and args.integrator not in INTEGRATORS:
            raise BadInputError(f"unknown integrator {args.integrator!r}; valid: {', '.join(INTEGRATORS)}")
        if args.dt is not None and not (math.isfinite(args.dt) and args.dt > 0):
            raise BadInputError(f"--dt must be a number of seconds > 0, got {args.dt!r}")
    size = open_display()
    if kind == "scene":
        result = run(args)
        live = live_run(result, args.duration)
        states = np.asarray(result.trajectory.qpos)
        states = states[
            :: max(1, len(states) // FRAMING_STATES)
        ]  # the framing needs the motion's extent, not every step
        camera_id = _camera_id(result.model, scenes.get(result.scene).camera)
        label = f"{result.scene} / {result.scenario}"
        verdict = "no exact reference" if result.verdict is None else result.verdict.value
        road = road_bump(result)
    else:
        assert model is not None  # a model file was loaded by _resolve
        result, road, camera_id = None, None, -1
        live = live_model(model, args.integrator, args.dt)
        states = live.data.qpos[None].copy()
        label = pathlib.Path(args.scene).name
        verdict = "its own setting, not validated"
    integrator = next(n for n, v in INTEGRATORS.items() if v == int(live.model.opt.integrator))
    setting = f"{integrator}, dt = {float(live.model.opt.timestep):g} s"
    exaggerate = args.exaggerate
    if exaggerate is None:  # the videos' default: a motion below 1 % of the body's size magnified to about 3 %
        exaggerate = render_scale.default_exaggeration(live.model, states) if kind == "scene" else 1.0

    def opened() -> None:
        speed = "real time" if args.slow_motion == 1 else f"1/{args.slow_motion:g} speed"
        drawn = "".join(f", {note}" for note in render_scale.labels(1.0, exaggerate)).replace("×", "x")
        print(
            f"viewing {label} ({setting}; {verdict}) live at {speed}{drawn}: space pauses, close the window to stop",
            flush=True,
        )

    viewed = show(
        live,
        states,
        camera_id=camera_id,
        size=size,
        label=label,
        setting=setting,
        road=road,
        slow_motion=args.slow_motion,
        exaggerate=exaggerate,
        close_after=args.close_after,
        opened=opened,
    )
    replays = f", {viewed.replays} replay{'s' if viewed.replays != 1 else ''}" if viewed.replays else ""
    print(
        f"closed after {viewed.wall_s:.2f} s: {viewed.simulated_s:.3f} s simulated"
        f" ({viewed.speed:.2f} x real time{replays}, {viewed.frames} frames)",
        flush=True,
    )
    return result
