"""`springlab view`: the live viewer steps the validated run, draws the videos' springs, and fails cleanly without a display.

The window test runs the command under a virtual X display, Debian's `xvfb` (its `Xvfb` server). .ci/run
installs it on CI (as root with apt-get); elsewhere this test finds it or skips, saying how to get it.
Set SPRINGLAB_REQUIRE_XVFB=1 (as .ci/run does) to turn that skip into a failure. The screenshot is the
X screen itself: Xvfb keeps its framebuffer in an XWD file (-fbdir), read here with numpy.
"""

from __future__ import annotations

import os
import re
import select
import shutil
import struct
import subprocess
import sys
import threading
import time

import mujoco
import numpy as np
import pytest

from springlab.cli import view
from springlab.cli.main import main
from springlab.render.stage import stage
from springlab.sim.simulate import INTEGRATORS

#: the slider's block and drawn spring colours (models/slider.xml: material "block", text "spring:spring")
BLOCK_RGB = np.array([0.85, 0.33, 0.18])
SPRING_RGB = np.array([0.15, 0.35, 0.85])


@pytest.mark.parametrize(
    "scene, scenario",
    [("slider", "step"), ("printer_head", "move"), ("nonlinear", "softening_escape")],
    ids=["constant force", "control sequence", "stopped early"],
)
def test_the_live_run_steps_exactly_the_validated_run_then_starts_again(scene, scenario, scenario_run):
    """One mj_step per physics step with row k of the controls held over step k is what mujoco.rollout
    does: the live states equal the run's recorded ones bit for bit (same model, setting, start and inputs),
    and after the run's last step (where a stop condition ended it, for the escape) it starts again."""
    result = scenario_run(scene, scenario)
    live = view.live_run(result)
    recorded = np.asarray(result.trajectory.qpos)
    assert live.data.time == 0.0 and np.array_equal(live.data.qpos, recorded[0])
    for k in range(1, result.steps + 1):
        live.advance(1)
        assert np.array_equal(live.data.qpos, recorded[k]), f"step {k}"
    assert live.model.opt.timestep == result.dt
    assert live.model.opt.integrator == INTEGRATORS[result.integrator]
    live.advance(1)  # the first step of the replay
    assert live.replays == 1 and np.array_equal(live.data.qpos, recorded[1])
    assert live.elapsed == pytest.approx((result.steps + 1) * result.dt, rel=1e-12)


def test_a_model_file_runs_at_its_own_setting_from_its_first_keyframe(tmp_path):
    """A model file's `<option>` is its setting and its first keyframe its start; it runs on without end."""
    path = tmp_path / "pendulum.xml"
    path.write_text(
        """<mujoco><option timestep="0.004" integrator="implicitfast"/>
        <worldbody><body><joint name="hinge" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.02" mass="1"/></body></worldbody>
        <keyframe><key qpos="0.3"/></keyframe></mujoco>"""
    )
    model = mujoco.MjModel.from_xml_path(str(path))
    live = view.live_model(model)
    assert live.model.opt.timestep == 0.004
    assert live.model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert live.data.qpos[0] == 0.3 and live.steps is None
    reference = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, reference, 0)
    for _ in range(50):
        mujoco.mj_step(model, reference)
    live.advance(50)
    assert np.array_equal(live.data.qpos, reference.qpos) and live.replays == 0


@pytest.mark.parametrize("scene, scenario", [("slider", "free"), ("car", "pitch_heave"), ("printer_head", "move")])
def test_the_viewer_camera_stands_where_the_videos_camera_stands(scene, scenario, scenario_run):
    """The free camera the viewer opens with sees what the videos' framed fixed camera sees: MuJoCo's own
    mjv_updateScene puts both at the same position, looking the same way, with the same frustum."""
    result = scenario_run(scene, scenario)
    camera_id = 0
    model, _, _ = stage(result.model, np.asarray(result.trajectory.qpos), camera_id, 640, 360)
    model.vis.global_.fovy = model.cam_fovy[camera_id]
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)

    def seen(camera):
        scene_ = mujoco.MjvScene(model, 2000)
        mujoco.mjv_updateScene(model, data, mujoco.MjvOption(), None, camera, mujoco.mjtCatBit.mjCAT_ALL, scene_)
        eye = scene_.camera[0]
        return np.array([*eye.pos, *eye.forward, *eye.up, eye.frustum_top, eye.frustum_near, eye.frustum_bottom])

    fixed = mujoco.MjvCamera()
    fixed.type, fixed.fixedcamid = mujoco.mjtCamera.mjCAMERA_FIXED, camera_id
    free = mujoco.MjvCamera()
    view._place_camera(free, model, camera_id, follows=False)
    # float32 in MjvGLCamera: a few units in the last place of the largest coordinate
    np.testing.assert_allclose(seen(free), seen(fixed), rtol=0, atol=1e-6 * max(1.0, float(model.stat.extent)))


