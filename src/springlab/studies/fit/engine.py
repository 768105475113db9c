"""The identification engine of `springlab fit`: a record against a scene, through `mujoco.sysid`.

* every free name is a `sysid.Parameter` with box bounds;
* the residual is `sysid.build_residual_fn` over one `sysid.ModelSequences`
  (the record): each candidate is compiled from the scene's MJCF (the scene's
  own MjSpec edits), rolled out by `sysid.sysid_rollout` (mujoco.rollout, all
  finite-difference columns in one batch) from the candidate's initial state,
  and compared at the recorded times (`modify_residual`);
* `sysid.optimize` with MuJoCo's Levenberg-Marquardt (`mujoco.minimize`) finds
  the estimate; `check_identifiable` refuses a rank-deficient Jacobian. A candidate
  whose model or rollout the fit made lately reuses it (`candidates`): the same numbers.

The model is simulated with RK4 on its own even grid, whose timestep follows from the accuracy the fit
needs, not from the sample rate, and is read at the recorded times by cubic Hermite interpolation of
position and velocity (fourth order, like RK4), so uneven or dense sampling costs nothing (`set_grid`).
Acceleration comes from fourth-order differences of the velocity on the grid.

A long record is fitted on its reduced rows (`Problem.compression`, springlab.studies.fit.reductions.Grouped):
within grid step k the signal at the samples is B_i c_k, the Hermite basis at the sample's place in the step
times the step's four coefficients (the end values plus the offset, and dt times the end slopes; a held sample,
before a fixed delay, reads the held value). The basis depends on the data's times only, so each step's samples
reduce once, before the fit, to at most 5 rows [W | z] (the factor of [B_k | y_k]), with
sum over the step of (B_i c_k - y_i)^2 = |W c_k - z|^2 for every candidate: sysid's residual is W c - z, about
5 rows per grid step instead of every sample, with the per-sample cost, gradient, Gauss-Newton matrix, estimate
and covariance (the residual variance divides by the true n - p; `intervals`, `accuracy`, `convergence`). The
fitted signal at every sample is read from one more rollout at the estimate (`Problem.signal`). Records of at most
reductions.BLOCK samples, fewer than COMPRESS_PER_STEP samples per step, or with a fitted delay (which moves the
samples within the steps) are fitted per sample.

The timestep (`choose_dt`). A model error e at the n samples moves estimate i by at most
sqrt((J^T J)^-1_ii) |e|_2 (the least-squares estimate is linear in the data), that is by at most
|e|_2 / sigma of its standard errors for noise sigma. The grid is therefore fine enough that the bound
|e|_2 <= sqrt(n) max|e| stays below ACCURACY_IN_SE sigma, with max|e| the error bound springlab's
verdict machinery derives for every run (springlab.runs.compare: 2 x the leading-order global error
C h^4 t |A^5 z(t)| of RK4, plus the round-off of the steps) plus the Hermite reading error
h^4 |x''''| / 384 (velocity and acceleration add their finite differences' errors), for the mode at
the start values and sigma estimated from the record (`data.noise_level`). A record too clean for that
(sigma -> 0) takes the exact-record grid |lambda| h = OMEGA_DT, whose frequency bias
(|lambda| h)^4 / 120 = 5e-8 is far below the 1e-6 an exact record is fitted to. The step never leaves
the range where compare's error estimate holds (`compare.estimate_range`), |lambda| h <= MAX_RATE_DT
(the reading's error constants), or span / 200. After the fit, `accuracy` measures the effect itself at
the estimate: the simulated signal against the closed form at every sample (e) moves the estimate by
J^+ e, held against max(ACCURACY_IN_SE standard errors, EXACT_ACCURACY of the name's scale); the fit
refines its grid once where that is not met.
"""

from __future__ import annotations

import contextlib
import dataclasses
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
from springlab.runs import compare
from springlab.scenes.base import Case, Reference, Scenario
from springlab.sim.simulate import quiet_mujoco

from . import candidates, reductions
from .data import Record, noise_level
from .models import FitModel

