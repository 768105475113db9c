"""Behaviour snapshot: run a fixed list of springlab commands, keep what they print and write, diff two runs.

A refactor must not change any command's output (issue 32). This script proves it:

    python tools/snapshot.py --output /tmp/snap-before        # on the commit before the change
    python tools/snapshot.py --output /tmp/snap-after         # on the change
    python tools/snapshot.py --diff /tmp/snap-before /tmp/snap-after

Every case of `CASES` runs `sys.executable -m springlab ...` in a fresh temporary folder (MUJOCO_GL=egl
unless set; PYTHONPATH and the rest of the environment passed through, so point PYTHONPATH at the
checkout's `src` to snapshot another checkout). Per case DIR/<case>/ holds `record.json` (each step's argv,
exit code, stdout and stderr, the temporary folder's path, and every file the case left: JSON and CSV by
content, every other file as exists + size class) and a copy of the JSON/CSV files under `files/`.

The snapshot is stored raw; masking happens when diffing, so a better mask needs no new baseline:

- timings: JSON keys whose values are measured times or rates (`TIMING_KEYS`), CSV columns of those names,
  and the few timing numbers the text prints (`TEXT_TIMINGS`) become `<timing>`;
- the case's temporary folder becomes `<tmp>`, springlab's and MuJoCo's versions become `<version>`;
- fields chosen *from* measured timings (the recommendations and Pareto fronts of tradeoff, refine,
  friction-settings and audit; `TIMING_CHOSEN`) are compared too but listed in a separate "timing-chosen"
  section that does not fail the diff: issue 32 makes them deterministic on purpose.

Floats are compared exactly (the refactor must be bit-identical); `--rtol R` lists floats equal within R
in a separate "near-equal" section that does not fail. The diff exits 1 when anything else differs.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import csv
import dataclasses
import difflib
import io
import json
import math
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from typing import Any

#: a small MJCF of no scene's: two blocks on springs in a chain, one motor (audit and frequency on a file)
CHAIN_XML = """<mujoco model="snapshot_chain">
  <option timestep="0.002" integrator="RK4" gravity="0 0 0"/>
  <worldbody>
    <body name="first">
      <joint name="x1" type="slide" axis="1 0 0" stiffness="100" damping="0.5"/>
      <geom type="box" size=".05 .05 .05" mass="1" contype="0" conaffinity="0"/>
      <body name="second" pos="0.2 0 0">
        <joint name="x2" type="slide" axis="1 0 0" stiffness="50" damping="0.2"/>
        <geom type="box" size=".05 .05 .05" mass="0.5" contype="0" conaffinity="0"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor name="push" joint="x1"/></actuator>
