"""A controller in the loop: MuJoCo runs between samples, the controller reads its sensors at each sample.

A sampled-data controller reads its sensors at t_k = k T, computes a control u_k and holds it until t_{k+1};
MuJoCo integrates the plant inside the sample (T / dt steps of the model's own integrator, a constant control
over each step: exact for every integrator's order, see simulate's docstring). So at each sample:

1. `mj_forward` (after `mj_step`, `data.sensordata` holds the values of the state *before* the last step,
   one step stale, like `data.energy`: the sensors are computed at the start of a step),
2. read `sensordata` (plus the sensor noise the caller adds, from its own seeded generator),
3. u_k = law(k, readings), written to `data.ctrl`,
4. `mj_step(model, data, nstep=T / dt)`.

The cost per sample is one forward pass and one Python call on top of the steps; `mujoco.rollout` cannot
run this loop (it takes open-loop controls only). `run_sampled` records the samples; springlab.sim.controller.closed_loop records
every step, for a scene's run (`Setup.controller`, a springlab.sim.controller.Controller: springlab.sim.simulate steps it).

Blow-ups: MuJoCo resets a diverging state silently; the run stops at the first BADQPOS/BADQVEL/BADQACC
warning or non-finite state and says so (`SampledRun.diverged_at`), so an unstable loop reads as unstable.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import mujoco
import numpy as np

from .controller import BAD_WARNINGS

__all__ = ["SampledRun", "run_sampled", "steps_per_sample"]


def steps_per_sample(control_rate_hz: float, dt: float) -> int:
    """MuJoCo steps of dt [s] in one controller period 1 / control_rate_hz [s].

    Raises
    ------
    ValueError
        A rate that is not a positive number, a period shorter than one step (the controller would update
        faster than MuJoCo steps), or a period that is not a whole number of steps (to 1e-9 of a step: the
        control must switch on step boundaries to be held exactly).
    """
    if not (math.isfinite(control_rate_hz) and control_rate_hz > 0):
        raise ValueError(f"control rate must be a positive number of Hz, got {control_rate_hz!r}")
    period = 1.0 / control_rate_hz
    if period < dt * (1 - 1e-9):
        raise ValueError(
            f"control rate {control_rate_hz:g} Hz is faster than MuJoCo's step ({dt:g} s, {1 / dt:g} Hz):"
            " use a rate of at most 1 / dt, or a smaller dt"
        )
    steps = round(period / dt)
    if abs(steps * dt - period) > 1e-9 * dt:
        raise ValueError(
            f"the control period {period:g} s is not a whole number of MuJoCo steps of {dt:g} s: choose dt = period / n"
        )
    return steps


@dataclasses.dataclass(frozen=True)
class SampledRun:
    """One sampled-data run.

    Attributes
    ----------
    time
        Sample times t_k [s], (K + 1,).
    readings
        What the controller read at each sample (sensordata plus noise) [sensor units], (K + 1, nsensordata).
    control
        u_k held over [t_k, t_{k+1}) [actuator units], (K, nu).
    qpos, qvel
        The state at each sample, (K + 1, nq) and (K + 1, nv).
    diverged_at
        Index of the first sample after which MuJoCo warned of a blow-up or the state was not finite, else None
        (the arrays then end there).
    """

    time: np.ndarray
    readings: np.ndarray
    control: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    diverged_at: int | None


def run_sampled(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    law: Callable[[int, np.ndarray], np.ndarray],
    *,
    steps_per_sample: int,
    samples: int,
    noise: Callable[[int, np.ndarray], np.ndarray] | None = None,
) -> SampledRun:
    """Run `samples` controller periods from `data`'s state (module docstring).

    Parameters
    ----------
    model, data
        The model (its integrator and timestep as set) and the initial state; `data` is advanced.
    law
        u_k = law(k, readings_k) [actuator units], an array of nu.
    steps_per_sample
        MuJoCo steps per controller period (the period is steps_per_sample * timestep [s]), >= 1.
    samples
        Controller periods K to run, >= 1.
    noise
        readings_k = sensordata + noise(k, sensordata), if given (the caller's seeded generator).

    Raises
    ------
    ValueError
        steps_per_sample or samples below 1.
    """
    if steps_per_sample < 1 or samples < 1:
        raise ValueError(f"steps_per_sample and samples must be >= 1, got {steps_per_sample} and {samples}")
    times, readings, controls, qpos, qvel = [], [], [], [], []
    for warning in BAD_WARNINGS:
        data.warning[warning].number = 0
    diverged = None
    for k in range(samples + 1):
        mujoco.mj_forward(model, data)
        reading = data.sensordata.copy()
        if noise is not None:
            reading = reading + noise(k, reading)
        times.append(data.time)
        readings.append(reading)
        qpos.append(data.qpos.copy())
        qvel.append(data.qvel.copy())
        if k == samples:
            break
        u = np.asarray(law(k, reading), dtype=float)
        data.ctrl[:] = u
        controls.append(u)
        mujoco.mj_step(model, data, nstep=steps_per_sample)
        bad = any(data.warning[w].number for w in BAD_WARNINGS)
        if bad or not (np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))):
            diverged = k
            break
    return SampledRun(
        time=np.array(times),
        readings=np.array(readings),
        control=np.array(controls).reshape(-1, model.nu),
        qpos=np.array(qpos),
        qvel=np.array(qvel),
        diverged_at=diverged,
    )
