"""`springlab demo`, the main job: validate every scene and write everything a user looks at.

The demo runs in steps. The core step validates every scene and writes each
scenario's trajectory.csv and summary.json under out/<scene>/<scenario>/.
Features that add to the demo (videos, plots, trade-off charts, design
studies) are steps listed in STEPS; each step takes the output folder and
returns the artifacts it wrote, for the report.

An interrupted demo never leaves a report that looks whole: while it runs,
out/INCOMPLETE.txt says so and the previous out/index.html is gone (its files
are being replaced); the marker goes only after the new index.html is in place.
"""

from __future__ import annotations

import concurrent.futures
import pathlib
import time
from collections.abc import Callable

from springlab import files, outputs, progress, scenes
from springlab.errors import BadInputError
from springlab.exact.linear import single_threaded_blas
from springlab.runs.run import Result, ValidationRow
from springlab.studies import auto, families
from springlab.studies.families import PhaseFamily

from . import workers
from .state import Artifact, DemoState


def core_step(state: DemoState, each_run: Callable[[tuple[str, str], Result], None] | None = None) -> list[Artifact]:
    """Validate every scene; run every scenario at its default setting and write its files.

    `each_run(key, result)`, when given, is called with each run as soon as it is made (the demo hands it to
    the workers that film it).
    """
    written = []
    for scene in scenes.SCENES.values():
        for scenario in scene.scenarios.values():
            result = auto.run_scene(scene.name, scenario.name)
            state.results[(scene.name, scenario.name)] = result
            if each_run is not None:
                each_run((scene.name, scenario.name), result)
            if scenario.exact:
                state.validation.append(ValidationRow.of(result))
            folder = pathlib.Path(scene.name) / scenario.name
            outputs.write(result, state.out / folder)
            written.append(Artifact(str(folder / "trajectory.csv"), "data", "trajectory", scene.name, scenario.name))
            written.append(Artifact(str(folder / "summary.json"), "data", "summary", scene.name, scenario.name))
    files.write_text_files(
        state.out, {"validation.json": files.dumps([row.to_dict() for row in state.validation]) + "\n"}
    )
    written.append(Artifact("validation.json", "data", "validation table"))
    return written


#: the demo's video settings: small enough that every scenario fits in the demo's time budget
DEMO_VIDEO: dict[str, int] = dict(fps=30, width=480, height=360)
#: longest video the demo films of a scenario [s of video] (the time overlay shows where it is)
DEMO_CLIP_SECONDS = 15.0


def media_step(state: DemoState) -> list[Artifact]:
    """Demo step: every scenario's composite video and plots, and each scene's zeta family.

    Videos are 480 x 360 (+ a 360 x 360 phase panel) at 30 fps and show at
    most the first DEMO_CLIP_SECONDS of a run, which keeps the demo within a
    few minutes on two cores. `run_demo` draws them on its worker processes
    (springlab.demo.workers), each run as soon as the core step made it: the
    same files, listed in the same order.
    """
    written = []
    films = progress.bar(len(state.results), description="demo: filming", unit="video")  # on a terminal only
    for key in state.results:
        artifacts, timing = _film(state, key)
        written += artifacts
        state.timings.append(timing)
        films.update(1)
    films.close()
    for name in scenes.SCENES:
        written += _zeta_family(state, name)
    return written


def _film(state: DemoState, key: tuple[str, str]) -> tuple[list[Artifact], tuple[str, float]]:
    """One run's composite video and plots (media_step's part for it): its artifacts and (what, wall time [s])."""
    # GL and matplotlib are imported only when the demo draws
    from springlab.render import scale as render_scale
    from springlab.render.media import default_slow_motion, plot_files, render_run

    scene_name, scenario_name = key
    result = state.results[key]
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
    written = [
        Artifact(
            str(video.relative_to(state.out)),
            "video",
            f"3D scene beside its phase-plane trace, {info['fps']:g} fps{shown}",
            scene_name,
            scenario_name,
        )
    ]
    try:
        family: PhaseFamily | None = families.run_phase_family(result)
    except BadInputError:
        family = None  # no phase plane with an equilibrium for this scenario
    for path, _, title in plot_files(result, folder, state.out, family):
        written.append(Artifact(path, "plot", title, scene_name, scenario_name))
    return written, (f"media {scene_name}/{scenario_name}", time.perf_counter() - start)