</mujoco>
"""

#: what a case may find in its folder before it runs
INPUTS: dict[str, Callable[[pathlib.Path], None]] = {
    "chain.xml": lambda folder: (folder / "chain.xml").write_text(CHAIN_XML),
}


@dataclasses.dataclass(frozen=True)
class Case:
    """One snapshot case: springlab command lines run one after the other in one fresh folder.

    Attributes
    ----------
    name
        the case's folder name in the snapshot.
    steps
        argument lists after `python -m springlab`; every step's output is kept (an earlier step can make
        the data a later one reads).
    inputs
        names of `INPUTS` written into the folder first.
    """

    name: str
    steps: tuple[tuple[str, ...], ...]
    inputs: tuple[str, ...] = ()


def _case(name: str, *argv: str, inputs: tuple[str, ...] = ()) -> Case:
    return Case(name, (tuple(argv),), inputs)


#: every scene of `springlab list` but the stay cable, run at its default scenario (the stay cable: STAY_CABLE)
SCENES = ("slider", "car", "printer_head", "kinematics", "nonlinear", "drill_string", "friction")
#: the printer head's shaped moves, its feedback loops and its resonance test, run with --json
PRINTER_CONTROL = ("move_zv", "move_ei", "feedback_motor", "feedback_carriage", "resonance_test")
#: every stay cable scenario, run with --json
STAY_CABLE = ("modes", "damper", "wind", "rain_wind")
TINY_VIDEO = ("--width", "64", "--height", "48", "--duration", "0.2")

#: the fixed list: every command of `springlab --help` but demo (minutes) and view (a window), with its
#: cheap options; writing commands write into `out` and print text, a few print --json as well
CASES: tuple[Case, ...] = (
    _case("version", "--version"),
    _case("help", "--help"),
    _case("list", "list"),
    _case("list_json", "list", "--json"),
    *(_case(f"run_{scene}", "run", scene, "--output", "out") for scene in SCENES),
    _case("run_slider_json", "run", "slider", "--json"),
    _case("run_slider_harmonic_set", "run", "slider", "harmonic", "--set", "mass=2", "--set", "damping=0.5", "--json"),
    _case("run_slider_euler_dt", "run", "slider", "underdamped", "--integrator", "euler", "--dt", "0.001"),
    _case("run_slider_record_every", "run", "slider", "step", "--record-every", "10", "--output", "out"),
    _case("run_car_road_bump", "run", "car", "road_bump", "--json"),
    _case("run_car_pitch_heave", "run", "car", "pitch_heave", "--duration", "1", "--output", "out"),
    _case("run_nonlinear_double_well", "run", "nonlinear", "double_well", "--json"),
    _case("run_friction_incline_hold", "run", "friction", "incline_hold", "--json"),
    _case("run_kinematics_tachograph", "run", "kinematics", "tachograph", "--json"),
    _case("run_printer_settle_tol", "run", "printer_head", "settle", "--tol", "1e-3", "--json"),
    # the scenes landed after the first baseline: their exact sides (eigen-solves, Lyapunov maps, held loops,
    # the resonance fit) are where a change to the exact layer shows first
    *(_case(f"run_printer_{name}", "run", "printer_head", name, "--json") for name in PRINTER_CONTROL),
    *(_case(f"run_stay_cable_{name}", "run", "stay_cable", name, "--json") for name in STAY_CABLE),
    _case("validate_all", "validate"),
    _case("validate_json", "validate", "slider", "kinematics", "--json"),
    _case("validate_override", "validate", "slider", "--integrator", "euler", "--dt", "0.001", "--json"),
    _case("plot_time", "plot", "slider", "step", "--output", "t.png"),
    _case("plot_phase_svg", "plot", "nonlinear", "double_well", "--kind", "phase", "--output", "p.svg"),
    _case("plot_zeta", "plot", "slider", "--kind", "zeta", "--output", "z.png"),
    _case("plot_family_pdf", "plot", "nonlinear", "softening", "--kind", "family", "--output", "f.pdf"),
    _case("plot_scene", "plot", "drill_string", "--kind", "scene", "--output", "s.png"),
    _case("render_mp4", "render", "slider", *TINY_VIDEO, "--output", "v.mp4"),
    _case("render_gif_composite", "render", "slider", "underdamped", *TINY_VIDEO, "--composite", "--output", "v.gif"),
    _case("tradeoff", "tradeoff", "slider", "exercise", "--tol", "1e-4", "--duration", "2", "--output", "out"),
    _case("tradeoff_json", "tradeoff", "car", "push_release", "--tol", "1e-3", "--duration", "1", "--json"),
    _case("stability", "stability", "--output", "out"),
    _case(
        "sweep_grid",
        "sweep",
        "slider",
        "free",
        "--vary",
        "mass=1:2:3",
        "--vary",
        "damping=0.1:1:2:log",
        "--output",
        "out",
    ),
    _case(
        "sweep_samples_json",
        "sweep",
        "slider",
        "harmonic",
        "--vary",
        "stiffness=50:200:4",
        "--samples",
        "5",
        "--seed",
        "3",
        "--json",
    ),
    _case("design", "design", "printer_head", "--levels", "3", "--plane", "5", "--sobol", "8", "--output", "out"),
    _case("audit_scene", "audit", "slider", "--duration", "1", "--output", "out"),
    _case(
        "audit_mjcf_json",
        "audit",
        "chain.xml",
        "--integrators",
        "rk4,euler",
        "--dt",
        "0.004,0.002,0.001",
        "--json",
        inputs=("chain.xml",),
    ),
    Case(
        "fit_slider",
        (
            ("run", "slider", "--output", "data"),
            ("fit", "slider", "data/trajectory.csv", "--output", "out"),
        ),
    ),
    _case(
        "frequency_scene",
        "frequency",
        "slider",
        "--band",
        "0.1:10",
        "--points",
        "40",
        "--dt",
        "1e-3",
        "--output",
        "out",
    ),
    _case("frequency_printer_answers", "frequency", "printer_head", "--points", "40", "--json"),
    _case(
        "frequency_car_set",
        "frequency",
        "car",
        "pitch_heave",
        "--set",
        "damping_ratio=0.05",
        "--points",
        "40",
        "--json",
    ),
    _case(
        "frequency_mjcf_sinestream",
        "frequency",
        "chain.xml",
        "--input",
        "push",
        "--response",
        "x2",
        "--points",
        "30",
        "--sinestream",
        "3",
        "--output",
        "out",
        inputs=("chain.xml",),
    ),
    _case(
        "friction_settings",
        "friction-settings",
        "friction",
        "coulomb_decay",
        "--integrators",
        "rk4",
        "--dt",
        "0.001,0.0005",
        "--tol",
        "1e-2",
        "--output",
        "out",
    ),
    _case(
        "refine", "refine", "drill_string", "--sizes", "2,4", "--integrators", "rk4", "--tol", "1e-2", "--output", "out"
    ),
    _case("interactive", "interactive", "slider", "free", "--output", "page", "--json"),
    _case("interactive_car_all", "interactive", "car", "--output", "page"),
    # exit 3: diverged
    _case("diverged_render_dt", "render", "slider", "--dt", "0.5", "--output", "v.mp4"),
    # bad input: one line, exit 2
    _case("bad_scene", "run", "nosuchscene"),
    _case("bad_scenario", "run", "slider", "nosuchscenario"),
    _case("bad_set", "run", "slider", "--set", "mass=-1"),
    _case("bad_set_name", "run", "slider", "--set", "colour=3"),
    _case("bad_dt", "run", "slider", "--dt", "0"),
    _case("bad_tol", "tradeoff", "slider", "free", "--tol", "0"),
    _case("bad_plot_kind", "plot", "slider", "--kind", "pie", "--output", "p.png"),
    _case("bad_plot_suffix", "plot", "slider", "--output", "t.jpg"),
    _case("bad_plot_zeta_two_modes", "plot", "car", "pitch_heave", "--kind", "zeta", "--output", "z.png"),
    _case("bad_audit_file", "audit", "missing.xml"),
    _case("bad_fit_file", "fit", "slider", "missing.csv"),
    _case("bad_frequency_band", "frequency", "slider", "--band", "10:1"),
    _case("bad_refine_scene", "refine", "slider"),
    _case("bad_refine_sizes", "refine", "drill_string", "--sizes", "4,x"),
    _case("bad_friction_scene", "friction-settings", "slider"),
    _case("bad_friction_dt", "friction-settings", "friction", "--dt", "0.001"),
    _case("bad_design_scene", "design", "slider"),
    _case("bad_design_levels", "design", "printer_head", "--levels", "4"),
    _case("bad_sweep_vary", "sweep", "slider", "--vary", "mass=1:2"),
    _case("bad_interactive_scene", "interactive", "drill_string", "--output", "page"),
    _case("bad_view_scene", "view", "nosuchscene"),
    _case("bad_validate_scene", "validate", "nosuchscene"),
)

#: JSON keys (and CSV columns) whose values are measured on this machine, read from the code at 50f4227:
#: time.perf_counter / time.thread_time spans and what is computed from them
TIMING_KEYS = frozenset(
    {
        "wall_time_s",  # run, validate, tradeoff/refine/audit rows, stability, sweep, design, frequency, friction
        "sweep_wall_time_s",  # tradeoff, refine
        "cpu_time_s",  # friction-settings rows (time.thread_time around the rollout)
        "timings_s",  # audit: the parts' wall times
        "cost_per_step_s",  # refine sizes: the fewest seconds of wall time per step
        "cost_per_simulated_second_s",  # refine sizes: cost_per_step_s / stable dt
        "cost_growth",  # refine: exponent fitted to those costs
        "step_cost_growth",  # refine: the same for cost_per_step_s
        "speedup",  # friction-settings pick: CPU time ratio
        "configurations_per_s",  # sweep, design: configurations / wall time
        "runs_per_s",  # design's sobol: runs / wall time
        "rollout_time_s",  # fit optimizer: summed rollout wall time
        "time_per_rollout_s",  # fit optimizer
        "seconds",  # render's statistics
    }
)

#: (case-name pattern, JSON path pattern): fields chosen from measured timings, shown apart, never failing.
#: A path is the dotted/indexed JSON path of a value, e.g. `recommendation.dt` or `pareto[3].integrator`.
TIMING_CHOSEN: tuple[tuple[str, str], ...] = (
    (r"^(tradeoff|refine|audit)", r"^(recommendation|pareto)(\.|\[|$)"),  # cheapest by wall time, its front
    (r"^friction_settings", r"^cases\[\d+\]\.(pick|pareto|answer)(\.|\[|$)"),  # by CPU time; answer names the pick
    # the extremes' advice: the cheapest integrator by a per-step cost timed once (extremes.py, _advice), and
    # the rows that run that advice (moved to `extremes_advised` by _reshape, so their count may change)
    (r"^stability", r"^extremes\[\d+\]\.advice$"),
    (r"^stability", r"^extremes_advised(\[|$)"),
)

_NUMBER = r"[0-9][0-9.e+-]*"
#: text lines of measured timings: (case pattern, line pattern, replacement). Specific on purpose, so a
#: physical time ("settles in 0.089 s") is never masked; the format strings are in cli/text.py.
TEXT_TIMINGS: tuple[tuple[str, str, str], ...] = (
    # run: "slider / free: rk4, dt = 0.005 s, 1000 steps in 20.7 ms"
    (r"^(run|fit)", rf"^(.* / .*: .*, \d+ steps) in {_NUMBER} ms$", r"\1 in <timing> ms"),
    # render: "... (0.2 s of simulation, 1/20 speed) in 1.3 s (95 frames/s)"
    (r"^render", rf"^(wrote .* speed\)) in {_NUMBER} s \({_NUMBER} frames/s\)$", r"\1 in <timing>"),
    # tradeoff and refine: "65 runs over 2 s in 1.7 s"
    (r"^(tradeoff|refine)", rf"^(.* \d+ runs over {_NUMBER} s) in {_NUMBER} s$", r"\1 in <timing>"),
    # tradeoff's table: wall [ms] and wall/sim s (the work column and the Pareto mark, by counted work, stay)
    (
        r"^tradeoff",
        rf"^(  \w+ +{_NUMBER} +\d+ +(?:{_NUMBER}|diverged) +{_NUMBER}) +{_NUMBER} +{_NUMBER}ms(  .*)$",
        r"\1 <timing> <timing>\2",
    ),
    # the pick's sentence (tradeoff's and refine's "tol ...", friction-settings' "pick: ..."): its run's time
    (
        r"^(tradeoff|refine|friction_settings)",
        rf"^(  .*) Measured time of its run: {_NUMBER} ms\.(.*)$",
        r"\1 Measured time of its run: <timing>.\2",
    ),
    (r"^stability", rf"^done in {_NUMBER} s$", "done in <timing>"),
    # sweep: "6 configurations (...) in 0.36 s on local (17/s, 1 chunks)"
    (
        r"^sweep",
        rf"^(.* configurations \(.*\)) in {_NUMBER} s on (.*) \({_NUMBER}/s, (.*)$",
        r"\1 in <timing> on \2 (<timing>, \3",
    ),
    # design: "81 configurations (...) in 3.5 s, 23/s on 2 threads", "56 runs in 2.1 s on local (27/s), ..."
    (r"^design", rf"^(.* configurations \(.*\)) in {_NUMBER} s, {_NUMBER}/s(.*)$", r"\1 in <timing>\2"),
    (
        r"^design",
        rf"^(Sobol indices .*: \d+ runs) in {_NUMBER} s on (\S+) \({_NUMBER}/s\)(.*)$",
        r"\1 in <timing> on \2\3",
    ),
    # fit: "19 rollouts of 1003 steps (27.2 ms each), 0.84 s"
    (r"^fit", rf"^(  optimizer: .* steps) \({_NUMBER} ms each\), {_NUMBER} s$", r"\1 (<timing>)"),
    # friction-settings: "friction: 32 runs in 7.5 s (rk4; ...)"
    (r"^friction_settings", rf"^(\w+: \d+ runs) in {_NUMBER} s (\(.*)$", r"\1 in <timing> \2"),
    # refine's sizes table: per step [us] and [ms/s] columns; the growth line
    (r"^refine", r"^( +\d+ +[0-9.e+-]+ +(?:[0-9.e+-]+|-))  .*$", r"\1 <timing>"),
    (r"^refine", r"^(  (?:cost per step ~|per simulated second at the stability limit:)).*$", r"\1 <timing>"),
    # the timings inside the lines TEXT_CHOSEN moves apart, so that section shows what was chosen
    # refine's Pareto front rows: "... error 1.5e-02) work 312, 0.132 ms" (the work stays)
    (r"^refine", rf"^(    \w+ = \d+ .*\) work {_NUMBER},) {_NUMBER} ms$", r"\1 <timing> ms"),
    (r"^audit", rf"^(cheapest meeting tol .*) at {_NUMBER}x the cost of yours(.*)$", r"\1 at <timing> the cost\2"),
    (r"^friction_settings", rf"^(.*), (?:{_NUMBER}x the cost of MuJoCo's defaults|cost unknown)\.$", r"\1, <timing>."),
    # friction-settings' Pareto front: "... rk4  0.001  3.51e-03  1.2e+04  17.56" (cpu [ms] masked, the work stays)
    (
        r"^friction_settings",
        rf"^(  .*  (?:euler|implicit|implicitfast|rk4|discrete) +{_NUMBER} +{_NUMBER} +{_NUMBER}) +{_NUMBER}$",
        r"\1 <timing>",
    ),
)

#: text lines chosen from measured timings: (case pattern, line pattern, what the main text keeps or None).
#: The line goes to the timing-chosen section; the main text keeps the replacement (None: drops the line).
TEXT_CHOSEN: tuple[tuple[str, str, str | None], ...] = (
    (r"^tradeoff", r"^  tol \S+: use .*$", None),
    (r"^refine", r"^  tol \S+: use .*$", None),
    (r"^refine", r"^    \w+ = \d+ +\w+ +dt = .* ms$", None),  # the Pareto front's rows
    (r"^audit", r"^cheapest meeting tol .*$", None),
    (r"^friction_settings", r"^(.*?) ?Cheapest setting meeting .*$", r"\1"),
    (
        r"^friction_settings",
        r"^  (Pareto front  .*|.*  (euler|implicit|implicitfast|rk4|discrete) +[0-9.e-]+ .*)$",
        None,
    ),
    (r"^stability", r"^  \w+ +\w+ +advised .*$", None),  # the advised run
    (r"^stability", r"^(.*  (?:accurate|inaccurate|diverged) +(?:[0-9.e+-]+|-))  .*$", r"\1"),  # the advice column
)

VERSION_KEYS = frozenset({"version", "springlab_version", "mujoco_version"})
FILE_CONTENT = (".json", ".csv")


def _size_class(size: int) -> str:
    """Coarse size: a figure's bytes move with its plotted timings, its decade rarely does."""
    if size == 0:
        return "empty"
    decade = int(math.log10(size))
    return f"1e{decade}-1e{decade + 1} bytes"