if TYPE_CHECKING:  # annotations only: mujoco.sysid is imported when a fit runs
    from mujoco import sysid

#: growth of the Levenberg-Marquardt regularizer per rejected step: mujoco.minimize's 10^0.1 spends ~70 rollouts
#: climbing from 1e-6 to 10 once the objective sits on its round-off floor at the optimum
MU_FACTOR = 10**0.5
#: Levenberg-Marquardt iterations at most per optimization
MAX_ITERATIONS = 100
#: |lambda| dt [-] of the exact-record grid on the fastest mode (frequency bias (|lambda| dt)^4 / 120 = 5e-8)
OMEGA_DT = 0.05
#: the simulation may move an estimate by at most this many of its standard errors [-]
ACCURACY_IN_SE = 0.1
#: ... or by this fraction of the name's scale, on records too clean for that [-]
EXACT_ACCURACY = 1e-7
#: largest |lambda| dt [-] of any grid: the Hermite reading's and the differences' error constants hold to it
MAX_RATE_DT = 1.0
#: largest |s| dt [-] of the fastest pole a multi-start grid must keep stable (RK4: 2.785 on the real axis)
STABLE_RATE_DT = 2.5
#: the reading's error of a signal s, h^4 (c4 |s''''| + c5 h |s'''''|), as (c4, c5, power of A whose state row
#: gives s'''', that row): position by cubic Hermite (1/384), velocity with slopes from fourth-order differences,
#: acceleration (a = v') itself from fourth-order differences (one-sided at the ends: h^4 |a''''| / 5)
READING = {"pos": (1 / 384, 0.0, 4, 0), "vel": (1 / 384, 8 / 135, 4, 1), "acc": (1 / 5 + 1 / 384, 8 / 135, 5, 1)}
#: relative singular value of the scaled Jacobian below which parameters are not identifiable
IDENTIFIABLE = 1e-9
#: samples per grid step (on average) from which a long record is fitted on its reduced rows (5 per step at most)
COMPRESS_PER_STEP = 10
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
        #: samples, and the span since the origin [s]: the model's times are read from the record when needed
        #: (`t`, `times`), not held beside it
        self.samples = int(record.time.size)
        self.span = float(record.time[-1] - record.origin)
        #: median spacing of the samples [s]
        self.spacing = float(np.median(np.diff(record.time), overwrite_input=True)) if self.samples > 1 else self.span
        self.scale = float(np.std(record.values)) or 1.0
        self.rollouts = 0
        self._spec: mujoco.MjSpec | None = None
        self.rollout_time = 0.0
        #: name -> (low, high) box bounds held fixed (multi-starts: the first start's); None: around the start
        self.bounds: dict[str, tuple[float, float]] | None = None
        #: noise level [signal unit] the grid is chosen for: the record's (data.noise_level)
        self.noise = noise_level(record.values)
        #: how the grid was chosen (fit.json's `timestep`)
        self.grid: dict[str, Any] = {}
        #: the record reduced to at most 5 rows per grid step (module docstring), or None: fitted per sample
        self.compression: reductions.Grouped | None = None
        self._compressed_delay = 0.0
        #: the latest compiled models and rollouts, and the rollouts' MjData (springlab.studies.fit.candidates)
        self.kept = candidates.Kept()
        self.set_grid(start)
        # a thread pool costs ~5 ms per rollout call: worth it only for long batches
        self.threads = 2 if self.steps * (len(free) + 1) >= 200_000 and (os.cpu_count() or 1) > 1 else 1

    # -- grid ------------------------------------------------------------------

    def fastest_rate(self, values: dict[str, float]) -> float:
        """Fastest pole |s| [1/s] of the motion at these values (0 for a polynomial)."""
        return self.how.fastest_rate(values, self.base, self.modal)

    def set_grid(self, values: dict[str, float], stable_rate: float | None = None, dt: float | None = None) -> None:
        """dt [s] and steps of the simulation grid covering the record (and a delay's reach): `choose_dt` at
        these values, or `dt` itself; never above STABLE_RATE_DT / `stable_rate` [1/s] (multi-starts: a grid
        stable anywhere in the box)."""
        span = self.span
        reach = 1.1 * span if "delay" in self.free else span
        described = dt is None  # choose_dt describes the grid at the dt it chooses
        if dt is None:
            dt, self.grid = choose_dt(self, values)
        if stable_rate is not None and stable_rate > 0 and dt > STABLE_RATE_DT / stable_rate:
            dt, described = STABLE_RATE_DT / stable_rate, False
            self.grid["rule"] = f"{self.grid['rule']}; stable at the fastest pole in the starts' box"
        if not described:
            self.grid.update(_described(self, values, dt))
        self.dt = dt
        self.steps = int(math.ceil(reach / self.dt)) + 3
        if self.steps > 5_000_000:
            rate = self.fastest_rate(values)
            raise BadInputError(
                f"the record spans {span:g} s, {span * rate / (2 * math.pi):.3g} periods of its mode:"
                " too long to simulate for a fit; cut it with --start or a shorter file"
            )
        self.grid.update(dt_s=self.dt, steps=self.steps)
        self.compression = self._compress()

    def _compress(self) -> reductions.Grouped | None:
        """The record's reduced rows on this grid (module docstring), or None where it is fitted per sample."""
        n = self.samples
        if n <= reductions.BLOCK or "delay" in self.free or n < COMPRESS_PER_STEP * (self.steps + 1):
            return None
        delay = float(self.start["delay"])
        self._compressed_delay = delay
        return reductions.Grouped(
            n, lambda index: self._locate(index, delay), 4, lambda index: self.record.values[index]
        )

    def _locate(self, index: np.ndarray, delay: float) -> tuple[np.ndarray, np.ndarray]:
        """(group, Hermite basis (m, 4)) of the samples `index` on the grid: group k + 1 for grid step k (as
        `hermite` places them), 0 for a sample before the delay (basis (1, 0, 0, 0): the held value)."""
        s = self.times(index) - delay
        x = np.clip(s, 0.0, None) / self.dt
        i = np.minimum(np.floor(x).astype(int), self.steps - 1)
        u = x - i
        u2, u3 = u * u, u * u * u
        basis = np.column_stack([2 * u3 - 3 * u2 + 1, u3 - 2 * u2 + u, -2 * u3 + 3 * u2, u3 - u2])
        held = s < 0
        basis[held] = (1.0, 0.0, 0.0, 0.0)
        return np.where(held, 0, i + 1), basis

    @property
    def t(self) -> np.ndarray:
        """(n,) times since the origin [s] of every sample (a new array: `times` reads some)."""
        return self.record.model_time

    def times(self, index: np.ndarray | slice) -> np.ndarray:
        """Times since the origin [s] of the samples `index` (equal to `t[index]`, without holding `t`'s copy)."""
        return self.record.time[index] - self.record.origin

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
        """The candidate's MjModel, set to RK4 at the fit's dt [s] (the latest ones kept: a model depends on dt
        and the scene parameters the scene's edit reads alone)."""

        def compiled(noted: dict[str, float]) -> mujoco.MjModel:
            with quiet_mujoco():
                model = self.spec(noted).compile()
            model.opt.integrator = int(mujoco.mjtIntegrator.mjINT_RK4)
            model.opt.timestep = self.dt
            return model

        return self.kept.model(self.dt, scene_params, compiled)

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

    def initial(
        self, model: mujoco.MjModel, values: dict[str, float], scratch: mujoco.MjData | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(full physics state at t = 0, (steps + 1, nu) controls) of a candidate; `scratch`: an MjData of a model
        of the same sizes to work in (reset first: a reset MjData is a new one, without the ~0.5 ms of making it)."""
        # the candidate's model carries the fit's sensor besides the scene's physics
        case = Case(self.scene, self.scenario, self.how.scene_params(values, self.base, self.modal), model)
        setup = case.setup(self.steps, self.dt)
        qpos, qvel = self.how.initial(case, values["x0"], values["v0"])
        if scratch is None:
            data = mujoco.MjData(model)
        else:
            data = scratch
            mujoco.mj_resetData(model, data)
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
        """sysid's custom rollout: each candidate from its own initial state and controls. A candidate whose
        model, initial state and controls equal a kept rollout's is that rollout (springlab.studies.fit.candidates;
        `rollouts` still counts it: the candidates the optimizer asked for). sysid hands no MjData (`solve` asks
        for none): the fit's own serve every call."""
        from mujoco import sysid

        keys, states, controls = [], [], []
        grid = np.arange(self.steps + 1) * self.dt
        datas = self.kept.datas(models[0], self.threads)
        for model, params in zip(models, param_dicts):
            values = self.values_of(params)
            state, control = self.initial(model, values, datas[0])
            scene_params = self.how.scene_params(values, self.base, self.modal)
            keys.append(candidates.rollout_key(self.dt, self.steps, scene_params, state, control))
            states.append(state)
            controls.append(sysid.TimeSeries(grid, control))
        for data in datas:  # handed to the rollout as new ones (a reset MjData is a new one)
            mujoco.mj_resetData(models[0], data)

        def simulate(new: list[int]) -> Sequence[sysid.SystemTrajectory]:
            start = _time.perf_counter()
            with quiet_mujoco():
                out = sysid.sysid_rollout(
                    models=[models[i] for i in new],
                    datas=datas,
                    control_signal=[controls[i] for i in new],
                    initial_states=[states[i] for i in new],
                    rollout_signal_mapping=mappings.get("rollout_signal_mapping"),
                    rollout_state_mapping=mappings.get("rollout_state_mapping"),
                    ctrl_mapping=mappings.get("ctrl_mapping"),
                )
            self.rollout_time += _time.perf_counter() - start
            return out

        self.rollouts += len(models)
        return self.kept.rollouts(keys, simulate)

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
        """sysid's residual hook: the candidate's signal at the recorded times minus the record, scaled (on a
        compressed record: its reduced rows, W c - z, against the reduced record z that `solve` hands sysid)."""
        from mujoco import sysid

        assert state is not None, "sysid passes every rollout's states as state="
        values = self.values_of(params)
        if self.compression is not None:
            assert values["delay"] == self._compressed_delay, "the reduction was made for this fixed delay"
            y = self.compression.model(self.coefficients(model, values, state))
            residual = (y - self.compression.data) / self.scale
        else:
            y = self.predict(model, values, state)
            residual = (y - self.record.values) / self.scale
        fitted = sysid.TimeSeries(measured.times, y[:, None], measured.signal_mapping)
        return residual, fitted, measured

    def grid_signal(
        self, model: mujoco.MjModel, values: dict[str, float], state: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """(the signal on the grid, its slope, the held value) [signal unit, per s] from a rollout's states
        ((steps, nstate), t = dt on), before the offset."""
        joint = model.joint(self.how.joint)
        q = np.concatenate([[values["x0"]], state[:, 1 + joint.qposadr[0]]])
        v = np.concatenate([[values["v0"]], state[:, 1 + model.nq + joint.dofadr[0]]])
        if self.record.signal == "pos":
            return q, v, values["x0"]
        if self.record.signal == "vel":
            return v, derivative(v, self.dt), 0.0
        a = derivative(v, self.dt)
        return a, derivative(a, self.dt), 0.0

    def predict(self, model: mujoco.MjModel, values: dict[str, float], state: np.ndarray) -> np.ndarray:
        """The signal at the recorded times [signal unit] from a rollout's states ((steps, nstate), t = dt on)."""
        return self.read(self.grid_signal(model, values, state), values, slice(None))

    def read(
        self, grid: tuple[np.ndarray, np.ndarray, float], values: dict[str, float], index: np.ndarray | slice
    ) -> np.ndarray:
        """The signal at the samples `index` [signal unit] from `grid_signal`'s (signal, slope, held value)."""
        y, dy, held = grid
        s = self.times(index) - values["delay"]
        return np.where(s < 0, held, hermite(s, self.dt, y, dy)) + values["offset"]

    def coefficients(self, model: mujoco.MjModel, values: dict[str, float], state: np.ndarray) -> np.ndarray:
        """(steps + 1, 4) the Hermite coefficients of a rollout by group (`_locate`): the held value, then per
        grid step its end values (plus the offset) and dt times its end slopes [signal unit]."""
        y, dy, held = self.grid_signal(model, values, state)
        offset = values["offset"]
        c = np.zeros((self.steps + 1, 4))
        c[0, 0] = held + offset
        c[1:, 0], c[1:, 1] = y[:-1] + offset, self.dt * dy[:-1]
        c[1:, 2], c[1:, 3] = y[1:] + offset, self.dt * dy[1:]
        return c

    def simulate(self, values: dict[str, float]) -> tuple[np.ndarray, np.ndarray, float]:
        """`grid_signal` of one rollout at these values (as sysid's rollout makes it)."""
        from mujoco import rollout

        model = self.compile(self.how.scene_params(values, self.base, self.modal))
        state, control = self.initial(model, values)
        with quiet_mujoco():
            states, _ = rollout.rollout(model, mujoco.MjData(model), state[None], control[None, :-1], nstep=self.steps)
        return self.grid_signal(model, values, states[0])

    def signal(self, values: dict[str, float]) -> np.ndarray:
        """(n,) the model's signal at every recorded time at these values [signal unit]: one rollout, read in
        blocks of samples (the fitted signal of a compressed record)."""
        grid = self.simulate(values)
        out = np.empty(self.samples)
        for start, stop in reductions.blocks(self.samples):
            out[start:stop] = self.read(grid, values, slice(start, stop))
        return out


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
    if problem.compression is not None:  # the reduced record, its rows numbered (module docstring)
        rows = problem.compression.rows
        measured = sysid.TimeSeries(np.arange(rows, dtype=float), problem.compression.data[:, None], mapping)
    else:
        measured = sysid.TimeSeries(record.time, record.values[:, None], mapping)
    with _quiet_sysid(), quiet_mujoco():
        sequence = sysid.ModelSequences("record", spec, "record", state0, sysid.TimeSeries(grid, control0), measured)
    residual_fn = sysid.build_residual_fn(
        models_sequences=[sequence],
        build_model=problem.build_model,
        custom_rollout=problem.rollout,
        modify_residual=problem.modify_residual,
        n_threads=0,  # sysid's MjData: the problem's own (`Problem.kept`)
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
            max_iters=MAX_ITERATIONS,
            gtol=1e-12,
            mu_factor=MU_FACTOR,
            iter_callback=_keep_last_jacobian,
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


def _keep_last_jacobian(trace: list) -> None:
    """mujoco.minimize's log keeps every iteration's residual and Jacobian (n x p floats each, ~500 B per sample
    over a fit); only the last one is read: drop the earlier ones as the optimization goes."""
    if len(trace) > 1 and trace[-2].jacobian is not None:
        trace[-2] = dataclasses.replace(trace[-2], residual=None, jacobian=None)


def _typical(problem: Problem, name: str) -> float:
    """A magnitude for scaling a free name when its start is 0."""
    amplitude = float(np.ptp(problem.record.values)) or 1.0
    span = problem.span
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


def error_bound(problem: Problem, values: dict[str, float], dt: float, roundoff: bool = True) -> float:
    """Bound [signal unit] on the simulated signal's error at the record's times on a grid of `dt` [s] (module
    docstring): compare's run error bound plus the Hermite reading (and the steps' round-off); 0 without a mode."""
    system = problem.how.system(values, problem.base, problem.modal, problem.force)
    if system is None:
        return 0.0
    a, rest = system
    span = problem.span
    times = np.linspace(0.0, span, 2001)
    known = dict(values, offset=0.0, delay=0.0)
    params = problem.how.scene_params(values, problem.base, problem.modal)
    x = problem.how.closed_form(times, params, known, "pos", problem.force) - rest
    v = problem.how.closed_form(times, params, known, "vel", problem.force)
    z = np.column_stack([x, v])
    joint = problem.how.joint
    reference = Reference(pos={joint: x}, vel={joint: v}, system=a, states=z, rows={joint: (0, 1)})
    predicted = compare.predicted_error(reference, "rk4", dt, times)
    rk4 = compare.SAFETY * np.array([predicted[f"{joint}_pos"], predicted[f"{joint}_vel"]])
    signal = problem.record.signal
    simulated = {"pos": rk4[0], "vel": rk4[1], "acc": abs(a[1, 0]) * rk4[0] + abs(a[1, 1]) * rk4[1]}[signal]
    c4, c5, power, row = READING[signal]
    fourth = float(np.max(np.abs(z @ np.linalg.matrix_power(a, power).T)[:, row]))
    fifth = float(np.max(np.abs(z @ np.linalg.matrix_power(a, power + 1).T)[:, row]))
    reading = dt**4 * (c4 * fourth + c5 * dt * fifth)
    size = float(np.max(np.abs(z @ np.linalg.matrix_power(a, power - 4).T)[:, row]))
    return float(simulated + reading + (_roundoff(span, dt, size) if roundoff else 0.0))


def _roundoff(span: float, dt: float, size: float) -> float:
    """compare's round-off allowance [signal unit] of the steps over `span` [s] on a signal of `size`."""
    return compare.ROUNDOFF_PER_STEP * span / dt * size


def choose_dt(problem: Problem, values: dict[str, float], describe: bool = True) -> tuple[float, dict[str, Any]]:
    """The grid's timestep [s] for the fit's accuracy at `values`, and how it was chosen (module docstring), with
    the grid's description at it (`_described`) unless `describe` is False (`Problem.set_grid` describes it)."""
    span = problem.span
    n = problem.samples
    needed = ACCURACY_IN_SE * problem.noise / math.sqrt(n)
    spacing = problem.spacing
    facts: dict[str, Any] = {"integrator": "rk4", "noise": problem.noise, "needed_error": needed}
    facts["median_sample_spacing_s"] = spacing
    system = problem.how.system(values, problem.base, problem.modal, problem.force)
    rate = problem.fastest_rate(values)
    if system is None or rate <= 0:
        dt = span / 200.0
        facts.update(rule="span / 200: the model is a polynomial, which RK4 integrates exactly")
        return dt, facts | (_described(problem, values, dt) if describe else {})
    eigenvalues = np.linalg.eigvals(system[0])
    exact = OMEGA_DT / rate
    # the bound grows as h^4 (leading order): scale it from the exact grid's
    leading = error_bound(problem, values, exact, roundoff=False)
    noisy = exact * (needed / leading) ** 0.25 if needed > 0 and leading > 0 else 0.0
    if noisy > exact:
        dt, rule = noisy, f"error bound sqrt(n) max|e| = {ACCURACY_IN_SE:g} x the noise level"
    else:
        dt, rule = exact, f"|lambda| dt = {OMEGA_DT:g}, the exact-record grid (the noise allows no coarser one)"
    limits = [(MAX_RATE_DT / rate, f"|lambda| dt = {MAX_RATE_DT:g}, the reading's limit"), (span / 200.0, "span / 200")]
    inside = compare.estimate_range(eigenvalues, "rk4", dt, span)
    if not inside.inside:
        limits.append((inside.largest_dt, "the range of compare's error estimate"))
    for limit, why in limits:
        if dt > limit:
            dt, rule = limit, why
    facts["rule"] = rule
    return dt, facts | (_described(problem, values, dt) if describe else {})


def _described(problem: Problem, values: dict[str, float], dt: float) -> dict[str, Any]:
    """A grid of `dt` [s] at `values` in fit.json's `timestep` terms: its error bound [signal unit] (round-off
    alone for a model without a mode), |lambda| dt and compare's estimate range (None without a mode)."""
    span = problem.span
    system = problem.how.system(values, problem.base, problem.modal, problem.force)
    if system is None:
        size = float(np.max(np.abs(problem.record.values))) or 1.0
        return {"error_bound": _roundoff(span, dt, size), "rate_dt": 0.0, "estimate_range": None}
    eigenvalues = np.linalg.eigvals(system[0])
    return {
        "error_bound": error_bound(problem, values, dt),
        "rate_dt": float(np.max(np.abs(eigenvalues))) * dt,
        "estimate_range": compare.estimate_range(eigenvalues, "rk4", dt, span).to_dict(),
    }


def accuracy(problem: Problem, solved: dict[str, Any]) -> dict[str, Any]:
    """The simulation's effect on the estimate, measured at it (module docstring).

    e, the simulated signal against the closed form at every sample, moves the least-squares estimate by
    J^+ e to first order (e is small: first order is all there is); 'ratio' <= 1 when no estimate moves by
    more than max(ACCURACY_IN_SE standard errors, EXACT_ACCURACY x the name's scale). On a compressed record
    e is taken to the reduced rows with the same rotations (reductions.Grouped.reduce), where the reduced
    Jacobian's pseudo-inverse gives the same J^+ e.

    Returns
    -------
    dict
        'error' max|e| [signal unit], 'effect' (J^+ e), 'standard_error', 'allowed' ((p,) [units of the names]),
        'ratio' (largest |effect| / allowed [-]), 'in_standard_errors' (largest |effect| / standard error [-]),
        'noise' (the residual's sigma [signal unit]).
    """
    x = np.asarray(solved["x"], float)
    values = problem.values(x)
    params = problem.how.scene_params(values, problem.base, problem.modal)
    residual = np.concatenate(solved["residuals"])  # scaled: (model - data) / problem.scale
    how, signal = problem.how, problem.record.signal
    if problem.compression is None:
        fitted = problem.record.values + residual * problem.scale
        closed = how.closed_form(problem.t, params, values, signal, problem.force)
        gap = (fitted - closed) / problem.scale
        error = float(np.max(np.abs(gap))) * problem.scale
    else:
        grid = problem.simulate(values)
        largest = [0.0]

        def samples_gap(index: np.ndarray) -> np.ndarray:
            closed = how.closed_form(problem.times(index), params, values, signal, problem.force)
            part = (problem.read(grid, values, index) - closed) / problem.scale
            largest[0] = max(largest[0], float(np.max(np.abs(part))))
            return part

        gap = problem.compression.reduce(samples_gap)
        error = largest[0] * problem.scale
    scale = np.asarray(solved["scale"], float)
    u, sv, vt = np.linalg.svd(np.asarray(solved["jacobian"], float) * scale, full_matrices=False)
    keep = sv > 0
    effect = (vt[keep].T @ ((u[:, keep].T @ gap) / sv[keep])) * scale  # J^+ e in the names' units
    inverse = (vt[keep].T / sv[keep] ** 2) @ vt[keep]  # (J^T J)^-1 in names scaled to O(1)
    n, p = problem.samples, x.size
    sigma = math.sqrt(float(residual @ residual) / max(n - p, 1))
    standard_error = np.sqrt(np.clip(np.diag(inverse), 0.0, None)) * scale * sigma
    allowed = np.maximum(ACCURACY_IN_SE * standard_error, EXACT_ACCURACY * scale)
    size = np.abs(effect)
    return {
        "error": error,
        "effect": effect,
        "standard_error": standard_error,
        "allowed": allowed,
        "ratio": float(np.max(size / allowed)) if p else 0.0,
        "in_standard_errors": float(np.max(size / np.where(standard_error > 0, standard_error, np.inf))) if p else 0.0,
        "noise": sigma * problem.scale,
    }


def residual_rms(problem: Problem, residual: np.ndarray) -> float:
    """RMS [signal unit] of the record minus the model, from sysid's (scaled) residual: per sample, or the
    reduced rows, whose squares sum to the per-sample sum (reductions.Grouped), over the true n samples."""
    if problem.compression is None:
        return float(np.sqrt(np.mean(residual**2))) * problem.scale
    return math.sqrt(float(residual @ residual) / problem.samples) * problem.scale
