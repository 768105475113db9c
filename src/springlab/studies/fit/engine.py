"""The identification engine of `springlab fit`: a record against a scene, through `mujoco.sysid`.

* every free name is a `sysid.Parameter` with box bounds;
* the residual is `sysid.build_residual_fn` over one `sysid.ModelSequences`
  (the record): each candidate is compiled from the scene's MJCF (the scene's
  own MjSpec edits), rolled out by `sysid.sysid_rollout` (mujoco.rollout, all
  finite-difference columns in one batch) from the candidate's initial state,
  and compared at the recorded times (`modify_residual`);
* `sysid.optimize` with MuJoCo's Levenberg-Marquardt (`mujoco.minimize`) finds
  the estimate; `check_identifiable` refuses a rank-deficient Jacobian.

The model is simulated with RK4 on its own even grid (omega dt <= 0.05 on the
fastest mode: relative bias (omega dt)^4 / 120 < 1e-7 in the frequency) and
read at the recorded times by cubic Hermite interpolation of position and
velocity (error (omega dt)^4 / 384), so uneven sampling costs nothing.
Acceleration comes from fourth-order differences of the velocity on the grid.
"""

from __future__ import annotations

import contextlib
import io
import logging
import math
import os
import time as _time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from springlab.errors import BadInputError
from springlab.scenes.base import Scenario
from springlab.sim.simulate import quiet_mujoco

from .data import Record
from .models import FitModel

if TYPE_CHECKING:  # annotations only: mujoco.sysid is imported when a fit runs
    from mujoco import sysid

#: growth of the Levenberg-Marquardt regularizer per rejected step: mujoco.minimize's 10^0.1 spends ~70 rollouts
#: climbing from 1e-6 to 10 once the objective sits on its round-off floor at the optimum
MU_FACTOR = 10**0.5
#: largest (fastest mode's rate x dt) of the fit's grid [-]
OMEGA_DT = 0.05
#: relative singular value of the scaled Jacobian below which parameters are not identifiable
IDENTIFIABLE = 1e-9
_FULL = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)
_STATUS = (
    "factorization failed",
    "insufficient reduction",
    "maximum iterations reached",
    "norm(dx) < tol",
    "norm(gradient) < tol",
)


@contextlib.contextmanager
def _quiet_sysid():
    """sysid logs tables and warnings through absl; springlab's terminal stays clean."""
    logger = logging.getLogger("absl")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)