def _run_case(case: Case, output: pathlib.Path, env: dict[str, str]) -> float:
    """Run one case in a fresh folder and store its record; its wall time [s]."""
    started = time.perf_counter()
    target = output / case.name
    target.mkdir(parents=True)
    with tempfile.TemporaryDirectory(prefix=f"snap-{case.name}-") as scratch:
        folder = pathlib.Path(scratch)
        for name in case.inputs:
            INPUTS[name](folder)
        before = {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()}
        steps = []
        for argv in case.steps:
            done = subprocess.run(
                [sys.executable, "-m", "springlab", *argv],
                cwd=folder,
                env=env,
                capture_output=True,
                text=True,
                timeout=600,
            )
            steps.append(
                {"argv": list(argv), "exit_code": done.returncode, "stdout": done.stdout, "stderr": done.stderr}
            )
        files: dict[str, Any] = {}
        for path in sorted(p for p in folder.rglob("*") if p.is_file()):
            relative = path.relative_to(folder).as_posix()
            if relative in before:
                continue
            if path.suffix in FILE_CONTENT:
                copy = target / "files" / relative
                copy.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(path, copy)
                files[relative] = {"content": True}
            else:
                files[relative] = {"size": _size_class(path.stat().st_size)}
        record = {"case": case.name, "folder": str(folder), "steps": steps, "files": files}
    (target / "record.json").write_text(json.dumps(record, indent=1) + "\n")
    return time.perf_counter() - started


