"""`make bench`: every user-facing path against its floor, in one run, one table.

Writes benchmarks/results.md (the table, the machine, then what each older bench_*.py script printed) and
benchmarks/results.json (the rows, for `python benchmarks/check.py`, which fails when a ratio is over its budget).

Each row: its work (steps, runs), its wall and CPU time, its floor and the ratio path / floor. The floor is what
the same work costs without springlab around it:

* `rollout`: a plain `mujoco.rollout` of the same steps on the same compiled model (configured and its MjData
  made beforehand), measured alternately with the path, best of several.
* `inside MuJoCo`: for a whole command, the time the same run of it spent inside MuJoCo's `rollout`, batch
  `rollout` and `mj_step` calls (counted by wrapping them; every simulation the command does, verification runs
  included): the rollouts of the same steps on the same compiled models.
* `import`: `import mujoco, numpy` in a fresh interpreter, against `import springlab`.
* `numpy` (exact-only work: the bare numpy/scipy cost of the same answer), `ffmpeg` (ffmpeg's own encoding of as
  many frames), `real time` (the live viewer), `issue 37's 150 s` (the demo: its wall time against the target):
  benchmarks/paths.py.

`validate` runs cold in a fresh interpreter: its row is the command's work (every compile, exact precomputation
and lazy import) against its rollouts, and `validate start-up` is the interpreter and the imports before it, a
row of its own. The other commands run in this process with springlab's caches cleared (`forget_cases`).

Ratios are taken on CPU time: the machine running the benchmark may be shared, and CPU time is what the
load disturbs least (wall times are in the table too). A row's budget is issue 37's target where it names one
(`run` 1.3, drill-string spin-up 2, `simulate` 1 / 0.9, `validate` 1.2); elsewhere it is marked `(set)`: for the
rows here the ratio measured when the row was added with room for noise, for the scripts' rows what the path is
expected to cost against its floor, its reason beside the number in the script.

The older benchmarks/bench_*.py scripts run after the rows, each with its arguments in SCRIPTS (a smaller size, or
only the parts no row above measures; the size is in its rows' work), and their output is pasted below the table.
Each adds its headline measurements to the table as rows: a line `BENCH_ROW {json of Row's fields}` in its output
(`measure.emit`), against the same floors. A script that only repeats what a row above measures is left out of the
default run (SCRIPTS says which row; `--only NAME` runs it at its own default size).

Run: PYTHONPATH=src python benchmarks/bench.py [--list] [--only NAME,...] [--skip NAME,...] [--no-scripts]
[--output DIR].
"""

from __future__ import annotations

import argparse
import compileall
import dataclasses
import importlib.util
import json
import os
import pathlib
import platform
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

import mujoco
import numpy as np
from mujoco import rollout

from measure import (  # noqa: F401 (bench.Row, bench.forget_cases: the names the tests and scripts read here)
    HERE,
    ROOT,
    ROW_PREFIX,
    RUN_BUDGET,
    SIMULATE_BUDGET,
    SPIN_UP_BUDGET,
    VALIDATE_BUDGET,
    Row,
    _clock,
    alternately,
    command_row,
    emit,
    forget_cases,
    fresh_import_cpu,
    inside_mujoco,
    raw_rollout,
    shown,
)

# -- rows ---------------------------------------------------------------------------------------------------


def run_rows(only: set[str] | None) -> list[Row]:
    """`springlab.run(scene)` for every scene's default scenario, and the drill string's spin-up."""
    import springlab
    from springlab import scenes

    rows = []
    cases = [(name, None) for name in scenes.SCENES] + [("drill_string", "spin_up")]
    for name, scenario in cases:
        label = f"run {name}" + (f" {scenario}" if scenario else "")
        if only and label not in only and "run" not in only:  # `--only "run slider"`: one of them
            continue
        forget_cases()
        wall, cpu = _clock()
        result = springlab.run(name, scenario)
        first = time.perf_counter() - wall, time.process_time() - cpu
        repeat = 3 if result.steps > 10_000 else 7
        timings = alternately(lambda: springlab.run(name, scenario), raw_rollout(result), repeat)
        budget = SPIN_UP_BUDGET if scenario == "spin_up" else RUN_BUDGET
        rows.append(
            Row(
                label + f" ({result.scenario})" * (scenario is None),
                f"{result.steps} steps {result.integrator} dt={result.dt:g} s, verdict and exact reference",
                *timings[:2],
                "rollout",
                *timings[2:],
                budget,
                "issue 37",
                f"first call {first[0]:.3g} s wall, {first[1]:.3g} s CPU (compile and exact precomputations)",
            )
        )
    return rows


