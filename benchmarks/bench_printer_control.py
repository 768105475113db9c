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

Run: PYTHONPATH=src python benchmarks/bench_printer_control.py
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np
from mujoco import rollout

import springlab
import springlab.sim.model_files
from springlab.exact import positioning, resonance, sampled_loop, shaping
from springlab.scenes.printer_head import control
from springlab.sim.sampled import run_sampled

DT = 1e-4


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


def one_second(kind: str) -> float:
    """Wall time [s] of one simulated second of `kind`: "sampled", "position actuator" or "open loop"."""
    samples, substeps = 5000, 2
    if kind == "sampled":
        spec = mujoco.MjSpec.from_file(str(springlab.sim.model_files.path("printer_head")))
        control.add_instruments(spec, force_limit=False)
        model = spec.compile()
        model.opt.timestep = DT
        law = sampled_loop.PidLaw(sampled_loop.Pid(2000.0, 30.0, 0.0, substeps * DT))
        address = model.sensor("motor_encoder").adr[0]
        start = time.perf_counter()
        run_sampled(
            model,
            mujoco.MjData(model),
            lambda k, readings: np.array([law.update(readings[address], 1e-3)]),
            steps_per_sample=substeps,
            samples=samples,
        )
        return time.perf_counter() - start
    spec = mujoco.MjSpec.from_file(str(springlab.sim.model_files.path("printer_head")))
    if kind == "position actuator":
        spec.delete(spec.actuator("drive"))
        servo = spec.add_actuator(name="servo", target="motor", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        servo.set_to_position(kp=2000.0, kv=30.0)
    model = spec.compile()
    model.opt.timestep = DT
    command = np.full((1, samples * substeps, 1), 1e-3 if kind == "position actuator" else 1.0)
    start = time.perf_counter()
    rollout.rollout(model, mujoco.MjData(model), _initial(model), command)
    return time.perf_counter() - start


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
    best = dict.fromkeys(kinds, math.inf)
    for _ in range(5):
        for kind in kinds:
            best[kind] = min(best[kind], one_second(kind))
    for kind in kinds:
        print(f"one simulated second, {kind:>17}: {best[kind] * 1e3:7.1f} ms")
    print(
        f"the sampled loop costs {best['sampled'] / best['open loop']:.1f}x the open-loop move and"
        f" {best['sampled'] / best['position actuator']:.1f}x MuJoCo's position actuator"
    )
    start = time.perf_counter()
    result = springlab.run("printer_head", "resonance_test")
    elapsed = time.perf_counter() - start
    q = result.quantities
    print(
        f"springlab run printer_head resonance_test (chirp, exact reference, fit, choice, verifying run):"
        f" {elapsed:.2f} s; measured {q['belt_frequency_hz_measured']:.4f} Hz"
        f" (+-{q['belt_frequency_ci95_width_hz'] / 2:.4f}), chose {q['chosen_shaper']}, {result.verdict}"
    )
    scene = {name: min(scene_second(name) for _ in range(5)) for name in ("feedback_motor", "move")}
    print(
        f"one simulated second through the scene: feedback_motor {scene['feedback_motor'] * 1e3:.1f} ms,"
        f" move {scene['move'] * 1e3:.1f} ms: the closed loop costs {scene['feedback_motor'] / scene['move']:.1f}x"
    )


if __name__ == "__main__":
    main()
