"""The rows of `make bench` beyond `run` and the in-process commands: each a user-facing path with its floor.

benchmarks/bench.py lists them (`benches`) and writes the table; this module measures them. Every function
returns `measure.Row`s. The floors (module docstring of bench.py): `inside MuJoCo` (the same run's time in
MuJoCo's rollout, batch rollout and mj_step calls), `rollout` (a plain rollout of the same steps), `numpy`
(the bare numpy/scipy cost of the same exact work), `ffmpeg` (ffmpeg's own encoding of as many frames of the
same size), `real time` (the simulated time itself, for the live viewer), issue 37's 150 s for the demo's wall time.

Paths in the table are repository-relative (`shown`), so the table reads the same on any machine.
"""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

import mujoco
import numpy as np

import measure
from measure import ROOT, Row

#: a fresh interpreter that runs one springlab command with MuJoCo's calls timed, and prints what it measured
_CHILD = """
import json, os, sys, time, contextlib
sys.path.insert(0, {benchmarks!r})
import measure
from springlab.cli.main import main
started_cpu, started = time.process_time(), time.perf_counter()
with open(os.devnull, "w") as sink, contextlib.redirect_stdout(sink), measure.inside_mujoco() as spent:
    code = main({argv!r})
wall, cpu = time.perf_counter() - started, time.process_time() - started_cpu
print(json.dumps(dict(code=code, startup_cpu=started_cpu, wall=wall, cpu=cpu, mujoco_wall=spent[0], mujoco_cpu=spent[1])))
"""


def children_cpu() -> float:
    """CPU time [s] of the finished child processes (ffmpeg, chromium, a fresh interpreter)."""
    import resource

    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def fresh(argv: list[str]) -> tuple[dict, float, float]:
    """Run `springlab ARGV` in a fresh interpreter: (its measurements, parent-side wall [s], its whole CPU [s])."""
    code = _CHILD.format(benchmarks=str(measure.HERE), argv=argv)
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    before_cpu, start = children_cpu(), time.perf_counter()
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=False)
    wall, cpu = time.perf_counter() - start, children_cpu() - before_cpu
    if done.returncode != 0 or not done.stdout.strip():
        raise RuntimeError(f"springlab {' '.join(argv)} failed in a fresh interpreter: {done.stderr[-500:]}")
    return json.loads(done.stdout.strip().splitlines()[-1]), wall, cpu


def validate_rows() -> list[Row]:
    """`springlab validate` cold, in a fresh interpreter: the command's work against its rollouts, and its
    start-up (the interpreter and `import springlab.cli.main`) against `import mujoco, numpy`, apart."""
    measured, wall, _ = fresh(["validate"])
    startup_floor = measure.fresh_import_cpu("import mujoco, numpy")
    whole = measured["startup_cpu"] + measured["cpu"]
    return [
        Row(
            "validate",
            "every exact scenario, cold: a fresh interpreter, every compile, exact precomputation and lazy import",
            measured["wall"],
            measured["cpu"],
            "inside MuJoCo",
            measured["mujoco_wall"],
            measured["mujoco_cpu"],
            measure.VALIDATE_BUDGET,
            "issue 37",
            f"exit {measured['code']}; the floor is the same run's rollouts (the same steps on the same compiled"
            f" models); the whole process, start-up included: {whole:.3g} s CPU,"
            f" {whole / measured['mujoco_cpu']:.2f}x the floor, {wall:.3g} s wall",
        ),
        Row(
            "validate start-up",
            "a fresh interpreter and `import springlab.cli.main` (before any scene runs)",
            wall - measured["wall"],
            measured["startup_cpu"],
            "import",
            float("nan"),
            startup_floor,
            5.0,
            "(set), as `import springlab`'s",
            "the part of a cold validate no scene's work changes: the interpreter and the imports; the floor is"
            " `import mujoco, numpy` in a fresh interpreter",
        ),
    ]


