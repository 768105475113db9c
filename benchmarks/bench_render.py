"""Speed of springlab's video path, side by side in one run.

1. Frames per second of springlab.render.video.render_video against a naive loop on
   the same slider trajectory (10 s at 30 fps = 300 frames, 640 x 480):
   the naive loop is what one writes first with MuJoCo's own tools:
   `mujoco.Renderer` with MuJoCo's default visual settings (shadows,
   reflections, skybox and haze on; the model's `shadowsize` restored to
   MuJoCo's default 4096), one `update_scene` + `render` call per frame
   collecting the frames, and the mp4 encoded afterwards with the same x264
   settings. render_video reuses one GL context, switches the extra passes
   and multisampling off, and encodes on ffmpeg's own process while the next
   frames render; also timed with multisampling on (`render --antialias`).
   Also the composite video (the same plus the 480 x 480 phase-plane panel).
   All are run alternately, best of N, and the ratios printed.
2. End to end: `springlab render slider undamped --duration 10`, `car road_bump`
   and `printer_head move` at 640 x 480 as fresh processes (interpreter start,
   imports, simulation, rendering, encoding): wall time and frames per second;
   the target is >= 30 frames/s. `--before SRC` times another checkout's
   src/ folder alternately with this one (before/after a change).

Rows of `make bench`'s table: `render SCENE SCENARIO, end to end` for the three
cases (wall time against the video's own length at 30 frames/s: the target).
Part 1's render_video is the table's `render` row (against ffmpeg's own
encoding of as many frames): `make bench` runs --end-to-end-only --repeat 2.

The machine may be shared: ratios measured side by side hold better than
absolute numbers. Run: python benchmarks/bench_render.py [--repeat N] [--before SRC] [--end-to-end-only]
"""

from __future__ import annotations

import argparse
import copy
import os
import pathlib
import subprocess
import sys
import tempfile
import time

# mujoco.Renderer (the naive path) takes its GL backend from MUJOCO_GL when mujoco is first imported
os.environ.setdefault("MUJOCO_GL", "egl")

import imageio_ffmpeg  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402

import springlab  # noqa: E402
from measure import Row, emit  # noqa: E402
from springlab.render import video as render  # noqa: E402

DURATION, FPS, WIDTH, HEIGHT = 10.0, 30, 640, 480
MUJOCO_DEFAULT_SHADOWSIZE = 4096


def naive_video(model: mujoco.MjModel, time_s: np.ndarray, qpos: np.ndarray, output: str) -> int:
    """The straightforward version: default visuals, one frame per call, encode afterwards."""
    model = copy.copy(model)
    model.vis.quality.shadowsize = MUJOCO_DEFAULT_SHADOWSIZE
    data = mujoco.MjData(model)
    at = render.frame_times(DURATION, FPS)
    states = render.sample_states(time_s, qpos, at)
    frames = []
    with mujoco.Renderer(model, HEIGHT, WIDTH) as renderer:
        for q in states:
            data.qpos[:] = q
            mujoco.mj_forward(model, data)
            renderer.update_scene(data, camera="side")
            frames.append(renderer.render())
    writer = imageio_ffmpeg.write_frames(
        output,
        (WIDTH, HEIGHT),
        fps=FPS,
        codec="libx264",
        quality=None,
        pix_fmt_out="yuv420p",
        macro_block_size=1,
        ffmpeg_log_level="error",
        output_params=["-preset", render.X264_PRESET, "-crf", str(render.X264_CRF)],
    )
    writer.send(None)
    for frame in frames:
        writer.send(frame)
    writer.close()
    return len(frames)


def fast_video(model, time_s, qpos, output, panel=None, antialias=False) -> int:
    info = render.render_video(
        model,
        time_s,
        qpos,
        output,
        fps=FPS,
        width=WIDTH,
        height=HEIGHT,
        duration=DURATION,
        camera="side",
        progress=False,
        panel=panel,
        antialias=antialias,
    )
    return info["frames"]


