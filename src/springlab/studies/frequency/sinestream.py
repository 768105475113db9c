"""The sinestream: the response estimated by simulating MuJoCo, one steady sine at a time, demodulated."""

from __future__ import annotations

import dataclasses
import math
import time as _time
from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np

from springlab.errors import BadInputError
from springlab.exact.linearize import Linearization, OperatingPoint
from springlab.exact.model_at_point import ModelAtPoint
from springlab.sim.simulate import quiet_mujoco
from springlab.studies.executor import Executor, chunked, resolve

from .inputs import Probe
from .linear import EPS
from .results import Sinestream

#: the demodulation's target relative accuracy: the settling time lets the slowest mode's transient decay to it
SINESTREAM_ACCURACY = 1e-7
#: whole periods demodulated per sine (at least), and samples in the window (at least)
ESTIMATE_PERIODS = 4
ESTIMATE_SAMPLES = 256
#: a sine's run is capped at this many steps (its stated accuracy then says what the shorter settling gives)
MAX_SINE_STEPS = 200_000
#: sines per executor chunk (one batched MuJoCo call each)
SINES_PER_CHUNK = 8
#: harmonics demodulated beside the fundamental (those below the Nyquist frequency of dt): a non-linear
#: response's harmonics are fitted, not aliased into the fundamental
HARMONICS = 5
#: the inputs a sine drives: every control and every generalized force, set before each step
CONTROL_SPEC = int(mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_QFRC_APPLIED)
STATE_SPEC = int(
    mujoco.mjtState.mjSTATE_TIME
    | mujoco.mjtState.mjSTATE_QPOS
    | mujoco.mjtState.mjSTATE_QVEL
    | mujoco.mjtState.mjSTATE_ACT
)


def drive(common: SineSetup, omega: float, phase: float, amplitude: float, first: int, count: int) -> np.ndarray:
    """(count, nu + nv) rows of (ctrl, qfrc_applied) for steps first .. first + count - 1: the operating point's
    controls with amplitude sin(phase + omega (k + 1/2) dt) added to the input, held over step k."""
    model = common.model
    rows = np.zeros((count, model.nu + model.nv))
    rows[:, : model.nu] = common.ctrl
    column = common.input_index if common.input_kind == "ctrl" else model.nu + common.input_index
    k = np.arange(first, first + count)
    rows[:, column] += amplitude * np.sin(phase + omega * (k + 0.5) * common.dt)
    return rows


def measure(common: SineSetup, out: dict[Any, np.ndarray], row: int) -> np.ndarray:
    """The response samples of one simulation of a batched rollout: a joint's after each step, a sensor's at
    each step's start (MuJoCo computes sensors in the step's forward pass)."""
    nq, nv = common.model.nq, common.model.nv
    kind, index = common.response_kind, common.response_index
    if kind == "sensor":
        values = out["sensordata"][row][:, index]
    elif kind == "pos":
        values = out[STATE_SPEC][row][:, 1 + common.qposadr]
    else:
        values = out[STATE_SPEC][row][:, 1 + nq + index]
    del nv
    return np.asarray(values, float) - common.offset


def record(common: SineSetup) -> list[Any]:
    return ["sensordata"] if common.response_kind == "sensor" else [STATE_SPEC]


def new_batch(
    common: SineSetup, starts: list[tuple[np.ndarray, np.ndarray, np.ndarray]], nthread: int
) -> mujoco.batch.Batch:
    """A mujoco.batch.Batch of the configured model with one simulation per start (qpos, qvel, act)."""
    from mujoco import batch as mjbatch

    from springlab.sim.simulate import configured

    model = configured(common.model, common.integrator, common.dt)
    batch = mjbatch.Batch(model, nsim=len(starts), nthread=nthread)
    for i, (qpos, qvel, act) in enumerate(starts):
        batch.time[i] = 0.0
        batch.qpos[i] = qpos
        batch.qvel[i] = qvel
        if model.na:
            batch.act[i] = act
    batch.warning[:] = 0
    return batch


