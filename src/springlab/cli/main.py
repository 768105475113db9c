"""Watch textbook vibration problems run in MuJoCo, each checked against its exact solution.

The `springlab` command line (argparse; every command calls the library).
Exit codes: 0 ok; 1 a validation fell outside its tolerance; 2 bad input;
3 the simulation diverged (nothing written); 130 interrupted (Ctrl-C, SIGINT);
143 terminated (SIGTERM). Errors are one line on stderr.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import pathlib
import signal
import sys
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from typing import Any, NoReturn

import numpy as np

from springlab import __version__, files, scenes
from springlab.cli import text as cli_text
from springlab.demo import steps as demo
from springlab.errors import BadInputError, SpringlabError
from springlab.plots import audit as charts_audit
from springlab.plots import charts
from springlab.plots import frequency as charts_frequency
from springlab.runs.compare import Verdict
from springlab.runs.run import Result, write_run
from springlab.sim.simulate import INTEGRATORS
from springlab.studies import auto, stability, tradeoff
from springlab.studies.audit.audit import audit as run_audit
from springlab.studies.audit.options import DEFAULT_PERTURB, DEFAULT_TOL
from springlab.studies.executor import CONNECT_TIMEOUT_S, Executor
from springlab.studies.frequency import DEFAULT_POINTS
from springlab.studies.frequency import DEFAULT_TOL as FREQUENCY_TOL
from springlab.studies.frequency import frequency as run_frequency

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT, EXIT_DIVERGED = 0, 1, 2, 3
#: 128 + the signal number, as shells report a process a signal ended
EXIT_INTERRUPTED, EXIT_TERMINATED = 128 + signal.SIGINT, 128 + signal.SIGTERM


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors and exit code 2."""

    def error(self, message: str) -> NoReturn:  # noqa: D401 - argparse hook
        raise BadInputError(f"{message} (see '{self.prog} --help')")

    def parse_known_args(self, args=None, namespace=None):  # noqa: D401 - argparse hook
        # a command's own parser takes options and positionals in any order
        # (`run slider --set x0=0.05 harmonic`); argparse's intermixed parsing calls
        # back into this method, hence the guard
        if self._subparsers is not None or getattr(self, "_intermixing", False):
            return super().parse_known_args(args, namespace)
        self._intermixing = True
        try:
            return self.parse_known_intermixed_args(args, namespace)
        finally:
            self._intermixing = False


def _parse_sets(pairs: Sequence[str]) -> dict[str, Any]:
    """['mass=2', ...] -> {'mass': '2'}; values are checked by the scene.

    The values are strings; typed Any because they travel as ``**parameters`` next to typed keywords.
    """
    out: dict[str, Any] = {}
    for pair in pairs or ():
        name, sep, value = pair.partition("=")
        if not sep or not name.strip():
            raise BadInputError(f"--set takes NAME=VALUE, got {pair!r}")
        out[name.strip()] = value.strip()
    return out


def _scene_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="scene name (see 'springlab list')")
    parser.add_argument("scenario", nargs="?", help="scenario name (default: the scene's first)")
    parser.add_argument(
        "--set", action="append", default=[], metavar="NAME=VALUE", help="override a parameter, SI units (repeatable)"
    )


def _timing_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--integrator",
        choices=None,
        metavar="NAME",
        help=f"one of {', '.join(INTEGRATORS)} (default: the scene's validated one), or auto:"
        " the cheapest setting that meets --tol (see 'springlab tradeoff')",
    )
    parser.add_argument("--dt", type=float, metavar="SECONDS", help="timestep [s]")
    parser.add_argument("--duration", type=float, metavar="SECONDS", help="simulated time [s]")
    parser.add_argument(
        "--tol",
        type=float,
        metavar="TOL",
        help="relative tolerance to hold the run to (default: the integrator's predicted error)",
    )


def _print_json(value: Any) -> None:
    print(files.dumps(value))


def _executor_arguments(parser: argparse.ArgumentParser) -> None:
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--workers", type=int, metavar="N", help="run the chunks on a local dask cluster of N worker processes"
    )
    where.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run the chunks on a running dask scheduler, e.g. tcp://10.0.0.5:8786"
        f" (unreachable for {CONNECT_TIMEOUT_S:g} s: exit 2)",
    )
    parser.add_argument(
        "--verbose",
        action="store_true",
        help="with --workers/--scheduler: let dask.distributed's own log lines through to stderr",
    )


def _executor(args: argparse.Namespace, nthread: int = 0) -> Executor:
    """Where a study's chunks run: locally (default, on `nthread` threads), --workers N or --scheduler ADDRESS."""
    return Executor(
        workers=args.workers,
        scheduler=args.scheduler,
        progress=False if args.json else None,
        nthread=nthread,
        quiet=not args.verbose,
    )


# -- commands -----------------------------------------------------------------