def _zeta_family(state: DemoState, name: str) -> list[Artifact]:
    """A scene's zeta family plot (none for a scene without a damping parameter or a single-mode reference)."""
    from springlab.plots import run as plots

    scene = scenes.SCENES[name]
    target = state.out / scene.name / "zeta_family.png"
    try:
        zetas = families.run_zeta_family(scene.name, scene.default_scenario)
    except BadInputError:
        return []  # no damping parameter, no exact linear reference, or several modes
    plots.save(plots.zeta_family(zetas), target)
    title = "the damping ratio from 0 to 2 (the chapter's zeta slider)"
    return [Artifact(str(target.relative_to(state.out)), "plot", title, scene.name, scene.default_scenario)]


def _film_job(key: tuple[str, str], result: Result) -> tuple[list[Artifact], tuple[str, float]]:
    """In a worker: one run's media (the run crosses as an argument; the workers were forked before it existed)."""
    return _film(DemoState(out=workers.forked_state().out, results={key: result}), key)


def _zeta_job(name: str) -> list[Artifact]:
    """In a worker: a scene's zeta family plot."""
    return _zeta_family(workers.forked_state(), name)


def _timed(step: Callable[[DemoState], list[Artifact]], state: DemoState) -> tuple[list[Artifact], float]:
    """One step on `state`: its artifacts and its wall time [s]."""
    start = time.perf_counter()
    artifacts = step(state)
    return artifacts, time.perf_counter() - start


def _step_job(step: Callable[[DemoState], list[Artifact]]) -> tuple[list[Artifact], list[tuple[str, float]], float]:
    """In a worker: one step; its artifacts, the finer timings it reported and its wall time [s]."""
    state = DemoState(out=workers.forked_state().out)
    artifacts, seconds = _timed(step, state)
    return artifacts, state.timings, seconds


#: the steps the workers start first, longest first (each step's CPU time [s] alone, measured once on a 2-core
#: machine): the films, short and many, queue behind them and fill the cores to the end; a step not listed starts
#: after the listed ones. The order changes only when each file is written, never what it holds.
STEP_CPU_S: dict[str, float] = {
    "design_step": 24.4,
    "random_load_step": 22.7,
    "friction_step": 19.6,
    "tradeoff_step": 9.1,
    "refine_step": 5.0,
    "frequency_step": 4.0,
    "control_step": 3.2,
    "audit_step": 1.6,
}


def report_step(state: DemoState) -> list[Artifact]:
    """out/index.html: validation table, plots, videos and a link to every artifact (springlab.demo.report)."""
    from . import report

    path = report.write_report(state, wall_time_s=time.perf_counter() - state.started)
    return [Artifact(path.name, "report", "this report")]


#: written into the output folder while the demo runs, removed once the report is complete
INCOMPLETE_MARKER = "INCOMPLETE.txt"
#: the report file, the folder's "this is whole" (report.write_report's name)
REPORT_NAME = "index.html"


def run_demo(out: str | pathlib.Path, log: Callable[[str], None] = print) -> DemoState:
    """Run every step into `out`; return the shared state (validation rows, artifacts).

    While it runs, `out`/INCOMPLETE.txt marks the folder incomplete and no
    index.html is there; an interruption (Ctrl-C, SIGTERM) or an error leaves
    it so.
    """
    state = DemoState(out=files.prepare_directory(out))
    files.write_text_files(
        state.out,
        {
            INCOMPLETE_MARKER: f"springlab demo started writing this folder at {time.strftime('%Y-%m-%d %H:%M:%S')}"
            " and has not finished: its files may be a mix of this run and an earlier one, and it has no report"
            " yet. Run 'springlab demo' again to complete it.\n"
        },
    )
    (state.out / REPORT_NAME).unlink(missing_ok=True)  # a stale report would describe files being replaced
    # one BLAS thread (exact.linear.single_threaded_blas): the workers and this process fill the cores, and
    # OpenBLAS's own threads on top of them wait on each other (the stay cable's Lyapunov solves took several times
    # their CPU); the same numbers on any machine, whatever its cores
    with single_threaded_blas():
        pool = workers.Workers(state)  # forked now, before any run or GL context exists in this process
        try:
            _run_steps(state, pool, log)
        except BaseException:
            pool.stop()  # interrupted or failed: nothing more is started, running jobs unwind their files
            raise
    (state.out / INCOMPLETE_MARKER).unlink(missing_ok=True)
    return state


