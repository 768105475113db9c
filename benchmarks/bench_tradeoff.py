"""Speed of springlab's trade-off sweep, side by side in one run.

1. The accuracy pass of the full slider `free` sweep (5 integrators x 13
   timesteps, 65 runs, 0.5 M steps): springlab.sim.batch.run_batched (one
   mujoco.batch.Batch, all CPUs, and on one thread) against a plain loop of
   springlab.sim.simulate.simulate calls; best of 3 each, in turn, and the ratios; the batch on one thread
   against a plain one-thread rollout of the same runs is the row `tradeoff accuracy pass, batched` of
   `make bench`'s table.
2. The whole `springlab tradeoff slider free --tol 1e-6` (sweep, timing pass,
   verified recommendation) against its 10 s budget (the table's `tradeoff` row
   measures the command at its default tolerance against its time inside MuJoCo).

Run: python benchmarks/bench_tradeoff.py
"""

from __future__ import annotations

import os
import time

import numpy as np

import measure
from springlab import scenes
from springlab.sim import batch
from springlab.sim.simulate import INTEGRATORS, simulate
from springlab.studies import tradeoff


def sweep_jobs():
    case = scenes.get("slider").case("free")
    chosen = case.scenario
    dts = tradeoff.timestep_grid(tradeoff.fastest_rate(case), chosen.duration)
    jobs = []
    for dt in dts:
        steps = round(chosen.duration / dt)
        setup = case.setup(steps, dt)
        jobs.extend(case.job(name, dt, steps, setup=setup) for name in INTEGRATORS)
    return jobs


def batched_vs_loop() -> None:
    jobs = sweep_jobs()
    steps = sum(job.steps for job in jobs)

    def loop():
        return [
            simulate(
                job.model,
                integrator=job.integrator,
                dt=job.dt,
                duration=job.steps * job.dt,
                qpos=job.setup.qpos,
                qvel=job.setup.qvel,
                control=job.setup.control,
            )
            for job in jobs
        ]

    # same numbers first: the comparison is only fair if both compute the same thing
    for a, b in zip(batch.run_batched(jobs), loop()):
        assert np.array_equal(a.qpos, b.qpos) and np.array_equal(a.qvel, b.qvel)
    timings = measure.side_by_side(
        [
            loop,
            lambda: batch.run_batched(jobs, nthread=0),
            lambda: batch.run_batched(jobs, nthread=1),
            measure.jobs_rollout(jobs),
        ],
        3,
    )
    (loop_time, _), (batch_all, _), (batch_one, batch_one_cpu), (floor, floor_cpu) = timings
    print(f"1) accuracy pass of the slider/free sweep: {len(jobs)} runs, {steps:,} steps, {os.cpu_count()} CPUs")
    print(f"   plain loop of simulate()       {loop_time:8.3f} s  ({steps / loop_time:,.0f} steps/s)")
    print(f"   run_batched, one thread        {batch_one:8.3f} s  ratio loop/batched {loop_time / batch_one:5.2f}")
    print(f"   run_batched, all CPUs          {batch_all:8.3f} s  ratio loop/batched {loop_time / batch_all:5.2f}")
    measure.emit(
        measure.Row(
            "tradeoff accuracy pass, batched",
            f"slider free: {len(jobs)} runs (5 integrators x {len(jobs) // 5} timesteps), {steps} steps, one thread",
            batch_one,
            batch_one_cpu,
            "rollout",
            floor,
            floor_cpu,
            # beyond the rollouts: the batch's setup per run and its divergence check per segment, as a run's 1.3
            measure.RUN_BUDGET,
            "(set), as a run's",
            "bench_tradeoff.py: springlab.sim.batch.run_batched on one thread (one mujoco.batch.Batch, per-run"
            " timestep and integrator, divergence checks) against a plain one-thread rollout of each run's steps on"
            f" its configured model; on all CPUs {batch_all:.3g} s wall",
        )
    )


def full_tradeoff() -> None:
    start = time.perf_counter()
    result = tradeoff.tradeoff("slider", "free", tol=1e-6)
    elapsed = time.perf_counter() - start
    pick = result.recommendation
    print(
        f"2) tradeoff slider free --tol 1e-6: {len(result.runs)} runs in {elapsed:.2f} s (budget 10 s);"
        f" recommendation {pick.integrator} dt = {pick.dt:g} s, error {pick.error:.2e}"
    )


if __name__ == "__main__":
    batched_vs_loop()
    full_tradeoff()
