"""The measuring kit of `make bench`: the row, the clocks, the MuJoCo-time counter and the floors that
benchmarks/bench.py (the table) and benchmarks/paths.py (the rows beyond `run`) both use.

It imports neither of them, so the two modules import it one way (bench.py lists the rows and writes the
table; paths.py measures the rows it owns).
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator, Sequence

import mujoco
import numpy as np
from mujoco import rollout

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
#: the issue's targets
RUN_BUDGET = 1.3
SPIN_UP_BUDGET = 2.0
SIMULATE_BUDGET = 1 / 0.9
VALIDATE_BUDGET = 1.2


@dataclasses.dataclass
class Row:
    """One measured path: its time, its floor's, their ratio and its budget."""

    name: str
    work: str
    wall_s: float
    cpu_s: float
    floor: str
    floor_wall_s: float
    floor_cpu_s: float
    budget: float
    budget_basis: str
    note: str = ""
    #: the ratio on wall times (a path whose CPU is in another process: the browser, real time)
    on_wall: bool = False

    @property
    def ratio(self) -> float:
        mine, floor = (self.wall_s, self.floor_wall_s) if self.on_wall else (self.cpu_s, self.floor_cpu_s)
        return mine / floor if floor > 0 else float("inf")

    def to_dict(self) -> dict:
        out = dataclasses.asdict(self)
        out["ratio"] = self.ratio
        return out


#: a line a bench_*.py script prints to add a row to the table: the prefix, then the row's fields as JSON
ROW_PREFIX = "BENCH_ROW "


def emit(row: Row) -> None:
    """Print `row` as a line of the table (`ROW_PREFIX` and its fields as JSON): bench.py reads it from a script's output."""
    print(ROW_PREFIX + json.dumps(dataclasses.asdict(row)), flush=True)


def _clock() -> tuple[float, float]:
    return time.perf_counter(), time.process_time()


def alternately(path: Callable[[], object], floor: Callable[[], object], repeat: int) -> tuple[float, ...]:
    """(wall, cpu) of path and of floor [s], each the best of `repeat`, measured alternately."""
    (path_wall, path_cpu), (floor_wall, floor_cpu) = side_by_side([path, floor], repeat)
    return path_wall, path_cpu, floor_wall, floor_cpu


def side_by_side(functions: Sequence[Callable[[], object]], repeat: int) -> list[tuple[float, float]]:
    """(wall, cpu) [s] of each function, the best of `repeat`, measured in turn (one of each, `repeat` times), so a
    change of the machine's load hits all of them alike."""
    best = [[np.inf, np.inf] for _ in functions]
    for _ in range(repeat):
        for k, fn in enumerate(functions):
            wall, cpu = _clock()
            fn()
            wall_end, cpu_end = _clock()
            best[k][0] = min(best[k][0], wall_end - wall)
            best[k][1] = min(best[k][1], cpu_end - cpu)
    return [(wall, cpu) for wall, cpu in best]


@dataclasses.dataclass(frozen=True)
class PerRun:
    """One configuration of a study's per-run comparison (bench_creep.py, bench_friction.py): its label as printed,
    its steps, the study's own chunk, a plain Python mj_step loop recording every step, and a plain rollout (the
    floor) of the same steps on the same configured model."""

    label: str
    steps: int
    study: Callable[[], object]
    plain_loop: Callable[[], object]
    rollout: Callable[[], object]


def per_run_comparison(runs: Iterable[PerRun], steps_width: int, repeat: int = 3) -> dict[str, float]:
    """Time each run's study, plain loop and rollout in turn (best of `repeat`), print a line per run (wall times, as
    the scripts always printed) and the mean ratio study / plain loop; return the sums over the runs: `study_wall`,
    `study_cpu`, `loop_wall`, `loop_cpu`, `rollout_wall`, `rollout_cpu` [s], `steps`, `runs` and `mean_ratio`."""
    totals = dict.fromkeys(("study_wall", "study_cpu", "loop_wall", "loop_cpu", "rollout_wall", "rollout_cpu"), 0.0)
    ratios, steps = [], 0
    for run in runs:
        (study, study_cpu), (plain, plain_cpu), (floor, floor_cpu) = side_by_side(
            [run.study, run.plain_loop, run.rollout], repeat
        )
        for key, value in zip(totals, (study, study_cpu, plain, plain_cpu, floor, floor_cpu)):
            totals[key] += value
        ratios.append(study / plain)
        steps += run.steps
        print(
            f"   {run.label}{run.steps:>{steps_width}} steps  study {study * 1e3:8.2f} ms"
            f"  plain loop {plain * 1e3:8.2f} ms  ratio {study / plain:5.2f}"
        )
    mean = float(np.mean(ratios))
    print(f"   mean ratio study/plain loop {mean:.2f} (below 1: the rollout's C loop beats Python's mj_step calls)")
    return totals | {"steps": steps, "runs": len(ratios), "mean_ratio": mean}