def _run_steps(state: DemoState, pool: workers.Workers, log: Callable[[str], None]) -> None:
    """Every step on the workers, the core step here (its runs go to the workers to be filmed as they come),
    then the final steps here; artifacts and timings in STEPS order whatever order the jobs finished in.

    Run one after the other, the demo took 199 s on an idle 2-core machine; with the media on two workers beside
    the studies it took 136-175 s with one core idle during the core step. Queued on two workers from the start,
    longest first, the cores stay busy to the end.
    """
    side = [step for step in STEPS if step not in (core_step, media_step)]
    queued = sorted(side, key=lambda step: -STEP_CPU_S.get(step.__name__, 0.0))  # sorted() is stable
    step_jobs = {step: pool.submit(_step_job, step) for step in queued}
    zeta_jobs = [pool.submit(_zeta_job, name) for name in scenes.SCENES]
    film_jobs: list[concurrent.futures.Future[tuple[list[Artifact], tuple[str, float]]]] = []
    started = time.perf_counter()
    for step in STEPS:
        if step is core_step:
            state.artifacts.extend(
                core_step(state, lambda key, result: film_jobs.append(pool.submit(_film_job, key, result)))
            )
            seconds, where = time.perf_counter() - started, ""
            state.timings.append(("core_step", seconds))
        elif step is media_step:
            for film in film_jobs:
                artifacts, timing = film.result()
                state.artifacts.extend(artifacts)
                state.timings.append(timing)
            for zeta in zeta_jobs:
                state.artifacts.extend(zeta.result())
            seconds, where = time.perf_counter() - started, " (on the workers, from the start)"
            state.timings.append(("media_step", seconds))
        else:
            artifacts, timings, seconds = step_jobs[step].result()
            where = " (on a worker)"
            state.artifacts.extend(artifacts)
            state.timings += [*timings, (step.__name__, seconds)]
        log(f"demo: {step.__name__} done in {seconds:.1f} s{where}")
    pool.finish()
    for step in FINAL_STEPS:
        artifacts, seconds = _timed(step, state)
        state.artifacts.extend(artifacts)
        state.timings.append((step.__name__, seconds))
        log(f"demo: {step.__name__} done in {seconds:.1f} s")


def tradeoff_step(state: DemoState) -> list[Artifact]:
    """The slider's speed-accuracy trade (with the setting for 1e-6) and the stability map, extremes, energy."""
    from springlab.studies import (
        stability,
        tradeoff,  # here: mujoco.batch and matplotlib only when this step runs
    )

    result = tradeoff.tradeoff("slider", "free", tol=1e-6)
    outputs.write(result, state.out / "tradeoff")
    report = stability.stability_report()
    outputs.write(report, state.out / "stability", amplification=stability.amplification_map())
    return [
        Artifact(
            "tradeoff/tradeoff.json",
            "data",
            "slider free: error, steps and wall time of every integrator"
            " x timestep; orders, Pareto front, cheapest setting for 1e-6",
            "slider",
            "free",
        ),
        Artifact(
            "tradeoff/tradeoff.png",
            "plot",
            "slider free: error vs timestep and error vs cost (Pareto front)",
            "slider",
            "free",
        ),
        Artifact(
            "stability/stability.json",
            "data",
            "measured stability boundaries vs theory, extremes table, undamped energy vs formulas",
        ),
        Artifact(
            "stability/stability.png",
            "plot",
            "stability map: measured per-step amplification over (zeta, omega*dt), theory and measured boundaries",
        ),
        Artifact("stability/energy.png", "plot", "undamped energy of each integrator vs its exact formula"),
    ]


def design_step(state: DemoState) -> list[Artifact]:
    """The printer head's design study: 7^4 = 2401 configurations, plus a 31 x 31 plane for the plot."""
    from springlab.studies.design import study as design  # here: mujoco.batch is only needed by this step

    study = design.run_study("printer_head")
    outputs.write(study, state.out / "design")
    state.timings.append(("design sweep (batched MuJoCo)", study.wall_time_s))
    return [
        Artifact(
            "design/design.json",
            "data",
            "printer head: how fast can it be positioned, which properties"
            " matter (elasticities, analytic estimate vs simulation)",
            "printer_head",
            "move",
        ),
        Artifact(
            "design/configurations.csv",
            "data",
            f"printer head: every one of the {study.size} configurations' move, settling and positioning time",
            "printer_head",
            "move",
        ),
        Artifact(
            "design/design.png",
            "plot",
            "printer head: positioning time over the two most influential properties; analytic estimate vs simulation",
            "printer_head",
            "move",
        ),
    ]