def check_finite(batch: mujoco.batch.Batch, values: list[np.ndarray], what: str) -> None:
    from springlab.errors import DivergedError
    from springlab.sim.simulate import BAD_WARNINGS

    warnings = np.array(batch.warning)
    if any(warnings[:, w, 1].any() for w in BAD_WARNINGS) or not all(np.isfinite(v).all() for v in values):
        raise DivergedError(f"{what} blew up in MuJoCo (non-finite state or MuJoCo's bad-state warnings)")


@dataclasses.dataclass(frozen=True)
class SineSetup:
    """What every chunk of sines needs: the model and its setting, where the input goes in and where the
    response is read, and the response's value at the operating point (subtracted from every sample)."""

    model: mujoco.MjModel
    integrator: str
    dt: float
    ctrl: np.ndarray
    input_kind: str
    input_index: int
    response_kind: str
    response_index: int
    qposadr: int
    offset: float


@dataclasses.dataclass(frozen=True, eq=False)
class SineRun:
    """One sine of a chunk: the state it starts from, qpos [m, rad], qvel [m/s, rad/s] and act, its angular
    frequency omega [rad/s], its amplitude [input unit] and its steps."""

    qpos: np.ndarray
    qvel: np.ndarray
    act: np.ndarray
    omega: float
    amplitude: float
    steps: int


@dataclasses.dataclass(frozen=True)
class SineChunk:
    """One executor chunk: the common setup and the sines it runs (one batched rollout)."""

    common: SineSetup
    runs: tuple[SineRun, ...]


def _sine_chunk(payload: SineChunk, nthread: int = 0) -> list[np.ndarray]:
    """Run one chunk of sines (one batched MuJoCo rollout, segment by segment as the shorter runs end) and
    return each run's response samples (a module-level function: it runs on dask workers too)."""
    common, runs = payload.common, payload.runs
    batch = new_batch(common, [(run.qpos, run.qvel, run.act) for run in runs], nthread)
    steps = np.array([run.steps for run in runs])
    records: list[list[np.ndarray]] = [[] for _ in runs]
    done = 0
    with quiet_mujoco():
        for end in np.unique(steps):
            ids = np.flatnonzero(steps >= end).astype(np.int32)
            count = int(end - done)
            control = np.stack([drive(common, runs[i].omega, 0.0, runs[i].amplitude, done, count) for i in ids])
            out = batch.rollout(count, control=control, control_spec=CONTROL_SPEC, record=record(common), ids=ids)
            for row, i in enumerate(ids):
                records[i].append(measure(common, out, row))
            done = int(end)
    values = [np.concatenate(r) for r in records]
    check_finite(batch, values, "a sine")
    return values


def demodulate(y: np.ndarray, t: np.ndarray, omega: float, dt: float | None = None) -> np.ndarray:
    """(Y_1, ..., Y_H): y(t) = a + b t + sum_h Re(Y_h exp(j h omega t)) by least squares (numpy.linalg.lstsq);
    the harmonics h = 2 .. HARMONICS below the Nyquist frequency of dt (None: the fundamental only)."""
    top = 1 if dt is None else max(1, min(HARMONICS, int(math.ceil(math.pi / (omega * dt))) - 1))
    t0 = t - t[0]
    columns = [np.ones_like(t), t0]
    for h in range(1, top + 1):
        columns += [np.cos(h * omega * t), np.sin(h * omega * t)]
    coef, *_ = np.linalg.lstsq(np.column_stack(columns), y, rcond=None)
    return np.array([complex(coef[2 + 2 * h], -coef[3 + 2 * h]) for h in range(top)])


