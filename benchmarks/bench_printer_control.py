"""Cost of the printer head's control pieces (issue 35), side by side in one run.

1. The resonance test as a printer runs it: a 2 s chirp through the motor in MuJoCo (one rollout), the
   accelerometer record with seeded noise, the fit of the belt mode (springlab.exact.resonance), the choice of
   shaper from the measured interval (springlab.exact.positioning.fastest_shaper over ZV, MZV, ZVD, EI) and the
   verifying shaped move in MuJoCo: the whole sequence's wall time (the issue asks for under 30 s on 2 cores).
2. The closed loop's cost against the open-loop move's: one simulated second of the sampled PD loop at 5 kHz
   (springlab.sim.sampled.run_sampled: mj_forward, a Python law and mj_step(nstep=2) per sample), of MuJoCo's own
   position actuator doing the continuous PD in one rollout, and of the open-loop force move in one rollout,
   all at dt = 0.1 ms. Best of several, measured alternately.
3. The same through the scene (issue 35's scenarios): `springlab.run("printer_head", "resonance_test")` end to
   end (the chirp run, the exact held reference and its tolerance, the fit, the choice, the verifying move_<shaper>
   run), and the stepping of one simulated second of `feedback_motor` (the controller in Case.simulate's loop,
   every step recorded) against `move`'s (one rollout).

Rows of `make bench`'s table: `printer head sampled PD loop` (part 2: the sampled loop against the open-loop
rollout of the same steps) and `run printer_head resonance_test` (part 3's run against its time inside MuJoCo).

Run: PYTHONPATH=src python benchmarks/bench_printer_control.py
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np
from mujoco import rollout

import measure
import springlab
import springlab.sim.model_files
from springlab.exact import positioning, resonance, sampled_loop, shaping
from springlab.scenes.printer_head import control
from springlab.sim.sampled import run_sampled

DT = 1e-4
#: the sampled loop against the open-loop rollout of the same steps: per 0.2 ms sample a Python law, mj_forward and
#: a 2-step mj_step call (tens of microseconds of Python and bindings against two RK4 steps of about 5 us): 5x
SAMPLED_BUDGET = 5.0
#: the resonance test's run against its rollouts (the chirp and the verifying move): beyond them the chirp's exact
#: held response (20000 samples of a two-mass model), the fit of the belt mode to the noisy record and the choice
#: among four shapers (closed forms): a run's 1.3 and that much again
RESONANCE_BUDGET = 2.0
#: warm runs of the resonance test averaged in its row
WARM_RUNS = 3


def _initial(model: mujoco.MjModel) -> np.ndarray:
    state = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, mujoco.MjData(model), state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    return state


def resonance_test_to_verified_move() -> tuple[float, str, float]:
    """(wall time [s], chosen shaper, verified residual [m]) of chirp, fit, choice and the shaped move."""
    start = time.perf_counter()
    spec = mujoco.MjSpec.from_file(str(springlab.sim.model_files.path("printer_head")))
    control.add_instruments(spec)
    model = spec.compile()
    model.opt.timestep = DT
    force = resonance.chirp(1.0, 50.0, 400.0, 2.0, DT)
    _, sensors = rollout.rollout(model, mujoco.MjData(model), _initial(model), force[None, :, None])
    record = sensors[0, ::3, model.sensor(control.ACCELEROMETER).adr[0]]
    noisy = record + 0.5 * np.random.default_rng(0).standard_normal(record.size)
    fit = resonance.fit_resonance(force, noisy, DT, 3, (50.0, 400.0))
    low, high = fit.frequency_ci95
    m_c, m_m = model.body("carriage").mass[0], model.body("motor").mass[0]
    total, distance = m_c + m_m, float(model.numeric("move_distance").data[0])
    band, limit = float(model.numeric("positioning_band").data[0]), float(model.actuator("drive").ctrlrange[1])
    duration = 2 * math.sqrt(distance * total / limit)
    candidates = [shaping.make_shaper(name, fit.frequency_hz, fit.damping_ratio) for name in shaping.SHAPERS]
    chosen, _ = positioning.fastest_shaper(
        candidates, (low, fit.frequency_hz, high), fit.damping_ratio, distance, duration, band
    )
    # the verifying move: the shaped command held on a 25 us grid, the shaper's times rounded to it
    dt = 2.5e-5
    n_half = math.ceil(duration / 2 / dt)
    level = total * distance / (n_half * dt) ** 2
    offsets = np.round(chosen.times / dt).astype(int)
    command = np.zeros(2 * n_half + offsets[-1] + int(0.02 / dt))
    for amplitude, offset in zip(chosen.amplitudes, offsets):
        command[offset : offset + n_half] += amplitude * level
        command[offset + n_half : offset + 2 * n_half] -= amplitude * level
    true_model = mujoco.MjModel.from_xml_path(str(springlab.sim.model_files.path("printer_head")))
    true_model.opt.timestep = dt
    states, _ = rollout.rollout(true_model, mujoco.MjData(true_model), _initial(true_model), command[None, :, None])
    residual = float(np.max(np.abs(states[0, 2 * n_half + offsets[-1] :, 1] - distance)))
    return time.perf_counter() - start, chosen.name, residual


def one_second(kind: str) -> tuple[float, float]:
    """Wall and CPU time [s] of one simulated second of `kind`: "sampled", "position actuator" or "open loop"."""
    samples, substeps = 5000, 2
    if kind == "sampled":
        spec = mujoco.MjSpec.from_file(str(springlab.sim.model_files.path("printer_head")))
        control.add_instruments(spec, force_limit=False)
        model = spec.compile()
        model.opt.timestep = DT
        law = sampled_loop.PidLaw(sampled_loop.Pid(2000.0, 30.0, 0.0, substeps * DT))
        address = model.sensor("motor_encoder").adr[0]
        start, start_cpu = time.perf_counter(), time.process_time()
        run_sampled(
            model,
            mujoco.MjData(model),
            lambda k, readings: np.array([law.update(readings[address], 1e-3)]),
            steps_per_sample=substeps,
            samples=samples,
        )
        return time.perf_counter() - start, time.process_time() - start_cpu
    spec = mujoco.MjSpec.from_file(str(springlab.sim.model_files.path("printer_head")))
    if kind == "position actuator":
        spec.delete(spec.actuator("drive"))
        servo = spec.add_actuator(name="servo", target="motor", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        servo.set_to_position(kp=2000.0, kv=30.0)
    model = spec.compile()
    model.opt.timestep = DT
    command = np.full((1, samples * substeps, 1), 1e-3 if kind == "position actuator" else 1.0)
    start, start_cpu = time.perf_counter(), time.process_time()
    rollout.rollout(model, mujoco.MjData(model), _initial(model), command)
    return time.perf_counter() - start, time.process_time() - start_cpu


def scene_second(scenario: str) -> float:
    """Wall time [s] of the stepping alone (Trajectory.wall_time_s) of one simulated second of a printer_head case."""
    from springlab import scenes

    case = scenes.get("printer_head").case(scenario)
    return case.simulate("rk4", DT, 1.0).wall_time_s


def main() -> None:
    elapsed, chosen, residual = resonance_test_to_verified_move()
    print(
        f"resonance test (2 s chirp) + fit + shaper choice + verifying move: {elapsed:.2f} s"
        f" (chose {chosen}; the verified move rings {residual * 1e6:.3g} um after it ends)"
    )
    kinds = ("sampled", "position actuator", "open loop")
    timings = {kind: [one_second(kind) for _ in range(5)] for kind in kinds}
    best = {kind: min(wall for wall, _ in timings[kind]) for kind in kinds}
    best_cpu = {kind: min(cpu for _, cpu in timings[kind]) for kind in kinds}
    for kind in kinds:
        print(f"one simulated second, {kind:>17}: {best[kind] * 1e3:7.1f} ms")
    print(
        f"the sampled loop costs {best['sampled'] / best['open loop']:.1f}x the open-loop move and"
        f" {best['sampled'] / best['position actuator']:.1f}x MuJoCo's position actuator"
    )
    start = time.perf_counter()
    result = springlab.run("printer_head", "resonance_test")
    elapsed = time.perf_counter() - start
    with measure.inside_mujoco() as spent:  # warm: the compile and the exact precomputations kept, as run's rows
        start, start_cpu = time.perf_counter(), time.process_time()
        for _ in range(WARM_RUNS):
            springlab.run("printer_head", "resonance_test")
        warm, warm_cpu = time.perf_counter() - start, time.process_time() - start_cpu
    q = result.quantities
    print(
        f"springlab run printer_head resonance_test (chirp, exact reference, fit, choice, verifying run):"
        f" {elapsed:.2f} s; measured {q['belt_frequency_hz_measured']:.4f} Hz"
        f" (+-{q['belt_frequency_ci95_width_hz'] / 2:.4f}), chose {q['chosen_shaper']}, {result.verdict}"
    )
    measure.emit(
        measure.Row(
            "printer head sampled PD loop",
            "one simulated second at 5 kHz, 10000 rk4 steps at 0.1 ms (mj_forward, a Python law and mj_step(nstep=2)"
            " per sample)",
            best["sampled"],
            best_cpu["sampled"],
            "rollout",
            best["open loop"],
            best_cpu["open loop"],
            SAMPLED_BUDGET,
            "(set)",
            "bench_printer_control.py: springlab.sim.sampled.run_sampled against one rollout of the open-loop move's"
            " 10000 steps on the same model, best of 5 each, measured in turn; MuJoCo's position actuator (the"
            f" continuous PD in one rollout) {best['position actuator'] * 1e3:.1f} ms",
        )
    )
    measure.emit(
        measure.Row(
            "run printer_head resonance_test",
            f"chirp, exact held reference, fit, shaper choice and the verifying move_{q['chosen_shaper']} run",
            warm / WARM_RUNS,
            warm_cpu / WARM_RUNS,
            "inside MuJoCo",
            spent[0] / WARM_RUNS,
            spent[1] / WARM_RUNS,
            RESONANCE_BUDGET,
            "(set)",
            f"bench_printer_control.py: `springlab.run` end to end, the mean of {WARM_RUNS} calls after a first one"
            f" ({elapsed:.3g} s wall: the compile and the exact precomputations), against the time they spent inside"
            " MuJoCo's rollouts",
        )
    )
    scene = {name: min(scene_second(name) for _ in range(5)) for name in ("feedback_motor", "move")}
    print(
        f"one simulated second through the scene: feedback_motor {scene['feedback_motor'] * 1e3:.1f} ms,"
        f" move {scene['move'] * 1e3:.1f} ms: the closed loop costs {scene['feedback_motor'] / scene['move']:.1f}x"
    )


if __name__ == "__main__":
    main()