def cmd_list(args: argparse.Namespace) -> int:
    catalogue: list[dict[str, Any]] = []
    for scene in scenes.SCENES.values():
        catalogue.append(
            {
                "scene": scene.name,
                "title": scene.title,
                "joints": list(scene.joints),
                "default_integrator": scene.integrator,
                "default_dt": scene.dt,
                "scenarios": {s.name: s.description for s in scene.scenarios.values()},
                # the setting `run` and `validate` use for each scenario (a scenario may validate its own dt)
                "scenario_settings": {
                    s.name: {"integrator": scene.integrator, "dt": s.dt or scene.dt, "duration": s.duration}
                    for s in scene.scenarios.values()
                },
                "parameters": {
                    p.name: {"unit": p.unit, "description": p.description, "valid": p.valid_range()}
                    for p in scene.parameters.values()
                },
            }
        )
    if args.json:
        _print_json(catalogue)
        return EXIT_OK
    cli_text.print_list(catalogue)
    return EXIT_OK


def _run(args: argparse.Namespace) -> Result:
    """springlab.run from the scene, timing and --set arguments that run, render and plot share."""
    return auto.run(
        args.scene,
        args.scenario,
        integrator=args.integrator,
        dt=args.dt,
        duration=args.duration,
        tol=args.tol,
        **_parse_sets(args.set),
    )


def cmd_run(args: argparse.Namespace) -> int:
    if args.record_every < 1:
        raise BadInputError(f"--record-every must be an integer >= 1, got {args.record_every}")
    result = _run(args)
    if args.output:
        write_run(args.output, result, every=args.record_every)
    if args.json:
        _print_json(result.to_dict())
    else:
        cli_text.print_run(result, args.output)
    for limit in result.model_limits:
        print(f"springlab: {result.scene} {result.scenario} is not validated: {limit}", file=sys.stderr)
    return EXIT_FAILED if result.passed is False else EXIT_OK


def cmd_validate(args: argparse.Namespace) -> int:
    rows = auto.validate(args.scenes, integrator=args.integrator, dt=args.dt, tol=args.tol)
    if args.json:
        _print_json([row.to_dict() for row in rows])
    else:
        cli_text.print_validate(rows)
    return EXIT_FAILED if any(not r.passed for r in rows) else EXIT_OK


def cmd_render(args: argparse.Namespace) -> int:
    """Simulate a scenario and film it off-screen (mp4 H.264 or gif), optionally with its phase plane."""
    from springlab.render import media
    from springlab.render import video as render  # GL and matplotlib only for the commands that draw

    render.check_video_arguments(args.output, args.fps, args.width, args.height)
    for name, value in (("--slow-motion", args.slow_motion), ("--exaggerate", args.exaggerate)):
        if value is not None:
            render.render_scale.check_factor(name, value)
    result = _run(args)
    files.prepare_directory(pathlib.Path(args.output).parent)
    info = media.render_run(
        result,
        args.output,
        fps=args.fps,
        width=args.width,
        height=args.height,
        composite=args.composite,
        slow_motion=args.slow_motion,
        exaggerate=args.exaggerate,
        antialias=args.antialias,
    )
    cli_text.print_render(info)
    return _verdict(result)


def cmd_plot(args: argparse.Namespace) -> int:
    """Plot a scenario: time series (default), phase plane, family of displacements or zeta family."""
    from springlab.plots import run as plots
    from springlab.studies import families

    plots.check_output(args.output)
    if args.kind == "zeta":
        figure = plots.zeta_family(
            families.run_zeta_family(
                args.scene,
                args.scenario,
                integrator=args.integrator,
                dt=args.dt,
                duration=args.duration,
                **_parse_sets(args.set),
            )
        )
        verdict = EXIT_OK
    else:
        result = _run(args)
        if args.kind == "family":
            figure = plots.phase_family(families.run_phase_family(result))
            verdict = EXIT_OK  # a family is a picture of many runs; the verdict belongs to single runs
        else:
            draw = {"time": plots.time_series, "phase": plots.phase_plane, "scene": plots.scene_figure}[args.kind]
            figure = draw(result)
            verdict = _verdict(result)
    print(f"wrote {plots.save(figure, args.output)}")
    return verdict