#: the printer head's control section: where it writes, and the side-by-side video's length [s of simulation]
CONTROL_FOLDER = pathlib.Path("printer_head") / "control"
CONTROL_CLIP_S = 0.1


def control_step(state: DemoState) -> list[Artifact]:
    """The printer head with control (issue 35): the answer table for the inkjet and a 3D-printer axis, the
    shapers' residual vibration with MuJoCo's points, the loops' step responses against the exact sampled loop,
    and the unshaped and ZV-shaped moves side by side in one video."""
    from springlab.plots import control as control_plots  # here: matplotlib, GL only when this step runs
    from springlab.render import scale as render_scale
    from springlab.render.video import render_video
    from springlab.scenes.printer_head import answers, figures

    folder = state.out / CONTROL_FOLDER
    start = time.perf_counter()
    tables = [answers.positioning_table(name) for name in answers.PRESETS]
    files.write_text_files(folder, {f"answers_{t.preset}.json": files.dumps(t.to_dict()) + "\n" for t in tables})
    written = [
        Artifact(
            str(CONTROL_FOLDER / f"answers_{table.preset}.json"),
            "data",
            table.question,
            "printer_head",
            answer="\n".join(table.sentences()),
        )
        for table in tables
    ]
    state.timings.append(("printer head control: the answer tables", time.perf_counter() - start))
    start = time.perf_counter()
    curves, responses = figures.shaper_curves(), figures.step_responses()
    control_plots.write(curves, responses, folder)
    written += [
        Artifact(
            str(CONTROL_FOLDER / "shapers.png"),
            "plot",
            "How much of the belt's vibration does each input shaper leave when the belt's frequency is off by up"
            " to 30 %? (exact curves, MuJoCo's runs as points)",
            "printer_head",
        ),
        Artifact(
            str(CONTROL_FOLDER / "step_response.png"),
            "plot",
            "Does MuJoCo run the sampled PD loop as the exact sampled-data loop says? (a 1 mm step, each encoder)",
            "printer_head",
        ),
    ]
    state.timings.append(("printer head control: the figures", time.perf_counter() - start))
    start = time.perf_counter()
    film = figures.side_by_side(duration=CONTROL_CLIP_S)
    slow = render_scale.default_slow_motion(CONTROL_CLIP_S, DEMO_VIDEO["fps"], [200.0])
    render_video(
        film.model,
        film.time,
        film.qpos,
        folder / "shaped_vs_unshaped.mp4",
        fps=DEMO_VIDEO["fps"],
        width=DEMO_VIDEO["width"],
        height=DEMO_VIDEO["height"],
        label=film.label,
        progress=False,
        slow_motion=slow,
        exaggerate=1.0,
    )
    written.append(
        Artifact(
            str(CONTROL_FOLDER / "shaped_vs_unshaped.mp4"),
            "video",
            f"the minimum-time move (top) and the ZV-shaped move (bottom) side by side: each carriage's and"
            f" motor's deviation from their centre of mass (the belt's ringing) drawn {film.exaggeration:g} times"
            f" larger (the ±10 µm band is ±{film.exaggeration * 1e-2:g} mm), 1/{slow:g} speed",
            "printer_head",
        )
    )
    state.timings.append(("printer head control: the video", time.perf_counter() - start))
    return written


#: the demo's refine study: the first sizes a scene declares (the rest take minutes) and this tolerance
DEMO_REFINE_SIZES = 5
DEMO_REFINE_TOL = 1e-3


