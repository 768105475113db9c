"""What a fit costs: a 10 s, 1 kHz slider record (10 001 samples) identified in under 2 s.

Prints the wall time of the whole fit (best of 3), the number of MuJoCo
rollouts it took and the time per rollout, beside one plain run of the same
motion (springlab.sim.simulate on the fit's grid) for the ratio.

Its row, `fit slider 10 s at 1 kHz, in process`, is one fit against its time inside MuJoCo. Not in `make bench`'s
default run: the table's `fit 10 s at 1 kHz` row runs the same fit of the same record through the command
(`bench.py --only bench_fit` runs it).

Run: python benchmarks/bench_fit.py
"""

import pathlib
import sys
import tempfile
import time

import numpy as np

import springlab
from springlab.sim.simulate import simulate

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from measure import Row, emit, inside_mujoco  # noqa: E402
from timing import best_of  # noqa: E402

TARGET_S = 2.0
m, k, d = 2.0, 800.0, 4.0
rng = np.random.default_rng(0)
t = np.arange(10_001) * 1e-3
x, _ = springlab.exact.analytic.free_response(t, m, k, d, 0.05, 0.0)
y = x + 0.002 + rng.normal(0, 5e-4, t.size)

with tempfile.TemporaryDirectory() as folder:
    data = pathlib.Path(folder) / "record.csv"
    data.write_text("time,slider_pos\n" + "".join(f"{a:.6f},{b:.9f}\n" for a, b in zip(t, y)))
    results, cpu = [], []

    def one_fit():
        start_cpu = time.process_time()
        results.append(springlab.fit("slider", data, mass=m, run_scene=False))
        cpu.append(time.process_time() - start_cpu)

    wall = best_of(one_fit, repeat=3)
    with inside_mujoco() as spent:  # one more, its time inside MuJoCo counted: the row's floor
        fit_wall = best_of(one_fit, repeat=1)
    start = time.perf_counter()
    springlab.fit("slider", data, mass=m)  # with the identified scene's run, as the CLI does
    wall_with_run = time.perf_counter() - start

fit = results[-1]
o = fit.optimizer
model = springlab.scenes.SCENES["slider"].build(fit.parameters, springlab.scenes.SCENES["slider"].scenario("free"))
plain = best_of(lambda: simulate(model, integrator="rk4", dt=o["dt"], duration=o["steps"] * o["dt"]), repeat=5)
print(f"record: {t.size} samples over {t[-1]:g} s; fitted {', '.join(fit.free)}")
print(f"verdict: {fit.verdict}")
print(
    f"fit (best of 3): {wall:.2f} s  [{'PASS' if wall < TARGET_S else 'FAIL'} < {TARGET_S:g} s]; with the scene's run:"
    f" {wall_with_run:.2f} s"
)
print(f"  CPU time of the fit (best of 3): {min(cpu):.2f} s (wall time above includes waiting for a shared core)")
print(
    f"  {o['iterations']} LM iterations, {o['rollouts']} rollouts of {o['steps']} RK4 steps (dt = {o['dt'] * 1e3:.2f} ms),"
    f" {o['time_per_rollout_s'] * 1e3:.2f} ms per rollout inside sysid, {o['rollout_time_s']:.2f} s rolling out"
)
print(
    f"  one plain springlab.sim.simulate of the same grid: {plain * 1e3:.2f} ms; fit / plain run = {wall / plain:.0f}"
)
emit(
    Row(
        "fit slider 10 s at 1 kHz, in process",
        f"{t.size} samples, free stiffness and damping, no scene run after it",
        fit_wall,
        cpu[-1],
        "inside MuJoCo",
        spent[0],
        spent[1],
        7.0,
        "(set), as `fit 10 s at 1 kHz`'s",
        "bench_fit.py: springlab.fit (the optimizer's Python between rollouts, the intervals and the closed-form"
        " cross-check) against the time it spent inside MuJoCo's rollouts",
    )
)