def frames_per_second(repeat: int, folder: pathlib.Path) -> None:
    from springlab.plots import panel as plots_panel

    result = springlab.run("slider", "undamped", duration=DURATION)
    args = (result.model, result.time, result.trajectory.qpos)
    paths = {
        "naive": naive_video,
        "springlab": fast_video,
        # the same with the model's 4x multisampling, as the naive path has (render --antialias)
        "antialias": lambda *a: fast_video(*a, antialias=True),
        # the composite video: the same plus a 480 x 480 phase-plane panel (built anew each run)
        "composite": lambda *a: fast_video(*a, panel=plots_panel.PhasePanel(result, HEIGHT)),
    }
    best = {name: np.inf for name in paths}
    frames = {}
    for _ in range(repeat):  # alternate, so all see the same machine load
        for name, make in paths.items():
            start = time.perf_counter()
            frames[name] = make(*args, str(folder / f"{name}.mp4"))
            best[name] = min(best[name], time.perf_counter() - start)
    print(f"1) render + encode, slider undamped, {frames['springlab']} frames {WIDTH}x{HEIGHT}, best of {repeat}")
    print(f"   {'path':<42}{'wall [s]':>10}{'frames/s':>10}")
    print(
        f"   {'naive: mujoco.Renderer, default visuals':<42}{best['naive']:>10.2f}"
        f"{frames['naive'] / best['naive']:>10.1f}"
    )
    print(
        f"   {'springlab.render.video.render_video':<42}{best['springlab']:>10.2f}"
        f"{frames['springlab'] / best['springlab']:>10.1f}"
    )
    print(
        f"   {'springlab, --antialias (4x multisampling)':<42}{best['antialias']:>10.2f}"
        f"{frames['antialias'] / best['antialias']:>10.1f}"
    )
    print(
        f"   {'springlab composite (+ 480x480 phase panel)':<42}{best['composite']:>10.2f}"
        f"{frames['composite'] / best['composite']:>10.1f}"
    )
    print(
        f"   speed-up over naive: {best['naive'] / best['springlab']:.2f}x"
        f" ({best['naive'] / best['antialias']:.2f}x with the same multisampling);"
        f" the composite costs {best['composite'] / best['springlab']:.2f}x a plain video"
    )


#: end-to-end cases: (scene, scenario, extra arguments); the car and printer exercise the drawn
#: springs, dampers, road and belt, and the defaults' slow motion (the printer move: 450 frames)
END_TO_END = (
    ("slider", "undamped", ["--duration", str(DURATION)]),
    ("car", "road_bump", []),
    ("printer_head", "move", []),
)


def _render_once(source: str | None, scene: str, scenario: str, extra: list[str], output: pathlib.Path):
    """(wall time [s], frames) of one fresh `springlab render` process, using `source` (a src/ folder) if given."""
    command = [sys.executable, "-m", "springlab.cli.main", "render", scene, scenario, *extra]
    command += ["--fps", str(FPS), "--width", str(WIDTH), "--height", str(HEIGHT), "--output", str(output)]
    env = dict(os.environ)
    if source:
        env["PYTHONPATH"] = source
    start = time.perf_counter()
    done = subprocess.run(command, check=True, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    frames = int(done.stdout.split(": ", 1)[1].split(" frames")[0])  # "wrote X: N frames, ..."
    return wall, frames


def end_to_end(repeat: int, folder: pathlib.Path, before: str | None = None) -> None:
    """Fresh processes, best of `repeat`; with `before` (another checkout's src/), both alternately."""
    versions = {"after": None, **({"before": before} if before else {})}
    print(f"2) end to end, a fresh process per run: springlab render SCENE SCENARIO at {WIDTH}x{HEIGHT}, {FPS} fps")
    print(f"   {'case':<26}{'version':<9}{'frames':>7}{'wall [s]':>10}{'frames/s':>10}")
    for scene, scenario, extra in END_TO_END:
        best = {name: (np.inf, 0) for name in versions}
        for _ in range(repeat):  # alternate, so both see the same load
            for name, source in versions.items():
                wall, frames = _render_once(source, scene, scenario, extra, folder / f"{name}.mp4")
                best[name] = min(best[name], (wall, frames))
        for name, (wall, frames) in best.items():
            verdict = (
                ""
                if name == "before"
                else f"  target >= {FPS} frames/s: {'met' if frames / wall >= FPS else 'NOT met'}"
            )
            print(f"   {scene + ' ' + scenario:<26}{name:<9}{frames:>7}{wall:>10.2f}{frames / wall:>10.1f}{verdict}")
        wall, frames = best["after"]
        emit(
            Row(
                f"render {scene} {scenario}, end to end",
                f"`springlab render {scene} {scenario}` in a fresh process, {frames} frames {WIDTH} x {HEIGHT}",
                wall,
                float("nan"),
                f"{FPS} frames/s",
                frames / FPS,
                float("nan"),
                1.0,
                "the script's target",
                f"bench_render.py: interpreter start, imports, simulation, rendering and encoding, best of {repeat};"
                f" {frames / wall:.1f} frames/s; ratio = wall time / the video's own length at {FPS} frames/s (1: it"
                " renders as fast as it plays)",
                on_wall=True,
            )
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per path (best is kept)")
    parser.add_argument("--before", metavar="SRC", help="another checkout's src/ folder to time end to end alongside")
    parser.add_argument("--end-to-end-only", action="store_true", help="skip the in-process comparison")
    args = parser.parse_args()
    print(
        f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start;"
        f" MUJOCO_GL={os.environ.get('MUJOCO_GL')}"
    )
    with tempfile.TemporaryDirectory() as folder:
        if not args.end_to_end_only:
            frames_per_second(args.repeat, pathlib.Path(folder))
        end_to_end(args.repeat, pathlib.Path(folder), args.before)
    print(f"load average {os.getloadavg()[0]:.2f} at the end")


if __name__ == "__main__":
    main()
