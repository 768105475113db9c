"""Speed of `springlab frequency` (issue 23's budgets, measured side by side in one run).

1. Exact and discrete responses of a 24-DOF model (a chain of 24 masses on springs and dampers, driven at its
   first mass, the last mass's position observed) at 500 frequencies: the linearization, the one-step map,
   both responses, the resonances and the band within tol (no per-integrator search), best of 3, against
   the issue's budget of 5 s; and the same with the five integrators' largest-dt search.
2. A 50-frequency sinestream of the printer head (rk4 at 0.1 ms, batched on all CPUs) against the issue's
   budget of 60 s on 2 cores, and against a plain Python loop of mujoco.mj_step (control set per step,
   position read per step) over the same number of steps, timed on a share of them and scaled; the ratio.
3. The docs' Duffing jump (issue 23 item 4): 31 frequencies swept up and down with continuation, each sine
   from the last's state, and the harmonic-balance comparison, against the same plain loop over its steps.

Row of `make bench`'s table: `frequency nonlinear sweep` (part 3, against its time inside MuJoCo). Parts 1 and 2
are the table's `frequency chain` and `frequency sinestream` rows (the chain without the search, the sinestream
against its time inside MuJoCo): `make bench` runs `bench_frequency.py duffing`.

Run: python benchmarks/bench_frequency.py [chain] [sinestream] [duffing]   (none named: all three)
"""

from __future__ import annotations

import os
import time

import mujoco
import numpy as np

import measure
import springlab
from timing import best_of

N_MASSES = 24
#: the sweep against its rollouts: each frequency's steps are one batched rollout from the last one's state; beyond
#: them each window is demodulated by numpy.linalg.lstsq over its samples (in a profile as long as the rollouts:
#: 6.6 of 14.9 s; a projection onto the window's sines and cosines would cost a fraction, in
#: springlab/studies/frequency/sinestream.py) and the harmonic balance solved along the branch (0.7 s): about 2.1x
SWEEP_BUDGET = 2.5
#: parts, by name on the command line (none named: all)
PARTS = ("chain", "sinestream", "duffing")


def chain_xml(n: int) -> str:
    """n masses in a row on slide joints, each tied to the previous by a joint spring and damper."""
    bodies = ""
    for i in range(n):
        bodies += (
            f'<body name="m{i}" pos="0.1 0 0"><joint name="j{i}" type="slide" axis="1 0 0" stiffness="{1000 + 50 * i}"'
            f' damping="0.5"/><inertial pos="0 0 0" mass="{0.5 + 0.02 * i}" diaginertia="1e-3 1e-3 1e-3"/>'
        )
    bodies += "</body>" * n
    return (
        '<mujoco><option timestep="1e-3" integrator="RK4" gravity="0 0 0"><flag contact="disable"/></option>'
        f"<worldbody>{bodies}</worldbody>"
        '<actuator><motor name="drive" joint="j0"/></actuator></mujoco>'
    )


def responses_of_a_large_model() -> None:
    model = mujoco.MjModel.from_xml_string(chain_xml(N_MASSES))
    args = dict(input="drive", response=f"j{N_MASSES - 1}", band=(0.1, 100.0), points=500)
    found = {}

    def without_search():
        found["one"] = springlab.frequency(model, integrators=(), **args)

    def with_search():
        found["all"] = springlab.frequency(model, **args)

    one = best_of(without_search, repeat=3)
    every = best_of(with_search, repeat=1)
    result = found["all"]
    print(f"1. {N_MASSES}-DOF chain, 500 frequencies, rk4 at 1 ms")
    print(f"   exact + discrete responses, resonances, band within tol: {one:.2f} s (budget 5 s)")
    print(f"   ... and the five integrators' largest dt covering the band: {every:.2f} s")
    print(f"   {len(result.resonances)} resonances found; {result.verdict()[0]}")


def plain_loop(model: mujoco.MjModel, steps: int, omega: float, dt: float) -> float:
    """Wall time [s] of a Python loop of mj_step with the sine set per step and the carriage read per step."""
    data = mujoco.MjData(model)
    model.opt.timestep = dt
    model.opt.integrator = int(mujoco.mjtIntegrator.mjINT_RK4)
    out = np.empty(steps)
    start = time.perf_counter()
    for k in range(steps):
        data.ctrl[0] = np.sin(omega * (k + 0.5) * dt)
        mujoco.mj_step(model, data)
        out[k] = data.qpos[0]
    return time.perf_counter() - start