def snapshot(output: pathlib.Path, only: set[str] | None, jobs: int) -> int:
    """Run the cases (all, or those named) into `output`, `jobs` at a time; 0 (2: bad arguments)."""
    unknown = (only or set()) - {c.name for c in CASES}
    if unknown:
        print(
            f"unknown case(s): {', '.join(sorted(unknown))}; valid: {', '.join(c.name for c in CASES)}", file=sys.stderr
        )
        return 2
    if output.exists() and any(output.iterdir()):
        print(f"{output} exists and is not empty: give a new folder", file=sys.stderr)
        return 2
    output.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env.setdefault("MUJOCO_GL", "egl")
    total = time.perf_counter()
    chosen = [case for case in CASES if not only or case.name in only]
    timings = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(jobs, 1)) as pool:
        running = {pool.submit(_run_case, case, output, env): case.name for case in chosen}
        for done in concurrent.futures.as_completed(running):
            timings[running[done]] = done.result()
            print(f"{running[done]:34s} {timings[running[done]]:6.1f} s", flush=True)
    wall = time.perf_counter() - total
    (output / "timings.json").write_text(json.dumps({"total_s": wall, "cases_s": timings}, indent=1) + "\n")
    print(f"{len(timings)} cases in {wall:.0f} s -> {output}")
    return 0


