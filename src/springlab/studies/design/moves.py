"""The design studies' batched move simulation: the printer head's `move` scenario for many
configurations at once, in one `mujoco.batch.Batch`.

A configuration is a value of each swept property (belt_stiffness k [N/m], carriage_mass m_c
[kg], damping_ratio zeta [-], drive_force F [N], and, for the Sobol study only,
move_distance D [m]) on top of the scene's `move` parameters; :mod:`springlab.studies.design.study` and
:mod:`springlab.studies.design.sobol` build the configurations, this module runs them.

How the runs are made: one `mujoco.batch.Batch` holds every configuration as
its own simulation, with per-simulation carriage mass (body_mass), belt
stiffness and damping (tendon_stiffness, tendon_damping), force limit
(actuator_ctrlrange) and timestep (opt.timestep). Each simulation gets
dt <= omega_dt / omega_n of its own belt mode (RK4; omega_dt = 0.1: at least 63
steps per period, relative phase error (omega dt)^4 / 120 = 1e-6 per radian), so
every configuration is resolved equally well and slow ones take no more steps
than fast ones; dt also divides the minimum half-move time sqrt(D M / F)
exactly, so every configuration makes the true minimum-time move at its full
force (rounding the switch onto a fixed grid would shift the residual
vibration's phase, and with it the settling time, with the resolution). Above
the band, whether a vibration peak that just grazes it counts decides half a
period of settling time: between omega_dt = 0.1 and 0.2, 26 of the 2401
default configurations differ by more than one step. The runs advance in chunks of steps through `Batch.rollout` (controls
(n, steps, 1), the bang-bang switches on each simulation's own step grid) and a
simulation stops as soon as its settling is certified: once the move is over
the carriage stays within |X - D| + (m_m / M) sqrt(2 E / k) of the target for
ever (printer_head.after_force_bound), and when that is inside the band its
last exit from the band is final.
"""

from __future__ import annotations

import time as _time
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np
from mujoco import batch as mjbatch

from springlab import scenes
from springlab.errors import DivergedError
from springlab.scenes.printer_head.scene import PrinterHead, after_force_bound, belt_damping_for, belt_omega
from springlab.sim.simulate import quiet_mujoco
from springlab.studies.executor import Executor, chunked

#: omega_n * dt of every simulation
OMEGA_DT = 0.1
#: steps per batched rollout call
CHUNK = 256
#: simulated time [s] after which an unsettled configuration is given up (reported as inf)
MAX_DURATION = 5.0
#: configurations per chunk: one batched call each (about 2 s on one core), the unit of work on a cluster
CHUNK_CONFIGURATIONS = 256
#: the (n,) arrays simulate_moves returns per configuration
_PER_CONFIGURATION = ("move_time_s", "settling_time_s", "positioning_time_s", "residual_amplitude_m", "dt_s", "steps")
#: the properties the belt damping of a configuration is computed from
_BELT_PROPERTIES = ("belt_stiffness", "carriage_mass", "damping_ratio")


def belt_damping(values: Mapping[str, np.ndarray], motor_mass: float) -> np.ndarray:
    """Belt damping c = 2 zeta sqrt(k mu) [N s/m] of each configuration."""
    m_c = np.asarray(values["carriage_mass"], float)
    # asarray: belt_damping_for takes floats or arrays; these are arrays
    return np.asarray(
        belt_damping_for(np.asarray(values["damping_ratio"]), np.asarray(values["belt_stiffness"]), m_c, motor_mass)
    )


def config_parameters(base: Mapping[str, float], values: Mapping[str, np.ndarray], i: int) -> dict[str, float]:
    """The scene parameters of configuration i (belt damping from its damping ratio)."""
    params = dict(base)
    for name in ("belt_stiffness", "carriage_mass", "drive_force", "move_distance"):
        if name in values:  # move_distance: only the Sobol study varies it
            params[name] = float(values[name][i])
    params["belt_damping"] = float(
        belt_damping({n: np.atleast_1d(values[n][i]) for n in _BELT_PROPERTIES}, base["motor_mass"])[0]
    )
    return params


def timesteps(values: Mapping[str, np.ndarray], base: Mapping[str, float], omega_dt: float = OMEGA_DT) -> np.ndarray:
    """Each configuration's timestep [s]: at most omega_dt / omega_n of its belt mode, and a whole
    fraction of its minimum half-move time sqrt(D M / F), so the bang-bang switches fall on the step
    grid exactly and every configuration makes the true minimum-time move at its full force (a
    rounded switch time would shift the residual vibration's phase with the resolution)."""
    m_c = np.asarray(values["carriage_mass"], float)
    motor_mass = base["motor_mass"]
    total = m_c + motor_mass
    largest = omega_dt / belt_omega(np.asarray(values["belt_stiffness"]), m_c, motor_mass)
    half = np.sqrt(move_distances(base, values) * total / np.asarray(values["drive_force"], float))
    return half / np.ceil(half / largest)


