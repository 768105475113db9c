"""Headless MuJoCo runs: integrators, timesteps, batched rollouts, divergence.

One run is one call to `mujoco.rollout` on the calling thread: no Python work
per step. Inputs are open-loop control sequences (one row per step, held over
the step) and MJCF-native generators, so RK4 keeps its order wherever the scene
says so. A run may instead carry a sampled-data controller (`Setup.controller`,
springlab.sim.controller.Controller): it reads the model's sensors every few steps
and holds its controls in between, so MuJoCo steps it from Python
(controller.closed_loop); its controls are still constant over each step.

MuJoCo resets a blown-up simulation *silently* (time jumps back, qpos zeroed).
`simulate` checks every run for that, for non-finite values and for MuJoCo's
BADQPOS/BADQVEL/BADQACC warnings, and raises `DivergedError` instead of
returning such a run.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import functools
import math
import operator
import threading
import time as _time
from collections.abc import Callable, Iterator, Mapping

import mujoco
import numpy as np
from mujoco import rollout as _rollout

from springlab.errors import BadInputError, DivergedError, UnknownNameError

from .controller import BAD_WARNINGS as BAD_WARNINGS  # re-exported: where the studies read it
from .controller import Controller, closed_loop

#: MuJoCo's five integrators by springlab name.
INTEGRATORS: Mapping[str, int] = {
    "euler": int(mujoco.mjtIntegrator.mjINT_EULER),
    "implicit": int(mujoco.mjtIntegrator.mjINT_IMPLICIT),
    "implicitfast": int(mujoco.mjtIntegrator.mjINT_IMPLICITFAST),
    "rk4": int(mujoco.mjtIntegrator.mjINT_RK4),
    "discrete": int(mujoco.mjtIntegrator.mjINT_DISCRETE),
}

#: Order of accuracy of each integrator on smooth problems.
ORDERS: Mapping[str, int] = {
    "euler": 1,
    "implicit": 1,
    "implicitfast": 1,
    "rk4": 4,
    "discrete": 1,
}
#: Leading local-error constant C of each integrator (local error C h^(p+1) A^(p+1) z on z' = A z): RK4's
#: 1/120 from R(hA) = e^(hA) - (hA)^5 / 120 + ..., the first-order methods' 1/2 (springlab.runs.compare)
ERROR_CONSTANTS: Mapping[str, float] = {name: (1.0 / 120.0 if order == 4 else 0.5) for name, order in ORDERS.items()}
#: safety factor on a predicted leading-order error, where a tolerance is derived from it
SAFETY = 2.0
#: round-off allowance per step, relative
ROUNDOFF_PER_STEP = 100 * np.finfo(float).eps

_FULL = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)
_CTRL = int(mujoco.mjtState.mjSTATE_CTRL)

#: Most steps one run may take (memory: 8 bytes x state size per step).
MAX_STEPS = 20_000_000


@dataclasses.dataclass
class Trajectory:
    """A recorded run, one row per physics step, t = 0 included.

    Attributes
    ----------
    time
        (n,) simulation time [s].
    qpos
        (n, nq) joint positions [m or rad].
    qvel
        (n, nv) joint velocities [m/s or rad/s].
    act
        (n, na) actuator activations (units of the actuator).
    integrator
        springlab integrator name.
    dt
        timestep [s].
    wall_time_s
        wall time of the stepping itself [s].
    stopped
        True when a stop condition ended the run before its duration.
    sensordata
        (n, nsensordata) the model's sensors at each recorded state [sensor units] (None: not recorded, as
        in batched runs).
    control
        (n - 1, nu) the controls held over each step [actuator units] of a run with a controller in the loop
        (None otherwise: the open-loop controls are the caller's).
    """

    time: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    act: np.ndarray
    integrator: str
    dt: float
    wall_time_s: float
    stopped: bool = False
    sensordata: np.ndarray | None = None
    control: np.ndarray | None = None

    @property
    def steps(self) -> int:
        """Number of physics steps taken."""
        return len(self.time) - 1


_log = threading.local()

#: one scratch MjData per thread, kept between runs: building one costs ~0.35 ms (its ~200 array views),
#: a tenth of a 1000-step RK4 run of a small model
_spare = threading.local()


@functools.cache
def _sizes() -> Callable[[mujoco.MjModel], tuple[int, ...]]:
    """A getter of every size field of MjModel (`nq`, `nbuffer`, `narena`, ...: its integer `n*` fields)."""
    probe = mujoco.MjModel.from_xml_string("<mujoco/>")
    return operator.attrgetter(*(n for n in dir(probe) if n.startswith("n") and type(getattr(probe, n)) is int))


def model_sizes(model: mujoco.MjModel) -> tuple[int, ...]:
    """`model`'s sizes (nq, nv, nbody, ..., narena, nbuffer): what an MjData's layout depends on."""
    return _sizes()(model)


def _layout(model: mujoco.MjModel) -> tuple[int, ...]:
    """What an MjData's memory is laid out by: the model's compilation signature and every size field."""
    return (model.signature, *model_sizes(model))


@contextlib.contextmanager
def _spare_data(model: mujoco.MjModel) -> Iterator[mujoco.MjData]:
    """A scratch MjData for `model`: this thread's spare when its layout matches, else a new one.

    An MjData holds nothing of its model but the sizes its arrays are laid out by (mujoco.rollout runs
    one data per thread over models of one size signature), and every run resets it (mj_resetData),
    so a run on the spare is the run on a fresh one, bit for bit. Not for models with plugins, whose
    instances are built from the model's attributes when the data is made. Borrowed, not shared: a
    run started inside another run's controller gets its own.
    """
    key = _layout(model) if not model.nplugin else None
    spare = getattr(_spare, "data", None)
    if key is not None and spare is not None and spare[0] == key:
        _spare.data = None
        data = spare[1]
    else:
        data = mujoco.MjData(model)
    try:
        yield data
    finally:  # a run that raised (a divergence) leaves it too: the next run resets it
        if key is not None:
            _spare.data = (key, data)


def _collect_warning(message: str) -> None:
    # MuJoCo's default handler prints and writes MUJOCO_LOG.TXT into the cwd;
    # springlab reports problems itself, in one clear line.
    getattr(_log, "messages", []).append(message)


@contextlib.contextmanager
def quiet_mujoco() -> Iterator[list[str]]:
    """Route MuJoCo's warnings into a list for the duration (no log file, no print)."""
    previous = mujoco.get_mju_user_warning()
    _log.messages = []
    mujoco.set_mju_user_warning(_collect_warning)
    try:
        yield _log.messages
    finally:
        mujoco.set_mju_user_warning(previous)


def integrator_id(name: str) -> int:
    """MuJoCo's enum value for an integrator name; UnknownNameError lists the valid names."""
    try:
        return INTEGRATORS[name]
    except KeyError:
        raise UnknownNameError("integrator", str(name), INTEGRATORS) from None


def check_timing(dt: float, duration: float) -> int:
    """Validate dt [s] and duration [s]; return the number of steps."""
    for label, value in (("dt", dt), ("duration", duration)):
        if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            raise BadInputError(f"{label} must be a finite number > 0 s, got {value!r}")
    steps = round(duration / dt)
    if steps < 1:
        raise BadInputError(f"duration {duration} s is shorter than one step of dt = {dt} s")
    if steps > MAX_STEPS:
        raise BadInputError(
            f"duration/dt = {steps} steps exceeds the limit of {MAX_STEPS}; use a larger dt or a shorter duration"
        )
    return steps


def configured(model: mujoco.MjModel, integrator: str, dt: float) -> mujoco.MjModel:
    """A copy of `model` set to `integrator` and timestep `dt` [s]; `model` itself is left as it was.

    A caller's model may serve many runs (a sweep, a reference built from it): writing the
    timestep into it would leak one run's setting into the next.
    """
    work = copy.copy(model)
    work.opt.integrator = integrator_id(integrator)
    work.opt.timestep = dt
    return work


def initial_state(
    model: mujoco.MjModel,
    qpos: np.ndarray | None = None,
    qvel: np.ndarray | None = None,
    act: np.ndarray | None = None,
    data: mujoco.MjData | None = None,
) -> np.ndarray:
    """The full physics state vector at t = 0 (defaults: the model's qpos0, rest).

    `data` (optional) is reset and used as scratch.
    """
    if data is None:
        data = mujoco.MjData(model)
    else:
        mujoco.mj_resetData(model, data)
    if qpos is not None:
        data.qpos[:] = qpos
    if qvel is not None:
        data.qvel[:] = qvel
    if act is not None:
        data.act[:] = act
    state = np.empty(mujoco.mj_stateSize(model, _FULL))
    mujoco.mj_getState(model, data, state, _FULL)
    return state


def simulate(
    model: mujoco.MjModel,
    *,
    integrator: str,
    dt: float,
    duration: float,
    qpos: np.ndarray | None = None,
    qvel: np.ndarray | None = None,
    act: np.ndarray | None = None,
    control: np.ndarray | None = None,
    data: mujoco.MjData | None = None,
    stop: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
    controller: Controller | None = None,
    prepared: bool = False,
) -> Trajectory:
    """Run `model` headless and record every step.

    Parameters
    ----------
    model
        compiled model; never modified (the run steps a copy with `integrator` and
        `dt` set, as mujoco.rollout never modifies its inputs).
    integrator
        one of INTEGRATORS.
    dt
        timestep [s].
    duration
        simulated time [s]; steps = round(duration / dt).
    qpos, qvel, act
        initial state (defaults: the model's rest state).
    control
        (nu,) constant or (steps, nu) per-step controls [actuator units];
        row k is held over step k, from t_k to t_k + dt.
    data
        scratch MjData to reuse (optional).
    stop
        optional event (qpos (n, nq), qvel (n, nv)) -> (n,) bool; the
        trajectory ends at the first step where it is True (`stopped` set), and
        whatever MuJoCo did after that step (e.g. a finite-time escape hitting
        its 1e10 limit) is discarded, not reported as a divergence.
    controller
        a sampled-data controller in the loop (springlab.sim.controller.Controller) instead of `control`:
        every `controller.steps_per_sample` steps it reads the sensors and sets the controls, held in between.
    prepared
        `model` is already a copy set to `integrator` and `dt` that nobody writes into (`configured`, kept by
        its caller with its `data`): step it as it is instead of copying it again.

    Returns
    -------
    Trajectory
        The Trajectory, t = 0 included, with the sensors at every state.

    Raises
    ------
    DivergedError
        MuJoCo flagged or silently reset the run, or it went non-finite.
    """
    steps = check_timing(dt, duration)
    if not prepared:
        model = configured(model, integrator, dt)
    if data is None:
        with _spare_data(model) as spare:
            return _simulate(model, spare, integrator, dt, steps, qpos, qvel, act, control, stop, controller)
    return _simulate(model, data, integrator, dt, steps, qpos, qvel, act, control, stop, controller)


def _simulate(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    integrator: str,
    dt: float,
    steps: int,
    qpos: np.ndarray | None,
    qvel: np.ndarray | None,
    act: np.ndarray | None,
    control: np.ndarray | None,
    stop: Callable[[np.ndarray, np.ndarray], np.ndarray] | None,
    controller: Controller | None,
) -> Trajectory:
    """`simulate`'s run of `steps` steps of the configured `model` on the scratch `data` (reset here)."""
    state0 = initial_state(model, qpos, qvel, act, data)
    if controller is not None:
        if control is not None:
            raise BadInputError("a run takes open-loop controls or a controller in the loop, not both")
        with quiet_mujoco() as messages:
            start = _time.perf_counter()
            states, sensordata, applied, flagged = closed_loop(model, data, state0, controller, steps)
            wall = _time.perf_counter() - start
        trajectory = dataclasses.replace(
            _split(model, states, integrator, dt, wall), sensordata=sensordata, control=applied
        )
        return _finished(trajectory, dt, stop, messages + (["unstable"] if flagged else []))
    controls = None
    if model.nu:
        controls = np.zeros((1, model.nu)) if control is None else np.asarray(control, float)
        controls = np.ascontiguousarray(np.broadcast_to(controls, (steps, model.nu)))[None]
    # rollout writes the states after each step straight behind the initial one (row 0): no copy of the whole
    # record afterwards (a 600 s stay cable run is 190 MB, and copying it cost a sixth of its rollout)
    states = np.empty((steps + 1, state0.size))
    states[0] = state0
    out = states[1:][None]
    sensors = np.empty((1, steps, model.nsensordata))
    with quiet_mujoco() as messages:
        start = _time.perf_counter()
        # skip_checks: the shapes are right by construction, and the checks cost per call
        _rollout.rollout(
            [model],
            [data],
            state0[None],
            controls,
            control_spec=_CTRL,
            state=out,
            sensordata=sensors,
            nstep=steps,
            skip_checks=True,
        )
        wall = _time.perf_counter() - start
    # rollout records the sensors of the state each step starts from; the last state's are computed here
    last = _sensors_at(model, data, states[-1], controls[0, -1] if controls is not None else None)
    trajectory = dataclasses.replace(
        _split(model, states, integrator, dt, wall), sensordata=np.concatenate([sensors[0], last[None]])
    )
    return _finished(trajectory, dt, stop, messages)


def _sensors_at(
    model: mujoco.MjModel, data: mujoco.MjData, state: np.ndarray, control: np.ndarray | None
) -> np.ndarray:
    """The sensors [sensor units] at a full physics state (and controls), by one forward pass on `data`."""
    if not model.nsensordata:
        return np.empty(0)
    mujoco.mj_setState(model, data, state, _FULL)
    if control is not None:
        data.ctrl[:] = control
    with np.errstate(all="ignore"):
        mujoco.mj_forward(model, data)
    return data.sensordata.copy()


def _finished(
    trajectory: Trajectory,
    dt: float,
    stop: Callable[[np.ndarray, np.ndarray], np.ndarray] | None,
    messages: list[str],
) -> Trajectory:
    """The run cut at its stop condition, checked for a blow-up (DivergedError)."""
    if stop is not None:
        trajectory, stopped = cut_at_stop(trajectory, stop)
        if stopped:
            # MuJoCo's warnings may come from steps after the event; a blow-up before it
            # still shows in the kept part (time jumping back, non-finite values)
            messages = []
    check_diverged(trajectory, dt, messages)
    return trajectory


def cut_at_stop(
    trajectory: Trajectory, stop: Callable[[np.ndarray, np.ndarray], np.ndarray]
) -> tuple[Trajectory, bool]:
    """The trajectory up to and including the first step where `stop` holds, and whether it did."""
    end = divergence_step(trajectory)
    end = len(trajectory.time) if end is None else end
    with np.errstate(all="ignore"):
        hits = np.flatnonzero(np.asarray(stop(trajectory.qpos[:end], trajectory.qvel[:end]), bool))
    if not hits.size:
        return trajectory, False
    keep = int(hits[0]) + 1
    return dataclasses.replace(
        trajectory,
        time=trajectory.time[:keep],
        qpos=trajectory.qpos[:keep],
        qvel=trajectory.qvel[:keep],
        act=trajectory.act[:keep],
        stopped=True,
        sensordata=None if trajectory.sensordata is None else trajectory.sensordata[:keep],
        control=None if trajectory.control is None else trajectory.control[: keep - 1],
    ), True


def _split(model, states, integrator, dt, wall) -> Trajectory:
    nq, nv, na = model.nq, model.nv, model.na
    return Trajectory(
        time=states[:, 0],
        qpos=states[:, 1 : 1 + nq],
        qvel=states[:, 1 + nq : 1 + nq + nv],
        act=states[:, 1 + nq + nv : 1 + nq + nv + na],
        integrator=integrator,
        dt=dt,
        wall_time_s=wall,
    )


def divergence_step(trajectory: Trajectory) -> int | None:
    """Index of the first step that shows a blow-up or a silent MuJoCo reset, else None."""
    t = trajectory.time
    dt = trajectory.dt
    # a reset sets time back to 0; rollout then repeats its last record
    bad_time = np.flatnonzero(np.abs(np.diff(t) - dt) > 1e-6 * dt + 1e-12 * np.abs(t[1:]))
    candidates = []
    if bad_time.size:
        candidates.append(int(bad_time[0]) + 1)
    # a finite sum has no inf or nan in it (either would carry through): the common case without the (steps, n)
    # masks; a sum that overflows, or a non-finite value in another column of the record, only sends the record
    # to the row-by-row test. Where qpos and qvel are columns of one contiguous record of these rows (a rollout's
    # states), the record is summed whole: one pass over its memory, where the two strided sums made two.
    record = trajectory.qpos.base
    whole = (
        isinstance(record, np.ndarray)
        and record is trajectory.qvel.base
        and record.ndim == 2
        and record.shape[0] == len(t)
        and record.flags.c_contiguous
    )
    with np.errstate(all="ignore"):
        if whole and isinstance(record, np.ndarray):
            sums: tuple[float, ...] = (float(np.sum(record)),)
        else:
            sums = (float(np.sum(trajectory.qpos)), float(np.sum(trajectory.qvel)))
    if not all(math.isfinite(total) for total in sums):
        finite = np.isfinite(trajectory.qpos).all(axis=1) & np.isfinite(trajectory.qvel).all(axis=1)
        if not finite.all():
            candidates.append(int(np.flatnonzero(~finite)[0]))
    return min(candidates) if candidates else None


def check_diverged(trajectory: Trajectory, dt: float, messages: list[str] | None = None) -> None:
    """Raise DivergedError if the run blew up (see module docstring)."""
    index = divergence_step(trajectory)
    flagged = any(("unstable" in m.lower() or "nan" in m.lower()) for m in (messages or []))
    if index is None and not flagged:
        return
    when = trajectory.time[index - 1] + dt if index else float("nan")
    where = f" at t = {when:.6g} s" if index else ""
    raise DivergedError(f"simulation diverged{where} ({trajectory.integrator}, dt = {dt:g} s)")


#: MuJoCo's cap on every |qpos|, |qvel| and |qacc| (mjMAXVAL, 1e10 in SI units): beyond it
#: mj_checkPos/Vel/Acc flag the run and reset it, whatever the timestep or integrator
MAX_VALUE = float(mujoco.mjMAXVAL)


def beyond_mujoco_limits(
    model: mujoco.MjModel,
    qpos: np.ndarray | None = None,
    qvel: np.ndarray | None = None,
    act: np.ndarray | None = None,
    control: np.ndarray | None = None,
) -> str | None:
    """Which part of the initial state is past MAX_VALUE, e.g. 'a position of 1e+300', or None.

    Checks qpos [m or rad], qvel [m/s or rad/s] and the acceleration [m/s^2 or
    rad/s^2] MuJoCo computes there (with the first control row); no timestep can
    run a state MuJoCo itself rejects.
    """
    data = mujoco.MjData(model)
    initial_state(model, qpos, qvel, act, data)
    if model.nu and control is not None:
        data.ctrl[:] = np.atleast_2d(np.asarray(control, float))[0]
    with quiet_mujoco(), np.errstate(all="ignore"):
        mujoco.mj_forward(model, data)
    for what, values in (("position", data.qpos), ("velocity", data.qvel), ("acceleration", data.qacc)):
        bad = ~np.isfinite(values) | (np.abs(values) > MAX_VALUE)
        if bad.any():
            return f"an initial {what} of {float(values[np.flatnonzero(bad)[0]]):.3g}"
    return None


@dataclasses.dataclass
class Setup:
    """Initial state and inputs of one run.

    Attributes
    ----------
    qpos, qvel, act
        initial state (None: the model's rest state).
    control
        (nu,) or (steps, nu) open-loop controls, held over each step.
    controller
        a sampled-data controller in the loop instead of `control` (springlab.sim.controller.Controller; None:
        open loop). Batched runners run such a job on its own (a closed loop cannot be batched).
    """

    qpos: np.ndarray | None = None
    qvel: np.ndarray | None = None
    act: np.ndarray | None = None
    control: np.ndarray | None = None
    controller: Controller | None = None