def refine_step(state: DemoState) -> list[Artifact]:
    """How much model each question needs, for every scene whose model size is a parameter (`Scene.refinable`):
    the first declared question at DEMO_REFINE_TOL over its first DEMO_REFINE_SIZES sizes."""
    from springlab.studies import refine

    written = []
    for name in refine.refinable_scenes():
        spec = scenes.get(name).refinable
        assert spec is not None  # refinable_scenes lists only scenes that declare it
        study = refine.refine(name, tol=DEMO_REFINE_TOL, sizes=spec.sizes[:DEMO_REFINE_SIZES])
        folder = pathlib.Path("refine") / name
        outputs.write(study, state.out / folder)
        state.timings.append((f"refine {name} ({study.quantity})", study.sweep_wall_time_s))
        pick = study.recommendation
        answer = (
            f"cheapest for {DEMO_REFINE_TOL:g}: {study.size_parameter} = {pick.details['size']}, {pick.integrator} at dt ="
            f" {pick.dt:.3g} s (verified)"
            if pick is not None and pick.verified
            else f"no setting meets {DEMO_REFINE_TOL:g}"
        )
        written += [
            Artifact(
                str(folder / "refine.png"),
                "plot",
                f"{name}: how much model does {study.description} need? error vs cost over"
                f" {study.size_parameter} x integrator x dt; {answer}",
                name,
                study.scenario,
            ),
            Artifact(str(folder / "refine.json"), "data", f"{name}: the refine study of {study.quantity}", name),
        ]
    return written


def audit_step(state: DemoState) -> list[Artifact]:
    """`springlab audit` on the car's model, as any MJCF would be: modes, limits, error vs cost."""
    from springlab.studies.audit.audit import audit

    result = audit("car")
    outputs.write(result, state.out / "audit")
    state.timings.append(("audit of the car model (springlab audit)", result.timings.total_s))
    return [
        Artifact(
            "audit/audit.png",
            "plot",
            "audit of the car model: modes, stability limit per integrator vs its own timestep, error vs cost"
            " with the Pareto front and the cheapest setting for 1e-3",
        ),
        Artifact("audit/audit.json", "data", "audit of the car model (springlab audit car --json)"),
    ]


#: the friction-settings study the demo runs: each swept setting at MuJoCo's default and at its last
#: declared value, MuJoCo's default integrator, implicitfast and rk4, the declared timesteps but the smallest
DEMO_FRICTION_INTEGRATORS = ("implicitfast", "rk4")
#: the question the demo's friction-settings section answers
FRICTION_QUESTION = "How much does MuJoCo's friction drift, and what does it cost to make it stop?"


def friction_step(state: DemoState) -> list[Artifact]:
    """Every scene that declares dry friction (Scene.dry_friction): a smaller friction-settings study for 1e-2."""
    from springlab.studies import friction_settings

    written = []
    default_integrator, _ = friction_settings.mujoco_defaults()
    for scene in scenes.SCENES.values():
        spec = scene.dry_friction
        if spec is None:
            continue
        values = {s.name: tuple(dict.fromkeys((s.mujoco_default, s.values[-1]))) for s in spec.settings}
        integrators = tuple(dict.fromkeys((default_integrator, *DEMO_FRICTION_INTEGRATORS)))
        study = friction_settings.friction_settings(
            scene.name,
            tol=1e-2,
            integrators=integrators,
            dts=spec.dts[:-1] if len(spec.dts) > 2 else spec.dts,
            values=values,
        )
        folder = pathlib.Path(scene.name) / "friction_settings"
        outputs.write(study, state.out / folder)
        state.timings.append((f"friction settings of {scene.name} ({study.runs} runs)", study.wall_time_s))
        written += [
            Artifact(
                str(folder / "friction_settings.png"),
                "plot",
                FRICTION_QUESTION,
                scene.name,
                answer=study.answer_by_case(),
            ),
            Artifact(
                str(folder / "friction_settings.json"),
                "data",
                f"{scene.name}: every run of MuJoCo's friction settings, the model errors and the picks for 1e-2",
                scene.name,
            ),
            Artifact(str(folder / "friction_settings.csv"), "data", f"{scene.name}: one row per run", scene.name),
        ]
    return written


#: the demo's frequency responses: fewer points than the command's default (the figures look the same)
DEMO_FREQUENCY_POINTS = 100
#: the integrators whose largest dt for the band the demo searches (None: MuJoCo's five)
DEMO_FREQUENCY_INTEGRATORS: tuple[str, ...] | None = None


