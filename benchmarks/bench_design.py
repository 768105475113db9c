"""Speed of the printer-head design sweep, side by side in one run.

The batched sweep (the printer head's design hook, springlab.scenes.printer_head.design.simulate_moves,
through springlab.studies.design.moves.simulate: one mujoco.batch.Batch, every
configuration its own simulation with its own timestep, settling certified and
stopped per simulation) against a plain Python loop over mujoco.mj_step that
integrates the same configurations for the same number of steps (taken from the
batched run, so both do identical physics work), with the same bang-bang control
set before every step. The loop runs on an evenly spaced subset and its time is
scaled per configuration; the ratio is configurations/s batched over looped.
Also the batch on one thread, to separate threading from the batching itself.

Its row, `design printer_head moves, batched`, is the batch on one thread against a plain rollout of the same
configurations for the same steps. Not in `make bench`'s default run: the table's `design printer_head` (the whole
command against its time inside MuJoCo) and `design printer_head --sobol` (the same batched moves against the same
rollout) rows measure the same path; `bench.py --only bench_design` runs it.

Run: PYTHONPATH=src python benchmarks/bench_design.py [levels] [loop subset]
"""

from __future__ import annotations

import os
import sys
import time

import mujoco
import numpy as np

import bench_sobol
import measure
from springlab import scenes
from springlab.scenes.printer_head import design as printer_design
from springlab.sim.simulate import quiet_mujoco
from springlab.studies.design import moves as design_moves
from springlab.studies.design import study as design


def loop_configurations(base, values, runs, indices) -> float:
    """Wall time [s] of a plain mj_step loop over configurations `indices` (same steps as the batch)."""
    scene = scenes.get("printer_head")
    scenario = scene.scenario("move")
    dt_all = runs.dt_s
    half_steps, force = printer_design.move_profiles(base, values, dt_all)
    start = time.perf_counter()
    with quiet_mujoco():
        for i in indices:
            params = printer_design.config_parameters(base, values, int(i))
            model = scene.build(params, scenario)  # per-configuration model, as a user's loop would
            model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
            model.opt.timestep = float(dt_all[i])
            data = mujoco.MjData(model)
            half, f = int(half_steps[i]), float(force[i])
            for step in range(int(runs.steps[i])):
                data.ctrl[0] = f if step < half else (-f if step < 2 * half else 0.0)
                mujoco.mj_step(model, data)
    return time.perf_counter() - start


def main() -> None:
    levels = int(sys.argv[1]) if len(sys.argv) > 1 else design.DEFAULT_LEVELS
    subset = int(sys.argv[2]) if len(sys.argv) > 2 else 40
    base = design.base_parameters("printer_head")
    values = design.configurations(design.make_grids("printer_head", base, levels))
    n = len(values["belt_stiffness"])
    print(f"printer_head design sweep: {n} configurations ({levels}^4), {os.cpu_count()} CPUs")

    start = time.perf_counter()
    runs = design_moves.simulate("printer_head", base, values)  # all threads
    wall = time.perf_counter() - start
    floor = bench_sobol.raw_rollout(base, values, np.asarray(runs.steps))
    (single_wall, single_cpu), (floor_wall, floor_cpu) = measure.side_by_side(
        [lambda: design_moves.simulate("printer_head", base, values, nthread=1), floor], 1
    )
    steps = int(runs.steps.sum())
    indices = np.linspace(0, n - 1, min(subset, n)).astype(int)
    loop_wall = loop_configurations(base, values, runs, indices)
    loop_steps = int(runs.steps[indices].sum())
    # scale the loop to the whole sweep by its steps (configurations differ in length)
    loop_full = loop_wall * steps / loop_steps

    batched_rate = n / wall
    single_rate = n / single_wall
    loop_rate = n / loop_full
    print(f"  {'runner':<34}{'wall [s]':>10}{'config/s':>11}{'Msteps/s':>10}{'x loop':>8}")
    print(
        f"  {'batch, ' + str(runs.nthread) + ' threads':<34}{wall:>10.2f}{batched_rate:>11.1f}"
        f"{steps / wall / 1e6:>10.2f}{batched_rate / loop_rate:>8.1f}"
    )
    print(
        f"  {'batch, 1 thread':<34}{single_wall:>10.2f}{single_rate:>11.1f}"
        f"{steps / single_wall / 1e6:>10.2f}{single_rate / loop_rate:>8.1f}"
    )
    print(
        f"  {'python mj_step loop (scaled)':<34}{loop_full:>10.2f}{loop_rate:>11.1f}"
        f"{loop_steps / loop_wall / 1e6:>10.2f}{1.0:>8.1f}"
    )
    print(
        f"  loop measured on {len(indices)} configurations, {loop_steps} steps in {loop_wall:.2f} s;"
        f" the sweep is {steps} steps ({steps / n:.0f} per configuration)"
    )
    measure.emit(
        measure.Row(
            "design printer_head moves, batched",
            f"{n} configurations ({levels}^4), {steps} steps rk4, one thread",
            single_wall,
            single_cpu,
            "rollout",
            floor_wall,
            floor_cpu,
            1.3,
            "(set), as `design printer_head --sobol`'s",
            "bench_design.py: the design hook's batched moves on one thread (settling certified and stopped per"
            " simulation) against a plain one-thread rollout of the same configurations for the same steps"
            " (bench_sobol.raw_rollout)",
        )
    )


if __name__ == "__main__":
    main()