def demo_row() -> Row:
    """`springlab demo` in a fresh interpreter against issue 37's target: 2.5 minutes of wall time on 2 cores.

    A wall-time row: the demo runs its studies and films on worker processes and encodes in ffmpeg's, so its work is
    spread over processes whose MuJoCo time this process cannot count; the CPU column is all of theirs."""
    with tempfile.TemporaryDirectory() as folder:
        measured, wall, cpu = fresh(["demo", "--output", folder])
        files = sum(1 for p in pathlib.Path(folder).rglob("*") if p.is_file())
    return Row(
        "demo",
        f"`springlab demo`: every step, {files} files",
        wall,
        cpu,
        "issue 37's 150 s",
        150.0,
        float("nan"),
        1.0,
        "issue 37",
        f"exit {measured['code']}; ratio = wall time / 150 s (on an idle 2-core machine); CPU of the process, its"
        f" workers and ffmpeg; inside MuJoCo in the main process (the core step's runs) {measured['mujoco_cpu']:.1f} s CPU",
        on_wall=True,
    )


# -- studies through the Python API, with their floors --------------------------------------------------------


def timed(fn: Callable[[], object]) -> tuple[object, float, float, float, float]:
    """(fn(), wall, cpu with the children's, MuJoCo's wall, MuJoCo's cpu) [s] of one call."""
    with measure.inside_mujoco() as spent:
        before = children_cpu()
        wall, cpu = measure._clock()
        out = fn()
        wall_end, cpu_end = measure._clock()
        children = children_cpu() - before
    return out, wall_end - wall, cpu_end - cpu + children, spent[0], spent[1]


def study_row(name: str, work: str, fn: Callable[[], object], budget: float, note: str = "") -> Row:
    """A study called in this process, cold (springlab's caches cleared), against its time inside MuJoCo."""
    measure.forget_cases()
    _, wall, cpu, floor_wall, floor_cpu = timed(fn)
    return Row(name, work, wall, cpu, "inside MuJoCo", floor_wall, floor_cpu, budget, "(set)", note)


def chain_xml(n: int) -> str:
    """n masses in a row on slide joints, springs and dampers between neighbours (bench_frequency.py's chain)."""
    sys.path.insert(0, str(measure.HERE))
    from bench_frequency import chain_xml as xml

    return xml(n)


def frequency_chain_row() -> Row:
    """The exact and discrete responses of a 24-DOF chain at 500 frequencies (no integrator search) against numpy
    solving the same 500 complex systems of the continuous model and of its zero-order-hold map."""
    import scipy.linalg

    import springlab

    n = 24
    model = mujoco.MjModel.from_xml_string(chain_xml(n))
    args = dict(input="drive", response=f"j{n - 1}", band=(0.1, 100.0), points=500, integrators=())

    def path() -> None:
        springlab.frequency(model, **args)

    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    stiffness = np.diag(model.jnt_stiffness.copy())
    damping = np.diag(model.dof_damping.copy())
    force = np.zeros(n)
    force[0] = 1.0
    omegas = 2 * np.pi * np.geomspace(0.1, 100.0, 500)
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(mass, stiffness), -np.linalg.solve(mass, damping)]])
    b = np.concatenate([np.zeros(n), np.linalg.solve(mass, force)])[:, None]

    def floor() -> None:
        # springs between neighbours: K's coupling is the chain's, but the cost is that of any 24 x 24 system
        for w in omegas:
            np.linalg.solve(stiffness - w**2 * mass + 1j * w * damping, force)
        block = scipy.linalg.expm(np.block([[a, b], [np.zeros((1, 2 * n + 1))]]) * model.opt.timestep)
        phi, gamma = block[: 2 * n, : 2 * n], block[: 2 * n, 2 * n :]
        for w in omegas:
            np.linalg.solve(np.exp(1j * w * model.opt.timestep) * np.eye(2 * n) - phi, gamma)

    timings = measure.alternately(path, floor, 3)
    return Row(
        "frequency chain",
        f"{n}-DOF chain, 500 frequencies: exact and discrete responses, resonances, band (no integrator search)",
        *timings[:2],
        "numpy",
        *timings[2:],
        25.0,
        "(set)",
        "the floor: numpy solving the 500 complex systems of the continuous model and of its zero-order hold",
    )