# --- masking ---------------------------------------------------------------------------------------------


def _mask_text(text: str, folder: str) -> str:
    """Temporary paths and versions of one text replaced by placeholders."""
    text = text.replace(folder, "<tmp>")
    text = re.sub(r"\bspringlab \d+(\.\d+)+\S*", "springlab <version>", text)
    return re.sub(r"\bMuJoCo \d+\.\d+\.\d+", "MuJoCo <version>", text)


def _split_text(text: str, folder: str, case: str) -> tuple[str, str]:
    """A printed text as (its lines with timings masked, its lines chosen from timings)."""
    timings = [(re.compile(line), repl) for pattern, line, repl in TEXT_TIMINGS if re.search(pattern, case)]
    choices = [(re.compile(line), keep) for pattern, line, keep in TEXT_CHOSEN if re.search(pattern, case)]
    kept, chosen = [], []
    for line in _mask_text(text, folder).splitlines():
        for pattern, replacement in timings:
            line = pattern.sub(replacement, line)
        for pattern, keep in choices:
            match = pattern.match(line)
            if match:
                chosen.append(re.sub(" {2,}", "  ", line))  # a table's width follows its longest (chosen) row
                line = None if keep is None else match.expand(keep)
                break
        if line is not None:
            kept.append(line)
    return "\n".join(kept), "\n".join(chosen)


