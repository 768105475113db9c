"""The stay cable's exact layer, measured: the stationary covariance at N = 400 and the universal curve's range.

1. The exact covariance of the N-element cable under a uniform white wind (a damper at 6 m, 0.1 % intrinsic
   damping): springlab.exact.random_vibration.second_order_covariance (the undamped modes plus the damper's
   low-rank term) against scipy's Bartels-Stewart (solve_continuous_lyapunov) on the same state matrix, timed
   alternately (best of several), N = 100, 200, 400; each one's error against the integral of the impulse
   responses (Van Loan's exponential and doubling, the tests' reference) where that is affordable (N <= 100).
   The held covariance (the same wind held over 10 ms steps: expm and solve_discrete_lyapunov) beside them.
2. The universal curve against the transcendental equation: the exact optimum damper and the largest damping
   ratio of modes 1-3 over a / L = 0.005 ... 0.1, the relative errors of the curve's a / (2L) and
   sqrt(T m) L / (n pi a).
3. The wind's records (issue 36): N = 100, 40 seeds x 600 s at the cheapest setting whose variance bias (the
   hold's and the integrator's, exact) is under 1 % (springlab.studies.settings ranks the candidate settings by
   counted work; the 40 records verify the pick: at least 38 inside their 99 % interval), run by
   springlab.studies.random_load on both cores, against a plain Python mj_step loop over the same steps, the
   same controls and starts (one core: what a user would write). Then the per-step overhead apart from the
   threads: 4 seeds on one thread each way, alternately, best of 2.

Rows of `make bench`'s table: `stay cable covariance` (part 1 at N = 400, against scipy) and, from part 3,
`stay cable wind records` (against their time inside MuJoCo). `make bench` runs it with --exact-only: part 3 is
what the table's `rms stay_cable` row measures (the same records through the command) and takes minutes.

Run: python benchmarks/bench_stay_cable.py [--records-only | --exact-only]
"""

from __future__ import annotations

import argparse
import math
import time

import mujoco
import numpy as np
import scipy.linalg

import measure
from springlab import scenes
from springlab.exact import cable as cb
from springlab.exact import random_vibration as rv
from springlab.scenes.stay_cable import stationary
from springlab.sim.simulate import configured
from springlab.studies import random_load, settings
from springlab.studies.executor import Executor
from timing import best_of

CABLE = cb.TautCable(300.0, 6.1e6, 70.0)
#: the structured covariance against scipy's general Lyapunov solve at N = 400: it eigen-decomposes the 400 x 400
#: symmetric pair instead of taking the Schur form of the 800 x 800 state matrix (about 8x fewer flops, a
#: symmetric solver besides) and adds the damper's rank-one term: at least 4x under scipy's
COVARIANCE_BUDGET = 0.25
#: the records against their time inside MuJoCo (the table's `rms stay_cable` row's budget): the seeded wind, the
#: exact answers and the variances' intervals beside the rollouts
RECORDS_BUDGET = 3.0
DAMPER_POSITION, DAMPER, STRUCTURAL, INTENSITY = 6.0, 3.3e5, 0.001, 30.0


def _problem(n: int):
    model = cb.LumpedCable.build(
        CABLE, n, structural_ratio=STRUCTURAL, damper_position=DAMPER_POSITION, damper_coefficient=DAMPER
    )
    b = np.zeros((2 * n, 1))
    b[n:, 0] = CABLE.spacing(n) / model.mass
    alpha = CABLE.structural_node_damping(n, STRUCTURAL) / model.mass[0]
    factor = np.zeros((n, 1))
    factor[CABLE.damper_node(n, DAMPER_POSITION) - 1, 0] = 1.0
    return model, b, alpha, factor


def _doubling(a: np.ndarray, noise: np.ndarray) -> np.ndarray:
    n = a.shape[0]
    h = 1e-3
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n], block[:n, n:], block[n:, n:] = -a * h, noise * h, a.T * h
    e = scipy.linalg.expm(block)
    phi = e[n:, n:].T
    p = phi @ e[:n, n:]
    t = h
    while t < 1e5:
        p, phi, t = p + phi @ p @ phi.T, phi @ phi, 2 * t
    return 0.5 * (p + p.T)