def simulate_row() -> Row:
    """springlab.sim.simulate against a plain rollout of the same steps (the issue: >= 0.9x its speed)."""
    from springlab import scenes
    from springlab.sim.simulate import configured, initial_state, simulate

    case = scenes.get("slider").case("free")
    dt, duration = 1e-3, 20.0
    steps = round(duration / dt)
    setup = case.setup(steps, dt)
    model = configured(case.model, "rk4", dt)
    data = mujoco.MjData(model)
    state = initial_state(model, setup.qpos, setup.qvel)[None]
    control = np.zeros((1, steps, model.nu))

    def path():
        simulate(case.model, integrator="rk4", dt=dt, duration=duration, qpos=setup.qpos, qvel=setup.qvel)

    timings = alternately(path, lambda: rollout.rollout(model, data, state, control, nstep=steps), 7)
    return Row(
        "simulate slider", f"{steps} steps rk4", *timings[:2], "rollout", *timings[2:], SIMULATE_BUDGET, "issue 37"
    )


def sobol_row(base_samples: int = 256) -> Row:
    """The printer head's Sobol study on one thread against a plain rollout of the same steps (bench_sobol.py)."""
    import bench_sobol
    from springlab.studies.design import moves, sobol
    from springlab.studies.executor import Executor

    base, values = bench_sobol.study_values(base_samples)
    steps = np.asarray(moves.simulate(bench_sobol.SCENE, base, values, nthread=1).steps)
    runs = len(steps)

    def path():
        sobol.run_sobol(bench_sobol.SCENE, base_samples, executor=Executor(nthread=1, progress=False))

    timings = alternately(path, bench_sobol.raw_rollout(base, values, steps), 2)
    default_runs = bench_sobol.default_runs()
    minutes = timings[1] / runs * default_runs / 2 / 60
    row = Row(
        "design printer_head --sobol",
        f"{runs} runs (N = {base_samples}), {int(steps.sum())} steps rk4, one thread",
        *timings[:2],
        "rollout",
        *timings[2:],
        1.3,
        "(set)",
        f"{timings[1] / runs * 1e3:.2f} ms CPU per run: {default_runs:,} runs on 2 idle cores {minutes:.1f} min"
        " (CPU x runs / 2; the LocalCluster scaling and the 64-core projection: bench_sobol.py below)",
    )
    return row


def import_row() -> Row:
    """`import springlab` in a fresh interpreter against `import mujoco, numpy`."""

    def timed(code: str) -> tuple[float, float]:
        best = (np.inf, np.inf)
        for _ in range(5):
            script = f"import time;w=time.perf_counter();{code};print(time.perf_counter()-w, time.process_time())"
            out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True).stdout
            wall, cpu = map(float, out.split())
            best = (min(best[0], wall), min(best[1], cpu))
        return best

    mine, floor = timed("import springlab"), timed("import mujoco, numpy")
    return Row("import springlab", "a fresh interpreter", *mine, "import", *floor, 5.0, "(set)")


#: (row name, argv with {out} for a temporary folder, work, budget, basis): commands measured in this process
COMMANDS = [
    (
        "sweep",
        ["sweep", "slider", "free", "--vary", "stiffness=10:1000:1000:log", "--output", "{out}"],
        "1000 configurations",
        3.0,
        "(set)",
    ),
    ("tradeoff", ["tradeoff", "slider", "free", "--output", "{out}"], "every integrator and dt", 2.5, "(set)"),
    # mostly exact work (the step maps' eigenvalues, bisected limits): its MuJoCo calls are a small floor
    ("stability", ["stability", "--output", "{out}"], "the stability limits", 250.0, "(set)"),
    (
        "friction-settings gripper",
        ["friction-settings", str(ROOT / "tests" / "data" / "gripper.xml"), "--hold", "1", "--output", "{out}"],
        "creep settings on a gripper",
        3.0,
        "(set)",
    ),
    ("rms stay_cable", ["rms", "stay_cable", "--output", "{out}"], "random load, stay cable", 3.0, "(set)"),
    ("design printer_head", ["design", "printer_head", "--output", "{out}"], "the design study", 3.0, "(set)"),
    (
        "refine",
        ["refine", "drill_string", "--output", "{out}"],
        "the drill string's element counts and settings for its question",
        1.6,
        "(set)",
    ),
]