def _verdict(result: Result) -> int:
    """Exit code of a run whose outputs were written: 1 when outside its tolerance or its model's range."""
    for limit in result.model_limits:
        print(f"springlab: {result.scene} {result.scenario} is not validated: {limit}", file=sys.stderr)
    if result.model_limits:
        return EXIT_FAILED
    if result.passed is False:
        if result.verdict is Verdict.NOT_VALIDATED and result.estimate_range is not None:
            why = f"not validated ({result.estimate_range.reason()})"
        elif result.tolerance is not None:
            why = f"outside its tolerance (max error above {result.tolerance:.2e})"
        else:  # held to its checks alone
            why = f"outside its tolerance ({result.message})"
        print(f"  note: {result.scene}/{result.scenario} is {why}; see 'springlab run'", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK


def cmd_tradeoff(args: argparse.Namespace) -> int:
    if args.output:
        files.check_directory(args.output)  # before seconds of computing, not after
    with _executor(args) as executor:
        result = tradeoff.tradeoff(
            args.scene, args.scenario, tol=args.tol, duration=args.duration, executor=executor, **_parse_sets(args.set)
        )
    if args.output:
        charts.write_tradeoff(result, args.output)
    if args.json:
        _print_json(result.to_dict())
    else:
        cli_text.print_tradeoff(result, args.output)
    pick = result.recommendation
    return EXIT_FAILED if pick is not None and not pick.found else EXIT_OK


def cmd_refine(args: argparse.Namespace) -> int:
    """How much model a question needs: model size x integrator x timestep (springlab.studies.refine)."""
    from springlab.plots import refine as refine_chart  # matplotlib only when this command draws
    from springlab.studies import refine

    if args.output:
        files.check_directory(args.output)  # before the study's minute of computing, not after
    sizes = None
    if args.sizes:
        try:
            sizes = [float(s) for s in args.sizes.split(",")]
        except ValueError:
            raise BadInputError(f"--sizes takes whole numbers 'a,b,c', got {args.sizes!r}") from None
    integrators = args.integrators.split(",") if args.integrators else tuple(INTEGRATORS)
    with _executor(args) as executor:
        result = refine.refine(
            args.scene,
            args.question,
            tol=args.tol,
            sizes=sizes,  # type: ignore[arg-type]  # checked as the size parameter by the study
            integrators=integrators,
            duration=args.duration,
            executor=executor,
            **_parse_sets(args.set),
        )
    if args.output:
        refine_chart.write_refine(result, args.output)
    if args.json:
        _print_json(result.to_dict())
    else:
        cli_text.print_refine(result, args.output)
    pick = result.recommendation
    return EXIT_FAILED if pick is not None and not pick.found else EXIT_OK


def cmd_audit(args: argparse.Namespace) -> int:
    if args.output:
        files.check_directory(args.output)  # before seconds of computing, not after
    with _executor(args) as executor:
        result = run_audit(
            args.model,
            keyframe=args.keyframe,
            settle_s=args.settle,
            tol=args.tol,
            integrators=_audit_integrators(args.integrators),
            dts=_audit_dts(args.dt),
            duration=args.duration,
            perturb=args.perturb,
            executor=executor,
        )
    if args.output:
        charts_audit.write_audit(result, args.output)
    if args.json:
        _print_json(result.to_dict())
    else:
        cli_text.print_audit(result, args.output)
    return EXIT_OK if result.own_ok else EXIT_FAILED


def _audit_integrators(text: str | None) -> list[str] | None:
    """--integrators 'a,b' -> ['a', 'b'] (None: all five)."""
    if text is None:
        return None
    names = [name.strip() for name in text.split(",") if name.strip()]
    if not names:
        raise BadInputError(f"--integrators needs at least one of {', '.join(INTEGRATORS)}")
    return names


def _audit_dts(text: str | None) -> list[float] | None:
    """--dt: seconds 'a,b,c', or a range 'LOW:HIGH:N' (N log-spaced values, each snapped to HIGH / m for an
    integer m so that they share checkpoints); None: the audit's default grid."""
    if text is None:
        return None
    spec = text.strip()
    try:
        if ":" in spec:
            low_text, high_text, count_text = spec.split(":")
            low, high, count = float(low_text), float(high_text), int(count_text)
            if not (0 < low < high and math.isfinite(high) and count >= 2):
                raise ValueError
            values = sorted({high / round(high / v) for v in np.geomspace(low, high, count)}, reverse=True)
        else:
            values = [float(v) for v in spec.split(",") if v.strip()]
    except ValueError:
        raise BadInputError(
            f"--dt must be seconds 'a,b,c' or a range 'LOW:HIGH:N' with 0 < LOW < HIGH, N >= 2; got {text!r}"
        ) from None
    if not values or any(not (math.isfinite(v) and v > 0) for v in values):
        raise BadInputError(f"every dt must be a finite number > 0 s, got {text!r}")
    return values


def cmd_frequency(args: argparse.Namespace) -> int:
    if args.output:
        files.check_directory(args.output)  # before the analysis, not after
    with _executor(args) as executor:
        result = run_frequency(
            args.model,
            args.scenario,
            input=args.input,
            response=args.response,
            band=args.band,
            points=args.points,
            integrator=args.integrator,
            dt=args.dt,
            tol=args.tol,
            sines=args.sinestream,
            executor=executor,
            parameters=_parse_sets(args.set),
            amplitudes=_parse_amplitudes(args.amplitude),
            sweep=args.sweep,
        )
    if args.output:
        charts_frequency.write_frequency(result, args.output)
    if args.json:
        _print_json(result.to_dict())
    else:
        cli_text.print_frequency(result, args.output)
    # several amplitudes ask whether the response depends on the amplitude: a non-linear model's departure from
    # its linearization is then the answer, not a failure; a sweep must stay within its harmonic-balance bound
    single = len(result.sinestreams) <= 1
    agrees = (result.sinestream is None or result.sinestream.agrees or not single) and result.sweeps_agree
    return EXIT_OK if result.covers_band and agrees else EXIT_FAILED


def _parse_amplitudes(text: str | None) -> tuple[float, ...] | None:
    """'A1,A2,...' -> floats (checked by springlab.frequency); None: the default amplitude."""
    if text is None:
        return None
    try:
        return tuple(float(part) for part in text.split(","))
    except ValueError:
        raise BadInputError(f"--amplitude takes A1,A2,... in input units (e.g. 0.5,2), got {text!r}") from None


def cmd_stability(args: argparse.Namespace) -> int:
    if args.output:
        files.check_directory(args.output)  # before seconds of computing, not after
    with _executor(args) as executor:
        report = stability.stability_report(full=args.full, executor=executor)
        amplification = stability.amplification_map(executor=executor) if args.output else None
    if args.output:
        assert amplification is not None  # computed above whenever there is an output folder
        charts.write_stability(report, amplification, args.output)
    if args.json:
        _print_json(report.to_dict())
    else:
        cli_text.print_stability(report, args.output)
    return EXIT_OK if report.passed else EXIT_FAILED


def cmd_design(args: argparse.Namespace) -> int:
    from springlab.plots import (
        design as design_chart,  # here, not at the top: mujoco.batch is only needed by this command
    )
    from springlab.studies.design import study as design

    if args.output:
        files.check_directory(args.output)  # before seconds of computing, not after
    overrides = _parse_sets(args.set)
    if args.sobol is not None:
        from springlab.studies.design import sobol

        _, spec = design.declaration(args.scene)
        sobol.check_base_samples(args.sobol, len(spec.sobol))  # bad input before minutes of simulation
    with _executor(args, nthread=args.threads) as executor:
        study = design.run_study(
            args.scene,
            levels=args.levels,
            plane_levels=args.plane,
            executor=executor,
            omega_dt=design.OMEGA_DT,
            sobol=args.sobol,
            seed=args.seed,
            **overrides,
        )
    if args.output:
        design.write(study, args.output)
        design_chart.plot(study, pathlib.Path(args.output) / "design.png")
        if study.sobol is not None:
            design_chart.plot_sobol(study.sobol, pathlib.Path(args.output) / "sobol.png")
    if args.json:
        _print_json(study.to_dict())
    else:
        cli_text.print_design(study, args.output)
        if study.sobol is not None:
            cli_text.print_sobol(study.sobol, args.output)
    return EXIT_OK


def cmd_sweep(args: argparse.Namespace) -> int:
    from springlab.plots import sweep as sweep_plot
    from springlab.studies import sweeps

    if args.output:
        files.check_directory(args.output)  # before seconds of computing, not after
    with _executor(args) as executor:
        result = sweeps.sweep(
            args.scene,
            args.scenario,
            vary=args.vary,
            samples=args.samples,
            seed=args.seed,
            integrator=args.integrator,
            dt=args.dt,
            duration=args.duration,
            executor=executor,
            **_parse_sets(args.set),
        )
    if args.output:
        sweep_plot.write(result, args.output, args.quantity)
    if args.json:
        _print_json(result.to_dict())
        return EXIT_OK
    cli_text.print_sweep(result, args.quantity, args.output)
    return EXIT_OK


def cmd_friction_settings(args: argparse.Namespace) -> int:
    from springlab.plots import friction_settings as friction_chart  # matplotlib only for this command
    from springlab.studies import friction_settings

    if args.output:
        files.check_directory(args.output)  # before minutes of computing, not after
    integrators = [name.strip() for name in args.integrators.split(",")] if args.integrators else None
    dts = _numbers("--dt", args.dt) if args.dt else None
    with _executor(args) as executor:
        study = friction_settings.friction_settings(
            args.scene,
            args.scenarios or None,
            tol=args.tol,
            integrators=integrators,
            dts=dts,
            executor=executor,
            **_parse_sets(args.set),
        )
    if args.output:
        friction_chart.write(study, args.output)
    if args.json:
        _print_json(study.to_dict())
    else:
        cli_text.print_friction_settings(study, args.output)
    return EXIT_FAILED if any(c.pick is not None and not c.pick.found for c in study.cases) else EXIT_OK


def _numbers(option: str, text: str) -> list[float]:
    """'a,b,c' -> [a, b, c] (floats), or BadInputError naming the option."""
    try:
        return [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise BadInputError(f"{option} takes numbers separated by commas, e.g. 0.002,0.001; got {text!r}") from None


def cmd_fit(args: argparse.Namespace) -> int:
    # here, not at the top: mujoco.sysid and scipy load only for fits; `from .fit import`, because
    # springlab.fit (the attribute) is the function once springlab/__init__ has run
    from springlab.plots.fit import plot_fit
    from springlab.studies.fit.fit import fit, write

    if args.output:
        files.check_directory(args.output)  # before seconds of computing, not after
    with _executor(args) as executor:
        result = fit(
            args.scene,
            args.data,
            args.scenario,
            map=args.map,
            free=args.free or None,
            scale=args.scale,
            time_scale=args.time_scale,
            start=args.start,
            degree=args.degree,
            starts=args.starts,
            executor=executor,
            show_progress=False if args.json else None,
            **_parse_sets(args.set),
        )
    if args.output:
        write(result, args.output)
        plot_fit(result, pathlib.Path(args.output) / "fit.png")
    if args.json:
        _print_json(result.to_dict())
    else:
        cli_text.print_fit(result, args.output)
    return EXIT_OK if result.converged else EXIT_FAILED


def cmd_demo(args: argparse.Namespace) -> int:
    """The main job: validate every scene and write everything under the output folder."""
    start = time.perf_counter()
    try:
        state = demo.run_demo(args.output)
    except (KeyboardInterrupt, Terminated) as stop:
        marker = pathlib.Path(args.output) / demo.INCOMPLETE_MARKER
        if marker.exists():
            stop.add_note(f"; {args.output}/ is incomplete (see {marker})")  # main() prints it
        raise
    cli_text.print_demo(state.validation, len(state.artifacts), state.out, time.perf_counter() - start)
    return EXIT_FAILED if any(not r.passed for r in state.validation) else EXIT_OK


def cmd_view(args: argparse.Namespace) -> int:
    """Watch a scene's validated run (or any MJCF) live in MuJoCo's interactive viewer (springlab.cli.view)."""
    from springlab.cli import view  # GLFW only for the command that opens a window

    result = view.command(args, _run)
    return EXIT_OK if result is None else _verdict(result)


# -- springlab interactive (issue 27): a scenario with real MuJoCo in the browser ---------------


def cmd_interactive(args: argparse.Namespace) -> int:
    """Write the scenario's interactive page (MuJoCo's WebAssembly build, sliders, exact solution, verdict)."""
    from springlab.render import interactive

    pages = interactive.write_interactive(args.scene, args.scenario, args.output)
    if args.json:
        _print_json([page.to_dict() for page in pages])
    else:
        others = f" and {len(pages) - 1} more scenarios beside it" if len(pages) > 1 else ""
        print(
            f"wrote {pages[0].path}{others} ({pages[0].size_bytes / 1e6:.1f} MB with MuJoCo"
            f" {interactive.MUJOCO_JS_MUJOCO} as WebAssembly); open it from disk or a web server"
        )
    return EXIT_OK


# -- parser --------------------------------------------------------------------

COMMANDS: dict[str, Callable[[argparse.Namespace], int]] = {}


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="springlab",
        description=__doc__.splitlines()[0],
        epilog="Start with 'springlab list' and 'springlab run slider'. Exit codes: 0 ok, 1 outside tolerance,"
        " 2 bad input, 3 diverged, 130 interrupted, 143 terminated.",
    )
    parser.add_argument("--version", action="version", version=f"springlab {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser, metavar="COMMAND")

    p = sub.add_parser("list", help="scenes, scenarios and parameters")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    COMMANDS["list"] = cmd_list

    p = sub.add_parser("run", help="simulate one scenario and compare it with its exact solution")
    _scene_arguments(p)
    _timing_arguments(p)
    p.add_argument("--output", metavar="DIR", help="write DIR/trajectory.csv and DIR/summary.json")
    p.add_argument("--record-every", type=int, default=1, metavar="N", help="keep every N-th step in the CSV")
    p.add_argument("--json", action="store_true", help="print summary.json")
    COMMANDS["run"] = cmd_run

    p = sub.add_parser("validate", help="check every exact scenario against its tolerance")
    p.add_argument("scenes", nargs="*", help="scene names (default: all)")
    p.add_argument("--integrator", metavar="NAME", help="override the scenes' integrator")
    p.add_argument("--dt", type=float, metavar="SECONDS", help="override the scenes' timestep [s]")
    p.add_argument(
        "--tol", type=float, metavar="TOL", help="relative tolerance to hold every run to (needed by --integrator auto)"
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    COMMANDS["validate"] = cmd_validate

    p = sub.add_parser(
        "render", help="film a scenario off-screen: mp4 (H.264) or gif, optionally beside its phase plane"
    )
    _scene_arguments(p)
    _timing_arguments(p)
    p.add_argument("--output", required=True, metavar="FILE", help="FILE.mp4 (H.264, plays in browsers) or FILE.gif")
    p.add_argument("--fps", type=float, default=30, help="frames per second; video time = simulation time (default 30)")
    p.add_argument("--width", type=int, default=640, help="width of the 3D view [px] (default 640)")
    p.add_argument("--height", type=int, default=480, help="height of the 3D view [px] (default 480)")
    p.add_argument(
        "--composite",
        action="store_true",
        help="add the phase-plane trace drawn as time advances, a height x height panel on the right",
    )
    p.add_argument(
        "--slow-motion",
        type=float,
        metavar="FACTOR",
        help="play FACTOR times slower (drawing only; default: short runs slowed to >= 90 frames and 6 frames"
        " per period of their fastest mode, e.g. the printer move at 1/50 speed; written on every frame)",
    )
    p.add_argument(
        "--exaggerate",
        type=float,
        metavar="FACTOR",
        help="draw displacements FACTOR times larger around their mean (drawing only; default: motions below"
        " 1%% of the body's size magnified to about 3%%, e.g. the car x30; written on every frame)",
    )
    p.add_argument(
        "--antialias",
        action="store_true",
        help="smooth edges by multisampling (about 3x slower per frame on a CPU renderer; default off)",
    )
    COMMANDS["render"] = cmd_render

    p = sub.add_parser("plot", help="plot a scenario: time series, phase plane, family, zeta family")
    _scene_arguments(p)
    _timing_arguments(p)
    p.add_argument("--output", required=True, metavar="FILE", help="FILE.png, FILE.svg or FILE.pdf")
    p.add_argument(
        "--kind",
        default="time",
        choices=("time", "phase", "family", "zeta", "scene"),
        help="time: x(t), v(t) with the exact solution and the error on a log axis (default); "
        "phase: phase plane with vector field, equilibria, separatrices; "
        "scene: the panels the scene declares (e.g. the drill string's speeds, twist and mode shapes); "
        "family: phase trajectories from several initial displacements; "
        "zeta: responses for damping ratios 0 to 2",
    )
    COMMANDS["plot"] = cmd_plot

    p = sub.add_parser("tradeoff", help="error vs cost of every integrator and timestep; cheapest setting for --tol")
    _scene_arguments(p)
    p.add_argument(
        "--tol", type=float, metavar="TOL", help="recommend the cheapest setting meeting this relative error"
    )
    p.add_argument("--duration", type=float, metavar="SECONDS", help="simulated time [s] (default: the scenario's)")
    _executor_arguments(p)
    p.add_argument("--output", metavar="DIR", help="write DIR/tradeoff.json and DIR/tradeoff.png")
    p.add_argument("--json", action="store_true", help="print tradeoff.json")
    COMMANDS["tradeoff"] = cmd_tradeoff

    p = sub.add_parser(
        "refine", help="how much model a question needs: model size x integrator x timestep, cheapest for --tol"
    )
    p.add_argument("scene", help="a scene whose model size is a parameter (see docs/cli.md)")
    p.add_argument("--question", metavar="QUANTITY", help="the quantity to answer (default: the scene's first)")
    p.add_argument(
        "--tol", type=float, metavar="TOL", help="recommend the cheapest verified setting meeting this relative error"
    )
    p.add_argument("--sizes", metavar="A,B,C", help="model sizes to sweep (default: the scene's)")
    p.add_argument("--integrators", metavar="A,B", help=f"integrators to sweep (default: {','.join(INTEGRATORS)})")
    p.add_argument("--duration", type=float, metavar="SECONDS", help="simulated time [s] (default: the scenario's)")
    p.add_argument(
        "--set", action="append", default=[], metavar="NAME=VALUE", help="override a parameter, SI units (repeatable)"
    )
    _executor_arguments(p)
    p.add_argument("--output", metavar="DIR", help="write DIR/refine.json and DIR/refine.png")
    p.add_argument("--json", action="store_true", help="print refine.json")
    COMMANDS["refine"] = cmd_refine

    p = sub.add_parser("stability", help="stability boundaries vs theory, extremes table, undamped energy")
    p.add_argument(
        "--full",
        action="store_true",
        help="more damping ratios and extreme cases, advice verified by running it (slower)",
    )
    _executor_arguments(p)
    p.add_argument("--output", metavar="DIR", help="write DIR/stability.json, stability.png and energy.png")
    p.add_argument("--json", action="store_true", help="print stability.json")
    COMMANDS["stability"] = cmd_stability

    p = sub.add_parser("audit", help="any MJCF: modes, stability limits, error vs cost, the cheapest setting for --tol")
    p.add_argument("model", help="path to an MJCF (or URDF) file, or a scene name")
    p.add_argument("--keyframe", metavar="NAME|INDEX", help="operating point (default: first keyframe, else qpos0)")
    p.add_argument(
        "--settle",
        type=float,
        metavar="SECONDS",
        help="let the model move this long at its own setting first and audit it where it comes to rest"
        " (a robot standing or lying on the floor; default: audit the keyframe as it is)",
    )
    p.add_argument(
        "--tol", type=float, default=DEFAULT_TOL, metavar="TOL", help="error tolerance in (0, 1) (default 1e-3)"
    )
    p.add_argument("--integrators", metavar="A,B", help=f"integrators to sweep (default: {','.join(INTEGRATORS)})")
    p.add_argument("--dt", metavar="LIST|RANGE", help="timesteps 'a,b,c' or 'LOW:HIGH:N' [s] (default: automatic)")
    p.add_argument("--duration", type=float, metavar="SECONDS", help="simulated time [s] (default 1; a scene's own)")
    p.add_argument(
        "--perturb",
        type=float,
        default=DEFAULT_PERTURB,
        metavar="SIZE",
        help="initial perturbation of the operating point [m or rad] (default 1e-3)",
    )
    p.add_argument("--output", metavar="DIR", help="write DIR/audit.json and DIR/audit.png")
    p.add_argument("--json", action="store_true", help="print audit.json")
    _executor_arguments(p)
    COMMANDS["audit"] = cmd_audit

    p = sub.add_parser(
        "frequency", help="frequency response of any model's linearization, and the band an integrator reproduces"
    )
    p.add_argument("model", help="path to an MJCF file, or a scene name")
    p.add_argument("scenario", nargs="?", help="a scene's scenario (default: the one its frequency response declares)")
    p.add_argument("--input", metavar="NAME", help="an actuator (its control) or JOINT:force (a force on the joint)")
    p.add_argument(
        "--response", metavar="NAME", help="JOINT (position), JOINT:vel, JOINT:acc, or a sensor SENSOR or SENSOR[i]"
    )
    p.add_argument(
        "--set", action="append", default=[], metavar="NAME=VALUE", help="a scene's parameter, SI units (repeatable)"
    )
    p.add_argument(
        "--band",
        metavar="FMIN:FMAX",
        help="frequency band [Hz] (default: a decade below the slowest mode to 3x the fastest)",
    )
    p.add_argument(
        "--points", type=int, default=DEFAULT_POINTS, metavar="N", help="log-spaced frequencies (default 200)"
    )
    p.add_argument(
        "--integrator", metavar="NAME", help=f"one of {', '.join(INTEGRATORS)} (default: the scene's or model's)"
    )
    p.add_argument("--dt", type=float, metavar="SECONDS", help="timestep [s] (default: the scene's or model's)")
    p.add_argument(
        "--tol",
        type=float,
        default=FREQUENCY_TOL,
        metavar="TOL",
        help="tolerance on the relative error |H_d / H - 1| in (0, 1) (default 1e-3)",
    )
    p.add_argument(
        "--sinestream",
        type=int,
        default=0,
        metavar="N",
        help="verify by simulating N sines in MuJoCo over the band and an octave above (default 0: none)",
    )
    p.add_argument(
        "--amplitude",
        metavar="A1,A2,...",
        help="sinestream input amplitudes in input units (N for a force); several show amplitude dependence",
    )
    p.add_argument(
        "--sweep",
        choices=("up", "down", "both"),
        help="sweep the band in frequency, each sine from the last one's state (a non-linear model's jump)",
    )
    p.add_argument("--output", metavar="DIR", help="write DIR/frequency.json, frequency.csv and bode.png")
    p.add_argument("--json", action="store_true", help="print frequency.json")
    _executor_arguments(p)
    COMMANDS["frequency"] = cmd_frequency

    p = sub.add_parser("design", help="design study: positioning time over a property sweep, ranked sensitivities")
    declared = ", ".join(name for name, scene in scenes.SCENES.items() if scene.design is not None)
    p.add_argument("scene", help=f"scene with a design study: {declared}")
    p.add_argument(
        "--levels",
        type=int,
        default=7,
        metavar="N",
        help="odd number of grid points per property, N^4 configurations (default 7: 2401)",
    )
    p.add_argument(
        "--plane",
        type=int,
        default=31,
        metavar="N",
        help="odd grid points per axis of the plotted plane over the two most influential properties,"
        " N^2 more configurations (default 31: 961; 0: plot the grid's slice)",
    )
    p.add_argument("--threads", type=int, default=0, metavar="N", help="batch threads (default 0: one per CPU)")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="start the sweep from another parameter value, SI units (repeatable)",
    )
    p.add_argument(
        "--sobol",
        type=int,
        nargs="?",
        const=16384,
        metavar="N",
        help="also Sobol indices of carriage mass, belt stiffness, damping ratio, force and move length:"
        " N x 7 runs, N a power of 2 (bare --sobol: 16384, 114,688 runs)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the Sobol sequence and bootstrap (default 0)")
    _executor_arguments(p)
    p.add_argument(
        "--output", metavar="DIR", help="write DIR/design.json, configurations.csv, design.png (and sobol.png)"
    )
    p.add_argument("--json", action="store_true", help="print design.json")
    COMMANDS["design"] = cmd_design

    p = sub.add_parser("sweep", help="run a scenario over a grid (or random samples) of parameters, batched")
    _scene_arguments(p)
    p.add_argument(
        "--vary",
        action="append",
        default=[],
        required=True,
        metavar="NAME=LOW:HIGH:N[:log]",
        help="vary a parameter over N values from LOW to HIGH, SI units (repeatable; :log for log spacing)",
    )
    p.add_argument("--samples", type=int, metavar="N", help="N random points in the box instead of the full grid")
    p.add_argument("--seed", type=int, default=0, help="seed of the random points (default 0)")
    p.add_argument("--integrator", metavar="NAME", help=f"one of {', '.join(INTEGRATORS)} (default: the scene's)")
    p.add_argument("--dt", type=float, metavar="SECONDS", help="timestep [s] (default: the scene's validated one)")
    p.add_argument("--duration", type=float, metavar="SECONDS", help="simulated time [s] (default: the scenario's)")
    p.add_argument(
        "--quantity", metavar="NAME", help="what sweep.png shows (default: the scenario's headline quantity)"
    )
    _executor_arguments(p)
    p.add_argument("--output", metavar="DIR", help="write DIR/sweep.csv and DIR/sweep.png")
    p.add_argument("--json", action="store_true", help="print the sweep (setting, counts, every row) as JSON")
    COMMANDS["sweep"] = cmd_sweep

    p = sub.add_parser(
        "friction-settings",
        help="MuJoCo's friction settings vs exact dry friction: model error, error vs cost, the cheapest for --tol",
    )
    frictional = ", ".join(name for name, scene in scenes.SCENES.items() if scene.dry_friction is not None)
    p.add_argument("scene", help=f"a scene with exact dry-friction cases: {frictional}")
    p.add_argument("scenarios", nargs="*", help="its cases to sweep (default: all)")
    p.add_argument("--tol", type=float, metavar="TOL", help="pick the cheapest setting meeting this relative error")
    p.add_argument("--integrators", metavar="A,B", help=f"integrators to sweep (default: {','.join(INTEGRATORS)})")
    p.add_argument("--dt", metavar="LIST", help="timesteps to sweep, e.g. 0.002,0.001 [s] (default: the scene's)")
    p.add_argument(
        "--set", action="append", default=[], metavar="NAME=VALUE", help="a parameter that is not swept (repeatable)"
    )
    _executor_arguments(p)
    p.add_argument(
        "--output", metavar="DIR", help="write friction_settings.json, friction_settings.csv, friction_settings.png"
    )
    p.add_argument("--json", action="store_true", help="print friction_settings.json")
    COMMANDS["friction-settings"] = cmd_friction_settings

    p = sub.add_parser("fit", help="identify a scene's parameters from a recorded signal (CSV)")
    # the scenes that declare a fit (Scene.fit), e.g. "slider, car, printer_head or kinematics"
    fittable = [name for name, scene in scenes.SCENES.items() if scene.fit is not None]
    listed = ", ".join(fittable[:-1]) + " or " + fittable[-1] if len(fittable) > 1 else "".join(fittable)
    p.add_argument("scene", help=listed)
    p.add_argument(
        "data", metavar="DATA.csv", help="header row (',', ';' or tab); time [s] and <joint>_pos, _vel or _acc [SI]"
    )
    p.add_argument("--scenario", metavar="S", help="the scenario the record shows (default: the scene's fit default)")
    p.add_argument(
        "--map", action="append", default=[], metavar="COLUMN=NAME", help="rename a file column (t=time, x=slider_pos)"
    )
    p.add_argument(
        "--free", action="append", default=[], metavar="NAME[,NAME...]", help="names to fit (default: the scene's)"
    )
    p.add_argument(
        "--set", action="append", default=[], metavar="NAME=VALUE", help="fix a parameter, SI units (repeatable)"
    )
    p.add_argument("--start", type=float, metavar="S", help="release time [s]: drop the record before it")
    p.add_argument(
        "--scale",
        type=float,
        metavar="FACTOR",
        help="SI units per unit of the signal column (mm: 0.001); default: the unit its name states (x_mm, x [mm]), else SI",
    )
    p.add_argument(
        "--time-scale",
        type=float,
        metavar="FACTOR",
        help="seconds per unit of the time column (ms: 0.001); default: the unit its name states (t_ms, t (ms)), else s",
    )
    p.add_argument("--degree", type=int, metavar="N", help="kinematics: degree 0-3 of the polynomial")
    p.add_argument(
        "--starts",
        type=int,
        default=1,
        metavar="N",
        help="independent optimizations, the lowest cost wins (default 1: the linear-algebra start)",
    )
    _executor_arguments(p)
    p.add_argument("--output", metavar="DIR", help="write fit.json, fit.png, trajectory.csv and summary.json")
    p.add_argument("--json", action="store_true", help="print fit.json")
    COMMANDS["fit"] = cmd_fit

    p = sub.add_parser("view", help="watch a scene's validated run (or any MJCF) live in MuJoCo's interactive viewer")
    p.add_argument("scene", metavar="SCENE|MODEL.xml", help="scene name (see 'springlab list') or an MJCF file")
    p.add_argument("scenario", nargs="?", help="scenario name (default: the scene's first)")
    p.add_argument(
        "--set", action="append", default=[], metavar="NAME=VALUE", help="override a parameter, SI units (repeatable)"
    )
    _timing_arguments(p)
    p.add_argument(
        "--slow-motion",
        type=float,
        default=1.0,
        metavar="FACTOR",
        help="run FACTOR times slower (default 1: real time)",
    )
    p.add_argument(
        "--exaggerate",
        type=float,
        metavar="FACTOR",
        help="draw displacements FACTOR times larger around their mean, as 'render' does (default: render's)",
    )
    p.add_argument("--close-after", type=float, metavar="SECONDS", help="close the window after SECONDS of wall time")
    COMMANDS["view"] = cmd_view
    p = sub.add_parser("interactive", help="a scenario as a web page running MuJoCo in the browser, with sliders")
    p.add_argument("scene", help="a scene that runs in the browser (slider)")
    p.add_argument("scenario", nargs="?", help="one of its scenarios that run in the browser (default: all of them)")
    p.add_argument("--output", required=True, metavar="DIR", help="folder for SCENE-SCENARIO.html and its scripts")
    p.add_argument("--json", action="store_true", help="print what was written as JSON")
    COMMANDS["interactive"] = cmd_interactive

    p = sub.add_parser("demo", help="the main job: validate everything, write out/")
    p.add_argument("--output", default="out", metavar="DIR", help="output folder (default: out)")
    COMMANDS["demo"] = cmd_demo
    return parser


class Terminated(BaseException):
    """SIGTERM arrived (a timeout, a batch scheduler): unwinds like Ctrl-C, so partial files are removed."""


def _raise_terminated(signum, frame) -> None:
    raise Terminated


@contextlib.contextmanager
def _sigterm_unwinds() -> Iterator[None]:
    """Turn SIGTERM into the Terminated exception for the duration (main thread only; restored after)."""
    try:
        previous = signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `springlab` console script; returns the exit code."""
    try:
        # the terminal gets springlab's one-line answers, never warning text (numpy's overflow
        # warnings at extreme values, library deprecations); the API leaves warnings alone
        with _sigterm_unwinds(), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            args = build_parser().parse_args(argv)
            return COMMANDS[args.command](args)
    except SystemExit as done:  # --help, --version
        return done.code if isinstance(done.code, int) else EXIT_OK
    except SpringlabError as error:
        print(f"springlab: error: {error}", file=sys.stderr)
        return error.exit_code
    except KeyboardInterrupt as stop:
        print(f"springlab: interrupted{''.join(getattr(stop, '__notes__', ()))}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated as stop:
        print(f"springlab: terminated{''.join(getattr(stop, '__notes__', ()))}", file=sys.stderr)
        return EXIT_TERMINATED
    except BrokenPipeError:
        # the reader went away (`springlab list | head`): stop quietly, as Unix tools do;
        # point stdout at devnull so the interpreter's final flush cannot raise again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141


if __name__ == "__main__":
    sys.exit(main())
