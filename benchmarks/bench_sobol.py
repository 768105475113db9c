"""The printer head's Sobol study: its cost per run against the raw rollout of the same steps, its
scaling on a dask LocalCluster, and its projection to the default 114,688 runs and to 64 cores.

1. Cost per run, side by side in one run, on one thread each (CPU time: the load of a shared machine
   disturbs it least): `run_sobol` (sampling, the scene's batched moves in chunks of 256 configurations,
   certified settling, SALib's analysis) against a plain `mujoco.rollout` of the same configurations
   for the same number of steps each (taken from the study's own runs), on one MjModel per configuration
   (its masses, belt, force limit and timestep) with the same bang-bang controls, grouped by step count,
   nothing in Python between steps. The floor's steps are the study's: what the study costs beyond them
   is the ratio; how many steps it needs is `steps per run` beside the positioning time in steps.
2. The same study on a `dask.distributed.LocalCluster` of 1 and 2 single-threaded workers (every worker
   warmed up first): wall time, the scaling 1 -> 2 workers, and the executor's per-task overhead (an empty
   task, `executor.ping`).
3. Projections of the default study (16384 x 7 = 114,688 runs): on this machine's 2 cores idle, from the
   CPU time per run (simulation) plus the analysis at that size; on 64 cores, 64 single-threaded dask
   workers, from the per-worker time of a chunk plus the per-task overhead (module `projection`).

Part 1 at N = 256 is the table's row `design printer_head --sobol` (bench.py's sobol_row); this script adds the
row `design printer_head --sobol, LocalCluster` (part 2's 2 workers, their CPU against part 1's rollout, the
projections in its note). `make bench` runs it at N = 64 (448 runs), stated in the row's work.

Run: PYTHONPATH=src python benchmarks/bench_sobol.py [N] [--no-cluster]   (N: base samples, default 256)
"""

from __future__ import annotations

import copy
import math
import sys
import time
from collections.abc import Callable

import mujoco
import numpy as np
from mujoco import rollout

import measure
from springlab import scenes
from springlab.scenes.base import Case
from springlab.scenes.printer_head import design as printer_design
from springlab.studies.design import moves, sobol
from springlab.studies.executor import Executor, ping

SCENE = "printer_head"
#: cores of the cluster the study is projected to
CLUSTER_CORES = 64
#: the workers' CPU over a plain rollout of the same steps: the study's own (the table's one-thread row: 1.3) and,
#: per chunk of 256 runs (about 1.5 s of CPU), its pickling and dask's bookkeeping (milliseconds): within 1.5
CLUSTER_BUDGET = 1.5


def default_runs() -> int:
    """Runs of the default study: N (D + 2) = 16384 x 7 = 114,688."""
    return sobol.DEFAULT_BASE_SAMPLES * (len(scenes.get(SCENE).design.sobol) + 2)


def _clock() -> tuple[float, float]:
    return time.perf_counter(), time.process_time()


def timed(fn: Callable[[], object]) -> tuple[float, float, object]:
    """(wall [s], CPU [s] of this process, result) of fn()."""
    wall, cpu = _clock()
    out = fn()
    return time.perf_counter() - wall, time.process_time() - cpu, out


def study_values(base_samples: int) -> tuple[dict[str, float], dict[str, np.ndarray]]:
    """The study's base parameters and its configurations (property -> (runs,) values), as `run_sobol` makes them."""
    scene = scenes.get(SCENE)
    spec = scene.design
    names = list(spec.sobol)
    base = moves.base_parameters(SCENE)
    spans = {p.name: p.span for p in (*spec.properties, *(spec.get(n) for n in names))}
    rows = sobol.sample(sobol.problem(names), base_samples)
    return base, sobol.properties(spec.hooks.defaults(base), spans, names, rows)


