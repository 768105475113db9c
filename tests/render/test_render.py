"""Off-screen video: the file decodes, its clock is the simulation's, and the picture shows the physics."""

import math
import os

import imageio_ffmpeg
import mujoco
import numpy as np
import pytest

from springlab import scenes
from springlab.cli.main import main
from springlab.errors import BadInputError
from springlab.plots import panel as plots_panel
from springlab.render import media, stage
from springlab.render import video as render
from springlab.runs.run import evaluate, run_scenario
from springlab.scenes.capabilities.drawing import Drawing


def _decode(path):
    """(meta, frames (n, h, w, 3) uint8) decoded by ffmpeg itself, independently of the writer."""
    # one decoding thread: the test workers fill the cores already, and H.264 decodes to the same pixels
    # whatever the threads (ffmpeg's own threads cost a third more CPU on these small videos)
    reader = imageio_ffmpeg.read_frames(str(path), input_params=["-threads", "1"])
    meta = next(reader)
    width, height = meta["size"]
    frames = [np.frombuffer(raw, np.uint8).reshape(height, width, 3) for raw in reader]
    return meta, np.array(frames)


def _block_mask(frames):
    """Pixels of the slider's orange block (material rgba 0.85 0.33 0.18), any shading of it."""
    # frame by frame in int16: a whole video as int64 channels and float products is gigabytes
    masks = []
    for frame in frames:
        r, g, b = (frame[..., i].astype(np.int16) for i in range(3))
        masks.append((r > 90) & (r > 2 * g) & (r > 2.5 * b))
    return np.array(masks)


@pytest.fixture(scope="module")
def undamped():
    # undamped slider: x(t) = 0.1 cos(10 t) m, a full swing across the rail every 0.31 s
    return run_scenario("slider", "undamped", duration=3.0)


def test_video_decodes_with_duration_times_fps_frames_of_the_asked_size(undamped, tmp_path):
    info = render.render_video(
        undamped.model,
        undamped.time,
        undamped.trajectory.qpos,
        tmp_path / "v.mp4",
        fps=20,
        width=320,
        height=240,
        duration=2.5,
        camera="side",
    )
    meta, frames = _decode(tmp_path / "v.mp4")
    assert frames.shape == (50, 240, 320, 3)  # 2.5 s x 20 fps
    assert info["frames"] == 50 and (info["width"], info["height"]) == (320, 240)
    assert meta["fps"] == pytest.approx(20) and meta["codec"].startswith("h264")
    assert "yuv420p" in meta["pix_fmt"]  # the pixel format browsers decode
    assert meta["duration"] == pytest.approx(2.5, abs=0.06)


def test_block_centroid_in_the_picture_tracks_the_simulated_position(undamped, tmp_path):
    info = render.render_video(
        undamped.model, undamped.time, undamped.trajectory.qpos, tmp_path / "v.mp4", fps=15, width=320, height=240
    )
    _, frames = _decode(tmp_path / "v.mp4")
    mask = _block_mask(frames)
    columns = np.arange(frames.shape[2])
    counts = mask.sum(axis=(1, 2))
    assert np.all(counts > 100), "the block is visible in every frame"
    centroid = (mask.sum(axis=1) * columns).sum(axis=1) / counts
    times = render.frame_times(info["frames"] / 15, 15)
    x = np.interp(times, undamped.time, undamped.pos["slider"])
    assert np.corrcoef(centroid, x)[0, 1] > 0.99
    # and it moves the right way by the right amount: about the same pixels per metre all along
    slope, offset = np.polyfit(x, centroid, 1)
    assert slope > 0 and np.max(np.abs(centroid - (slope * x + offset))) < 0.05 * slope * 0.2


def test_frames_are_sampled_at_the_video_clock_not_the_physics_steps():
    times = render.frame_times(2.0, 30)
    assert len(times) == 60 and times[0] == 0.0
    np.testing.assert_allclose(np.diff(times), 1 / 30, rtol=0, atol=1e-15)
    # linear interpolation of a recording reproduces any linear motion exactly, between steps too
    recorded = np.linspace(0.0, 2.0, 7)
    states = np.column_stack([3 * recorded + 1, -recorded])
    sampled = render.sample_states(recorded, states, times)
    np.testing.assert_allclose(sampled, np.column_stack([3 * times + 1, -times]), atol=1e-12)


def test_gif_frames_last_one_over_fps_each(undamped, tmp_path):
    from PIL import Image

    render.render_video(
        undamped.model,
        undamped.time,
        undamped.trajectory.qpos,
        tmp_path / "v.gif",
        fps=12,
        width=160,
        height=120,
        duration=1.0,
    )
    with Image.open(tmp_path / "v.gif") as gif:
        assert gif.size == (160, 120)
        delays = []
        for index in range(gif.n_frames):
            gif.seek(index)
            delays.append(gif.info["duration"])
    assert len(delays) == 12 and sum(delays) == 1000  # [ms]: the clock does not drift