def test_without_a_display_one_line_and_exit_2(monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    assert main(["view", "slider", "free"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.count("\n") == 1 and "no display" in err and "DISPLAY" in err and "Traceback" not in err


def test_a_display_glfw_cannot_open_is_one_line_and_exit_2(monkeypatch, capsys, tmp_path):
    """A display that names no server: GLFW's own reason, one line, exit 2 (not a window that never opens)."""
    monkeypatch.setenv("DISPLAY", f"unix:{os.getpid() % 50000 + 10000}")  # no such X server socket
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["view", "slider"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "GLFW cannot open" in err and "Traceback" not in err


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["view", "no_such_scene"], "no such model file or scene 'no_such_scene'; scenes: car,"),
        (["view", "slider", "no_such_scenario"], "unknown scenario of slider 'no_such_scenario'; valid:"),
        (["view", "slider", "--slow-motion", "0.5"], "--slow-motion must be a finite number >= 1"),
        (["view", "slider", "--close-after", "-1"], "--close-after must be a number of seconds > 0"),
    ],
)
def test_bad_input_is_one_line_and_exit_2_before_the_display_is_looked_at(argv, needle, monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)  # a name error wins over the missing display
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and needle in err


def test_a_model_file_refuses_scene_options(tmp_path, capsys):
    path = tmp_path / "m.xml"
    path.write_text("<mujoco><worldbody><body><joint type='slide'/><geom size='0.1'/></body></worldbody></mujoco>")
    assert main(["view", str(path), "--set", "mass=2"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--set goes with a scene name" in err


# -- the window under a virtual display ---------------------------------------------------------


def _xvfb() -> str:
    path = shutil.which("Xvfb")
    if path:
        return path
    if os.environ.get("SPRINGLAB_REQUIRE_XVFB"):
        pytest.fail("Xvfb is required here (SPRINGLAB_REQUIRE_XVFB) but not on PATH")
    pytest.skip("the viewer test needs Debian's xvfb (apt-get install xvfb; .ci/run installs it when run as root)")


def read_xwd(path) -> np.ndarray:
    """The (height, width, 3) uint8 RGB picture of an XWD file (X Window Dump: big-endian header, then
    colour map entries, then pixels in the header's byte order and masks), 24/32 bits per pixel."""
    raw = path.read_bytes()
    header = struct.unpack(">25I", raw[:100])
    size, width, height, byte_order, bits, line = header[0], header[4], header[5], header[7], header[11], header[12]
    masks, colours = header[14:17], header[19]
    assert bits == 32, f"{bits} bits per pixel"
    words = np.frombuffer(raw, "<u4" if byte_order == 0 else ">u4", height * line // 4, size + 12 * colours)
    words = words.reshape(height, line // 4)[:, :width]
    out = np.empty((height, width, 3), np.uint8)
    for i, mask in enumerate(masks):
        out[..., i] = (words & mask) >> ((mask & -mask).bit_length() - 1)
    return out


def _like(picture: np.ndarray, rgb: np.ndarray) -> np.ndarray:
    """Pixels whose colour is `rgb` under some light: the same channel ratios within 25 %, not dark."""
    pixels = picture.astype(float) + 1.0
    brightest = pixels.max(axis=-1, keepdims=True)
    ratios = pixels / brightest
    expected = rgb / rgb.max()
    return np.all(np.abs(ratios - expected) < 0.25, axis=-1) & (brightest[..., 0] > 60)


@pytest.fixture
def display(tmp_path):
    """A fresh Xvfb screen (960 x 540, black root): (DISPLAY value, path of its framebuffer XWD file)."""
    server = _xvfb()
    read, write = os.pipe()
    process = subprocess.Popen(
        [server, "-displayfd", str(write), "-screen", "0", "960x540x24", "-br", "-fbdir", str(tmp_path)]
        + ["-nolisten", "tcp"],
        pass_fds=(write,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write)
    try:
        ready, _, _ = select.select([read], [], [], 30)
        number = os.read(read, 64).decode().strip() if ready else ""
        assert number.isdigit(), "Xvfb did not report its display number within 30 s"
        yield f":{number}", tmp_path / "Xvfb_screen0"
    finally:
        os.close(read)
        process.terminate()
        process.wait(timeout=30)


@pytest.mark.slow  # 3.5 s on two cores, 5 s pinned to one: the window is open 1.2 s, the command starts in 2
def test_the_window_shows_the_block_and_its_drawn_spring_moving_in_real_time(display):
    """`springlab view slider free` under Xvfb: the window opens (its first line says so), the X screen
    shows the block in its colour and the spring the videos draw (in the spring's colour: it exists only
    as a user_scn drawing), the block moves between two screenshots a quarter period apart, the window
    closes itself after --close-after, and the simulated time kept up with the wall clock."""
    name, framebuffer = display
    env = {**os.environ, "DISPLAY": name, "MUJOCO_GL": "egl"}  # the videos' setting does not stop the viewer
    env.pop("WAYLAND_DISPLAY", None)
    command = [sys.executable, "-m", "springlab", "view", "slider", "free", "--close-after", "1.2"]
    process = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    watchdog = threading.Timer(120, process.kill)  # a window that never opens must not hang the suite
    watchdog.start()
    try:
        first = process.stdout.readline()
        assert first.startswith("viewing slider / free (rk4, dt = 0.005 s; PASS) live at real time"), (
            first + process.stderr.read()
        )
        time.sleep(0.5)
        before = read_xwd(framebuffer)
        time.sleep(0.16)  # a quarter of the slider's period 2 pi / 10 rad/s
        after = read_xwd(framebuffer)
        rest, errors = process.communicate(timeout=60)
    finally:
        watchdog.cancel()
        process.kill()
    assert process.returncode == 0, errors
    closing = re.match(r"closed after ([\d.]+) s: ([\d.]+) s simulated \(([\d.]+) x real time", rest)
    assert closing, rest
    wall, simulated = float(closing[1]), float(closing[2])
    assert wall >= 1.2 and 0.5 * wall <= simulated <= wall + 0.02  # never ahead of the clock, not far behind
    for picture in (before, after):
        block, spring = _like(picture, BLOCK_RGB), _like(picture, SPRING_RGB)
        assert block.sum() > 2000, f"{block.sum()} pixels of the block's colour"
        assert spring.sum() > 200, f"{spring.sum()} pixels of the spring's colour"
        assert np.nonzero(spring)[1].mean() < np.nonzero(block)[1].mean()  # the spring runs from the wall on the left
    shift = np.nonzero(_like(after, BLOCK_RGB))[1].mean() - np.nonzero(_like(before, BLOCK_RGB))[1].mean()
    assert abs(shift) > 3, f"the block moved {shift:.1f} px"


def test_small_motions_are_drawn_magnified_around_the_runs_mean_and_the_physics_is_not(scenario_run):
    """The car's push and release moves by millimetres: like its video, the window draws it x30 around the
    run's mean position (q_drawn = mean + 30 (q - mean) on every coordinate), while the stepped state stays
    the run's; the springs the videos draw are appended to the viewer's scene each frame."""
    result = scenario_run("car", "push_release")
    live = view.live_run(result)
    states = np.asarray(result.trajectory.qpos)
    centre = states.mean(axis=0)
    model, drawings, _ = stage(live.model, states, 0, 640, 360)
    picture = view._Picture(model, mujoco.MjData(model), drawings, 30.0, centre)
    scene = mujoco.MjvScene(model, 2000)
    live.advance(137)
    picture.show(live, scene)
    np.testing.assert_array_equal(live.data.qpos, states[137])
    np.testing.assert_allclose(picture.data.qpos, centre + 30.0 * (states[137] - centre), rtol=1e-13, atol=1e-15)
    assert scene.ngeom > 0 and all(scene.geoms[i].category == mujoco.mjtCatBit.mjCAT_DECOR for i in range(scene.ngeom))
