"""What the executor costs and buys, side by side in one run.

1. Printer-head design configurations per second per core: local threads vs a
   dask LocalCluster with 1 and 2 worker processes (same chunks), the scaling
   efficiency 1 -> 2 workers, and the executor's per-task overhead (a chunk that
   does nothing).
2. The default Sobol study (16384 x 7 = 114,688 runs): projected wall time on
   this machine from the measured rate, and on a 64-core cluster from the
   per-core rate and the per-task overhead.
3. A 1000-configuration slider sweep: springlab's batched path (the sweep's
   chunks through `batch.run_batched`) vs raw threaded `mujoco.rollout` over
   the same compiled models (target >= 0.9x); the whole sweep with every row
   evaluated; and a scipy `solve_ivp` loop at the same accuracy.
4. `springlab.run` over the bare simulation (target <= 1.15), and what the
   cached spec saves per run.

`make bench` runs `bench_executor.py chunks`: part 3's first comparison alone, its row `sweep chunks, batched`.
Parts 1 and 2 are what bench_sobol.py measures on the Sobol study (the LocalCluster's scaling and the 64-core
projection), the rest of 3 is the table's `sweep` row (the whole command against its time inside MuJoCo) and 4 is
its `run` rows (every scene's default run against its raw rollout).

Run: python benchmarks/bench_executor.py [design] [sweep | chunks] [run]   (numbers depend on the load of the machine;
no part named: design, sweep and run)
"""

from __future__ import annotations

import math
import os
import time

import mujoco
import numpy as np
from mujoco import rollout

import measure
from springlab import scenes
from springlab.exact import analytic
from springlab.runs.run import run_scenario
from springlab.scenes.base import parsed_spec
from springlab.sim import model_files
from springlab.sim.batch import Job, run_rollout
from springlab.sim.simulate import initial_state, simulate
from springlab.studies import sweeps
from springlab.studies.design import moves as design_moves
from springlab.studies.design import sobol
from springlab.studies.design import study as design
from springlab.studies.executor import Executor, chunked, ping
from timing import best_of


def design_throughput() -> dict[str, float]:
    base = design.base_parameters("printer_head")
    values = design.configurations(design.make_grids("printer_head", base, 5))  # 625 configurations, 10 chunks of 64
    n = len(values["belt_stiffness"])
    cores = os.cpu_count() or 1

    def rate(executor: Executor, workers: int = 1) -> float:
        # warm up every worker (imports and the cached spec on its first task), not just the first one
        warm = {k: v[: 64 * workers] for k, v in values.items()}
        design_moves.run_moves("printer_head", base, warm, executor=executor, chunk_size=64)
        return n / best_of(
            lambda: design_moves.run_moves("printer_head", base, values, executor=executor, chunk_size=64), repeat=3
        )

    print(f"1) printer-head design run, {n} configurations in chunks of 64, {cores} cores")
    rates = {"local threads": rate(Executor(progress=False))}
    overhead = {}
    for workers in (1, 2):
        with Executor(workers=workers, progress=False) as executor:
            rates[f"LocalCluster {workers} worker{'s' if workers > 1 else ''}"] = rate(executor, workers)
            if workers == 2:
                executor.map(ping, list(range(10)))
                tasks = 200
                overhead["task_s"] = best_of(lambda: executor.map(ping, list(range(tasks))), repeat=3) / tasks * workers
    used = {"local threads": cores, "LocalCluster 1 worker": 1, "LocalCluster 2 workers": 2}
    print(f"   {'runner':<24}{'configs/s':>11}{'configs/s/core':>16}")
    for name, value in rates.items():
        print(f"   {name:<24}{value:>11.1f}{value / used[name]:>16.1f}")
    efficiency = rates["LocalCluster 2 workers"] / (2 * rates["LocalCluster 1 worker"])
    print(f"   scaling efficiency 1 -> 2 workers: {efficiency:.0%} (target >= 80 % on 2 free cores)")
    print(f"   per-task overhead (empty chunk, 2 workers): {overhead['task_s'] * 1e3:.2f} ms per task per worker")
    return {"per_core": rates["LocalCluster 1 worker"], "two_core": max(rates.values()), **overhead}


def sobol_projection(measured: dict[str, float]) -> None:
    runs = sobol.DEFAULT_BASE_SAMPLES * (len(scenes.get("printer_head").design.sobol) + 2)
    chunks = math.ceil(runs / sobol.CHUNK_CONFIGURATIONS)
    here = runs / measured["two_core"]
    cluster = runs / (64 * measured["per_core"]) + chunks / 64 * measured["task_s"]
    print(f"2) default Sobol study: {runs:,} runs in {chunks} chunks")
    print(f"   projected on this machine (best 2-core rate): {here / 60:.1f} min")
    print(f"   projected on 64 cores (per-core rate, + overhead per task): {cluster:.0f} s")