def test_camera_backs_off_when_the_motion_leaves_the_view(tmp_path):
    # the chapter's exercise starts 5 m out, far outside the camera's 0.9 m wide view of the rail
    result = run_scenario("slider", "exercise")
    position = result.model.cam_pos[0].copy()
    render.render_video(
        result.model,
        result.time,
        result.trajectory.qpos,
        tmp_path / "v.mp4",
        fps=5,
        width=640,
        height=480,
        duration=6.0,
    )
    np.testing.assert_array_equal(result.model.cam_pos[0], position)  # the caller's model is untouched
    _, frames = _decode(tmp_path / "v.mp4")
    assert np.all(_block_mask(frames).sum(axis=(1, 2)) > 0), "the block stays in the picture, at 5 m and at 0"


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(output="v.avi"), "unsupported output extension"),
        (dict(fps=0), "fps must be > 0"),
        (dict(width=0), "width must be between"),
        (dict(height=10_000), "height must be between"),
        (dict(output="v.gif", fps=60), "GIF supports at most 50 fps"),
        (dict(camera="nope"), "unknown camera 'nope'; the model's cameras are: 'side'"),
    ],
)
def test_bad_arguments_are_refused_before_anything_is_written(undamped, tmp_path, kwargs, message):
    arguments = dict(output="v.mp4", fps=30, width=64, height=48)
    arguments.update(kwargs)
    output = tmp_path / arguments.pop("output")
    with pytest.raises(BadInputError, match=message):
        render.render_video(undamped.model, undamped.time, undamped.trajectory.qpos, output, **arguments)
    assert list(tmp_path.iterdir()) == []


def test_a_failure_mid_video_leaves_no_partial_file(undamped, tmp_path):
    def panel(index, t):
        if index == 5:
            raise RuntimeError("panel failed")
        return np.zeros((48, 20, 3), np.uint8)

    with pytest.raises(RuntimeError, match="panel failed"):
        render.render_video(
            undamped.model,
            undamped.time,
            undamped.trajectory.qpos,
            tmp_path / "v.mp4",
            width=64,
            height=48,
            panel=panel,
        )
    assert list(tmp_path.iterdir()) == []