def sinestream_of_the_printer_head() -> None:
    found = {}

    def analysis_only():
        found["base"] = springlab.frequency("printer_head", integrators=())

    def with_sines():
        found["sines"] = springlab.frequency("printer_head", integrators=(), sines=50)

    base = best_of(analysis_only, repeat=3)
    total = best_of(with_sines, repeat=3)
    stream = found["sines"].sinestream
    share = 20_000
    scene_model = springlab.SCENES["printer_head"].model_spec().compile()
    loop = min(plain_loop(scene_model, share, 2 * np.pi * 100.0, 1e-4) for _ in range(3)) * stream.steps / share
    print(f"2. printer head, 50-frequency sinestream (rk4 at 0.1 ms), {os.cpu_count()} CPUs")
    print(f"   {stream.steps} steps: whole analysis {total:.2f} s (budget 60 s), of which sines {total - base:.2f} s")
    print(
        f"   plain Python mj_step loop over the same steps: {loop:.2f} s (timed on {share} steps, scaled);"
        f" ratio loop / sinestream: {loop / (total - base):.1f}x"
    )
    print(f"   every estimate within its stated accuracy of the discrete response: {stream.agrees}")


def sweep_of_the_duffing_spring() -> None:
    """The docs' Duffing jump: 31 frequencies up and down (continuation, rk4 at 1 ms), against a plain loop."""
    args = dict(input="force", response="block", k3=1e4, damping=1.0, band=(1.5, 3.0))
    found = {}

    def analysis_only():
        found["base"] = springlab.frequency("nonlinear", integrators=(), **args)

    def with_sweep():
        found["sweep"] = springlab.frequency(
            "nonlinear", integrators=(), sines=31, amplitudes=(2.0,), sweep="both", **args
        )

    ((base, base_cpu),) = measure.side_by_side([analysis_only], 3)
    with measure.inside_mujoco() as spent:
        ((total, total_cpu),) = measure.side_by_side([with_sweep], 1)
    result = found["sweep"]
    steps = sum(b.steps for b in result.sweeps)
    share = 20_000
    scene_model = springlab.SCENES["nonlinear"].model_spec().compile()
    loop = min(plain_loop(scene_model, share, 2 * np.pi * 2.0, 1e-3) for _ in range(3)) * steps / share
    print("3. nonlinear (hardening, damped), 31-frequency sweep up and down at 2 N (rk4 at 1 ms)")
    print(
        f"   {steps} steps: whole analysis {total:.2f} s, of which the sweeps and harmonic balance {total - base:.2f} s"
    )
    print(
        f"   plain Python mj_step loop over the same steps: {loop:.2f} s (timed on {share} steps, scaled);"
        f" ratio loop / sweep: {loop / (total - base):.1f}x"
    )
    print(f"   every point within its harmonic-balance bound: {result.sweeps_agree}")
    measure.emit(
        measure.Row(
            "frequency nonlinear sweep",
            f"Duffing spring, 31 frequencies up and down at 2 N with continuation, {steps} rk4 steps at 1 ms, and the"
            " harmonic balance",
            total - base,
            total_cpu - base_cpu,
            "inside MuJoCo",
            spent[0],
            spent[1],
            SWEEP_BUDGET,
            "(set)",
            "bench_frequency.py: the sweeps and the harmonic-balance comparison (the whole analysis less the same"
            " analysis without them) against the time the whole analysis spent inside MuJoCo's rollouts;"
            f" a plain Python mj_step loop over the same steps {loop:.2f} s",
        )
    )


if __name__ == "__main__":
    import sys

    parts = set(sys.argv[1:]) or set(PARTS)
    if parts - set(PARTS):
        sys.exit(f"unknown parts {', '.join(sorted(parts - set(PARTS)))}; valid: {', '.join(PARTS)}")
    if "chain" in parts:
        responses_of_a_large_model()
    if "sinestream" in parts:
        sinestream_of_the_printer_head()
    if "duffing" in parts:
        sweep_of_the_duffing_spring()