def _mask_json(value: Any, folder: str) -> Any:
    """A JSON value with timing keys, versions and the temporary folder masked."""
    if isinstance(value, dict):
        return {
            key: "<timing>" if key in TIMING_KEYS else "<version>" if key in VERSION_KEYS else _mask_json(item, folder)
            for key, item in value.items()
        }
    if isinstance(value, list):
        return [_mask_json(item, folder) for item in value]
    if isinstance(value, str):
        return _mask_text(value, folder)
    return value


def _parse_json(text: str) -> Any:
    """JSON of a text, or None where it is none."""
    try:
        return json.loads(text)
    except ValueError:
        return None


def _csv_rows(text: str, folder: str) -> list[dict[str, Any]]:
    """A CSV's rows as {column: cell}, timing columns masked."""
    return [
        {key: "<timing>" if key in TIMING_KEYS else _mask_text(cell or "", folder) for key, cell in row.items()}
        for row in csv.DictReader(io.StringIO(text))
    ]


# --- diffing ---------------------------------------------------------------------------------------------


@dataclasses.dataclass
class Found:
    """What one case's comparison found, by section."""

    differs: list[str] = dataclasses.field(default_factory=list)
    timing_chosen: list[str] = dataclasses.field(default_factory=list)
    near: list[str] = dataclasses.field(default_factory=list)