def common_setup(at: ModelAtPoint, probe: Probe, integrator: str, dt: float) -> SineSetup:
    """What every chunk needs: the model, the setting, the input and the response, and the response at the
    operating point (a sensor's from the model's forward pass there, `at.data`)."""
    model, point = at.model, at.point
    qposadr = 0
    if probe.response_kind == "sensor":
        offset = float(at.data.sensordata[probe.response_index])
    else:
        qposadr = int(model.jnt_qposadr[int(model.dof_jntid[probe.response_index])])
        if probe.response_kind == "pos":
            offset = float(point.qpos[qposadr])
        else:
            offset = float(point.qvel[probe.response_index])
    return SineSetup(
        model=model,
        integrator=integrator,
        dt=dt,
        ctrl=np.array(point.ctrl, float),
        input_kind=probe.input_kind,
        input_index=probe.input_index,
        response_kind=probe.response_kind,
        response_index=probe.response_index,
        qposadr=qposadr,
        offset=offset,
    )


def default_amplitude(model: mujoco.MjModel, point: OperatingPoint, kind: str, index: int) -> float:
    """The sinestream's input amplitude when none is given: 1 input unit, or half the room an actuator's
    control range leaves at the operating point [input unit].

    Raises
    ------
    BadInputError
        the operating point's control sits on its limit.
    """
    if kind != "ctrl":
        return 1.0
    low, high = model.actuator_ctrlrange[index]
    limited = bool(model.actuator_ctrllimited[index]) and high > low
    base = float(point.ctrl[index])
    amplitude = min(1.0, 0.5 * min(high - base, base - low)) if limited else 1.0
    if amplitude <= 0:
        raise BadInputError("the operating point's control sits on its limit: no room for a sine")
    return float(amplitude)


def check_amplitudes(
    model: mujoco.MjModel, point: OperatingPoint, kind: str, index: int, amplitudes: Any
) -> tuple[float, ...]:
    """The amplitudes as floats > 0, each inside an actuator's control range around the operating point."""
    try:
        values = tuple(float(a) for a in amplitudes)
    except (TypeError, ValueError):
        raise BadInputError(f"amplitudes must be numbers > 0 in input units, got {amplitudes!r}") from None
    if not values or not all(math.isfinite(a) and a > 0 for a in values):
        raise BadInputError(f"amplitudes must be finite numbers > 0 in input units, got {amplitudes!r}")
    if kind == "ctrl" and bool(model.actuator_ctrllimited[index]):
        low, high = model.actuator_ctrlrange[index]
        room = min(high - point.ctrl[index], point.ctrl[index] - low)
        if max(values) > room:
            raise BadInputError(
                f"amplitude {max(values):g} leaves the actuator's control range {low:g}..{high:g} around"
                f" {point.ctrl[index]:g}; give amplitudes <= {room:g}"
            )
    return values


def settle_rate(linear: Linearization) -> tuple[float, float]:
    """(sigma [1/s], cond(V)): the slowest decaying non-rigid mode's rate and the mode basis' condition number."""
    moving = [-lam.real for lam in linear.eigenvalues if abs(lam) > linear.growth_tolerance and lam.real < 0]
    sigma = min(moving) if moving else math.inf
    _, vectors = linear.eigenvectors  # eig(A), computed once per linearization
    condition = float(np.linalg.cond(vectors)) if vectors.size else 1.0
    return sigma, condition


