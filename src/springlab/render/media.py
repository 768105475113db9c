"""Videos and plots of runs, for the CLI (`render`, `plot`) and the demo's media step.

`render_run` turns a Result into a video (the 3D scene, optionally beside its
phase-plane trace: the composite video); `plot_files` writes one scenario's
plots (the demo's media step, springlab.demo.steps, calls both for every scenario). Nothing here knows a particular scene: everything comes from the Scene
hooks (camera, phase_field, equilibria, separatrices) and the Result.
"""

from __future__ import annotations

import math
import os
import pathlib
from typing import Any

from springlab import scenes
from springlab.errors import BadInputError, SpringlabError
from springlab.render import scale as render_scale
from springlab.render import stage
from springlab.render import video as render
from springlab.runs.run import Result
from springlab.studies.families import PhaseFamily


def render_run(
    result: Result,
    output: str | os.PathLike,
    *,
    fps: int = 30,
    width: int = 640,
    height: int = 480,
    duration: float | None = None,
    composite: bool = False,
    progress: bool | None = None,
    slow_motion: float | None = None,
    exaggerate: float | None = None,
    antialias: bool = False,
) -> dict[str, Any]:
    """Render a run to `output` (.mp4 H.264 or .gif); see render.render_video for the result dict.

    Parameters
    ----------
    result
        the run (springlab.run).
    output
        video file; written completely or not at all.
    fps
        frames per second of the video (video time = simulation time).
    width, height
        size of the 3D view [px].
    duration
        seconds of simulation to show (default: the whole run).
    composite
        put the phase-plane trace (a height x height panel, one
        phase plane per reported joint, up to 3, stacked) to the right of the
        3D view; the video is then (width + height) x height.
    progress
        progress bar on stderr (None: when stderr is a terminal).
    slow_motion
        factor >= 1 [-] the video is slowed by (drawing only); None:
        render_scale.default_slow_motion of the shown duration and the scene's
        vibration modes (short runs slowed until they fill 90 frames and their
        fastest mode gets 6 frames per period; the printer move: 1/50 speed).
    exaggerate
        factor >= 1 [-] displacements are drawn magnified by; None:
        render_scale.default_exaggeration of the motion (the car: x30).
    antialias
        multisampled edges (about 3x the frame time on a CPU rasteriser).

    Raises
    ------
    BadInputError
        bad size, fps, extension or unwritable output.
    SpringlabError
        no off-screen OpenGL context or the encoder failed.
    """
    render.check_video_arguments(output, fps, width, height)
    scene = scenes.get(result.scene)
    end = float(result.time[-1])
    if duration is not None:
        duration = min(float(duration), end) if end > 0 else float(duration)
    if slow_motion is None:
        slow_motion = default_slow_motion(result, duration if duration is not None else end, fps)
    panel = None
    if composite:
        from springlab.plots import (
            panel as plots_panel,  # imported here: matplotlib adds ~0.8 s to start-up, a plain video does not need it
        )

        panel = plots_panel.PhasePanel(result, height)
    try:
        return render.render_video(
            result.model,
            result.time,
            result.trajectory.qpos,
            output,
            fps=fps,
            width=width,
            height=height,
            camera=scene.camera,
            duration=duration,
            label=f"{result.scene} / {result.scenario}",
            progress=progress,
            panel=panel,
            slow_motion=slow_motion,
            exaggerate=exaggerate,
            road_bump=stage.road_bump(result),  # the quarter car's road
            antialias=antialias,
        )
    except RuntimeError as error:  # GL context or ffmpeg: not the user's input, still one clean line
        raise SpringlabError(f"cannot render {str(output)!r}: {error}") from None


def default_slow_motion(result: Result, duration: float, fps: float) -> float:
    """render_scale.default_slow_motion for `duration` [s] of a run, from its scene's vibration modes [Hz]."""
    try:
        modes = result.case.modes()
    except (BadInputError, NotImplementedError):
        modes = []
    return render_scale.default_slow_motion(duration, fps, [omega / (2 * math.pi) for omega, _ in modes])


def plot_files(
    result: Result, folder: pathlib.Path, out: pathlib.Path, family: PhaseFamily | None = None
) -> list[tuple[str, str, str]]:
    """Write a run's plots into `folder`: [(path relative to `out`, kind of plot, title)].

    Time series and phase plane always, the scene's own figure where it declares one; the family of initial displacements when
    one is given (studies.families.run_phase_family of the same run).
    """
    from springlab.plots import run as plots  # see render_run: matplotlib only when plots are drawn

    written = []
    figures = [
        ("time_series.png", "time series with the exact solution and the error", lambda: plots.time_series(result)),
        ("phase_plane.png", "phase plane", lambda: plots.phase_plane(result)),
        ("scene.png", "the scene's own figure (its declared panels)", lambda: plots.scene_figure(result)),
    ]
    if family is not None:
        figures.append(
            (
                "phase_family.png",
                "phase trajectories from several initial displacements",
                lambda: plots.phase_family(family),
            )
        )
    for name, title, make in figures:
        try:
            figure = make()
        except BadInputError:
            continue  # the scene does not define this figure for the scenario
        plots.save(figure, folder / name)
        written.append((str((folder / name).relative_to(out)), name, title))
    return written