def move_distances(base: Mapping[str, float], values: Mapping[str, np.ndarray]) -> np.ndarray:
    """(n,) move distance [m] per configuration: values["move_distance"] if varied, else the base's."""
    n = len(values["belt_stiffness"])
    return np.broadcast_to(np.asarray(values.get("move_distance", base["move_distance"]), float), (n,)).copy()


def move_profiles(
    base: Mapping[str, float], values: Mapping[str, np.ndarray], dt: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(steps per half-move, force [N]) per configuration, as PrinterHead.move_profile."""
    half_steps = np.empty(len(dt), int)
    force = np.empty(len(dt))
    for i in range(len(dt)):
        half_steps[i], force[i] = PrinterHead.move_profile(config_parameters(base, values, i), float(dt[i]))
    return half_steps, force


def simulate_moves(
    base: Mapping[str, float],
    values: Mapping[str, np.ndarray],
    *,
    omega_dt: float = OMEGA_DT,
    nthread: int = 0,
    chunk: int = CHUNK,
    max_duration: float = MAX_DURATION,
) -> dict[str, Any]:
    """Run the `move` scenario for every configuration in one mujoco.batch.Batch.

    Parameters
    ----------
    base
        scene parameters (move_distance [m], positioning_band [m], motor_mass [kg], ...).
    values
        property -> (n,) values (springlab.studies.design.study.PROPERTIES).
    omega_dt
        omega_n dt [-] of every simulation (RK4).
    nthread
        batch threads (0: one per CPU).
    chunk
        steps per rollout call.
    max_duration
        simulated time [s] after which an unsettled configuration is given up.

    Returns
    -------
    dict[str, Any]
        dict of (n,) arrays: move_time_s, settling_time_s, positioning_time_s,
        residual_amplitude_m, dt_s, steps (per configuration); and steps_total,
        wall_time_s, nthread.

    Raises
    ------
    DivergedError
        a simulation blew up (MuJoCo's warning counters rose).
    """
    scene = scenes.get("printer_head")
    assert isinstance(scene, PrinterHead)
    scenario = scene.scenario("move")
    params = dict(base)
    model = scene.build(params, scenario)
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    n = len(values["belt_stiffness"])
    m_m = params["motor_mass"]
    m_c = np.asarray(values["carriage_mass"], float)
    total = m_c + m_m
    stiffness = np.asarray(values["belt_stiffness"], float)
    damping = belt_damping(values, m_m)
    limit = np.asarray(values["drive_force"], float)
    distance, band = move_distances(params, values), params["positioning_band"]
    dt = timesteps(values, params, omega_dt)
    half_steps, force = move_profiles(params, values, dt)
    move_steps = 2 * half_steps

    with quiet_mujoco():
        batch = mjbatch.Batch(model, nsim=n, nthread=nthread)
        batch.body("carriage").mass = m_c[:, None]
        belt = model.tendon("belt").id
        batch.expand("tendon_stiffness")[:, belt] = stiffness
        batch.expand("tendon_damping")[:, belt] = damping
        batch.actuator("drive").ctrlrange = np.column_stack([-limit, limit])
        batch.expand("opt.timestep")[:] = dt
        batch.set_const()
        # start: belt stretched by `deflection`, centre of mass at rest at 0 (as the scene)
        stretch0 = params["deflection"]
        batch.joint("carriage").qpos = (-m_m * stretch0 / total)[:, None]
        batch.joint("motor").qpos = (m_c * stretch0 / total)[:, None]
    carriage = model.joint("carriage").qposadr[0]
    motor = model.joint("motor").qposadr[0]

    steps = np.zeros(n, int)  # steps taken by each simulation
    excess = np.abs(-m_m * stretch0 / total - distance) - band  # |q_c - D| - band at the current state
    last_exit = np.zeros(n)  # time [s] of the last exit from the band so far
    residual = np.zeros(n)
    settled = np.zeros(n, bool)
    active = np.arange(n)
    offsets = np.arange(chunk)
    start = _time.perf_counter()
    while active.size:
        taken = steps[active][:, None] + offsets[None, :]  # index of each step about to be taken
        half = half_steps[active][:, None]
        f = force[active][:, None]
        control = np.where(taken < half, f, np.where(taken < 2 * half, -f, 0.0))[..., None]
        with quiet_mujoco():
            record = batch.rollout(chunk, control, record=("qpos", "qvel"), ids=active)
        if np.any(batch.warning[active, :, 1] > 0):
            bad = active[np.any(batch.warning[active, :, 1] > 0, axis=1)]
            raise DivergedError(f"design sweep: {len(bad)} simulations diverged (first: configuration {bad[0]})")
        qpos, qvel = record["qpos"], record["qvel"]
        deviation = qpos[:, :, carriage] - distance[active][:, None]
        chunk_excess = np.column_stack([excess[active], np.abs(deviation) - band])
        # the last sample outside the band in [current state, chunk end]; exits interpolated linearly
        outside = chunk_excess > 0
        has = outside.any(axis=1)
        last = chunk - np.argmax(outside[:, ::-1], axis=1)  # column of the last True
        rows = np.flatnonzero(has)
        sims = active[rows]
        col = last[rows]
        inner = col < chunk
        t_col = (steps[sims] + col) * dt[sims]
        a = chunk_excess[rows, col]
        b = chunk_excess[rows, np.minimum(col + 1, chunk)]
        last_exit[sims] = np.where(inner, t_col + dt[sims] * a / np.where(inner, a - b, 1.0), t_col)
        # the residual vibration: samples at or after the end of the move (state index taken + 1)
        after = (taken + 1) >= move_steps[active][:, None]
        residual[active] = np.maximum(residual[active], np.max(np.where(after, np.abs(deviation), 0.0), axis=1))
        excess[active] = chunk_excess[:, -1]
        steps[active] += chunk
        # certify: force off, and the energy bound inside the band
        q_c, q_m = qpos[:, -1, carriage], qpos[:, -1, motor]
        v_c, v_m = qvel[:, -1, carriage], qvel[:, -1, motor]
        centre = (m_c[active] * q_c + m_m * q_m) / total[active]
        bound = after_force_bound(centre - distance[active], q_m - q_c, v_m - v_c, m_c[active], m_m, stiffness[active])
        certified = (steps[active] >= move_steps[active]) & (bound <= band)
        settled[active[certified]] = True
        active = active[~certified & (steps[active] * dt[active] <= max_duration)]
    wall = _time.perf_counter() - start

    move_time = move_steps * dt
    settling = np.where(settled, np.maximum(last_exit - move_time, 0.0), np.inf)
    return {
        "move_time_s": move_time,
        "settling_time_s": settling,
        "positioning_time_s": move_time + settling,
        "residual_amplitude_m": residual,
        "dt_s": dt,
        "steps": steps,
        "steps_total": int(steps.sum()),
        "wall_time_s": wall,
        "nthread": batch.nthread,
    }


def moves_chunk(payload: Mapping[str, Any], nthread: int = 0) -> dict[str, Any]:
    """One chunk of a design study (a module-level function of plain data, for dask workers):
    simulate_moves on payload["base"], payload["values"] and payload["omega_dt"]."""
    return simulate_moves(payload["base"], payload["values"], omega_dt=payload["omega_dt"], nthread=nthread)


def run_moves(
    base: Mapping[str, float],
    values: Mapping[str, np.ndarray],
    *,
    omega_dt: float = OMEGA_DT,
    executor: Executor | None = None,
    chunk_size: int = CHUNK_CONFIGURATIONS,
    description: str = "design",
) -> dict[str, Any]:
    """simulate_moves over every configuration, cut into chunks of `chunk_size` on `executor`.

    Each simulation's result depends only on its own parameters, and the chunks are concatenated
    in order, so the arrays are identical whichever executor runs them (and whatever the chunk size).
    Returns what simulate_moves returns; wall_time_s is the whole map's.
    """
    runner = Executor(progress=False) if executor is None else executor
    n = len(values["belt_stiffness"])
    pieces = chunked(n, chunk_size)
    payloads = [
        {
            "base": dict(base),
            "values": {name: np.asarray(v)[piece.start : piece.stop] for name, v in values.items()},
            "omega_dt": omega_dt,
        }
        for piece in pieces
    ]
    start = _time.perf_counter()
    parts = runner.map(moves_chunk, payloads, description=description, sizes=[len(p) for p in pieces], unit="config")
    out: dict[str, Any] = {key: np.concatenate([part[key] for part in parts]) for key in _PER_CONFIGURATION}
    out["steps_total"] = int(out["steps"].sum())
    out["wall_time_s"] = _time.perf_counter() - start
    out["nthread"] = int(parts[0]["nthread"]) if parts else 0
    out["executor"] = runner.describe()
    return out