def covariance_timings() -> None:
    print("exact covariance of the N-element cable (uniform white wind, damper at 6 m, 0.1 % intrinsic)")
    print(f"{'N':>5} {'structured [s]':>15} {'scipy [s]':>10} {'ratio':>7} {'held 10 ms [s]':>15}  errors vs integral")
    for n in (100, 200, 400):
        model, b, alpha, factor = _problem(n)
        a, w = model.state_matrix(), np.array([[INTENSITY]])
        (structured, structured_cpu), (bartels, bartels_cpu) = measure.side_by_side(
            [
                lambda m=model, b=b, al=alpha, f=factor, w=w: rv.second_order_covariance(
                    m.mass, m.stiffness, al, f, np.array([DAMPER]), b, w
                ),
                lambda a=a, b=b, w=w: rv.continuous_covariance(a, b @ w @ b.T),
            ],
            3,
        )
        held = best_of(lambda a=a, b=b: rv.held_covariance(a, b, w, 0.01), repeat=1)
        errors = ""
        if n <= 100:
            brute = _doubling(a, b @ w @ b.T)
            scale = np.sqrt(np.outer(np.diag(brute), np.diag(brute)))
            p1 = rv.second_order_covariance(model.mass, model.stiffness, alpha, factor, np.array([DAMPER]), b, w)
            p2 = rv.continuous_covariance(a, b @ w @ b.T)
            errors = (
                f"structured {np.max(np.abs(p1 - brute) / scale):.1e}, scipy {np.max(np.abs(p2 - brute) / scale):.1e}"
            )
        print(f"{n:>5} {structured:>15.3f} {bartels:>10.3f} {bartels / structured:>7.1f} {held:>15.3f}  {errors}")
    measure.emit(
        measure.Row(
            "stay cable covariance",
            f"the exact stationary covariance of the {n}-element cable ({2 * n} states), uniform white wind, a damper",
            structured,
            structured_cpu,
            "scipy",
            bartels,
            bartels_cpu,
            COVARIANCE_BUDGET,
            "(set)",
            "bench_stay_cable.py: springlab.exact.random_vibration.second_order_covariance (the undamped modes and"
            " the damper's low-rank term) against scipy's Bartels-Stewart (solve_continuous_lyapunov) on the same"
            " state matrix, in turn, best of 3; CPU of all BLAS threads",
        )
    )


def universal_range() -> None:
    print("\nthe universal curve against the transcendental equation (exact / curve - 1)")
    print(f"{'a/L':>7} {'mode':>5} {'zeta_max':>12} {'curve a/2L':>11} {'error':>9} {'eta_opt error':>14}")
    for ratio in (0.005, 0.01, 0.02, 0.05, 0.1):
        for mode in (1, 2, 3):
            eta_opt, zeta_max = cb.exact_optimum(mode, ratio)
            eta_u, zeta_u = cb.universal_optimum(mode, ratio)
            print(
                f"{ratio:>7g} {mode:>5} {zeta_max:>12.6g} {zeta_u:>11.6g} {zeta_max / zeta_u - 1:>9.2e}"
                f" {eta_opt / eta_u - 1:>14.2e}"
            )


#: the records' cable, count and length (issue 36)
RECORD_NODES, RECORD_SEEDS, RECORD_S = 100, 40, 600.0
#: the candidate timesteps: these fractions of each integrator's stability limit on the cable's modes
RECORD_FRACTIONS = (0.95, 0.9, 0.85, 0.8, 0.75, 0.7, 0.65, 0.6, 0.5, 0.4, 0.3, 0.2)
#: the bias the setting must stay under [-] (the hold's and the integrator's, on the mid-span variance)
RECORD_BIAS = 0.01


def cheapest_unbiased(case) -> settings.Run:
    """The cheapest (integrator, dt) whose exact variance bias at mid-span is under RECORD_BIAS, by counted work."""
    rows = []
    mid = stationary.cable_model(case).midspan - 1
    for integrator in ("euler", "implicitfast", "implicit", "rk4"):
        limit = settings.limit_dt(case.modes(), lambda w, z, i=integrator: case.stability_limit(i, w, z))
        for fraction in RECORD_FRACTIONS:
            dt = RECORD_S / math.ceil(RECORD_S / (limit * fraction))
            steps = round(RECORD_S / dt)
            exact = stationary.wind_exact(case, integrator, dt)
            bias = abs(float(exact.integrator_covariance[mid, mid] / exact.continuous[mid, mid]) - 1)
            cost = settings.counted_cost(integrator, steps * RECORD_SEEDS, case.model.nv)
            rows.append(settings.Run(settings.Setting(integrator, dt), steps * RECORD_SEEDS, bias, cost))
    return min((r for r in rows if r.error is not None and r.error < RECORD_BIAS), key=lambda r: (r.cost, r.error))