def per_run_row(name: str, work: str, found: dict[str, float], budget: float, note: str) -> Row:
    """The table's row of a `per_run_comparison` (its sums `found`): the study's chunks against the plain rollouts of
    the same steps, a budget set by the script, and the plain Python loop's cost beside them in the note."""
    return Row(
        name,
        work,
        found["study_wall"],
        found["study_cpu"],
        "rollout",
        found["rollout_wall"],
        found["rollout_cpu"],
        budget,
        "(set)",
        f"{note}; a plain Python mj_step loop recording every step costs"
        f" {found['loop_cpu'] / found['rollout_cpu']:.2f}x the rollout",
    )


@contextlib.contextmanager
def inside_mujoco() -> Iterator[list[float]]:
    """Count the wall and CPU time [s] spent inside mujoco.rollout.rollout, mujoco.mj_step and the batch's rollout.

    The calls run MuJoCo's own threads: their CPU time is this process's over the call, the threads' included."""
    spent = [0.0, 0.0]

    def timed(fn: Callable) -> Callable:
        def wrapper(*args, **kwargs):
            wall, cpu = _clock()
            try:
                return fn(*args, **kwargs)
            finally:
                wall_end, cpu_end = _clock()
                spent[0] += wall_end - wall
                spent[1] += cpu_end - cpu

        return wrapper

    from mujoco import batch

    originals = (rollout.rollout, mujoco.mj_step, batch.Batch.rollout)
    rollout.rollout, mujoco.mj_step, batch.Batch.rollout = (timed(fn) for fn in originals)
    try:
        yield spent
    finally:
        rollout.rollout, mujoco.mj_step, batch.Batch.rollout = originals


def forget_cases() -> None:
    """Drop what springlab keeps per parameter set, so the next call is a first call."""
    from springlab.exact import linear
    from springlab.runs import compare
    from springlab.scenes import base
    from springlab.scenes.drill_string import continuum

    base._COMPILED.clear()
    base._WORK.__dict__.clear()
    compare._estimate_range.cache_clear()
    continuum._roots.cache_clear()
    continuum._SPIN_UPS.clear()
    linear._EIGEN.clear()


def raw_rollout(result) -> Callable[[], object]:
    """A plain rollout of a result's steps on a configured copy of its compiled model."""
    from springlab.sim.simulate import configured, initial_state

    case = result.case
    model = configured(case.model, result.integrator, result.dt)
    data = mujoco.MjData(model)
    setup = case.setup(result.steps, result.dt)
    state = initial_state(model, setup.qpos, setup.qvel, setup.act)[None]
    control = np.zeros((result.steps, model.nu)) if setup.control is None else np.asarray(setup.control, float)
    control = np.ascontiguousarray(np.broadcast_to(control, (result.steps, model.nu)))[None]
    return lambda: rollout.rollout(model, data, state, control, nstep=result.steps)


def jobs_rollout(jobs) -> Callable[[], object]:
    """A plain one-thread rollout of each of `springlab.sim.batch.Job`s' steps, each on a configured copy of its
    compiled model (its integrator and timestep), from its initial state with its controls: the floor of a batch."""
    from springlab.sim.simulate import configured, initial_state

    inputs = []
    for job in jobs:
        model = configured(job.model, job.integrator, job.dt)
        setup = job.setup
        state = initial_state(model, setup.qpos, setup.qvel, setup.act)[None]
        control = np.zeros((job.steps, model.nu)) if setup.control is None else np.asarray(setup.control, float)
        control = np.ascontiguousarray(np.broadcast_to(control, (job.steps, model.nu)))[None]
        inputs.append((model, mujoco.MjData(model), state, control, job.steps))

    def run() -> None:
        for model, data, state, control, steps in inputs:
            rollout.rollout(model, data, state, control, nstep=steps)

    return run


def command_row(name: str, argv: list[str], work: str, budget: float, basis: str, *, cold: bool = True) -> Row:
    """A whole command in this process against the time it spent inside MuJoCo (springlab's caches cleared first
    unless `cold` is False; the modules other rows imported stay imported: `validate` is the fresh-interpreter row)."""
    from springlab.cli.main import main

    with tempfile.TemporaryDirectory() as folder:
        concrete = [a.replace("{out}", folder) for a in argv]
        if cold:
            forget_cases()
        with contextlib.redirect_stdout(open(os.devnull, "w")), inside_mujoco() as spent:
            wall, cpu = _clock()
            code = main(concrete)
            wall_end, cpu_end = _clock()
    row = Row(name, work, wall_end - wall, cpu_end - cpu, "inside MuJoCo", spent[0], spent[1], budget, basis)
    row.note = f"exit {code}; springlab " + shown(" ".join(argv).replace("{out}", "OUT"))
    return row


def fresh_import_cpu(code: str, repeat: int = 5) -> float:
    """CPU time [s] of a fresh interpreter running `code` (the interpreter's start included), best of `repeat`."""
    best = np.inf
    for _ in range(repeat):
        script = f"import time;{code};print(time.process_time())"
        out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True).stdout
        best = min(best, float(out))
    return best


def shown(text: str) -> str:
    """`text` with this checkout's, the installed packages' and the temporary folders' paths made machine-independent."""
    import sysconfig

    text = text.replace(str(ROOT) + os.sep, "")
    text = text.replace(sysconfig.get_paths()["purelib"] + os.sep, "site-packages" + os.sep)
    return text.replace(tempfile.gettempdir() + os.sep, "TMP" + os.sep)