def steady_start(
    at: ModelAtPoint, b: np.ndarray, omega: float, amplitude: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(qpos, qvel, act) on the linearization's steady state at t = 0 of `amplitude` sin(omega t) on the input
    whose column is b [input unit, rad/s]."""
    model, point, a = at.model, at.point, at.linear.A
    nv = model.nv
    state = np.linalg.solve(1j * omega * np.eye(a.shape[0]) - a, b * (-1j * amplitude))
    start = state.real
    qpos = point.qpos.copy()
    mujoco.mj_integratePos(model, qpos, start[:nv], 1.0)
    return qpos, point.qvel + start[nv : 2 * nv], point.act + start[2 * nv :]


def sinestream(
    at: ModelAtPoint,
    b: np.ndarray,
    probe: Probe,
    integrator: str,
    dt: float,
    frequencies_hz: np.ndarray,
    discrete: np.ndarray,
    exact_of: Callable[[np.ndarray], np.ndarray],
    uncertainty: np.ndarray,
    amplitude: float,
    executor: Executor | None = None,
) -> Sinestream:
    """Simulate MuJoCo at each frequency and demodulate (`Sinestream`; the module docstring says how).

    Each sine u_k = U sin(omega (k + 1/2) dt), held over step k on the input (an actuator's control or a
    joint's `qfrc_applied`), starts on the exact linearization's steady state (so only the small
    discrete-minus-exact difference is left to decay), runs `settle` (the slowest non-rigid mode's envelope
    exp(-sigma t) times the mode basis' condition number down to SINESTREAM_ACCURACY), then ESTIMATE_PERIODS
    whole periods (at least ESTIMATE_SAMPLES samples) of the response (a joint's position or velocity, or a
    sensor) are demodulated by least squares on (1, t, cos h omega t, sin h omega t) with the harmonics h
    below Nyquist. `uncertainty` (m,) is the discrete response's own relative finite-difference error (its maps
    at the steps h and 2 h compared). The stated accuracy is the linear model's: for a non-linear one the
    estimate is the first harmonic per input amplitude (its describing function) and may part from it.

    Raises
    ------
    BadInputError
        the response is a joint's acceleration (the run records positions and velocities; a sensor can
        measure one).
    """
    if probe.response_kind == "acc":
        raise BadInputError(
            "the sinestream measures a joint's position or velocity, or a sensor; not a joint's acceleration"
            " (add an accelerometer sensor)"
        )
    started = _time.perf_counter()
    sigma, condition = settle_rate(at.linear)
    exact = exact_of(frequencies_hz)
    runs, meta = [], []
    for f in frequencies_hz:
        omega = 2 * math.pi * float(f)
        period = 1.0 / float(f)
        settle = math.log(condition / SINESTREAM_ACCURACY) / sigma if math.isfinite(sigma) else 0.0
        periods = max(ESTIMATE_PERIODS, math.ceil(ESTIMATE_SAMPLES * dt / period))
        estimate_steps = int(round(periods * period / dt))
        settle_steps = min(int(math.ceil(settle / dt)), max(MAX_SINE_STEPS - estimate_steps, 0))
        steps = settle_steps + estimate_steps
        qpos, qvel, act = steady_start(at, b, omega, amplitude)
        runs.append(SineRun(qpos, qvel, act, omega, amplitude, steps))
        left = condition * math.exp(-sigma * settle_steps * dt) if math.isfinite(sigma) else 0.0
        rounding = 1e3 * EPS * math.sqrt(steps)
        meta.append((omega, settle_steps, estimate_steps, periods, min(left, 1.0) + rounding))
    common = common_setup(at, probe, integrator, dt)
    shift = 0 if probe.response_kind == "sensor" else 1  # a joint's sample k is after step k
    chunks = chunked(len(runs), SINES_PER_CHUNK)
    payloads = [SineChunk(common, tuple(runs[i] for i in chunk)) for chunk in chunks]
    results = [y for part in resolve(executor).map(_sine_chunk, payloads, description="sines") for y in part]
    estimates = []
    for y, (omega, _, estimate_steps, _, _) in zip(results, meta):
        t = (np.arange(len(y)) + shift) * dt
        window = slice(len(y) - estimate_steps - shift, len(y))
        estimates.append(demodulate(y[window], t[window], omega, dt)[0] / (-1j * amplitude))
    arrays = [
        np.asarray(frequencies_hz, float),
        np.array(estimates),
        np.asarray(discrete),
        np.asarray(exact),
        np.array([m[4] for m in meta]),
        np.array([m[1] * dt for m in meta]),
        np.array([m[3] for m in meta]),
        np.asarray(uncertainty, float),
    ]
    for array in arrays:
        array.setflags(write=False)
    return Sinestream(
        frequencies_hz=arrays[0],
        estimate=arrays[1],
        discrete=arrays[2],
        exact=arrays[3],
        accuracy=arrays[4],
        amplitude=float(amplitude),
        settle_s=arrays[5],
        estimate_periods=arrays[6],
        uncertainty=arrays[7],
        steps=int(sum(run.steps for run in runs)),
        wall_time_s=_time.perf_counter() - started,
    )
