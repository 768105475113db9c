"""Speed of `springlab audit` on a 27-DOF model nobody here wrote: dm_control's humanoid.

1. Linearization and stability limits alone (springlab.exact.linearize + springlab.studies.audit.limits: modes,
   five integrators' limits measured on the one-step map and confirmed by nonlinear runs), best of 3,
   against the 2 s budget.
2. The sweep's runs, batched (springlab.sim.batch.run_batched: one mujoco.batch.Batch, all CPUs) against
   a plain Python loop of mujoco.mj_step over the same (integrator, dt) settings, side by side; the
   ratio. (On the grid's 10 coarsest timesteps x 5 integrators, to keep the plain loop short.)
3. The whole audit, 5 integrators x 12 timesteps (+ the model's own), 1 s of motion, against the
   60 s budget, with the wall time of each stage.

Run: python benchmarks/bench_audit.py   (needs dm_control, the `test` extra)
"""

from __future__ import annotations

import os
import pathlib
import time

import dm_control
import mujoco

from springlab.exact.linearize import linearize, operating_point
from springlab.sim import batch
from springlab.sim.simulate import INTEGRATORS, Setup, quiet_mujoco
from springlab.studies.audit.audit import audit
from springlab.studies.audit.limits import stability_limits
from timing import best_of

HUMANOID = pathlib.Path(dm_control.__file__).parent / "suite" / "humanoid.xml"


def limits_alone(model) -> float:
    def work():
        linear = linearize(model, operating_point(model))
        stability_limits(model, linear, list(INTEGRATORS), 1.0)

    return best_of(work, repeat=3)


def batched_vs_loop(model, dts) -> None:
    point = operating_point(model)
    setup = Setup(point.qpos, point.qvel, point.act, point.ctrl)
    settings = [(name, dt) for name in INTEGRATORS for dt in dts]
    jobs = [batch.Job(model, name, dt, round(1.0 / dt), setup) for name, dt in settings]
    steps = sum(job.steps for job in jobs)

    def loop():
        for name, dt in settings:
            work = model.__copy__()
            work.opt.integrator, work.opt.timestep = INTEGRATORS[name], dt
            data = mujoco.MjData(work)
            point.load(work, data)
            for _ in range(round(1.0 / dt)):
                mujoco.mj_step(work, data)

    with quiet_mujoco():  # the coarsest runs blow up (that is the point of them): no warning text
        batched = best_of(lambda: batch.run_batched(jobs), repeat=1)
        plain = best_of(loop, repeat=1)
    print(f"2. {len(jobs)} runs, {steps} steps: batched {batched:.2f} s, plain mj_step loop {plain:.2f} s")
    print(f"   ratio loop / batched: {plain / batched:.2f}x ({os.cpu_count()} CPUs)")


def main() -> None:
    print(f"load average before: {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    model = mujoco.MjModel.from_xml_path(str(HUMANOID))
    seconds = limits_alone(model)
    print(f"1. humanoid ({model.nv} DOF) linearization + limits of 5 integrators: {seconds:.2f} s (budget 2 s)")
    start = time.perf_counter()
    result = audit(str(HUMANOID), duration=1.0, tol=1e-2)
    total = time.perf_counter() - start
    dts = sorted({r.dt for r in result.runs}, reverse=True)
    batched_vs_loop(model, dts[:10])
    stages = ", ".join(f"{k.removesuffix('_s')} {v:.1f} s" for k, v in result.timings.to_dict().items())
    print(f"3. whole audit, {len(result.runs)} runs over {result.duration:g} s: {total:.1f} s (budget 60 s); {stages}")
    for line in result.message.splitlines():
        print(f"   {line}")
    print(f"load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