def _short(value: Any) -> str:
    text = json.dumps(value) if not isinstance(value, float) else repr(value)
    return text if len(text) <= 100 else text[:97] + "..."


def _near(old: Any, new: Any, rtol: float) -> bool:
    numbers = (int, float)
    if rtol <= 0 or isinstance(old, bool) or isinstance(new, bool):
        return False
    if not (isinstance(old, numbers) and isinstance(new, numbers)):
        return False
    return math.isclose(old, new, rel_tol=rtol)


def _compare(old: Any, new: Any, path: str, chosen: Callable[[str], bool], rtol: float, found: Found) -> None:
    """Record every difference between two masked JSON values under `path`."""
    if isinstance(old, dict) and isinstance(new, dict):
        for key in list(old) + [k for k in new if k not in old]:
            where = f"{path}.{key}" if path and not path.endswith(": ") else f"{path}{key}"
            if key not in new:
                _note(found, chosen(where), f"{where}: {_short(old[key])} -> (removed)")
            elif key not in old:
                _note(found, chosen(where), f"{where}: (new) -> {_short(new[key])}")
            else:
                _compare(old[key], new[key], where, chosen, rtol, found)
        return
    if isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            _note(found, chosen(path), f"{path}: {len(old)} items -> {len(new)} items")
        for index, (a, b) in enumerate(zip(old, new)):
            _compare(a, b, f"{path}[{index}]", chosen, rtol, found)
        return
    same = old == new and type(old) is type(new)
    if isinstance(old, float) and isinstance(new, float) and math.isnan(old) and math.isnan(new):
        same = True
    if same:
        return
    line = f"{path}: {_short(old)} -> {_short(new)}"
    if chosen(path):
        found.timing_chosen.append(line)
    elif _near(old, new, rtol):
        found.near.append(line)
    else:
        found.differs.append(line)


def _note(found: Found, is_chosen: bool, line: str) -> None:
    (found.timing_chosen if is_chosen else found.differs).append(line)


def _text_diff(old: str, new: str, label: str, into: list[str]) -> None:
    if old == new:
        return
    lines = difflib.unified_diff(
        old.splitlines(), new.splitlines(), f"{label} (old)", f"{label} (new)", n=0, lineterm=""
    )
    into.extend(line for line in lines if not line.startswith("@@"))


def _reshape(value: Any, case: str) -> Any:
    """stability.json's advised rows apart from its limit rows: how many there are depends on timed costs."""
    if case.startswith("stability") and isinstance(value, dict) and isinstance(value.get("extremes"), list):
        rows = value["extremes"]
        value = {
            **value,
            "extremes": [r for r in rows if r.get("kind") != "advised"],
            "extremes_advised": [r for r in rows if r.get("kind") == "advised"],
        }
    return value


def _load(root: pathlib.Path, name: str) -> tuple[dict[str, Any], str] | None:
    path = root / name / "record.json"
    if not path.exists():
        return None
    record = json.loads(path.read_text())
    return record, record["folder"]


def _content(root: pathlib.Path, case: str, relative: str, folder: str) -> Any:
    """A written file's masked content: JSON as a value, CSV as rows."""
    text = (root / case / "files" / relative).read_text()
    if relative.endswith(".json"):
        return _reshape(_mask_json(json.loads(text), folder), case)
    return _csv_rows(text, folder)


