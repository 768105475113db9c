"""Videos show the physics: measured on decoded frames against the simulated (or closed-form) motion.

Each test decodes the mp4 with ffmpeg (independently of the writer), finds a
body by its material colour, and compares its image position with the
trajectory the video claims to show. The slow-motion and exaggeration factors
change only the drawing, so frame k shows simulation time k / (fps S).
"""

import math

import imageio_ffmpeg
import numpy as np
import pytest

from springlab import scenes
from springlab.render import media
from springlab.render import scale as render_scale
from springlab.render import video as render
from springlab.runs.run import run_scenario


def _decode(path):
    # one decoding thread: the test workers fill the cores already, and H.264 decodes to the same pixels
    # whatever the threads (ffmpeg's own threads cost a third more CPU on these small videos)
    reader = imageio_ffmpeg.read_frames(str(path), input_params=["-threads", "1"])
    meta = next(reader)
    width, height = meta["size"]
    return np.array([np.frombuffer(raw, np.uint8).reshape(height, width, 3) for raw in reader])


def _rgb(frames):
    return (frames[..., i].astype(np.int16) for i in range(3))  # int16: a video in int64 is gigabytes


def _per_frame(mask, frames):
    """mask(frames) evaluated one frame at a time: its float products stay one frame large."""
    return np.concatenate([mask(frames[i : i + 1]) for i in range(len(frames))])


def _paint(frames):
    """The car's blue paint (0.16 0.38 0.72), any shading, not the pale blue glass."""
    r, g, b = _rgb(frames)
    return (b > 100) & (b > 1.6 * r) & (b > 1.25 * g) & (r < 110)


def _frame_times(info, duration):
    return render.frame_times(duration * info["slow_motion"], info["fps"]) / info["slow_motion"]


def _row_centroid(mask):
    # from each row's pixel count: the same integer sums as weighting every pixel, without a video-sized
    # array of weights (450 frames of 240 x 320 int64 are 280 MB)
    counts = mask.sum(axis=2)
    return (counts * np.arange(mask.shape[1])).sum(axis=1) / counts.sum(axis=1)


def _column_centroid(mask):
    counts = mask.sum(axis=1)  # each column's pixel count, as _row_centroid
    return (counts * np.arange(mask.shape[2])).sum(axis=1) / counts.sum(axis=1)


@pytest.mark.slow
def test_the_exaggerated_car_body_follows_the_heave_by_at_least_ten_pixels(tmp_path):
    result = run_scenario("car", "push_release")
    info = media.render_run(result, tmp_path / "car.mp4", progress=False)
    assert info["exaggeration"] > 1  # a 4.9 mm motion of a 4.2 m car is magnified by default
    frames = _decode(tmp_path / "car.mp4")
    row = _row_centroid(_per_frame(_paint, frames))
    heave = np.interp(_frame_times(info, float(result.time[-1])), result.time, result.pos["heave"])
    assert abs(np.corrcoef(row, heave)[0, 1]) > 0.99
    assert np.ptp(row) >= 10  # [px]
    # and it moves by the exaggerated amount: a rigid heave moves the paint's centroid like the body
    slope = np.polyfit(heave, row, 1)[0]
    assert slope < 0  # image rows grow downwards


