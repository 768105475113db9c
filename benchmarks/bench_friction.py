"""Speed of springlab's friction-settings study, side by side in one run.

1. Cost per run: the study's chunk (springlab.studies.friction_settings.settings_chunk: build the model,
   set it up, one mujoco.rollout call, compare with the exact answer, measure the events) against a plain
   Python loop of mujoco.mj_step on the same compiled model, the same settings and steps, recording qpos
   and qvel, and against a plain mujoco.rollout of the same steps on the same compiled model (the floor: the
   table's row `friction-settings friction, per run`); measured in turn, best of 3 (measure.per_run_comparison,
   bench_creep.py's loop too), on 16 configurations spread over the four cases, the integrators and the timesteps.
2. The full sweep (`springlab friction-settings friction --tol 1e-2 --workers 2`: 4,560 runs, the picks
   verified) against its 5-minute budget on 2 cores, with the machine's load average beside it (a machine
   shared with other jobs stretches the wall time, not the CPU time each run reports).

`make bench` runs it with --skip-full (part 2 alone takes minutes; the table's `friction-settings gripper` row
runs the whole command on a model file).

Run: python benchmarks/bench_friction.py [--skip-full]
"""

from __future__ import annotations

import os
import sys
import time

import mujoco
import numpy as np
from mujoco import rollout

import measure
from springlab import scenes
from springlab.scenes import get
from springlab.sim.simulate import INTEGRATORS, check_timing, initial_state
from springlab.studies import friction_settings
from springlab.studies.executor import Executor

#: (scenario, integrator, dt [s]) of the per-run comparison, each at MuJoCo's defaults and at the last values
SAMPLE = [
    ("coulomb_decay", "euler", 2e-3),
    ("coulomb_decay", "rk4", 5e-4),
    ("contact_decay", "implicitfast", 1e-3),
    ("contact_decay", "rk4", 2.5e-4),
    ("incline_hold", "euler", 2e-3),
    ("incline_hold", "discrete", 1e-3),
    ("incline_slide", "implicitfast", 5e-4),
    ("incline_slide", "rk4", 1e-3),
]
#: the chunk's budget over the plain rollout of its steps: beyond the rollout it builds the case from the scene's
#: MJCF (parse and compile, a few ms a run), evaluates the exact answer at every recorded step and measures the
#: events; on runs of 1e3 to 1e5 steps that is tens of percent, not a multiple
CHUNK_BUDGET = 1.6


def _settings(scenario: str, last: bool) -> dict[str, float]:
    spec = get("friction").dry_friction
    case = spec.case(scenario)
    return {s.name: float(s.values[-1] if last else s.mujoco_default) for s in spec.settings_of(case.friction)}


def _plain_loop(scenario: str, integrator: str, dt: float, settings: dict[str, float]):
    """The same run as a plain mj_step loop (build once, outside the timing, then step and record), and as a plain
    rollout of the same steps on the same model (the floor)."""
    case = scenes.case("friction", scenario, settings)
    model, chosen = case.model, case.scenario
    model.opt.integrator, model.opt.timestep = INTEGRATORS[integrator], dt
    steps = check_timing(dt, chosen.duration)
    setup = case.setup(steps, dt)
    data = mujoco.MjData(model)

    def run():
        mujoco.mj_resetData(model, data)
        data.qpos[:], data.qvel[:] = setup.qpos, setup.qvel
        qpos, qvel = np.empty((steps, model.nq)), np.empty((steps, model.nv))
        for i in range(steps):
            mujoco.mj_step(model, data)
            qpos[i], qvel[i] = data.qpos, data.qvel
        return qpos, qvel

    state = initial_state(model, setup.qpos, setup.qvel, setup.act)[None]
    control = np.zeros((steps, model.nu)) if setup.control is None else np.asarray(setup.control, float)
    control = np.ascontiguousarray(np.broadcast_to(control, (steps, model.nu)))[None]
    floor_data = mujoco.MjData(model)

    def floor():
        return rollout.rollout(model, floor_data, state, control, nstep=steps)

    return run, floor, steps


def per_run() -> float:
    """Print the per-run comparison and emit its row; return the mean ratio springlab / plain loop."""
    print("1) cost per run: the study's chunk (build, set up, rollout, compare, measure) vs a plain mj_step loop")
    runs = []
    for scenario, integrator, dt in SAMPLE:
        for last in (False, True):
            settings = _settings(scenario, last)
            loop, floor, steps = _plain_loop(scenario, integrator, dt, settings)
            duration = get("friction").scenario(scenario).duration
            case = get("friction").dry_friction.case(scenario)
            payload = friction_settings.chunk_of("friction", case, {}, duration, [[(settings, integrator, dt)]])
            which = "last values" if last else "MuJoCo's defaults"
            label = f"{scenario:<14}{integrator:<13}dt {dt:<8g}{which:<18}"
            study = lambda p=payload: friction_settings.settings_chunk(p, nthread=1)  # noqa: E731
            runs.append(measure.PerRun(label, steps, study, loop, floor))
    found = measure.per_run_comparison(runs, steps_width=7)
    measure.emit(
        measure.per_run_row(
            "friction-settings friction, per run",
            f"{found['runs']} sweep runs over the four cases (euler, implicitfast, discrete, rk4; MuJoCo's defaults"
            f" and the last swept values), {found['steps']} steps in all",
            found,
            CHUNK_BUDGET,
            "bench_friction.py: the study's chunk (the case built from the scene's MJCF, set up, one rollout, compared"
            " with its exact answer, its events measured) against a plain rollout of the same steps on the same"
            " compiled model",
        )
    )
    return found["mean_ratio"]


def full_sweep() -> None:
    load = os.getloadavg()[0]
    start = time.perf_counter()
    with Executor(workers=2, progress=False) as executor:
        study = friction_settings.friction_settings("friction", tol=1e-2, executor=executor)
    wall = time.perf_counter() - start
    cpu = sum(r.cpu_time_s for case in study.cases for r in case.runs)
    print(
        f"2) friction-settings friction --tol 1e-2 --workers 2: {study.runs} runs in {wall:.0f} s (budget 300 s);"
        f" {cpu:.0f} s of CPU in the simulations ({cpu / study.runs * 1e3:.1f} ms a run);"
        f" load average {load:.1f} before, {os.getloadavg()[0]:.1f} after, on {os.cpu_count()} CPUs"
    )
    for case in study.cases:
        pick = case.pick
        found = (
            f"{case.describe(pick.row.settings)}, {pick.row.integrator} at {pick.row.dt:g} s"
            if pick and pick.row
            else "none"
        )
        print(f"   {case.scenario:<14} pick for 1e-2: {found}")


if __name__ == "__main__":
    per_run()
    if "--skip-full" not in sys.argv:
        full_sweep()
