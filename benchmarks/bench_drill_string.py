"""The drill string's costs, measured side by side in one run.

1. Scale: wall time per step of the string of N elements, N = 8 ... 4096, in its two MJCF encodings:
   'tendons' (every rotor on its own hinge to the world, elements as fixed tendons: a diagonal mass matrix,
   the scene's) and 'chain' (every rotor hinged to the one above: a dense mass matrix; MuJoCo refuses body
   trees deeper than about 1000). Plain mj_step loops (RK4, the scene's integrator), the two encodings timed
   alternately at each N (best of 3), an encoding dropped once a step costs more than STEP_BUDGET_S or its
   total passes its share of a minute. Prints the table and the growth exponents (least squares on
   log(time) vs log(N) for N >= 64); `--figure PATH` draws the curves (docs/images/drill_string_scale.png).
2. N = 256, 10 s of simulated time at the cheapest setting that meets 1e-3 on f1 (springlab.studies.refine at
   that one size, verified by a run): springlab's run of it (simulate: one mujoco.rollout call), the whole
   `springlab.run` (reference, quantities, checks), and a plain Python mj_step loop on the same model and
   setting; their wall times and ratios.

Rows of `make bench`'s table: `drill string step N = ..., tendons` (part 1: the largest N's cost per step against
N = 64's scaled linearly) and `run drill_string modes N = 256` (part 2's run against a plain rollout of the same
steps on the same model). `make bench` runs it with --quick (N up to 512, three integrators in the refine).

Run: python benchmarks/bench_drill_string.py [--figure docs/images/drill_string_scale.png] [--quick]
"""

from __future__ import annotations

import argparse
import math
import time

import mujoco
import numpy as np
from mujoco import rollout

import measure
import springlab
from springlab import scenes
from springlab.scenes.drill_string import build
from springlab.sim.simulate import configured, initial_state, simulate
from springlab.studies import refine
from timing import best_of

SIZES = (8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096)
#: an encoding is dropped once one step costs more than this [s] ...
STEP_BUDGET_S = 0.05
#: ... or its timing has taken more than this [s] in total
ENCODING_BUDGET_S = 30.0
#: the growth row: the largest N's cost per step against this N's scaled linearly
GROWTH_FROM = 64
#: ... within this: the tendon encoding is linear in N (a diagonal mass matrix, each tendon two rotors), MuJoCo's
#: fixed cost per step makes small N dearer per element (so the ratio sits at or below 1); above 1.5 the growth
#: is superlinear (a denser matrix or a solver's iterations growing with N)
GROWTH_BUDGET = 1.5


def _model(size: int, encoding: str) -> mujoco.MjModel:
    scene = scenes.get("drill_string")
    scenario = scene.scenario("spin_up")
    params = scene.resolve(scenario, {"n_elements": size})
    spec = scene.model_spec()
    build.generate(spec, params, encoding=encoding)
    model = configured(spec.compile(), "rk4", 1e-4)
    return model


def _per_step(model: mujoco.MjModel) -> float:
    """Best-of-3 wall time of one mj_step [s], over enough steps to take about 0.2 s."""
    data = mujoco.MjData(model)
    data.qvel[0] = 1.0  # the top drive turning: every element loaded
    start = time.perf_counter()
    mujoco.mj_step(model, data)
    once = max(time.perf_counter() - start, 1e-6)
    steps = max(5, min(20000, int(0.2 / once)))

    def loop() -> None:
        for _ in range(steps):
            mujoco.mj_step(model, data)

    return best_of(loop, repeat=3) / steps


def scale(figure: str | None, sizes: tuple[int, ...]) -> None:
    print("1) wall time per RK4 step vs elements N, both encodings timed alternately (plain mj_step loop)")
    print(f"   {'N':>6}{'tendons [us]':>15}{'chain [us]':>13}{'chain / tendons':>17}")
    times: dict[str, dict[int, float]] = {"tendons": {}, "chain": {}}
    spent = {"tendons": 0.0, "chain": 0.0}
    for size in sizes:
        row = {}
        for encoding in ("tendons", "chain"):
            if encoding == "chain" and size > build.CHAIN_DEPTH_LIMIT:
                continue
            previous = times[encoding]
            if previous and (max(previous.values()) > STEP_BUDGET_S or spent[encoding] > ENCODING_BUDGET_S):
                continue
            start = time.perf_counter()
            row[encoding] = _per_step(_model(size, encoding))
            spent[encoding] += time.perf_counter() - start
            times[encoding][size] = row[encoding]
        tendons, chain = row.get("tendons"), row.get("chain")
        print(
            f"   {size:>6}{tendons * 1e6 if tendons else math.nan:>15.1f}{chain * 1e6 if chain else math.nan:>13.1f}"
            f"{chain / tendons if tendons and chain else math.nan:>17.2f}"
        )
    exponents = {}
    for encoding, points in times.items():
        large = [(n, t) for n, t in points.items() if n >= 64]
        if len(large) >= 2:
            slope, _ = np.polyfit(np.log([n for n, _ in large]), np.log([t for _, t in large]), 1)
            exponents[encoding] = float(slope)
    print(
        "   growth exponents (time per step ~ N^p, N >= 64): "
        + ", ".join(f"{k} p = {v:.2f}" for k, v in exponents.items())
    )
    if "tendons" in exponents:
        print(
            f"   the physical limit is linear in N (p = 1): the tendon encoding's p - 1 = {exponents['tendons'] - 1:+.2f}"
        )
        largest = max(times["tendons"])
        measure.emit(
            measure.Row(
                f"drill string step N = {largest}, tendons",
                f"one RK4 step of the {largest}-element string (the scene's encoding), plain mj_step loop",
                times["tendons"][largest],
                float("nan"),
                f"linear in N from N = {GROWTH_FROM}",
                times["tendons"][GROWTH_FROM] * largest / GROWTH_FROM,
                float("nan"),
                GROWTH_BUDGET,
                "(set)",
                f"bench_drill_string.py: the cost per step against N = {GROWTH_FROM}'s scaled linearly (the physical"
                f" limit: each element touches two rotors); fitted exponent {exponents['tendons']:.2f} for N >= 64",
                on_wall=True,
            )
        )
    if figure:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6.4, 4.4), layout="constrained")
        ax = fig.subplots()
        for encoding, style in (("tendons", "o-"), ("chain", "s-")):
            points = sorted(times[encoding].items())
            if points:
                label = f"{encoding}" + (f": ~N^{exponents[encoding]:.2f}" if encoding in exponents else "")
                ax.loglog([n for n, _ in points], [t * 1e6 for _, t in points], style, label=label)
        reference = sorted(times["tendons"].items())
        if reference:
            n0, t0 = reference[0]
            ax.loglog(
                [n for n, _ in reference], [t0 * 1e6 * n / n0 for n, _ in reference], "k:", lw=0.8, label="linear in N"
            )
        ax.set_xlabel("elements N")
        ax.set_ylabel("wall time per RK4 step [us]")
        ax.set_title("drill string: cost per step of the two MJCF encodings")
        ax.legend()
        fig.savefig(figure, dpi=110)
        print(f"   wrote {figure}")