@pytest.mark.slow
def test_the_road_bump_rises_and_falls_under_the_front_wheel_with_r_of_t(tmp_path):
    result = run_scenario("car", "road_bump")
    info = media.render_run(result, tmp_path / "bump.mp4", progress=False)
    assert info["slow_motion"] == 1 and info["exaggeration"] == 1  # the bump at real speed, real size
    frames = _decode(tmp_path / "bump.mp4")
    times = _frame_times(info, float(result.time[-1]))
    p = result.parameters
    passing = times < p["bump_length"] / p["speed"]
    bump = np.where(passing, p["bump_height"] * np.sin(np.pi * p["speed"] * times / p["bump_length"]), 0.0)
    # the front wheel's column: the tire's dark pixels in the right half of the first frame
    r, g, b = _rgb(frames[:1])
    tire = (r < 60) & (g < 60) & (b < 60)
    tire[..., : frames.shape[2] // 2] = False
    column = int(round(_column_centroid(tire)[0]))
    window = frames[:, :, column - 12 : column + 12]
    r, g, b = _rgb(window)
    # the drawn bump's warm asphalt: not the grey road, not the yellow springs, below the wheel centre
    road = (r > g + 20) & (g > b + 20) & (r > 80) & (g < 0.75 * r) & (b > 30)
    road[:, : frames.shape[1] // 2] = False
    # the bump's visible height in the wheel's column: its top face (constant) plus its front face (r(t))
    extent = (road.sum(axis=2) >= road.shape[2] // 2).sum(axis=1)  # [px]
    on = passing & (times > 0)
    assert np.corrcoef(extent[on], bump[on])[0, 1] > 0.95
    assert np.ptp(extent[on]) >= 5
    assert np.all(extent[times > 1.0] == 0)  # gone once the wheel has left it


@pytest.mark.slow
def test_the_printer_move_is_slowed_to_many_frames_and_the_carriage_follows_its_simulated_position(tmp_path):
    result = run_scenario("printer_head", "move")
    # a quarter of the default pixels: the carriage is still tens of pixels wide, and the frames, slow
    # motion and exaggeration are the defaults under test
    info = media.render_run(result, tmp_path / "move.mp4", width=320, height=240, progress=False)
    assert info["frames"] >= 90
    # the 195 Hz belt gets frames per period enough to be seen ringing, not aliased
    belt_hz = result.case.modes()
    frequency = max(omega for omega, _ in belt_hz) / (2 * math.pi)
    assert info["fps"] * info["slow_motion"] / frequency >= render_scale.FRAMES_PER_PERIOD
    frames = _decode(tmp_path / "move.mp4")

    def blue(f):  # the carriage's material 0.2 0.45 0.8
        r, g, b = _rgb(f)
        return (b > 120) & (b > 1.5 * r) & (g > 70) & (g < 0.8 * b)

    carriage = _per_frame(blue, frames)
    column = _column_centroid(carriage)
    position = np.interp(_frame_times(info, float(result.time[-1])), result.time, result.pos["carriage"])
    assert np.corrcoef(column, position)[0, 1] > 0.99


def _inside_masks():
    """Scene -> mask of its moving body's material, for the in-frame check."""

    def orange(f):  # slider block and the kinematics vehicle: 0.85 0.33 0.18
        r, g, b = _rgb(f)
        return (r > 90) & (r > 2 * g) & (r > 2.5 * b)

    def green(f):  # the non-linear block: 0.2 0.55 0.35
        r, g, b = _rgb(f)
        return (g > 70) & (g > 1.3 * r) & (g > 1.2 * b)

    def carriage(f):
        r, g, b = _rgb(f)
        return (b > 120) & (b > 1.5 * r) & (g > 70) & (g < 0.8 * b)

    def cable(f):  # the stay cable's dark strand (0.15 0.2 0.3), below the three overlay lines of text
        dark = f.max(axis=-1) < 110
        dark[:, : f.shape[1] * 55 // 240, :] = False
        return dark

    return {
        "slider": orange,
        "kinematics": orange,
        "nonlinear": green,
        "car": _paint,
        "printer_head": carriage,
        "friction": orange,  # the box has the slider's block colour
        "drill_string": orange,  # the orange stripes along its rotors, which turn with them
        "stay_cable": cable,
    }


CASES = [(s.name, c) for s in scenes.SCENES.values() for c in s.scenarios]
#: frames drawn and decoded per in-frame check, spread evenly over the run (a 1,500-frame drill string video cost a
#: minute; 60 cost 10 s of CPU more over the 42 cases than 30). Their number is not what the check holds: the camera
#: is fitted to the moving geoms' points in exactly the states the video draws (render/framing.py: frame_camera),
#: so the frames that bind the fit, the extreme positions among them, are drawn and checked whatever their number,
#: and the frames between them add positions inside what they span; 30 still put one every thirtieth of the run
MAX_FRAMES = 30


@pytest.mark.slow
@pytest.mark.parametrize("scene, scenario", CASES)
def test_the_moving_body_is_inside_the_frame_in_every_frame(scene, scenario, tmp_path, scenario_run):
    result = scenario_run(scene, scenario)
    duration = min(float(result.time[-1]), 12.0)
    # the default slow motion at 10 fps (what a user sees), at most MAX_FRAMES frames spread over the run:
    # the framing is fixed for the video, so sparser frames still test every part of the motion. Where even
    # 1 fps would exceed them (the printer's 2 s chirp at 1/200 speed: 400 s of video; the drill string's modes:
    # 150 s) a fraction of a frame per second keeps the cap (the video's fps may be any positive number)
    slow_motion = media.default_slow_motion(result, duration, 10)
    video_seconds = duration * slow_motion
    fps = min(10, int(MAX_FRAMES // video_seconds)) if video_seconds <= MAX_FRAMES else MAX_FRAMES / video_seconds
    info = media.render_run(
        result,
        tmp_path / "v.mp4",
        fps=fps,
        slow_motion=slow_motion,
        width=320,
        height=240,
        duration=duration,
        progress=False,
    )
    frames = _decode(tmp_path / "v.mp4")
    assert len(frames) == info["frames"] <= MAX_FRAMES  # every rendered frame is checked
    mask = _per_frame(_inside_masks()[scene], frames)
    assert np.all(mask.sum(axis=(1, 2)) > 30), "the body is visible in every frame"
    border = mask[:, [0, -1], :].any(axis=(1, 2)) | mask[:, :, [0, -1]].any(axis=(1, 2))
    assert not border.any(), f"the body touches the edge in frames {np.flatnonzero(border)[:10]} of {info['frames']}"


def _text_ink(frames):
    """Dark text pixels in the top-left corner, where the overlay is written."""
    corner = frames[:, : frames.shape[1] // 3, : frames.shape[2] // 2]
    return (corner.max(axis=-1) < 80).sum(axis=(1, 2))


@pytest.mark.parametrize("option", ["exaggerate", "slow_motion"])
def test_a_scale_factor_other_than_one_is_written_on_every_frame(option, tmp_path):
    result = run_scenario("car", "push_release", duration=0.5)  # white sky behind the text: only the text is dark
    plain = dict(slow_motion=1, exaggerate=1)
    scaled = {**plain, option: 3}
    common = dict(fps=10, width=320, height=240, duration=0.5, camera="side", label="car / push_release")
    render.render_video(result.model, result.time, result.trajectory.qpos, tmp_path / "a.mp4", **common, **plain)
    render.render_video(result.model, result.time, result.trajectory.qpos, tmp_path / "b.mp4", **common, **scaled)
    ink_plain, ink_scaled = _text_ink(_decode(tmp_path / "a.mp4")), _text_ink(_decode(tmp_path / "b.mp4"))
    # one more line of text ("motion ×3" or "1/3 speed") on every frame of the scaled video
    assert ink_scaled.min() > ink_plain.max() + 30


def test_exaggeration_scales_every_coordinate_about_its_mean_and_leaves_the_trajectory_alone():
    result = run_scenario("car", "road_bump", duration=0.5)
    states = result.trajectory.qpos.copy()
    drawn = render_scale.exaggerated(result.model, states, 5.0)
    np.testing.assert_array_equal(states, result.trajectory.qpos)  # drawing only
    centre = states.mean(axis=0)
    np.testing.assert_allclose(drawn - centre, 5.0 * (states - centre), rtol=0, atol=1e-12)


def test_default_factors_follow_the_stated_rules():
    # a 3 s run at 30 fps already has 90 frames: real speed (the car's road bump)
    assert render_scale.default_slow_motion(3.0, 30, [11.5]) == 1
    # 0.3 s with a 195 Hz mode: >= 90 frames and 6 frames per period -> 39 -> the nice 50
    assert render_scale.default_slow_motion(0.3, 30, [194.9]) == 50
    assert [render_scale.nice_at_least(v) for v in (0.5, 1, 1.2, 2.5, 4, 17, 39, 51)] == [1, 1, 2, 3, 5, 20, 50, 100]


def _mark_spacing(row_bright):
    """Pixel distance between neighbouring distance marks along one image row, from the bright runs' centres."""
    edges = np.diff(np.concatenate([[0], row_bright.astype(int), [0]]))
    centres = 0.5 * (np.flatnonzero(edges == 1) + np.flatnonzero(edges == -1) - 1)
    gaps = np.diff(centres)
    gaps = gaps[gaps > 0.5 * np.max(gaps, initial=0)] if gaps.size else gaps
    return float(np.min(gaps)) if gaps.size else math.nan  # a mark hidden by a wheel doubles a gap


@pytest.mark.slow
def test_the_tachograph_vehicle_is_drawn_bus_length_against_the_distance_marks(tmp_path):
    # Chapter 5.2: the tachograph is a touring bus's; springlab draws it 12 m long (scenes/_kinematics_bus.py).
    # Marks lie every MARK_SPACING m on the road. The bus's near side stands between the road's near edge
    # (largest mark spacing in px) and the road seen under the bus (smallest), so 12 m measured with those two
    # spacings must bracket the image length; quantisation: +-1 px at each end of the bus, +-1 px per spacing.
    from springlab.render.drawings import MARK_SPACING
    from springlab.scenes.kinematics.bus import BUS_LENGTH

    result = run_scenario("kinematics", "tachograph")
    # at real speed: frame k shows t = k / 2 s (the default slow motion would stretch 12 s to 120 frames and put
    # frames 4, 12 and 20 in the first 2 s); the length in pixels does not depend on when a frame is shown
    media.render_run(
        result, tmp_path / "v.mp4", fps=2, slow_motion=1, width=640, height=480, duration=12.0, progress=False
    )
    frames = _decode(tmp_path / "v.mp4")
    checked = 0
    for frame in frames[[4, 12, 20]]:  # pulling away, cruising, braking: t = 2, 6, 10 s
        r, g, b = (frame[..., i].astype(int) for i in range(3))
        body = (r > 90) & (r > 2 * g) & (r > 2.5 * b)  # the bus's paint (0.85 0.33 0.18)
        columns, rows = np.flatnonzero(body.any(axis=0)), np.flatnonzero(body.any(axis=1))
        length_px = columns.max() - columns.min() + 1
        road = (np.abs(r - g) < 15) & (np.abs(g - b) < 25) & (r > 50) & (r < 140)
        road_rows = [y for y in range(rows.max() + 3, frame.shape[0]) if road[y].sum() > frame.shape[1] // 2]
        bright = (r > 150) & (np.abs(r - b) < 30)  # the white marks, lit
        spacings = np.array([_mark_spacing(bright[y]) for y in road_rows])
        spacings = spacings[np.isfinite(spacings)]
        spacings = spacings[spacings < 1.5 * np.median(spacings)]  # rows where one gap spans a hidden mark
        near, far = float(np.max(spacings)), float(np.min(spacings))
        assert MARK_SPACING * (length_px - 2) / (near + 1) <= BUS_LENGTH
        assert MARK_SPACING * (length_px + 2) / (far - 1) >= BUS_LENGTH
        assert near / far < 1.3  # the bracket is tight: a 4.2 m car would fail it by a factor of 2.5
        checked += 1
    assert checked == 3