def plain_loop(case, integrator: str, dt: float, steps: int, seeds) -> list[float]:
    """Each seed's sample variance at mid-span by a Python mj_step loop (the same starts and controls)."""
    model = configured(case.model, integrator, dt)
    data = mujoco.MjData(model)
    mid = stationary.cable_model(case).midspan - 1
    out = []
    for seed in seeds:
        setup = stationary.seeded_setup(case, steps, dt, seed)
        mujoco.mj_resetData(model, data)
        data.qpos[:], data.qvel[:] = setup.qpos, setup.qvel
        control = np.asarray(setup.control)[:, 0]
        total = 0.0
        for k in range(steps):
            data.ctrl[0] = control[k]
            mujoco.mj_step(model, data)
            total += data.qpos[mid] ** 2
        out.append(total / steps)
    return out


def wind_records() -> None:
    scene = scenes.get("stay_cable")
    params = {"n_elements": RECORD_NODES}
    case = scene.case("wind", params)
    start = time.perf_counter()
    pick = cheapest_unbiased(case)
    choose = time.perf_counter() - start
    integrator, dt = pick.integrator, pick.dt
    steps = round(RECORD_S / dt)
    print(
        f"\nthe wind's records: N = {RECORD_NODES}, {RECORD_SEEDS} seeds x {RECORD_S:g} s; the cheapest setting whose"
        f" variance bias is under {RECORD_BIAS:.0%}: {integrator} at dt = {dt:.4g} s (bias {pick.error:.3%}, chosen"
        f" in {choose:.1f} s from the exact biases)"
    )
    with measure.inside_mujoco() as spent:
        start, start_cpu = time.perf_counter(), time.process_time()
        study = random_load.ensemble("stay_cable", seeds=RECORD_SEEDS, integrator=integrator, dt=dt, **params)
        study_s, study_cpu = time.perf_counter() - start, time.process_time() - start_cpu
    print(
        f"  springlab (random_load.ensemble, 2 threads): {study_s:.1f} s in all ({study.wall_time_s:.1f} s of records,"
        f" {study.exact_time_s:.1f} s of exact answers); {study.inside} of {RECORD_SEEDS} inside their 99 % interval"
    )
    start = time.perf_counter()
    looped = plain_loop(case, integrator, dt, steps, range(RECORD_SEEDS))
    loop_s = time.perf_counter() - start
    same = max(abs(a / b - 1) for a, b in zip(looped, study.variances))
    print(
        f"  plain mj_step loop (one core): {loop_s:.1f} s; ratio springlab / loop = {study_s / loop_s:.2f}"
        f" (the records agree to {same:.1e})"
    )
    few = range(4)
    with Executor(progress=False, nthread=1) as one:
        threads = best_of(
            lambda: random_load.records(scene, "wind", params, integrator, dt, steps, list(few), one), repeat=2
        )
    loop = best_of(lambda: plain_loop(case, integrator, dt, steps, few), repeat=2)
    print(f"  one thread each, 4 seeds: springlab {threads:.1f} s, loop {loop:.1f} s, ratio {threads / loop:.2f}")
    measure.emit(
        measure.Row(
            "stay cable wind records",
            f"N = {RECORD_NODES}, {RECORD_SEEDS} seeds x {RECORD_S:g} s, {integrator} at dt = {dt:.4g} s, 2 threads",
            study_s,
            study_cpu,
            "inside MuJoCo",
            spent[0],
            spent[1],
            RECORDS_BUDGET,
            "(set), as `rms stay_cable`'s",
            "bench_stay_cable.py: random_load.ensemble (the records, their exact answers and intervals) against the"
            f" time it spent inside MuJoCo's rollouts; a plain Python mj_step loop over the same steps {loop_s:.1f} s",
        )
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records-only", action="store_true", help="only the wind's records (part 3)")
    parser.add_argument("--exact-only", action="store_true", help="only the exact layer (parts 1 and 2)")
    args = parser.parse_args()
    if not args.exact_only:
        wind_records()
    if args.records_only:
        raise SystemExit(0)
    covariance_timings()
    universal_range()
    print(
        f"\n(mode 1 of the default stay: f1 = {CABLE.frequencies_hz(1)[0]:.4f} Hz, sqrt(T m) = {CABLE.impedance:.0f} N s/m,"
        f" the universal optimum at 6 m: {CABLE.impedance / (math.pi * DAMPER_POSITION / CABLE.length):.0f} N s/m)"
    )