def sinestream_row() -> Row:
    """A 50-frequency sinestream of the printer head (rk4 at 0.1 ms, batched) against its time inside MuJoCo."""
    import springlab

    found: dict[str, object] = {}

    def call() -> None:
        found["result"] = springlab.frequency("printer_head", integrators=(), sines=50)

    row = study_row("frequency sinestream", "", call, 2.0)
    stream = found["result"].sinestream  # type: ignore[attr-defined]
    row.work = f"printer head, 50-frequency sinestream, {stream.steps} rk4 steps at 0.1 ms, batched"
    return row


def fit_rows(folder: pathlib.Path) -> list[Row]:
    """`springlab fit` of a 10 s record at 1 kHz, and of a 2-million-row file (10 s at 200 kHz)."""
    import springlab

    mass, stiffness, damping = 2.0, 800.0, 4.0
    rng = np.random.default_rng(0)
    rows = []
    for label, samples, floor_reads in (("fit 10 s at 1 kHz", 10_001, False), ("fit 2M rows", 2_000_001, True)):
        t = np.linspace(0.0, 10.0, samples)
        x, _ = springlab.exact.analytic.free_response(t, mass, stiffness, damping, 0.05, 0.0)
        y = x + 0.002 + rng.normal(0, 5e-4, t.size)
        data = folder / f"record-{samples}.csv"
        np.savetxt(
            data, np.column_stack([t, y]), fmt=["%.7f", "%.9f"], delimiter=",", header="time,slider_pos", comments=""
        )
        argv = ["fit", "slider", str(data), "--set", f"mass={mass:g}", "--output", str(folder / f"out-{samples}")]
        budget = 20.0 if floor_reads else 7.0  # the optimizer's Python between rollouts; the reader's parsing
        row = measure.command_row(
            label, argv, f"{samples} samples, slider, free stiffness and damping", budget, "(set)"
        )
        if floor_reads:  # reading the file is part of the floor: numpy.loadtxt of it at once
            start_wall, start_cpu = measure._clock()
            np.loadtxt(data, delimiter=",", skiprows=1)
            end_wall, end_cpu = measure._clock()
            row.floor = "inside MuJoCo + numpy.loadtxt"
            row.floor_wall_s += end_wall - start_wall
            row.floor_cpu_s += end_cpu - start_cpu
        rows.append(row)
    return rows


def render_row(folder: pathlib.Path) -> Row:
    """`springlab render slider` (640 x 480, 30 fps) against ffmpeg encoding as many frames of that size."""
    import imageio_ffmpeg

    from springlab.cli.main import main

    video = folder / "render.mp4"
    argv = ["render", "slider", "--output", str(video)]
    with contextlib.redirect_stdout(open(os.devnull, "w")):
        main(argv)  # a first call: GL context, fonts, the run itself
        _, wall, cpu, _, _ = timed(lambda: main(argv))
    reader = imageio_ffmpeg.read_frames(str(video))
    meta = next(reader)
    frames = sum(1 for _ in reader)
    width, height = meta["size"]
    picture = np.random.default_rng(0).integers(0, 255, (height, width, 3), dtype=np.uint8)

    def encode() -> None:
        writer = imageio_ffmpeg.write_frames(
            str(folder / "floor.mp4"),
            (width, height),
            fps=30,
            codec="libx264",
            quality=None,
            output_params=["-preset", "veryfast", "-crf", "20"],
            ffmpeg_log_level="error",
            macro_block_size=1,
        )
        writer.send(None)
        for _ in range(frames):
            writer.send(picture)
        writer.close()

    _, floor_wall, floor_cpu, _, _ = timed(encode)
    return Row(
        "render",
        f"slider free, {frames} frames {width} x {height} at 30 fps",
        wall,
        cpu,
        "ffmpeg",
        floor_wall,
        floor_cpu,
        5.0,
        "(set)",
        f"{frames / wall:.0f} frames/s against ffmpeg's own {frames / floor_wall:.0f} frames/s encoding as many frames"
        " (x264 veryfast, crf 20, no drawing); CPU of both includes ffmpeg's process",
    )