def _compare_case(old_root: pathlib.Path, new_root: pathlib.Path, name: str, rtol: float) -> Found:
    found = Found()
    old, new = _load(old_root, name), _load(new_root, name)
    if old is None or new is None:
        found.differs.append("missing in the " + ("old" if old is None else "new") + " snapshot")
        return found
    (old_record, old_folder), (new_record, new_folder) = old, new
    patterns = [re.compile(p) for case, p in TIMING_CHOSEN if re.search(case, name)]

    def chosen(path: str) -> bool:
        # a path inside a file or printed JSON: "<label>: <json path>"
        inner = path.split(": ", 1)[-1] if ": " in path else path
        return any(p.search(inner) for p in patterns)

    for index, (a, b) in enumerate(zip(old_record["steps"], new_record["steps"])):
        step = f"step {index + 1}" if len(old_record["steps"]) > 1 else ""
        if a["argv"] != b["argv"]:
            found.differs.append(f"{step} argv: {a['argv']} -> {b['argv']}")
        if a["exit_code"] != b["exit_code"]:
            found.differs.append(f"{step} exit code: {a['exit_code']} -> {b['exit_code']}".strip())
        for stream in ("stdout", "stderr"):
            label = f"{step} {stream}".strip()
            old_json, new_json = _parse_json(a[stream]), _parse_json(b[stream])
            if old_json is not None and new_json is not None:
                _compare(
                    _reshape(_mask_json(old_json, old_folder), name),
                    _reshape(_mask_json(new_json, new_folder), name),
                    f"{label}: ",
                    chosen,
                    rtol,
                    found,
                )
            else:
                (old_text, old_chosen), (new_text, new_chosen) = (
                    _split_text(a[stream], old_folder, name),
                    _split_text(b[stream], new_folder, name),
                )
                _text_diff(old_text, new_text, label, found.differs)
                _text_diff(old_chosen, new_chosen, label, found.timing_chosen)
    if len(old_record["steps"]) != len(new_record["steps"]):
        found.differs.append(f"steps: {len(old_record['steps'])} -> {len(new_record['steps'])}")
    old_files, new_files = old_record["files"], new_record["files"]
    for relative in sorted(set(old_files) | set(new_files)):
        if relative not in new_files:
            found.differs.append(f"{relative}: no longer written")
        elif relative not in old_files:
            found.differs.append(f"{relative}: newly written")
        elif "content" in old_files[relative] and "content" in new_files[relative]:
            _compare(
                _content(old_root, name, relative, old_folder),
                _content(new_root, name, relative, new_folder),
                f"{relative}: ",
                chosen,
                rtol,
                found,
            )
        elif old_files[relative] != new_files[relative]:
            found.differs.append(f"{relative}: {old_files[relative]} -> {new_files[relative]}")
    return found


def diff(old_root: pathlib.Path, new_root: pathlib.Path, rtol: float) -> int:
    """Print the differences between two snapshots case by case; 1 if anything outside the masks differs."""
    names = [c.name for c in CASES]
    present = [n for n in names if (old_root / n).exists() or (new_root / n).exists()]
    extra = sorted(
        {p.name for root in (old_root, new_root) for p in root.iterdir() if p.is_dir() and p.name not in names}
    )
    failing = 0
    for name in present + extra:
        found = _compare_case(old_root, new_root, name, rtol)
        if not (found.differs or found.timing_chosen or found.near):
            continue
        print(f"== {name}")
        for title, lines in (
            ("differs", found.differs),
            ("timing-chosen", found.timing_chosen),
            ("near-equal", found.near),
        ):
            if lines:
                print(f"  {title}:")
                print("\n".join(f"    {line}" for line in lines))
        failing += bool(found.differs)
    print(f"{len(present + extra)} cases compared; {failing} differ outside masked and timing-chosen fields")
    return 1 if failing else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n", 1)[0], epilog="See the module docstring.")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--output", type=pathlib.Path, metavar="DIR", help="run the cases, store the snapshot in DIR")
    mode.add_argument("--diff", nargs=2, type=pathlib.Path, metavar=("OLD", "NEW"), help="compare two snapshots")
    parser.add_argument("--only", metavar="NAME,...", help="with --output: run only these cases")
    parser.add_argument("--jobs", type=int, default=2, help="with --output: cases run at once (default 2)")
    parser.add_argument("--rtol", type=float, default=0.0, help="with --diff: list floats equal within RTOL apart")
    parser.add_argument("--list", action="store_true", help="print the cases and exit")
    args = parser.parse_args(argv)
    if args.list:
        print("\n".join(f"{c.name:34s} " + " ; ".join(" ".join(step) for step in c.steps) for c in CASES))
        return 0
    if args.diff:
        return diff(args.diff[0], args.diff[1], args.rtol)
    if args.output is None:
        parser.error("give --output DIR, --diff OLD NEW or --list")
    return snapshot(args.output, set(args.only.split(",")) if args.only else None, args.jobs)


if __name__ == "__main__":
    sys.exit(main())