def cheapest_at_256(quick: bool) -> None:
    size, duration, tol = 256, 10.0, 1e-3
    integrators = (
        ("euler", "implicitfast", "rk4") if quick else ("euler", "implicit", "implicitfast", "rk4", "discrete")
    )
    print(f"2) N = {size}, {duration:g} s at the cheapest setting meeting {tol:g} on f1 (refine at one size)")
    # the cheapest settings sit at the stability limits: the grid's fine end (w_max dt 0.2, 0.5) only costs minutes
    study = refine.refine(
        "drill_string",
        "mode_1_frequency_hz",
        tol=tol,
        sizes=[size],
        integrators=integrators,
        duration=duration,
        omega_dt=(1.0, 1.9, 2.8, 8.0, 30.0),
    )
    pick = study.recommendation
    assert pick is not None and pick.verified and pick.integrator and pick.dt, "no setting meets the tolerance"
    print(
        f"   cheapest: {pick.integrator} at dt = {pick.dt:.4g} s (discretization {pick.details['discretization_error']:.2e},"
        f" integration {pick.details['integration_error']:.2e}); study took {study.sweep_wall_time_s:.1f} s"
    )
    case = scenes.get("drill_string").case("modes", {"n_elements": size})
    model = case.model
    steps = round(duration / pick.dt)
    setup = case.setup(steps, pick.dt)

    def springlab_simulate() -> None:
        simulate(
            model,
            integrator=pick.integrator,
            dt=pick.dt,
            duration=duration,
            qpos=setup.qpos,
            qvel=setup.qvel,
            control=setup.control,
        )

    def springlab_run() -> None:
        springlab.run(
            "drill_string", "modes", integrator=pick.integrator, dt=pick.dt, duration=duration, n_elements=size
        )

    raw = configured(model, pick.integrator, pick.dt)
    data = mujoco.MjData(raw)

    def plain_loop() -> None:
        mujoco.mj_resetData(raw, data)
        data.qpos[:] = setup.qpos
        for _ in range(steps):
            mujoco.mj_step(raw, data)

    floor = rollout.rollout
    state = initial_state(raw, setup.qpos, setup.qvel)[None]
    control = np.zeros((steps, raw.nu)) if setup.control is None else np.asarray(setup.control, float)
    control = np.ascontiguousarray(np.broadcast_to(control, (steps, raw.nu)))[None]
    floor_data = mujoco.MjData(raw)
    names = ("plain", "simulate", "run", "rollout")
    measured = measure.side_by_side(  # in turn, best of 3 each
        [plain_loop, springlab_simulate, springlab_run, lambda: floor(raw, floor_data, state, control, nstep=steps)],
        3,
    )
    timings = {name: wall for name, (wall, _) in zip(names, measured)}
    cpu = {name: used for name, (_, used) in zip(names, measured)}
    print(f"   {steps} steps; plain mj_step loop {timings['plain']:.3f} s")
    print(
        f"   springlab simulate (one rollout) {timings['simulate']:.3f} s: {timings['simulate'] / timings['plain']:.2f} x the loop"
    )
    print(
        f"   springlab.run (+ exact reference, quantities, checks) {timings['run']:.3f} s:"
        f" {timings['run'] / timings['plain']:.2f} x the loop"
    )
    measure.emit(
        measure.Row(
            f"run drill_string modes N = {size}",
            f"{steps} steps {pick.integrator} dt={pick.dt:.4g} s (the cheapest setting meeting {tol:g} on f1),"
            " verdict and exact reference",
            timings["run"],
            cpu["run"],
            "rollout",
            timings["rollout"],
            cpu["rollout"],
            measure.SPIN_UP_BUDGET,
            "issue 37, as the spin-up's",
            f"bench_drill_string.py: springlab.run (the exact reference of {2 * size + 2} states at every step, the"
            f" error estimate over its modes, the quantities and the f1 check) against a plain rollout of the same"
            f" steps on the same configured model; simulate {cpu['simulate'] / cpu['rollout']:.2f}x the rollout",
        )
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figure", help="write the scale curve to this PNG")
    parser.add_argument("--quick", action="store_true", help="N up to 512 and three integrators")
    args = parser.parse_args()
    scale(args.figure, SIZES[:7] if args.quick else SIZES)
    cheapest_at_256(args.quick)


if __name__ == "__main__":
    main()
