"""Speed of `springlab friction-settings MODEL.xml` on the test gripper (tests/data/gripper.xml), side by side.

1. Cost per run: the study's chunk (springlab.studies.friction_hold.hold_chunk: apply the settings, one
   mujoco.rollout call over the sweep window, read the box's slip and contacts every 10 ms) against a plain
   Python loop of mujoco.mj_step on the same compiled model and settings, recording the box's position every
   step; measured alternately, best of 3, on 8 configurations (MuJoCo's defaults and the last swept values;
   euler and rk4; the model's timestep and its half).
2. The whole study (`springlab friction-settings tests/data/gripper.xml --hold 60 --tol 0.025 --workers 2`:
   the model's own settings over the whole hold, the sweep, the picks verified by runs of the whole hold)
   against its 5-minute budget on 2 cores, with the machine's load average beside it.

Run: python benchmarks/bench_creep.py [--skip-full]
"""

from __future__ import annotations

import os
import pathlib
import sys
import time

import mujoco
import numpy as np

from springlab.sim.simulate import INTEGRATORS
from springlab.studies import friction_hold, held
from springlab.studies.executor import Executor
from timing import best_of

GRIPPER = pathlib.Path(__file__).resolve().parents[1] / "tests" / "data" / "gripper.xml"
#: (integrator, dt [s]) of the per-run comparison, each at MuJoCo's defaults and at the last swept values
SAMPLE = [("euler", 2e-3), ("euler", 1e-3), ("rk4", 2e-3), ("rk4", 1e-3)]


def _plain_loop(model: mujoco.MjModel, plan: held.HoldPlan, integrator: str, dt: float, duration: float):
    """The same run as a plain mj_step loop on a configured copy, the box's position recorded every step."""
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

    return run, steps


def per_run() -> float:
    """Print the per-run comparison; return the mean ratio study / plain loop."""
    print(
        "1) cost per run: the study's chunk (settings, rollout, slip and contacts every 10 ms) vs a plain mj_step loop"
    )
    model = mujoco.MjModel.from_xml_path(str(GRIPPER))
    plan, settings, _, _ = held.find_hold(model, str(GRIPPER), hold_s=60.0)
    window = friction_hold.SWEEP_WINDOW_S
    ratios = []
    for integrator, dt in SAMPLE:
        for last in (False, True):
            chosen = {s.name: float(s.values[-1] if last else s.mujoco_default) for s in settings}
            configured = held.configure(model, chosen, plan)
            loop, steps = _plain_loop(configured, plan, integrator, dt, window)
            job = ((tuple(chosen.items()), integrator, dt),)
            payload = friction_hold.HoldChunk(model, plan, window, (job,))
            study_times, loop_times = [], []
            for _ in range(3):  # alternately, the best of each kept
                study_times.append(best_of(lambda p=payload: friction_hold.hold_chunk(p), repeat=1))
                loop_times.append(best_of(loop, repeat=1))
            study, plain = min(study_times), min(loop_times)
            ratios.append(study / plain)
            which = "last values" if last else "MuJoCo's defaults"
            print(
                f"   {integrator:<7}dt {dt:<7g}{which:<18}{steps:>6} steps  study {study * 1e3:8.2f} ms"
                f"  plain loop {plain * 1e3:8.2f} ms  ratio {study / plain:5.2f}"
            )
    mean = float(np.mean(ratios))
    print(f"   mean ratio study/plain loop {mean:.2f} (below 1: the rollout's C loop beats Python's mj_step calls)")
    return mean


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