def slider_sweep(whole_sweep: bool = True) -> None:
    vary = {"damping": (0.5, 40.0, 25, "log"), "stiffness": (100.0, 2000.0, 40)}
    scene = scenes.get("slider")
    chosen = scene.scenario("free")
    dt, duration = chosen.dt or scene.dt, chosen.duration
    steps = round(duration / dt)
    values = sweeps.configurations([sweeps.typed_axis(name, spec) for name, spec in vary.items()])
    n = len(values["damping"])
    cases = [scene.case(chosen, {k: float(values[k][i]) for k in values}) for i in range(n)]
    params, models = [case.params for case in cases], [case.model for case in cases]
    setups = [case.setup(steps, dt) for case in cases]
    jobs = [Job(m, scene.integrator, dt, steps, s) for m, s in zip(models, setups)]
    print(f"3) slider sweep, {n} configurations x {steps} steps ({scene.integrator}, dt = {dt:g} s)")

    def springlab_batched():
        for piece in chunked(n, sweeps.CHUNK_CONFIGURATIONS):
            run_rollout(jobs[piece.start : piece.stop], private_models=True)

    nthread = os.cpu_count() or 1
    for m in models:
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
        m.opt.timestep = dt
    datas = [mujoco.MjData(models[0]) for _ in range(nthread)]
    states = np.stack([initial_state(m, s.qpos, s.qvel) for m, s in zip(models, setups)])
    with rollout.Rollout(nthread=nthread) as pool:
        # interleaved, so both see the same load
        (raw, raw_cpu), (ours, ours_cpu) = measure.side_by_side(
            [lambda: pool.rollout(models, datas, states, nstep=steps), springlab_batched], 3
        )
    print(f"   raw threaded rollout ({nthread} threads):   {raw:.3f} s")
    print(f"   springlab batched chunks:             {ours:.3f} s   raw / springlab = {raw / ours:.2f} (target >= 0.9)")
    measure.emit(
        measure.Row(
            "sweep chunks, batched",
            f"slider free: {n} configurations x {steps} steps rk4, {nthread} threads",
            ours,
            ours_cpu,
            "rollout",
            raw,
            raw_cpu,
            measure.SIMULATE_BUDGET,
            "issue 37, as simulate's",
            "bench_executor.py: the sweep's chunks through springlab.sim.batch.run_rollout against a raw threaded"
            " mujoco.rollout of the same compiled models and steps (CPU of all threads)",
        )
    )
    if not whole_sweep:
        return
    whole = best_of(lambda: sweeps.sweep("slider", "free", vary=vary), repeat=1)
    print(f"   whole sweep (build, run, evaluate):   {whole:.3f} s   ({n / whole:.0f} configurations/s)")
    result = sweeps.sweep("slider", "free", vary=vary)
    target = np.array([max(row.errors.values()) for row in result.rows])
    scipy_time, worst = _solve_ivp_loop(params, dt, steps, target)
    print(
        f"   scipy solve_ivp loop (DOP853, rtol = each row's springlab error / 1000; worst row's error over"
        f" springlab's {worst:.2f}):"
        f" {scipy_time:.3f} s   scipy / whole sweep = {scipy_time / whole:.1f}"
    )


def _solve_ivp_loop(params, dt, steps, target) -> tuple[float, float]:
    from scipy.integrate import solve_ivp

    t = np.arange(steps + 1) * dt
    worst = 0.0
    start = time.perf_counter()
    for p, tol in zip(params, target):
        m, k, d, x0, v0 = (p[n] for n in ("mass", "stiffness", "damping", "x0", "v0"))
        solution = solve_ivp(
            lambda _, z: (z[1], -(k * z[0] + d * z[1]) / m),
            (0.0, t[-1]),
            (x0, v0),
            method="DOP853",
            t_eval=t,
            rtol=tol / 1000,  # DOP853 is 8th order: a tight tolerance costs few more steps
            atol=tol * abs(x0) / 1000,
        )
        x, v = analytic.free_response(t, m, k, d, x0, v0)
        # judged as springlab judges a run: max |error| / max |exact| of position and velocity
        for simulated, exact in ((solution.y[0], x), (solution.y[1], v)):
            worst = max(worst, float(np.max(np.abs(simulated - exact)) / np.max(np.abs(exact)) / tol))
    return time.perf_counter() - start, worst


def run_overhead() -> None:
    scene = scenes.get("slider")
    print("4) springlab.run over the bare simulation (same model, setting and steps)")
    for name in ("free", "harmonic"):
        case = scene.case(name)
        chosen, model = case.scenario, case.model
        dt = chosen.dt or scene.dt
        steps = round(chosen.duration / dt)
        setup = case.setup(steps, dt)
        bare = best_of(
            lambda: simulate(
                model, integrator=scene.integrator, dt=dt, duration=chosen.duration, qpos=setup.qpos,
                qvel=setup.qvel, act=setup.act, control=setup.control,
            ),
            repeat=30,
        )  # fmt: skip
        whole = best_of(lambda: run_scenario("slider", name), repeat=30)
        print(f"   {name:<9} simulate {bare * 1e3:7.3f} ms  run {whole * 1e3:7.3f} ms  run/simulate {whole / bare:.3f}")
    path = str(model_files.path("slider"))
    parse = best_of(lambda: mujoco.MjSpec.from_file(path), repeat=50)
    copy = best_of(lambda: parsed_spec(path).copy(), repeat=50)
    print(f"   MJCF parse {parse * 1e3:.3f} ms vs copy of the cached spec {copy * 1e3:.3f} ms per run")


if __name__ == "__main__":  # LocalCluster workers are spawned processes: they re-import this file
    import sys

    parts = set(sys.argv[1:]) or {"design", "sweep", "run"}  # e.g. `bench_executor.py sweep run`, or `chunks`
    if "design" in parts:
        sobol_projection(design_throughput())
    if "sweep" in parts or "chunks" in parts:
        slider_sweep(whole_sweep="sweep" in parts)
    if "run" in parts:
        run_overhead()