def audit_command() -> tuple[str, list[str], str, float, str]:
    """The audit of dm_control's humanoid (27 DOF, lying on the floor after 3 s), as bench_audit.py runs it."""
    import dm_control

    humanoid = pathlib.Path(dm_control.__file__).parent / "suite" / "humanoid.xml"
    argv = ["audit", str(humanoid), "--settle", "3", "--tol", "1e-2", "--output", "{out}"]
    return "audit humanoid", argv, "dm_control's humanoid, 27 DOF on the floor, 5 integrators", 1.6, "(set)"


def script_rows(text: str) -> list[Row]:
    """The rows a script printed (`ROW_PREFIX` lines: Row's fields as JSON)."""
    rows = []
    for line in text.splitlines():
        if line.startswith(ROW_PREFIX):
            fields = json.loads(line[len(ROW_PREFIX) :])
            rows.append(Row(**{k: v for k, v in fields.items() if k in Row.__dataclass_fields__}))
    return rows


def scripts(timeout: float, chosen: list[str]) -> list[tuple[str, float, str]]:
    """The older benchmarks/bench_*.py in `chosen` with their arguments (SCRIPTS), as each prints itself: (name and
    arguments, wall [s], its output)."""
    out = []
    for script in sorted(HERE.glob("bench_*.py")):
        if script.stem not in chosen:
            continue
        arguments = list(SCRIPTS[script.stem].arguments)
        start = time.perf_counter()
        try:
            done = subprocess.run(
                [sys.executable, str(script), *arguments],
                capture_output=True,
                text=True,
                timeout=timeout,
                cwd=ROOT,
                check=False,
            )
            text = done.stdout + (f"\n(exit {done.returncode})\n{done.stderr[-2000:]}" if done.returncode else "")
        except subprocess.TimeoutExpired:
            text = f"(stopped after {timeout:g} s)"
        out.append((" ".join([script.name, *arguments]), time.perf_counter() - start, text))
        print(f"  {out[-1][0]}: {out[-1][1]:.1f} s", flush=True)
    return out


def byte_compile_springlab() -> None:
    """Byte-compile springlab's sources, as `pip install` leaves an installed package's.

    The cold rows (validate, the imports) measure a user's fresh process; with PYTHONDONTWRITEBYTECODE set (as
    in some containers) an editable install would otherwise recompile every module in every fresh process
    (about 0.2 s of validate's CPU), a cost no installed copy pays.
    """
    spec = importlib.util.find_spec("springlab")
    for folder in (spec.submodule_search_locations or []) if spec else []:
        compileall.compile_dir(folder, quiet=1)


def machine() -> dict:
    """What the numbers were measured on."""
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    return {
        "platform": platform.platform(),
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
        "cpus": os.cpu_count(),
        "load_average_1_5_15": list(load),
        "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
    }


