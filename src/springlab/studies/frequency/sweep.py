"""The sweep: up and down in frequency, each sine continuing from the last one's state (a non-linear
model's branches and jumps), compared with the first-order harmonic balance."""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable

import numpy as np

from springlab.errors import BadInputError
from springlab.exact import harmonic_balance as hb
from springlab.exact.model_at_point import ModelAtPoint
from springlab.sim.simulate import quiet_mujoco

from .inputs import Probe
from .results import SweepBranch
from .sinestream import (
    CONTROL_SPEC,
    ESTIMATE_PERIODS,
    ESTIMATE_SAMPLES,
    check_finite,
    common_setup,
    demodulate,
    drive,
    measure,
    new_batch,
    record,
    settle_rate,
    steady_start,
)

#: each sweep frequency settles until the slowest mode's envelope falls to this, from where the last one ended
SWEEP_ACCURACY = 1e-4
#: the sweep's branches differ (hysteresis) where their first harmonics part by more than this many times
#: SWEEP_ACCURACY
HYSTERESIS_FACTOR = 100.0
SWEEP_DIRECTIONS = ("up", "down", "both")


def run_sweeps(
    at: ModelAtPoint,
    b: np.ndarray,
    probe: Probe,
    integrator: str,
    dt: float,
    grid: np.ndarray,
    amplitudes: tuple[float, ...],
    directions: tuple[str, ...],
) -> list[SweepBranch]:
    """Continuation sweeps, one chain per (amplitude, direction), all chains in one mujoco.batch.Batch.

    At each frequency the input u_k = U sin(phi + omega (k + 1/2) dt) continues the last frequency's phase phi
    (no jump in the drive), runs ln(1 / SWEEP_ACCURACY) / sigma (sigma: the slowest decaying mode of the
    linearization; for a one-degree-of-freedom oscillator the mean decay of any periodic orbit's neighbours is
    c / (2 m) too, by Liouville) and then 2 ESTIMATE_PERIODS whole periods, demodulated with their harmonics
    (`demodulate`); the halves of that window demodulated alone give the residue. The first frequency of each
    chain starts on the linearization's steady state.
    """
    if probe.response_kind == "acc":
        raise BadInputError(
            "the sweep measures a joint's position or velocity, or a sensor; not a joint's acceleration"
        )
    sigma, _ = settle_rate(at.linear)
    if not math.isfinite(sigma):
        raise BadInputError("the model has no damped mode: a sweep has no steady state to continue along")
    settle = math.log(1.0 / SWEEP_ACCURACY) / sigma
    chains = [(a, d) for a in amplitudes for d in directions]
    orders = [grid if d == "up" else grid[::-1] for _, d in chains]
    first = [2 * math.pi * float(order[0]) for order in orders]
    starts = [steady_start(at, b, w, a) for w, (a, _) in zip(first, chains)]
    common = common_setup(at, probe, integrator, dt)
    shift = 0 if probe.response_kind == "sensor" else 1
    # every chain advances together, one batched rollout per frequency index (threads across chains): the same
    # settling for all, and each chain's own whole-period window at the end of it
    batch = new_batch(common, starts, min(len(chains), os.cpu_count() or 1))
    phases = [0.0] * len(chains)
    found: list[list[np.ndarray]] = [[] for _ in chains]
    ids = np.arange(len(chains), dtype=np.int32)
    total = 0
    settle_steps = int(math.ceil(settle / dt))
    with quiet_mujoco():
        for i in range(len(grid)):
            freqs = [float(order[i]) for order in orders]
            windows = []
            for f in freqs:
                periods = max(2 * ESTIMATE_PERIODS, 2 * math.ceil(0.5 * ESTIMATE_SAMPLES * dt * f))
                windows.append(int(round(periods / f / dt)))
            steps = settle_steps + max(windows)
            control = np.stack(
                [drive(common, 2 * math.pi * f, phases[j], chains[j][0], 0, steps) for j, f in enumerate(freqs)]
            )
            out = batch.rollout(steps, control=control, control_spec=CONTROL_SPEC, record=record(common), ids=ids)
            ys = [measure(common, out, j) for j in range(len(chains))]
            check_finite(batch, ys, "a sweep")
            t = (np.arange(steps) + shift) * dt
            for j, (amplitude, _) in enumerate(chains):
                f, y, window = freqs[j], ys[j], windows[j]
                omega = 2 * math.pi * f
                tail, half = slice(steps - window, steps), slice(steps - window // 2, steps)
                early = slice(steps - window, steps - window // 2)
                whole = demodulate(y[tail], t[tail], omega, dt)
                late = demodulate(y[half], t[half], omega, dt)[0]
                before = demodulate(y[early], t[early], omega, dt)[0]
                phasor = -1j * amplitude * np.exp(1j * phases[j])
                third = abs(whole[2]) / abs(whole[0]) if len(whole) >= 3 and abs(whole[0]) > 0 else math.nan
                residue = abs(late - before) / max(abs(whole[0]), 1e-300)
                found[j].append(np.array([f, whole[0] / phasor, abs(whole[0]), third, residue], complex))
                phases[j] = math.fmod(phases[j] + omega * steps * dt, 2 * math.pi)
            total += steps * len(chains)
    branches = []
    for j, (amplitude, direction) in enumerate(chains):
        rows = np.array(found[j])
        branches.append(
            SweepBranch(
                direction=direction,
                amplitude=float(amplitude),
                frequencies_hz=rows[:, 0].real.copy(),
                estimate=rows[:, 1].copy(),
                response_amplitude=rows[:, 2].real.copy(),
                third_harmonic=rows[:, 3].real.copy(),
                residue=rows[:, 4].real.copy(),
                steps=total // len(chains),
            )
        )
    return branches


def mark_jumps(branches: list[SweepBranch]) -> list[SweepBranch]:
    """Each branch with its jump: where the up and down sweeps at its amplitude stop differing, in its direction."""
    out = []
    for branch in branches:
        other = next((o for o in branches if o.amplitude == branch.amplitude and o.direction != branch.direction), None)
        if other is None:
            out.append(branch)
            continue
        mine = dict(zip(branch.frequencies_hz, branch.estimate))
        theirs = dict(zip(other.frequencies_hz, other.estimate))
        grid = np.sort(branch.frequencies_hz)
        differ = [
            abs(mine[f] - theirs[f]) / max(abs(mine[f]), abs(theirs[f])) > HYSTERESIS_FACTOR * SWEEP_ACCURACY
            for f in grid
        ]
        inside = np.nonzero(differ)[0]
        jump = None
        if inside.size:
            if branch.direction == "up" and inside[-1] + 1 < len(grid):
                jump = (float(grid[inside[-1]]), float(grid[inside[-1] + 1]))
            if branch.direction == "down" and inside[0] > 0:
                jump = (float(grid[inside[0] - 1]), float(grid[inside[0]]))
        out.append(dataclasses.replace(branch, jump_hz=jump))
    return out


def compare_with_harmonic_balance(
    branches: list[SweepBranch],
    duffing: hb.Duffing,
    dt: float,
    linear_error: Callable[[np.ndarray], np.ndarray],
) -> list[SweepBranch]:
    """Each branch with the harmonic-balance amplitude nearest each measured one, its derived bound, and the fold
    where its direction's branch ends (springlab.exact.harmonic_balance); the sine held over steps of dt [s]
    drives with its first harmonic, sinc(omega dt / 2) times the force, at each point and at each fold."""
    out = []
    for branch in branches:
        omegas = 2 * math.pi * branch.frequencies_hz
        hold = np.sinc(omegas * dt / (2 * math.pi))  # a held sine's first harmonic: sinc(omega dt / 2)
        forces = duffing.gain * branch.amplitude * hold
        predicted, bound = [], []
        integrator = linear_error(branch.frequencies_hz)
        for omega, force, measured, residue, err in zip(
            omegas, forces, branch.response_amplitude, branch.residue, integrator
        ):
            roots = hb.amplitudes(duffing, float(force), float(omega))
            root = float(roots[np.argmin(np.abs(np.log(roots / measured)))])
            predicted.append(root)
            bound.append(hb.amplitude_bound(duffing, float(force), root, float(omega)) + (2 * residue + err) * measured)
        # the fold where the branch the sweep starts on ends (harmonic balance followed from the first point)
        first, last = float(branch.frequencies_hz[0]), float(branch.frequencies_hz[-1])
        force = duffing.gain * branch.amplitude
        fold = hb.fold_bracket(duffing, force, first, last, float(branch.response_amplitude[0]), hold_dt=dt)
        out.append(dataclasses.replace(branch, predicted=np.array(predicted), bound=np.array(bound), fold_hz=fold))
    return out
