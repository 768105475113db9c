"""Speed of `springlab audit` on a 27-DOF model nobody here wrote: dm_control's humanoid, lying on the floor
(settled for 3 s at its own setting: 7 contacts, 5 joint limits, dry friction).

1. The stability limits two ways at that operating point, side by side (alternating, best of 3): the linear
   path (the one-step map measured and bisected per integrator, confirmed by runs; what a smooth model
   gets) and the brute-force fallback the audit takes there (bisection of blow-up of runs of >= 2000
   steps from the audit's start, five integrators batched per round); the ratio.
2. The sweep's runs, batched (springlab.sim.batch.run_batched: one mujoco.batch.Batch, all CPUs) against
   a plain Python loop of mujoco.mj_step over the same (integrator, dt) settings, side by side; the
   ratio (CPU times: the row `audit humanoid runs, batched` of `make bench`'s table). (On the grid's 8 coarsest
   timesteps x 5 integrators, to keep the plain loop short.)
3. The whole audit (`springlab audit humanoid.xml --settle 3 --tol 1e-2`), 5 integrators x 12 timesteps
   (+ the model's own), 1 s of motion, against the issue's budget of 2 minutes on 2 cores, with the wall
   time of each stage (the table's `audit humanoid` row times the same command against its time inside MuJoCo).

Run: python benchmarks/bench_audit.py   (needs dm_control, the `test` extra)
"""

from __future__ import annotations

import math
import os
import pathlib
import time

import dm_control
import mujoco
import numpy as np

import measure
from springlab.exact.constraints import watch
from springlab.exact.map_limits import map_limit
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.predicted_limits import predictions
from springlab.sim import batch
from springlab.sim.simulate import INTEGRATORS, Setup, quiet_mujoco
from springlab.studies.audit.audit import audit
from springlab.studies.audit.limits import CONFIRM_ABOVE, RunProbe, stability_limits
from timing import best_of

HUMANOID = pathlib.Path(dm_control.__file__).parent / "suite" / "humanoid.xml"
#: the humanoid falls from its standing qpos0 and lies on the floor within this time [s]
SETTLE_S = 3.0


def limits_two_ways(model) -> None:
    at = ModelAtPoint.at(model, settle_s=SETTLE_S)
    point = at.point
    start = Setup(point.qpos, point.qvel, point.act, point.ctrl)
    seen = watch(model, start, 1.0)
    probe = RunProbe(start, 1.0, seen.peak_speed, float(np.linalg.norm(model.opt.gravity)), 0.1)
    found: dict[str, dict] = {}

    def linear_path():
        predicted = predictions(at, list(INTEGRATORS))
        maps = {name: map_limit(at, name, 1.0, p.limit_s, CONFIRM_ABOVE) for name, p in predicted.items()}
        found["map"] = stability_limits(at, predicted, maps)

    def brute_force():
        found["runs"] = stability_limits(at, predictions(at, list(INTEGRATORS)), None, probe=probe)

    linear_s, brute_s = math.inf, math.inf
    for _ in range(3):  # alternating, so both see the same load
        linear_s = min(linear_s, best_of(linear_path, repeat=1))
        brute_s = min(brute_s, best_of(brute_force, repeat=1))
    print(f"1. humanoid ({model.nv} DOF) lying down, limits of 5 integrators: linear path {linear_s:.2f} s,")
    print(f"   brute-force fallback {brute_s:.2f} s: ratio {brute_s / linear_s:.2f}x")
    for name in INTEGRATORS:
        a, b = found["map"][name], found["runs"][name]
        print(
            f"   {name:<13} map {a.limit_dt_measured_s or float('nan'):.3g} s (confirmed {a.confirmed}),"
            f" runs {b.limit_dt_s or float('nan'):.3g} s, bounded up to {b.runs_bounded_dt_s or float('nan'):.3g} s"
        )


def batched_vs_loop(model, dts, point) -> None:
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
        (batched, batched_cpu), (plain, plain_cpu) = measure.side_by_side([lambda: batch.run_batched(jobs), loop], 1)
    print(f"2. {len(jobs)} runs, {steps} steps: batched {batched:.2f} s, plain mj_step loop {plain:.2f} s")
    print(f"   ratio loop / batched: {plain / batched:.2f}x ({os.cpu_count()} CPUs)")
    measure.emit(
        measure.Row(
            "audit humanoid runs, batched",
            f"{len(jobs)} runs of 1 s (5 integrators x the grid's {len(dts)} coarsest timesteps), {steps} steps",
            batched,
            batched_cpu,
            "mj_step loop",
            plain,
            plain_cpu,
            # the batch's CPU (both threads) against one thread's Python loop: the same steps, so at most a run's
            # 1.3 for the batch's setup and divergence checks (the loop's Python per step makes it nearer 1 or below)
            measure.RUN_BUDGET,
            "(set), as a run's",
            "bench_audit.py: springlab.sim.batch.run_batched (one mujoco.batch.Batch, all CPUs: CPU of all threads)"
            " against a plain mj_step loop over the same settings and steps on copies of the same compiled model",
        )
    )


def main() -> None:
    print(f"load average before: {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    model = mujoco.MjModel.from_xml_path(str(HUMANOID))
    limits_two_ways(model)
    start = time.perf_counter()
    result = audit(str(HUMANOID), settle_s=SETTLE_S, duration=1.0, tol=1e-2)
    total = time.perf_counter() - start
    dts = sorted({r.dt for r in result.runs}, reverse=True)
    batched_vs_loop(model, dts[:8], result.linear.point)
    stages = ", ".join(f"{k.removesuffix('_s')} {v:.1f} s" for k, v in result.timings.to_dict().items())
    print(f"3. whole audit, {len(result.runs)} runs over {result.duration:g} s: {total:.1f} s (budget 120 s); {stages}")
    for line in result.message.splitlines():
        print(f"   {line}")
    print(f"load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