def frequency_step(state: DemoState) -> list[Artifact]:
    """Every scene's frequency questions (`Scene.frequency`): bode.png, frequency.json and frequency.csv under
    out/<scene>/frequency/<scenario>/, and the verdict (the band the scene's setting reproduces, the largest dt
    per integrator, the resonances and what they mean) as the answer, in the scene's section of the report."""
    from springlab.studies import frequency

    written = []
    for scene in scenes.SCENES.values():
        for scenario in frequency.declared_scenarios(scene.name):
            start = time.perf_counter()
            result = frequency.frequency(
                scene.name, scenario, points=DEMO_FREQUENCY_POINTS, integrators=DEMO_FREQUENCY_INTEGRATORS
            )
            folder = pathlib.Path(scene.name) / "frequency" / scenario
            outputs.write(result, state.out / folder)
            state.timings.append((f"frequency response of {scene.name}/{scenario}", time.perf_counter() - start))
            question = (
                f"Frequency response ({scenario}), {result.description}: up to which frequency does"
                f" {result.integrator} at dt = {result.dt:.3g} s reproduce it to {result.tol:g}, and what does each"
                " integrator need?"
            )
            # scene-level artifacts (no scenario): the report shows their answers in the scene's own block
            written += [
                Artifact(str(folder / "bode.png"), "plot", question, scene.name, answer="\n".join(result.verdict())),
                Artifact(
                    str(folder / "frequency.json"),
                    "data",
                    f"{scene.name} {scenario}: the exact and discrete responses, resonances, band per integrator",
                    scene.name,
                ),
            ]
    return written


#: the demo's records of each random-load scenario (the command's default is 40; the demo keeps a few)
DEMO_SEEDS = 8


def random_load_step(state: DemoState) -> list[Artifact]:
    """Every scene with a scenario under a random load (`Scene.random_load`): DEMO_SEEDS seeded records against
    the exact RMS and their intervals (springlab.studies.random_load), rms.png and rms.json under
    out/<scene>/rms/, the answer in the scene's section of the report."""
    from springlab.studies import random_load

    written = []
    for scene in scenes.SCENES.values():
        spec = scene.random_load
        if spec is None:
            continue
        result = random_load.ensemble(scene.name, seeds=DEMO_SEEDS)
        folder = pathlib.Path(scene.name) / "rms"
        outputs.write(result, state.out / folder)
        state.timings.append((f"{DEMO_SEEDS} records of {scene.name}/{spec.scenario}", result.wall_time_s))
        written += [
            Artifact(str(folder / "rms.png"), "plot", result.question, scene.name, spec.scenario, answer=result.answer),
            Artifact(
                str(folder / "rms.json"),
                "data",
                f"{scene.name}: {DEMO_SEEDS} seeded records of {spec.scenario} against the exact RMS",
                scene.name,
            ),
        ]
    return written


# -- issue 27: the textbook's interactive figure, real MuJoCo in the browser ----------------------


def interactive_step(state: DemoState) -> list[Artifact]:
    """Every scene's browser pages (springlab.render.interactive) under out/interactive/; skipped, in one
    line, where npm cannot supply MuJoCo's WebAssembly build (no Node.js and nothing cached)."""
    from springlab.render import interactive

    written: list[Artifact] = []
    for scene_name in interactive.interactive_scenes():
        try:
            pages = interactive.write_interactive(scene_name, None, state.out / "interactive")
        except interactive.NodeUnavailableError as error:
            print(f"demo: interactive page skipped: {error}")
            return written
        for page in pages:
            written.append(
                Artifact(
                    str(page.path.relative_to(state.out)),
                    "interactive",
                    f"interactive: move the damping ratio, mass, stiffness, dt and the integrator and watch MuJoCo"
                    f" (in your browser, {page.size_bytes / 1e6:.1f} MB) against the exact solution and springlab's"
                    " verdict",
                    page.scene,
                    page.scenario,
                )
            )
    return written


#: the demo's steps, in order (defined once, here: nothing is added at import time)
STEPS: tuple[Callable[[DemoState], list[Artifact]], ...] = (
    core_step,
    media_step,
    tradeoff_step,
    design_step,
    audit_step,
    friction_step,
    refine_step,
    frequency_step,
    random_load_step,
    control_step,
    interactive_step,
)
#: steps that run after every step in STEPS (the report lists everything)
FINAL_STEPS: tuple[Callable[[DemoState], list[Artifact]], ...] = (report_step,)