class Problem:
    """One record against one scene: parameters, the sysid residual, predictions."""

    def __init__(
        self,
        how: FitModel,
        scenario: Scenario,
        base: dict[str, float],
        record: Record,
        free: list[str],
        start: dict[str, float],
        modal: bool,
        force: float,
    ):
        self.how, self.scene, self.scenario = how, how.scene, scenario
        self.base, self.record, self.free, self.modal, self.force = base, record, free, modal, force
        self.start = dict(start)
        self.t = record.model_time
        self.scale = float(np.std(record.values)) or 1.0
        self.rollouts = 0
        self._spec: mujoco.MjSpec | None = None
        self.rollout_time = 0.0
        #: name -> (low, high) box bounds held fixed (multi-starts: the first start's); None: around the start
        self.bounds: dict[str, tuple[float, float]] | None = None
        self.set_grid(start)
        # a thread pool costs ~5 ms per rollout call: worth it only for long batches
        self.threads = 2 if self.steps * (len(free) + 1) >= 200_000 and (os.cpu_count() or 1) > 1 else 1

    # -- grid ------------------------------------------------------------------

    def fastest_rate(self, values: dict[str, float]) -> float:
        """Fastest pole |s| [1/s] of the motion at these values (0 for a polynomial)."""
        return self.how.fastest_rate(values, self.base, self.modal)

    def set_grid(self, values: dict[str, float], rate: float | None = None) -> None:
        """dt [s] and steps of the simulation grid covering the record (and a delay's reach).

        `rate` [1/s] overrides the values' fastest rate (multi-starts: a grid stable over the whole box)."""
        span = float(self.t[-1])
        reach = 1.1 * span if "delay" in self.free else span
        rate = self.fastest_rate(values) if rate is None else rate
        # bounds let omega move 10x: keep even that stable (RK4 limit 2.8), accurate at the start
        self.dt = min(OMEGA_DT / rate if rate > 0 else math.inf, span / 200.0)
        self.steps = int(math.ceil(reach / self.dt)) + 3
        if self.steps > 5_000_000:
            raise BadInputError(
                f"the record spans {span:g} s, {span * rate / (2 * math.pi):.3g} periods of its mode:"
                " too long to simulate for a fit; cut it with --start or a shorter file"
            )

    # -- values ----------------------------------------------------------------

    def values(self, vector: np.ndarray) -> dict[str, float]:
        """Every fit name's value (SI): the start, with the free ones taken from `vector` (in `free` order)."""
        values = dict(self.start)
        values.update(zip(self.free, (float(v) for v in np.ravel(vector))))
        return values

    def values_of(self, params: sysid.ParameterDict) -> dict[str, float]:
        """`values` of a sysid.ParameterDict."""
        return self.values(np.array([params[n].value[0] for n in self.free]))

    # -- the pieces sysid calls ----------------------------------------------------

    def build_model(self, params: sysid.ParameterDict, spec: mujoco.MjSpec | None = None) -> mujoco.MjModel:
        """Compile the scene for a candidate: its own MjSpec edits, one jointpos sensor for sysid's bookkeeping."""
        scene_params = self.how.scene_params(self.values_of(params), self.base, self.modal)
        return self.compile(scene_params)

    def compile(self, scene_params: dict[str, float]) -> mujoco.MjModel:
        """The candidate's MjModel, set to RK4 at the fit's dt [s]."""
        with quiet_mujoco():
            model = self.spec(scene_params).compile()
        model.opt.integrator = int(mujoco.mjtIntegrator.mjINT_RK4)
        model.opt.timestep = self.dt
        return model

    def spec(self, scene_params: dict[str, float]) -> mujoco.MjSpec:
        """The scene's MjSpec with its edits for these parameters and the signal's sensor."""
        if self._spec is None:
            self._spec = self.scene.model_spec()
        spec = self._spec.copy()  # parse the MJCF once per fit, not once per candidate
        self.scene.edit(spec, scene_params, self.scenario)
        spec.add_sensor(
            name="fit_signal",
            type=mujoco.mjtSensor.mjSENS_JOINTPOS,
            objtype=mujoco.mjtObj.mjOBJ_JOINT,
            objname=self.how.joint,
        )
        return spec

    def initial(self, model: mujoco.MjModel, values: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """(full physics state at t = 0, (steps + 1, nu) controls) of a candidate."""
        params = self.how.scene_params(values, self.base, self.modal)
        setup = self.scene.setup(model, params, self.scenario, self.steps, self.dt)
        qpos, qvel = self.how.initial(model, params, values["x0"], values["v0"])
        data = mujoco.MjData(model)
        data.qpos[:], data.qvel[:] = qpos, qvel
        if setup.act is not None:
            data.act[:] = setup.act
        state = np.empty(mujoco.mj_stateSize(model, _FULL))
        mujoco.mj_getState(model, data, state, _FULL)
        control = np.zeros((self.steps + 1, model.nu))
        if setup.control is not None and model.nu:
            rows = np.atleast_2d(np.asarray(setup.control, float))
            control[:] = rows[-1]  # a constant control, or the last row held (sysid drops the final row)
            control[: min(len(rows), self.steps + 1)] = rows[: self.steps + 1]
        return state, control

    def rollout(
        self,
        *,
        models: Sequence[mujoco.MjModel],
        datas: Sequence[mujoco.MjData],
        control_signal: Sequence[sysid.TimeSeries],
        initial_states: Sequence[np.ndarray],
        param_dicts: Sequence[sysid.ParameterDict],
        **mappings: Any,
    ) -> Sequence[sysid.SystemTrajectory]:
        """sysid's custom rollout: each candidate from its own initial state and controls."""
        from mujoco import sysid

        states, controls = [], []
        grid = np.arange(self.steps + 1) * self.dt
        for model, params in zip(models, param_dicts):
            state, control = self.initial(model, self.values_of(params))
            states.append(state)
            controls.append(sysid.TimeSeries(grid, control))
        start = _time.perf_counter()
        with quiet_mujoco():
            out = sysid.sysid_rollout(
                models=list(models),
                datas=datas,
                control_signal=controls,
                initial_states=states,
                rollout_signal_mapping=mappings.get("rollout_signal_mapping"),
                rollout_state_mapping=mappings.get("rollout_state_mapping"),
                ctrl_mapping=mappings.get("ctrl_mapping"),
            )
        self.rollout_time += _time.perf_counter() - start
        self.rollouts += len(models)
        return out

    def modify_residual(
        self,
        params: sysid.ParameterDict,
        predicted: sysid.TimeSeries,
        measured: sysid.TimeSeries,
        model: mujoco.MjModel,
        return_pred_all: bool,
        state: np.ndarray | None = None,
        **_: Any,
    ) -> tuple[np.ndarray, sysid.TimeSeries, sysid.TimeSeries]:
        """sysid's residual hook: the candidate's signal at the recorded times minus the record, scaled."""
        from mujoco import sysid

        assert state is not None, "sysid passes every rollout's states as state="
        values = self.values_of(params)
        y = self.predict(model, values, state)
        residual = (y - self.record.values) / self.scale
        fitted = sysid.TimeSeries(measured.times, y[:, None], measured.signal_mapping)
        return residual, fitted, measured

    def predict(self, model: mujoco.MjModel, values: dict[str, float], state: np.ndarray) -> np.ndarray:
        """The signal at the recorded times [signal unit] from a rollout's states ((steps, nstate), t = dt on)."""
        joint = model.joint(self.how.joint)
        q = np.concatenate([[values["x0"]], state[:, 1 + joint.qposadr[0]]])
        v = np.concatenate([[values["v0"]], state[:, 1 + model.nq + joint.dofadr[0]]])
        s = self.t - values["delay"]
        if self.record.signal == "pos":
            y = hermite(s, self.dt, q, v)
            held = values["x0"]
        elif self.record.signal == "vel":
            y = hermite(s, self.dt, v, derivative(v, self.dt))
            held = 0.0
        else:
            a = derivative(v, self.dt)
            y = hermite(s, self.dt, a, derivative(a, self.dt))
            held = 0.0
        return np.where(s < 0, held, y) + values["offset"]


def hermite(s: np.ndarray, dt: float, y: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """Cubic Hermite interpolation of grid values y (slopes dy) at times s [s] (grid i dt, s >= 0 used)."""
    x = np.clip(s, 0.0, None) / dt
    i = np.minimum(np.floor(x).astype(int), y.size - 2)
    u = x - i
    u2, u3 = u * u, u * u * u
    return (
        (2 * u3 - 3 * u2 + 1) * y[i]
        + (u3 - 2 * u2 + u) * dt * dy[i]
        + (-2 * u3 + 3 * u2) * y[i + 1]
        + (u3 - u2) * dt * dy[i + 1]
    )


def derivative(y: np.ndarray, dt: float) -> np.ndarray:
    """d y / dt on an even grid, fourth-order finite differences (one-sided at the ends)."""
    d = np.empty_like(y)
    d[2:-2] = (y[:-4] - 8 * y[1:-3] + 8 * y[3:-1] - y[4:]) / (12 * dt)
    d[0] = (-25 * y[0] + 48 * y[1] - 36 * y[2] + 16 * y[3] - 3 * y[4]) / (12 * dt)
    d[1] = (-3 * y[0] - 10 * y[1] + 18 * y[2] - 6 * y[3] + y[4]) / (12 * dt)
    d[-1] = (25 * y[-1] - 48 * y[-2] + 36 * y[-3] - 16 * y[-4] + 3 * y[-5]) / (12 * dt)
    d[-2] = (3 * y[-1] + 10 * y[-2] - 18 * y[-3] + 6 * y[-4] - y[-5]) / (12 * dt)
    return d


def solve(problem: Problem, record: Record) -> dict[str, Any]:
    """Run sysid's optimize on the problem; return the estimate, Jacobian, residuals, status and timing."""
    from mujoco import sysid

    spec = problem.spec(problem.how.scene_params(problem.start, problem.base, problem.modal))
    model0 = problem.build_model(_parameter_dict(problem))
    state0, control0 = problem.initial(model0, problem.start)
    grid = np.arange(problem.steps + 1) * problem.dt
    mapping = {"fit_signal": (sysid.SignalType.MjSensor, np.array([0]))}
    measured = sysid.TimeSeries(record.time, record.values[:, None], mapping)
    with _quiet_sysid(), quiet_mujoco():
        sequence = sysid.ModelSequences("record", spec, "record", state0, sysid.TimeSeries(grid, control0), measured)
    residual_fn = sysid.build_residual_fn(
        models_sequences=[sequence],
        build_model=problem.build_model,
        custom_rollout=problem.rollout,
        modify_residual=problem.modify_residual,
        n_threads=problem.threads,
        resample_true=False,
    )
    params = _parameter_dict(problem)
    # x_scale: a parameter's own size, or for the state and offset the motion's (an absolute height of
    # 0.1 m would hide a 4 mm bounce)
    scale = np.array(
        [
            _typical(problem, n)
            if n in ("x0", "v0", "offset", "delay")
            else max(abs(problem.start[n]), _typical(problem, n))
            for n in problem.free
        ]
    )
    log = io.StringIO()
    started = _time.perf_counter()
    with _quiet_sysid():
        optimum, result = sysid.optimize(
            params,
            residual_fn,
            optimizer="mujoco",
            verbose=False,
            x_scale=scale,
            output=log,
            max_iters=100,
            gtol=1e-12,
            mu_factor=MU_FACTOR,
        )
        x = optimum.as_vector()
        residuals, _, _ = residual_fn(x, optimum)
    wall = _time.perf_counter() - started
    text = log.getvalue()
    status = next((s for s in _STATUS if s in text), "unknown")
    iterations = text.count("iter:")
    return {
        "x": x,
        "jacobian": np.asarray(result.jac, float),
        "residuals": residuals,
        "status": status,
        "iterations": iterations,
        "wall_time_s": wall,
        "sysid_params": optimum,
        "residual_fn": residual_fn,
        "scale": scale,
    }


def _typical(problem: Problem, name: str) -> float:
    """A magnitude for scaling a free name when its start is 0."""
    amplitude = float(np.ptp(problem.record.values)) or 1.0
    span = float(problem.t[-1])
    rate = problem.fastest_rate(problem.start) or 1.0 / span
    return {
        "v0": amplitude * rate,
        "delay": span / 100,
        "zeta": 0.1,
        "a0": amplitude / span**2,
        "jerk": amplitude / span**3,
    }.get(name, amplitude)


def _parameter_dict(problem: Problem):
    from mujoco import sysid

    params = sysid.ParameterDict()
    for name in problem.free:
        if problem.bounds is not None:
            low, high = problem.bounds[name]
        else:
            low, high = problem.how.bounds(name, problem.start[name], problem.record)
        value = min(max(problem.start[name], low + 1e-3 * (high - low)), high - 1e-3 * (high - low))
        problem.start[name] = value
        params.add(sysid.Parameter(name, nominal=value, min_value=low, max_value=high))
    return params


def check_identifiable(problem: Problem, jacobian: np.ndarray) -> None:
    """BadInputError naming the combination the record cannot resolve (rank-deficient scaled Jacobian)."""
    norms = np.linalg.norm(jacobian, axis=0)
    if np.any(norms == 0):
        name = problem.free[int(np.flatnonzero(norms == 0)[0])]
        raise BadInputError(f"{name} has no effect on this record: it cannot be fitted from it; fix it with --set")
    _, sv, vt = np.linalg.svd(jacobian / norms, full_matrices=False)
    if sv[-1] < IDENTIFIABLE * sv[0]:
        direction = np.abs(vt[-1])
        names = [problem.free[i] for i in np.argsort(direction)[::-1] if direction[i] > 0.1]
        raise BadInputError(
            f"{', '.join(names)} cannot be told apart from this record (they change it the same way);"
            " fix one of them with --set"
        )