def test_composite_panel_marker_follows_the_phase_point(undamped):
    panel = plots_panel.PhasePanel(undamped, 240)
    times = np.linspace(0, 1.5, 24)
    images = np.array([panel(i, t) for i, t in enumerate(times)])
    assert images.shape == (24, 240, 240, 3)
    # the current point is the only saturated red in the panel (C3 marker)
    r, g, b = (images[..., i].astype(int) for i in range(3))
    red = (r > 180) & (g < 80) & (b < 80)
    rows, cols = np.arange(240)[:, None], np.arange(240)[None, :]
    count = red.sum(axis=(1, 2))
    assert np.all(count > 10)
    col = (red * cols).sum(axis=(1, 2)) / count
    row = (red * rows).sum(axis=(1, 2)) / count
    x = np.interp(times, undamped.time, undamped.pos["slider"])
    v = np.interp(times, undamped.time, undamped.vel["slider"])
    assert np.corrcoef(col, x)[0, 1] > 0.99
    assert np.corrcoef(row, v)[0, 1] < -0.99  # image rows grow downwards
    # the trace grows: more of the trajectory colour (C0) with time
    blue = ((b > 150) & (r < 80)).sum(axis=(1, 2))
    assert blue[-1] > blue[len(blue) // 4] > blue[0]


def test_render_command_writes_a_composite_video(tmp_path, capsys):
    output = tmp_path / "sub" / "c.mp4"
    code = main(
        [
            "render",
            "car",
            "pitch_heave",
            "--duration",
            "0.5",
            "--fps",
            "20",
            "--width",
            "160",
            "--height",
            "120",
            "--composite",
            "--slow-motion",
            "1",
            "--output",
            str(output),
        ]
    )
    assert code == 0, capsys.readouterr().err
    meta, frames = _decode(output)
    assert frames.shape == (10, 120, 160 + 120, 3)  # the phase panel is height x height


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--output", "v.webm"], "unsupported output extension '.webm'"),
        (["--output", "v.mp4", "--fps", "-5"], "fps must be > 0"),
        (["--output", "v.mp4", "--width", "0"], "width must be between 1 and 8192"),
        (["--output", "v.mp4", "--set", "mass=-1"], "mass must be a finite number >= 1e-15 kg"),
    ],
)
def test_render_command_bad_input_exits_2_with_one_line(tmp_path, cli, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    code, _, err = cli("render", "slider", *argv)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_render_command_exits_3_on_divergence_and_writes_nothing(tmp_path, capsys):
    # omega dt = 10 rad/s x 0.5 s = 5, beyond RK4's stability limit (about 2.8)
    code = main(["render", "slider", "--dt", "0.5", "--output", str(tmp_path / "v.mp4")])
    assert code == 3 and "diverged" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_render_run_clips_to_the_requested_seconds(undamped, tmp_path):
    info = media.render_run(undamped, tmp_path / "v.mp4", fps=10, width=64, height=48, duration=1.0, slow_motion=1)
    assert info["frames"] == 10
    assert math.isclose(info["frames"] / info["fps"], 1.0)
    # slowed down, the same second of simulation fills S times the frames
    info = media.render_run(undamped, tmp_path / "v.mp4", fps=10, width=64, height=48, duration=1.0, slow_motion=4)
    assert info["frames"] == 40 and info["slow_motion"] == 4


def test_declared_springs_are_drawn_between_their_sites():
    # the slider's spring is a custom "spring:" text, drawn as a capsule from the wall to the block
    result = run_scenario("slider", "free", duration=0.1)
    springs = render.drawn_springs(result.model)
    assert len(springs) == 1
    first, second, width, rgba = springs[0]
    assert result.model.site(first).name == "spring_anchor" and result.model.site(second).name == "spring_hook"
    assert width > 0 and rgba.shape == (4,)


def test_odd_sizes_are_padded_to_even_for_h264(undamped, tmp_path):
    info = render.render_video(
        undamped.model,
        undamped.time,
        undamped.trajectory.qpos,
        tmp_path / "v.mp4",
        fps=10,
        width=81,
        height=61,
        duration=0.5,
    )
    meta, frames = _decode(tmp_path / "v.mp4")
    assert (info["width"], info["height"]) == (82, 62) == tuple(meta["size"])  # yuv420p needs even sizes
    assert frames.shape == (5, 62, 82, 3)


def test_the_video_gets_ordinary_file_permissions_not_the_temp_files(undamped, tmp_path):
    umask = os.umask(0o022)
    try:
        render.render_video(
            undamped.model,
            undamped.time,
            undamped.trajectory.qpos,
            tmp_path / "v.mp4",
            fps=10,
            width=64,
            height=48,
            duration=0.3,
        )
    finally:
        os.umask(umask)
    assert (tmp_path / "v.mp4").stat().st_mode & 0o777 == 0o644
    assert [p.name for p in tmp_path.iterdir()] == ["v.mp4"]  # no temporary file left next to it


def test_multisampling_only_when_asked_and_the_model_keeps_its_own_setting(undamped):
    # without multisampling an edge pixel is one surface's colour or the other's; with it (antialias=True,
    # the model's offsamples, MuJoCo's default 4) edge pixels are blends, so the picture has more distinct
    # colours. The sample count is set for the GL context only, never in the caller's model.
    from springlab.render.gl import OffscreenScene

    model = undamped.model
    before = (model.vis.global_.offwidth, model.vis.global_.offheight, model.vis.quality.offsamples)
    assert before[2] > 0  # the model asks for multisampling
    data = mujoco.MjData(model)
    data.qpos[:] = undamped.trajectory.qpos[0]
    mujoco.mj_forward(model, data)
    colours = {}
    for multisample in (False, True):
        scene = OffscreenScene(model, 640, 480, -1, multisample=multisample)
        try:
            frame = np.empty((480, 640, 3), np.uint8)
            scene.render(data, frame)
        finally:
            scene.close()
        colours[multisample] = len(np.unique(frame.reshape(-1, 3), axis=0))
        assert (model.vis.global_.offwidth, model.vis.global_.offheight, model.vis.quality.offsamples) == before
    assert colours[True] > colours[False]


def test_the_road_a_run_draws_is_the_one_its_scene_declares_and_no_other():
    # the renderer recognises no scene by its parts: what it draws beyond the model comes from Scene.drawing
    for scene in scenes.SCENES.values():
        for name in scene.scenarios:
            case = scene.case(name)
            road = case.drawing().road
            if road is not None:  # the wheels it is drawn under are the case's own geoms
                for geom in filter(None, (road.wheel_geom, road.other_axle_geom)):
                    assert mujoco.mj_name2id(case.model, mujoco.mjtObj.mjOBJ_GEOM, geom) >= 0, (scene.name, name)
    result = run_scenario("car", "road_bump", duration=0.05)
    road = stage.road_bump(result)
    p = result.parameters
    assert road is not None and (road.height, road.length, road.speed) == (
        p["bump_height"],
        p["bump_length"],
        p["speed"],
    )
    assert stage.road_bump(run_scenario("car", "push_release", duration=0.05)) is None

    class Undeclared(type(scenes.get("car"))):  # the same parameters and model, no road declared
        def drawing(self, case):
            return Drawing()

    case = Undeclared().case("road_bump")
    assert stage.road_bump(evaluate(case, case.simulate("rk4", 1e-3, 0.05))) is None
