"""Speed of `springlab friction-settings MODEL.xml` on the test gripper (tests/data/gripper.xml), side by side.

1. Cost per run: the study's chunk (springlab.studies.friction_hold.hold_chunk: apply the settings, one
   mujoco.rollout call over the sweep window, read the box's slip and contacts every 10 ms) against a plain
   Python loop of mujoco.mj_step on the same compiled model and settings, recording the box's position every
   step, and against a plain mujoco.rollout of the same steps on the same configured model (the floor: the
   table's row `friction-settings gripper, per run`); measured in turn, best of 3 (measure.per_run_comparison,
   bench_friction.py's loop too), on 8 configurations (MuJoCo's defaults and the last swept values; euler and
   rk4; the model's timestep and its half).
2. The whole study (`springlab friction-settings tests/data/gripper.xml --hold 60 --tol 0.025 --workers 2`:
   the model's own settings over the whole hold, the sweep, the picks verified by runs of the whole hold)
   against its 5-minute budget on 2 cores, with the machine's load average beside it.

`make bench` runs it with --skip-full: part 2 is the table's `friction-settings gripper` row at a longer hold.

Run: python benchmarks/bench_creep.py [--skip-full]
"""

from __future__ import annotations

import os
import pathlib
import sys
import time

import mujoco
import numpy as np
from mujoco import rollout

import measure
from springlab.sim.simulate import INTEGRATORS, initial_state
from springlab.studies import friction_hold, held
from springlab.studies.executor import Executor

GRIPPER = pathlib.Path(__file__).resolve().parents[1] / "tests" / "data" / "gripper.xml"
#: (integrator, dt [s]) of the per-run comparison, each at MuJoCo's defaults and at the last swept values
SAMPLE = [("euler", 2e-3), ("euler", 1e-3), ("rk4", 2e-3), ("rk4", 1e-3)]
#: the chunk's budget over the plain rollout of its steps: beyond the rollout it configures a copy of the model and
#: reads the box's slip and contacts every 10 ms (one state in 5 to 10): a few percent, held to issue 37's 1.3 of a run
CHUNK_BUDGET = 1.3


def _plain_loop(model: mujoco.MjModel, plan: held.HoldPlan, integrator: str, dt: float, duration: float):
    """The same run as a plain mj_step loop on a configured copy, the box's position recorded every step; and as
    a plain rollout of the same steps on that copy (the floor)."""
    work = held.configure(model, {}, plan)
    work.opt.integrator, work.opt.timestep = INTEGRATORS[integrator], dt
    data = mujoco.MjData(work)
    steps = round(duration / dt)
    box = plan.bodies[0]

    def run():
        mujoco.mj_resetData(work, data)
        data.qpos[:], data.qvel[:], data.ctrl[:] = plan.qpos, plan.qvel, plan.ctrl
        where = np.empty((steps, 3))
        for i in range(steps):
            mujoco.mj_step(work, data)
            where[i] = data.xipos[box]
        return where

    state = initial_state(work, plan.qpos, plan.qvel, plan.act)[None]
    control = np.ascontiguousarray(np.broadcast_to(np.asarray(plan.ctrl, float), (1, steps, work.nu)))
    floor_data = mujoco.MjData(work)

    def floor():
        return rollout.rollout(work, floor_data, state, control, nstep=steps)

    return run, floor, steps


def per_run() -> float:
    """Print the per-run comparison and emit its row; return the mean ratio study / plain loop."""
    print(
        "1) cost per run: the study's chunk (settings, rollout, slip and contacts every 10 ms) vs a plain mj_step loop"
    )
    model = mujoco.MjModel.from_xml_path(str(GRIPPER))
    plan, settings, _, _ = held.find_hold(model, str(GRIPPER), hold_s=60.0)
    window = friction_hold.SWEEP_WINDOW_S
    runs = []
    for integrator, dt in SAMPLE:
        for last in (False, True):
            chosen = {s.name: float(s.values[-1] if last else s.mujoco_default) for s in settings}
            configured = held.configure(model, chosen, plan)
            loop, floor, steps = _plain_loop(configured, plan, integrator, dt, window)
            job = ((tuple(chosen.items()), integrator, dt),)
            payload = friction_hold.HoldChunk(model, plan, window, (job,))
            which = "last values" if last else "MuJoCo's defaults"
            label = f"{integrator:<7}dt {dt:<7g}{which:<18}"
            runs.append(measure.PerRun(label, steps, lambda p=payload: friction_hold.hold_chunk(p), loop, floor))
    found = measure.per_run_comparison(runs, steps_width=6)
    measure.emit(
        measure.per_run_row(
            "friction-settings gripper, per run",
            f"{found['runs']} sweep runs of {window:g} s (euler and rk4 at 2 and 1 ms, MuJoCo's defaults and the last"
            f" swept values), {found['steps']} steps in all",
            found,
            CHUNK_BUDGET,
            "bench_creep.py: the study's chunk (settings applied, one rollout, the box's slip and contacts read every"
            " 10 ms) against a plain rollout of the same steps on the same configured model",
        )
    )
    return found["mean_ratio"]


def full_study() -> None:
    load = os.getloadavg()[0]
    start = time.perf_counter()
    with Executor(workers=2, progress=False) as executor:
        study = friction_hold.friction_hold(GRIPPER, hold_s=60.0, tol=0.025, executor=executor)
    wall = time.perf_counter() - start
    case = study.cases[0]
    cpu = sum(r.cpu_time_s for r in case.runs)
    print(
        f"2) friction-settings {GRIPPER.name} --hold 60 --workers 2: {study.runs} runs in {wall:.0f} s (budget"
        f" 300 s); {cpu:.0f} s of CPU in the sweep's simulations ({cpu / study.runs * 1e3:.1f} ms a run);"
        f" load average {load:.1f} before, {os.getloadavg()[0]:.1f} after, on {os.cpu_count()} CPUs"
    )
    print(f"   {study.answer}")


if __name__ == "__main__":
    per_run()
    if "--skip-full" not in sys.argv:
        full_study()