def markdown(rows: list[Row], where: dict, reports: list[tuple[str, float, str]]) -> str:
    lines = [
        "# springlab benchmarks",
        "",
        f"`make bench` (benchmarks/bench.py) on {where['platform']}, {where['cpus']} CPUs, Python {where['python']},"
        f" MuJoCo {where['mujoco']}, {where['date_utc']} UTC; load average at the end"
        f" {', '.join(f'{x:.1f}' for x in where['load_average_1_5_15'])}. Ratio = CPU time / the floor's CPU time;"
        " `python benchmarks/check.py` fails when one is over its budget. The floor column is the floor's CPU time,"
        " or its wall time where marked (a path whose CPU is in another process: the browser, the live viewer)."
        " `python benchmarks/bench.py --list` gives each row group's rough wall time; `--only`, `--skip` choose."
        " springlab's sources are byte-compiled first, as an installed package's are."
        + (
            f" This table was run as `python benchmarks/bench.py {where['arguments']}`: the rows and scripts it left out"
            " are absent."
            if where.get("arguments")
            else ""
        ),
        "",
        "| path | work | wall [s] | CPU [s] | floor | floor [s] | ratio | budget | note |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        over = " **over**" if r.ratio > r.budget else ""
        lines.append(
            f"| {r.name} | {r.work} | {r.wall_s:.4g} | {r.cpu_s:.4g} | {r.floor} |"
            f" {(r.floor_wall_s if r.on_wall else r.floor_cpu_s):.4g}{' wall' if r.on_wall else ''} |"
            f" {r.ratio:.2f}{over} | {r.budget:.2f} {r.budget_basis} | {r.note} |"
        )
    if reports:
        lines += ["", "## The scripts (benchmarks/bench_*.py), as they print", ""]
        for name, wall, text in reports:
            # its rows are in the table above: the JSON lines are left out of what it printed
            printed = "\n".join(line for line in text.splitlines() if not line.startswith(ROW_PREFIX))
            found = len(script_rows(text))
            rows_in_table = f"; its {found} row{'s' * (found != 1)} in the table" if found else ""
            lines += [f"### {name} ({wall:.1f} s{rows_in_table})", "", "```", printed.rstrip(), "```", ""]
    return "\n".join(lines) + "\n"


@dataclasses.dataclass(frozen=True)
class Bench:
    """A named group of rows (what --only and --skip take), with a rough wall time [s] on an idle 2-core machine."""

    name: str
    estimate_s: float
    measure: Callable[[pathlib.Path], list[Row]]


def _command(name: str) -> Callable[[pathlib.Path], list[Row]]:
    spec = next(c for c in COMMANDS if c[0] == name)
    return lambda folder: [command_row(*spec)]


def benches(selected: set[str] | None) -> list[Bench]:
    """Every row group of the table, in the table's order; then one per older bench_*.py script."""
    import paths

    def view(folder: pathlib.Path) -> list[Row]:
        row = paths.view_row()
        return [row] if row else []

    out = [
        Bench("run", 30, lambda folder: run_rows(selected)),
        Bench("simulate", 3, lambda folder: [simulate_row()]),
        Bench("sobol", 60, lambda folder: [sobol_row()]),
        Bench("validate", 25, lambda folder: paths.validate_rows()),
        *(Bench(name, estimate, _command(name)) for name, estimate in _COMMAND_ESTIMATES.items()),
        Bench("audit humanoid", 12, lambda folder: [command_row(*audit_command())]),
        Bench("fit", 30, paths.fit_rows),
        Bench("frequency chain", 5, lambda folder: [paths.frequency_chain_row()]),
        Bench("frequency sinestream", 5, lambda folder: [paths.sinestream_row()]),
        Bench("render", 6, lambda folder: [paths.render_row(folder)]),
        Bench("interactive", 15, paths.interactive_rows),
        Bench("view", 10, view),
        Bench("demo", 150, lambda folder: [paths.demo_row()]),
        Bench("import", 8, lambda folder: [import_row()]),
    ]
    return out


#: rough wall time [s] of each in-process command row on an idle 2-core machine (the idle clean-clone table of c8cf198:
#: the command's wall time, with room for a first call's imports)
_COMMAND_ESTIMATES = {
    "sweep": 10,
    "tradeoff": 5,
    "stability": 6,
    "friction-settings gripper": 6,
    "rms stay_cable": 60,
    "design printer_head": 15,
    "refine": 35,
}


@dataclasses.dataclass(frozen=True)
class Script:
    """An older benchmarks/bench_*.py as `make bench` runs it: its arguments there (a smaller size is stated in its
    rows' work), its rough wall time [s] with them on an idle 2-core machine, and why it is left out of the default
    run if it is (a table row measures the same; `--only NAME` still runs it, at its own default size)."""

    arguments: tuple[str, ...]
    estimate_s: float
    skipped: str = ""


#: every older script: how `make bench` runs it (estimates: idle 2-core wall times, the scripts' CPU time when they
#: were measured on a shared machine; a skipped script's is its own default run's)
SCRIPTS = {
    "bench_audit": Script((), 35),
    "bench_creep": Script(("--skip-full",), 20),
    "bench_design": Script((), 90, "the table's `design printer_head` and `--sobol` rows time the same batched moves"),
    "bench_drill_string": Script(("--quick",), 60),
    "bench_executor": Script(("chunks",), 30),
    "bench_fit": Script((), 20, "the table's `fit 10 s at 1 kHz` row times the same fit of the same record"),
    "bench_fit_bigfile": Script(("--readers-only", "--repeat", "2"), 25),
    "bench_frequency": Script(("duffing",), 20),
    "bench_friction": Script(("--skip-full",), 20),
    "bench_growth": Script(("--quick",), 60),
    "bench_printer_control": Script((), 10),
    "bench_render": Script(("--end-to-end-only", "--repeat", "2"), 30),
    "bench_simulate": Script((), 10),
    "bench_sobol": Script(("64",), 45),
    "bench_stability_limit": Script(
        (), 30, "the table's `stability` row times the chart these limits are drawn on, in the whole command"
    ),
    "bench_stay_cable": Script(("--exact-only",), 60),
    "bench_tradeoff": Script((), 25),
}


def default_scripts() -> list[str]:
    """The scripts `make bench` runs (those not skipped)."""
    return [name for name, script in SCRIPTS.items() if not script.skipped]


def _chosen(name: str, only: set[str] | None, skip: set[str]) -> bool:
    if name in skip:
        return False
    if only is None:
        return name not in SCRIPTS or not SCRIPTS[name].skipped
    return name in only or (name == "run" and any(o.startswith("run ") for o in only))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="", help="comma-separated row groups to run (see --list)")
    parser.add_argument("--skip", default="", help="comma-separated row groups to leave out (see --list)")
    parser.add_argument("--list", action="store_true", help="list the row groups with their rough wall times, and stop")
    parser.add_argument("--no-scripts", action="store_true", help="leave out the bench_*.py scripts")
    parser.add_argument("--script-timeout", type=float, default=900.0)
    parser.add_argument("--output", default=str(HERE), help="where results.md and results.json go")
    args = parser.parse_args(argv)
    only = {s.strip() for s in args.only.split(",") if s.strip()} or None
    skip = {s.strip() for s in args.skip.split(",") if s.strip()}
    groups = [b for b in benches(only) if _chosen(b.name, only, skip)]
    known = {b.name for b in benches(None)} | set(SCRIPTS)
    unknown = sorted((only or set()) - known - {o for o in (only or set()) if o.startswith("run ")} | (skip - known))
    if unknown:
        parser.error(f"unknown row groups {', '.join(unknown)}; valid: {', '.join(sorted(known))}")
    chosen_scripts = [] if args.no_scripts else [n for n in SCRIPTS if _chosen(n, only, skip)]
    estimate = sum(b.estimate_s for b in groups) + sum(SCRIPTS[n].estimate_s for n in chosen_scripts)
    if args.list:
        for b in benches(None):
            print(f"{b.name:28s} ~{b.estimate_s:5.0f} s")
        for name, script in SCRIPTS.items():
            how = " ".join(["python", f"benchmarks/{name}.py", *script.arguments])
            if script.skipped:
                how = f"not in the default run: {script.skipped}; --only {name} runs it"
            print(f"{name:28s} ~{script.estimate_s:5.0f} s  (a script, its rows and its own output: {how})")
        print(f"chosen: about {estimate / 60:.0f} minutes on an idle 2-core machine (rough)")
        return 0
    byte_compile_springlab()
    print(f"rows (about {estimate / 60:.0f} minutes on an idle 2-core machine, rough):", flush=True)
    rows: list[Row] = []
    with tempfile.TemporaryDirectory() as scratch:
        for group in groups:
            start = time.perf_counter()
            found = group.measure(pathlib.Path(scratch))
            rows += found
            ratios = ", ".join(f"{r.name} {r.ratio:.2f}" for r in found)
            print(
                f"  {group.name} ({time.perf_counter() - start:.0f} s, ~{group.estimate_s:.0f}): {ratios}", flush=True
            )
    reports = scripts(args.script_timeout, chosen_scripts)
    for _, _, text in reports:
        rows += script_rows(text)
    where = machine()
    # a partial run says so in its header: a table from --only/--skip/--no-scripts is not the whole `make bench`
    where["arguments"] = " ".join(
        [f"--only {args.only}"] * bool(args.only)
        + [f"--skip {args.skip}"] * bool(args.skip)
        + ["--no-scripts"] * args.no_scripts
    )
    folder = pathlib.Path(args.output)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "results.json").write_text(
        json.dumps({"machine": where, "rows": [r.to_dict() for r in rows]}, indent=1) + "\n"
    )
    (folder / "results.md").write_text(markdown(rows, where, reports))
    print(f"wrote {folder / 'results.md'} and results.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