def view_row() -> Row | None:
    """`springlab view slider --close-after 3` under a virtual X display: the live viewer's real-time factor."""
    if shutil.which("xvfb-run") is None:
        return None
    argv = [sys.executable, "-m", "springlab", "view", "slider", "--close-after", "3"]
    before, start = children_cpu(), time.perf_counter()
    done = subprocess.run(["xvfb-run", "-a", *argv], capture_output=True, text=True, check=False)
    wall, cpu = time.perf_counter() - start, children_cpu() - before
    line = next((s for s in done.stdout.splitlines() if "x real time" in s), "")
    try:
        speed = float(line.split("(")[-1].split(" x real time")[0])
    except ValueError:
        speed = float("nan")
    simulated = 3.0 * speed if speed == speed else float("nan")
    return Row(
        "view",
        "slider free in MuJoCo's viewer for 3 s of wall time (xvfb-run)",
        3.0,
        cpu,
        "real time",
        simulated,
        float("nan"),
        1.1,
        "(set)",
        f"exit {done.returncode}; real-time factor {speed:.3g} (simulated seconds per wall second); ratio = wall time"
        " over the simulated time it showed (1: real time);"
        f" the whole process (start-up, the run, the window) {wall:.3g} s wall, {cpu:.3g} s CPU",
        on_wall=True,
    )


def interactive_rows(folder: pathlib.Path) -> list[Row]:
    """The slider's interactive page in headless chromium: its load (MuJoCo's WebAssembly compiled, the first run
    drawn) and one slider move (recompile, run, redraw), each against a native rollout of the same steps."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        return []
    sys.path.insert(0, str(ROOT / "tests"))
    import springlab
    from helpers.browser import RESULT_AFTER, DevTools
    from springlab.render import interactive

    page = interactive.write_interactive("slider", "free", folder / "page")[0]
    result = springlab.run("slider", "free")
    rollout = measure.raw_rollout(result)
    best = [np.inf] * 2
    for _ in range(3):
        wall = time.perf_counter()
        rollout()
        best[0] = min(best[0], time.perf_counter() - wall)
    tools = DevTools(chromium, folder / "profile")
    try:
        start = time.perf_counter()
        session = tools.open(page.path.as_uri())
        tools.evaluate(session, RESULT_AFTER.format(after=0))
        load = time.perf_counter() - start
        start = time.perf_counter()
        tools.evaluate(
            session,
            "(() => { const e = document.getElementById('zeta'); e.value = '0.3'; e.dispatchEvent(new Event('input'));"
            f" return {RESULT_AFTER.format(after=1)}; }})()",
        )
        move = time.perf_counter() - start
    finally:
        tools.close()
    work = f"slider free, {result.steps} steps rk4 in MuJoCo's WebAssembly build"
    floor_note = "; the floor: a native rollout of the same steps (wall: the browser's CPU is in its own processes)"
    return [
        Row(
            "interactive page load",
            work + ", drawn",
            load,
            float("nan"),
            "rollout",
            best[0],
            float("nan"),
            2000.0,
            "(set)",
            "navigation to the first result published (WebAssembly compiled, MJCF compiled, run, plots)" + floor_note,
            on_wall=True,
        ),
        Row(
            "interactive slider move",
            work + " after a damping-ratio move",
            move,
            float("nan"),
            "rollout",
            best[0],
            float("nan"),
            200.0,
            "(set)",
            "input event to the next result published" + floor_note,
            on_wall=True,
        ),
    ]