def raw_rollout(base: dict[str, float], values: dict[str, np.ndarray], steps: np.ndarray) -> Callable[[], None]:
    """A plain single-threaded `mujoco.rollout` of every configuration for `steps` each (the floor)."""
    scene = scenes.get(SCENE)
    case = Case.compiled(scene, scene.scenario(scene.design.scenario), base)
    n = len(steps)
    dt = printer_design.timesteps(values, base, moves.OMEGA_DT)
    half_steps, force = printer_design.move_profiles(base, values, dt)
    damping = printer_design.belt_damping(values, base["motor_mass"])
    carriage, belt = case.model.body("carriage").id, case.model.tendon("belt").id
    models, states = [], []
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    for i in range(n):
        model = copy.copy(case.model)
        model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
        model.opt.timestep = dt[i]
        model.body_mass[carriage] = values["carriage_mass"][i]
        model.tendon_stiffness[belt] = values["belt_stiffness"][i]
        model.tendon_damping[belt] = damping[i]
        model.actuator_ctrlrange[0] = (-values["drive_force"][i], values["drive_force"][i])
        data = mujoco.MjData(model)
        mujoco.mj_setConst(model, data)
        total = values["carriage_mass"][i] + base["motor_mass"]
        data.qpos[model.joint("carriage").qposadr[0]] = -base["motor_mass"] * base["deflection"] / total
        data.qpos[model.joint("motor").qposadr[0]] = values["carriage_mass"][i] * base["deflection"] / total
        state = np.empty(mujoco.mj_stateSize(model, spec))
        mujoco.mj_getState(model, data, state, spec)
        models.append(model)
        states.append(state)
    groups = [np.flatnonzero(steps == s) for s in np.unique(steps)]
    inputs = []
    for group in groups:
        count = int(steps[group[0]])
        taken = np.arange(count)[None, :]
        half, f = half_steps[group][:, None], force[group][:, None]
        control = np.where(taken < half, f, np.where(taken < 2 * half, -f, 0.0))[..., None]
        inputs.append(([models[i] for i in group], np.stack([states[i] for i in group]), control, count))
    data = mujoco.MjData(case.model)

    def run() -> None:
        for group_models, group_states, control, count in inputs:
            rollout.rollout(group_models, data, group_states, control, nstep=count)

    return run


def cost_per_run(base_samples: int) -> dict[str, float]:
    """Part 1: the study and its floor on one thread each, alternately, best of two (printed)."""
    base, values = study_values(base_samples)
    runs = len(values["belt_stiffness"])
    hook = moves.simulate(SCENE, base, values, nthread=1)  # the steps each configuration takes in the study
    steps = np.asarray(hook.steps)
    floor = raw_rollout(base, values, steps)
    best = [math.inf] * 4
    study = None
    for _ in range(2):
        wall, cpu, study = timed(
            lambda: sobol.run_sobol(SCENE, base_samples, executor=Executor(nthread=1, progress=False))
        )
        best[0], best[1] = min(best[0], wall), min(best[1], cpu)
        wall, cpu, _ = timed(floor)
        best[2], best[3] = min(best[2], wall), min(best[3], cpu)
    assert isinstance(study, sobol.SobolStudy)
    settled_steps = hook.positioning_time_s / hook.dt_s
    print(f"1) {SCENE} Sobol study, N = {base_samples}: {runs} runs, one thread each (CPU time)")
    print(
        f"   steps per run {steps.mean():.0f} (move {np.mean(hook.move_time_s / hook.dt_s):.0f}, positioning time"
        f" {np.mean(settled_steps):.0f}; stopped at the first {printer_design.CHUNK}-step chunk end after the"
        f" settling is certified)"
    )
    print(f"   {'path':<44}{'wall [s]':>10}{'CPU [s]':>10}{'CPU/run [ms]':>14}{'ns/step':>9}")
    for label, wall, cpu in (
        ("run_sobol (whole study)", best[0], best[1]),
        ("raw mujoco.rollout, same steps", *best[2:]),
    ):
        print(f"   {label:<44}{wall:>10.2f}{cpu:>10.2f}{cpu / runs * 1e3:>14.3f}{cpu / steps.sum() * 1e9:>9.0f}")
    print(f"   ratio (CPU): {best[1] / best[3]:.2f}")
    return {
        "runs": runs,
        "cpu_per_run_s": best[1] / runs,
        "floor_cpu_per_run_s": best[3] / runs,
        "floor_wall_per_run_s": best[2] / runs,
        "study": study,
    }


def analysis_cost() -> float:
    """CPU time [s] of SALib's analysis (100 bootstrap resamples) at the default N (on a stand-in output)."""
    names = list(scenes.get(SCENE).design.sobol)
    space = sobol.problem(names)
    rows = sobol.sample(space, sobol.DEFAULT_BASE_SAMPLES)
    output = 0.05 + 0.01 * np.sum(rows, axis=1)
    return timed(lambda: sobol.analyze(space, output))[1]


def cluster(base_samples: int, reference: sobol.SobolStudy) -> dict[str, float]:
    """Part 2: the study on LocalClusters of 1 and 2 workers (wall [s]), and the per-task overhead [s]."""
    out: dict[str, float] = {}
    for workers in (1, 2):
        with Executor(workers=workers, progress=False) as executor:
            # warm every worker: imports and the scene's cached spec on its first task
            sobol.run_sobol(SCENE, 4 * workers, executor=executor)
            before = sum(executor.client.run(time.process_time).values())
            wall, _, study = timed(lambda: sobol.run_sobol(SCENE, base_samples, executor=executor))
            out[f"worker_cpu_{workers}"] = sum(executor.client.run(time.process_time).values()) - before
            assert isinstance(study, sobol.SobolStudy)
            same = (
                study.to_dict()["S1"] == reference.to_dict()["S1"]
                and study.to_dict()["ST"] == reference.to_dict()["ST"]
            )
            out[f"wall_{workers}"] = wall
            out[f"same_{workers}"] = float(same)
            executor.map(ping, list(range(10)))
            tasks = 200
            out[f"task_{workers}"] = timed(lambda: executor.map(ping, list(range(tasks))))[0] / tasks * workers
    return out


