"""Videos and plots of runs, for the CLI (`render`, `plot`) and the demo's media step.

`render_run` turns a Result into a video (the 3D scene, optionally beside its
phase-plane trace: the composite video); `media_step` is the demo step that
writes every scenario's video and plots; `plot_files` writes one scenario's
plots. Nothing here knows a particular scene: everything comes from the Scene
hooks (camera, phase_field, equilibria, separatrices) and the Result.
"""

from __future__ import annotations

import math
import os
import pathlib
import time
from typing import Any

from . import api, progress, render, render_scale, scenes
from .errors import BadInputError, SpringlabError
from .outputs import Artifact

#: the demo's video settings: small enough that every scenario fits in the demo's time budget
DEMO_VIDEO: dict[str, int] = dict(fps=30, width=480, height=360)
#: longest video the demo films of a scenario [s of video] (the time overlay shows where it is)
DEMO_CLIP_SECONDS = 15.0


def render_run(
    result: api.Result,
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
        the run (api.run).
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
        from . import plots_panel  # imported here: matplotlib adds ~0.8 s to start-up, a plain video does not need it

        panel = plots_panel.PhasePanel(result, height)
    road_bump = None
    if {"bump_height", "bump_length", "speed"} <= set(result.parameters) and "road" in _joint_names(result.model):
        # the quarter car: the road it drives over is drawn, the exciter that realizes it is not
        p = result.parameters
        road_bump = render.RoadBump(
            p["bump_height"], p["bump_length"], p["speed"], "wheel_front_right", "wheel_rear_right"
        )
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
            road_bump=road_bump,
            antialias=antialias,
        )
    except RuntimeError as error:  # GL context or ffmpeg: not the user's input, still one clean line
        raise SpringlabError(f"cannot render {str(output)!r}: {error}") from None


def _joint_names(model) -> set[str]:
    return {model.joint(j).name for j in range(model.njnt)}


def default_slow_motion(result: api.Result, duration: float, fps: float) -> float:
    """render_scale.default_slow_motion for `duration` [s] of a run, from its scene's vibration modes [Hz]."""
    scene = scenes.get(result.scene)
    try:
        modes = scene.modes(result.model, result.parameters, scene.scenario(result.scenario))
    except (BadInputError, NotImplementedError):
        modes = []
    return render_scale.default_slow_motion(duration, fps, [omega / (2 * math.pi) for omega, _ in modes])


def plot_files(result: api.Result, folder: pathlib.Path, out: pathlib.Path) -> list[tuple[str, str, str]]:
    """Write a run's plots into `folder`: [(path relative to `out`, kind of plot, title)].

    Time series and phase plane always; the family of initial displacements
    and the zeta family where the scene defines them (skipped otherwise).
    """
    from . import plots  # see render_run: matplotlib only when plots are drawn

    written = []
    figures = [
        ("time_series.png", "time series with the exact solution and the error", lambda: plots.time_series(result)),
        ("phase_plane.png", "phase plane", lambda: plots.phase_plane(result)),
    ]
    scene = scenes.get(result.scene)
    scenario = scene.scenario(result.scenario)
    if (
        len(result.pos) == 1
        and scene.phase_field(result.model, result.parameters, scenario) is not None
        and scene.equilibria(result.model, result.parameters, scenario)
    ):
        figures.append(
            (
                "phase_family.png",
                "phase trajectories from several initial displacements",
                lambda: plots.family_of(result),
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


def media_step(state) -> list[Artifact]:
    """Demo step: every scenario's composite video and plots, and each scene's zeta family.

    Videos are 480 x 360 (+ a 360 x 360 phase panel) at 30 fps and show at
    most the first DEMO_CLIP_SECONDS of a run, which keeps the demo within a
    few minutes on two cores.
    """
    from . import plots  # see render_run: matplotlib only when plots are drawn

    written = []
    films = progress.bar(len(state.results), description="demo: filming", unit="video")  # on a terminal only
    for (scene_name, scenario_name), result in state.results.items():
        folder = state.out / scene_name / scenario_name
        start = time.perf_counter()
        video = folder / "video.mp4"
        slow = default_slow_motion(result, float(result.time[-1]), DEMO_VIDEO["fps"])
        clip = min(DEMO_CLIP_SECONDS / slow, float(result.time[-1]))
        info = render_run(
            result,
            video,
            fps=DEMO_VIDEO["fps"],
            width=DEMO_VIDEO["width"],
            height=DEMO_VIDEO["height"],
            duration=clip,
            composite=True,
            progress=False,
            slow_motion=slow,
        )
        shown = "" if clip >= float(result.time[-1]) else f", first {clip:g} s of {float(result.time[-1]):g} s"
        shown += "".join(", " + note for note in render_scale.labels(info["slow_motion"], info["exaggeration"]))
        written.append(
            Artifact(
                str(video.relative_to(state.out)),
                "video",
                f"3D scene beside its phase-plane trace, {info['fps']:g} fps{shown}",
                scene_name,
                scenario_name,
            )
        )
        for path, _, title in plot_files(result, folder, state.out):
            written.append(Artifact(path, "plot", title, scene_name, scenario_name))
        state.timings.append((f"media {scene_name}/{scenario_name}", time.perf_counter() - start))
        films.update(1)
    films.close()
    for scene in scenes.SCENES.values():
        target = state.out / scene.name / "zeta_family.png"
        try:
            figure = plots.zeta_family(scene.name, scene.default_scenario)
        except BadInputError:
            continue  # no damping parameter, no exact linear reference, or several modes
        plots.save(figure, target)
        written.append(
            Artifact(
                str(target.relative_to(state.out)),
                "plot",
                "the damping ratio from 0 to 2 (the chapter's zeta slider)",
                scene.name,
                scene.default_scenario,
            )
        )
    return written