def projection(cost: dict[str, float], measured: dict[str, float] | None, analysis_s: float) -> str:
    """Part 3: the default study on this machine's 2 idle cores and on a 64-core cluster (printed; returned in a
    line for the table's note)."""
    runs = default_runs()
    chunks = math.ceil(runs / sobol.CHUNK_CONFIGURATIONS)
    cpu = cost["cpu_per_run_s"]
    print(f"3) the default study: {runs:,} runs in {chunks} chunks of {sobol.CHUNK_CONFIGURATIONS}")
    here = (cpu * runs / 2 + analysis_s) / 60
    print(f"   2 idle cores (CPU per run x runs / 2 + analysis {analysis_s:.1f} s): {here:.1f} min")
    if measured is None:
        return f"{runs:,} runs projected on 2 idle cores {here:.1f} min"
    # a chunk on a worker: the workers' CPU per run on the 2-worker cluster (simulation, pickling, dask's own)
    chunk_s = measured["worker_cpu_2"] / cost["runs"] * sobol.CHUNK_CONFIGURATIONS
    overhead = measured["task_2"]
    rounds = math.ceil(chunks / CLUSTER_CORES)
    print(
        f"   {CLUSTER_CORES} single-threaded workers: {rounds} rounds of {CLUSTER_CORES} chunks x ({chunk_s:.2f} s of"
        f" CPU + {overhead * 1e3:.1f} ms per task) + analysis {analysis_s:.1f} s ="
        f" {rounds * (chunk_s + overhead) + analysis_s:.0f} s (cluster start and imports not counted)"
    )
    return (
        f"{runs:,} runs projected on 2 idle cores {here:.1f} min, on {CLUSTER_CORES} single-threaded dask workers"
        f" {rounds * (chunk_s + overhead) + analysis_s:.0f} s"
    )


def cluster_row(cost: dict[str, float], measured: dict[str, float], projected: str) -> measure.Row:
    """The study on the 2-worker LocalCluster: the workers' CPU against a plain rollout of the same steps."""
    runs = cost["runs"]
    return measure.Row(
        "design printer_head --sobol, LocalCluster",
        f"{runs} runs (N = {runs // (len(scenes.get(SCENE).design.sobol) + 2)}), 2 single-threaded dask workers",
        measured["wall_2"],
        measured["worker_cpu_2"],
        "rollout",
        cost["floor_wall_per_run_s"] * runs,
        cost["floor_cpu_per_run_s"] * runs,
        CLUSTER_BUDGET,
        "(set)",
        f"bench_sobol.py: the workers' CPU against a plain one-thread rollout of the same steps; scaling 1 -> 2"
        f" workers {measured['wall_1'] / (2 * measured['wall_2']):.0%}; {projected}",
    )


def main(argv: list[str]) -> None:
    base_samples = int(argv[0]) if argv and not argv[0].startswith("-") else 256
    cost = cost_per_run(base_samples)
    measured = None
    if "--no-cluster" not in argv:
        measured = cluster(base_samples, cost["study"])
        runs = cost["runs"]
        print(f"2) the same study on a dask LocalCluster (single-threaded workers, warmed up), {runs} runs")
        for workers in (1, 2):
            wall = measured[f"wall_{workers}"]
            same = "identical" if measured[f"same_{workers}"] else "DIFFERENT"
            print(
                f"   {workers} worker{'s' * (workers > 1)}: {wall:.2f} s wall, {runs / wall:.0f} runs/s;"
                f" workers' CPU {measured[f'worker_cpu_{workers}'] / runs * 1e3:.2f} ms per run; indices {same} to the"
                f" local run; per-task overhead {measured[f'task_{workers}'] * 1e3:.1f} ms"
            )
        print(f"   scaling 1 -> 2 workers: {measured['wall_1'] / (2 * measured['wall_2']):.0%}")
    projected = projection(cost, measured, analysis_cost())
    if measured is not None:
        measure.emit(cluster_row(cost, measured, projected))


if __name__ == "__main__":  # LocalCluster workers are spawned processes: they re-import this file
    main(sys.argv[1:])
