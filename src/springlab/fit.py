"""From measurements to a model: identify a scene's parameters from a recorded signal.

`fit(scene, data)` reads a record (springlab.fit_data), decides what may be
fitted (springlab.fit_models), and identifies it with MuJoCo in the loop using
MuJoCo's own system-identification toolbox, `mujoco.sysid`:

* every free name is a `sysid.Parameter` with box bounds;
* the residual is `sysid.build_residual_fn` over one `sysid.ModelSequences`
  (the record): each candidate is compiled from the scene's MJCF (the scene's
  own MjSpec edits), rolled out by `sysid.sysid_rollout` (mujoco.rollout, all
  finite-difference columns in one threaded batch) from the candidate's
  initial state, and compared at the recorded times (`modify_residual`);
* `sysid.optimize` with MuJoCo's Levenberg-Marquardt (`mujoco.minimize`) finds
  the estimate, `sysid.calculate_intervals` its covariance and 95 % intervals
  (Student t on n - p degrees of freedom, noise variance from the residual).

The model is simulated with RK4 on its own even grid (omega dt <= 0.05 on the
fastest mode: relative bias (omega dt)^4 / 120 < 1e-7 in the frequency) and
read at the recorded times by cubic Hermite interpolation of position and
velocity (error (omega dt)^4 / 384), so uneven sampling costs nothing.
Acceleration comes from fourth-order differences of the velocity on the grid.
Derived quantities (omega_n, zeta from k, d, m, or k, d from omega_n, zeta
given m) carry intervals by the delta method. Every estimate is cross-checked
against the closed form (springlab.analytic) fitted independently with scipy.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import logging
import math
import os
import time as _time
from collections.abc import Mapping, Sequence
from typing import Any

import mujoco
import numpy as np

from . import api, fit_data, fit_results, scenes
from .errors import BadInputError, ParameterError, SpringlabError
from .fit_models import ALIASES, FITS, MODAL, SceneFit
from .simulate import quiet_mujoco

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


@dataclasses.dataclass
class FitResult:
    """An identified scene.

    Attributes:
      scene, scenario: what was fitted.
      record: the cleaned record (springlab.fit_data.Record).
      free: fitted names, in order.
      estimates: name -> {'value', 'ci95' [low, high], 'unit'}.
      derived: the same for quantities computed from the estimates.
      correlation: (p, p) correlation matrix of the estimates.
      covariance: (p, p) covariance [units of the names].
      residual_rms: RMS of measured - fitted [signal unit].
      dof: degrees of freedom n - p.
      parameters: the scene's parameters at the estimate (SI).
      fitted: (n,) the fitted signal at the recorded times.
      cross_check: the closed form fitted independently, and how far it is.
      optimizer: status, iterations, rollouts, times.
      verdict: the one-line answer.
      converged: whether the optimizer stopped on a tolerance.
      run: the identified scene's own run (api.Result) or None, and `run_note`.
    """

    scene: str
    scenario: str
    record: fit_data.Record
    free: list[str]
    estimates: dict[str, dict[str, Any]]
    derived: dict[str, dict[str, Any]]
    correlation: np.ndarray
    covariance: np.ndarray
    residual_rms: float
    dof: int
    parameters: dict[str, float]
    fitted: np.ndarray
    cross_check: dict[str, Any]
    optimizer: dict[str, Any]
    verdict: str = ""
    converged: bool = True
    run: Any = None
    run_note: str = ""
    curves: dict[str, Any] = dataclasses.field(default_factory=dict)
    amplitude: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        """fit.json's content (see DESIGN.md, `fit`)."""
        r = self.record
        return {
            "scene": self.scene,
            "scenario": self.scenario,
            "signal": r.name,
            "signal_unit": r.unit,
            "column": r.column,
            "free": self.free,
            "estimates": self.estimates,
            "derived": self.derived,
            "correlation": {a: dict(zip(self.free, row)) for a, row in zip(self.free, self.correlation.tolist())},
            "residual_rms": self.residual_rms,
            "degrees_of_freedom": self.dof,
            "samples": int(r.time.size),
            "rows": r.rows,
            "skipped_nan_rows": r.skipped_nan,
            "dropped_before_start": r.dropped_before_start,
            "time_origin_s": r.origin,
            "time_span_s": [float(r.time[0]), float(r.time[-1])],
            "data_notes": r.notes,
            "parameters": self.parameters,
            "curves": self.curves,
            "cross_check": self.cross_check,
            "optimizer": self.optimizer,
            "converged": self.converged,
            "run_note": self.run_note,
            "verdict": self.verdict,
        }


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


def _canonical(name: str) -> str:
    return ALIASES.get(name, name)


class _Problem:
    """One record against one scene: parameters, the sysid residual, predictions."""

    def __init__(self, how: SceneFit, scenario, base: dict[str, float], record, free, start, modal, force):
        self.how, self.scene, self.scenario = how, scenes.get(how.scene), scenario
        self.base, self.record, self.free, self.modal, self.force = base, record, free, modal, force
        self.start = dict(start)
        self.t = record.model_time
        self.scale = float(np.std(record.values)) or 1.0
        self.rollouts = 0
        self._spec = None
        self.rollout_time = 0.0
        self.set_grid(start)
        # a thread pool costs ~5 ms per rollout call: worth it only for long batches
        self.threads = 2 if self.steps * (len(free) + 1) >= 200_000 and (os.cpu_count() or 1) > 1 else 1

    # -- grid ------------------------------------------------------------------

    def fastest_rate(self, values: dict[str, float]) -> float:
        """Fastest pole |s| [1/s] of the mode at these values (0 for kinematics)."""
        if "omega_n" not in values:
            return 0.0
        params = self.how.scene_params(values, self.base, self.modal)
        m = self.how.mode_mass(params)
        k, d = params[self.how.stiffness], params[self.how.damping]
        omega, zeta = math.sqrt(k / m), d / (2 * math.sqrt(k * m))
        return omega * (zeta + math.sqrt(max(zeta * zeta - 1.0, 0.0))) if zeta > 1 else omega

    def set_grid(self, values: dict[str, float]) -> None:
        """dt [s] and steps of the simulation grid covering the record (and a delay's reach)."""
        span = float(self.t[-1])
        reach = 1.1 * span if "delay" in self.free else span
        rate = self.fastest_rate(values)
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
        values = dict(self.start)
        values.update(zip(self.free, (float(v) for v in np.ravel(vector))))
        return values

    def values_of(self, params) -> dict[str, float]:
        return self.values(np.array([params[n].value[0] for n in self.free]))

    # -- the pieces sysid calls ----------------------------------------------------

    def build_model(self, params, spec=None) -> mujoco.MjModel:
        """Compile the scene for a candidate: its own MjSpec edits, one jointpos sensor for sysid's bookkeeping."""
        scene_params = self.how.scene_params(self.values_of(params), self.base, self.modal)
        return self.compile(scene_params)

    def compile(self, scene_params: dict[str, float]) -> mujoco.MjModel:
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

    def initial(self, model, values):
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

    def rollout(self, *, models, datas, control_signal, initial_states, param_dicts, **mappings):
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

    def modify_residual(self, params, predicted, measured, model, return_pred_all, state=None, **_):
        """sysid's residual hook: the candidate's signal at the recorded times minus the record, scaled."""
        from mujoco import sysid

        values = self.values_of(params)
        y = self.predict(model, values, state)
        residual = (y - self.record.values) / self.scale
        fitted = sysid.TimeSeries(measured.times, y[:, None], measured.signal_mapping)
        return residual, fitted, measured

    def predict(self, model, values, state) -> np.ndarray:
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


def _solve(problem: _Problem, record) -> dict[str, Any]:
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


def _typical(problem: _Problem, name: str) -> float:
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


def _parameter_dict(problem: _Problem):
    from mujoco import sysid

    params = sysid.ParameterDict()
    for name in problem.free:
        low, high = problem.how.bounds(name, problem.start[name], problem.record)
        value = min(max(problem.start[name], low + 1e-3 * (high - low)), high - 1e-3 * (high - low))
        problem.start[name] = value
        params.add(sysid.Parameter(name, nominal=value, min_value=low, max_value=high))
    return params


def _identifiability(problem: _Problem, jacobian: np.ndarray) -> None:
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


def fit(
    scene: str,
    data: str | os.PathLike,
    scenario: str | None = None,
    *,
    map: Mapping[str, str] | Sequence[str] | None = None,  # noqa: A002 - the CLI's --map
    free: Sequence[str] | None = None,
    scale: float = 1.0,
    start: float | None = None,
    degree: int | None = None,
    run_scene: bool = True,
    **parameters: Any,
) -> FitResult:
    """Identify `scene` from the record in `data` (a CSV file).

    Args:
      scene: 'slider', 'car', 'printer_head' or 'kinematics'.
      data: CSV with a header: `time` [s] and one signal `<joint>_pos` [m],
        `<joint>_vel` [m/s] or `<joint>_acc` [m/s^2] (see springlab.fit_data).
      scenario: the scene's scenario the record shows (None: the fit's default for the scene).
      map: file column -> springlab name, e.g. {'t': 'time', 'x_mm': 'slider_pos'}.
      free: names to fit (None: the scene's default; see springlab.fit_models).
      scale: factor [SI per file unit] applied to the signal, e.g. 0.001 for mm.
      start: release time [s]: the record before it is dropped (None: detected).
      degree: kinematics only: the polynomial's degree 0-3 (frees x0, v0, a0, jerk in order).
      run_scene: also run the identified scene (FitResult.run) for trajectory.csv.
      **parameters: fixed values: scene parameters (e.g. mass=2.0 [kg]) and
        x0 [m], v0 [m/s], offset [signal unit], delay [s].

    Returns:
      The FitResult (estimates with 95 % intervals, derived quantities, verdict).

    Raises:
      BadInputError: bad file or names, or a free set the record cannot identify.
    """
    if scene not in FITS:
        raise BadInputError(
            f"scene {scene!r} cannot be fitted; valid: {', '.join(FITS)} (nonlinear has no identification yet)"
        )
    how = FITS[scene]
    scene_obj = scenes.get(scene)
    scenario = how.scenarios[0] if scenario is None else scenario
    if scenario not in how.scenarios:
        valid = ", ".join(how.scenarios)
        if scenario not in scene_obj.scenarios:
            raise BadInputError(f"unknown scenario {scenario!r} of {scene}; a fit takes one of: {valid}")
        raise BadInputError(f"{scene} {scenario} cannot be fitted from a record; a fit takes one of: {valid}")
    chosen = scene_obj.scenario(scenario)
    nuisance = {}
    for name, value in parameters.items():
        if name in ("x0", "v0", "offset", "delay") and name not in scene_obj.parameters:
            try:
                nuisance[name] = float(value)
            except (TypeError, ValueError):
                nuisance[name] = math.nan
            if not math.isfinite(nuisance[name]):
                raise ParameterError(f"{name} must be a finite number, got {value!r}")
    scene_values = {k: v for k, v in parameters.items() if k not in nuisance}
    base = scene_obj.resolve(chosen, scene_values)
    # a fitted delay models the held part before a release itself: keep it in the record
    wants_delay = any("delay" in str(item) for item in (free or ()))
    record = fit_data.load(
        data,
        (how.joint,),
        mapping=fit_data.parse_map(map),
        scale=scale,
        start=start,
        detect_release=not wants_delay,
        signals=how.signals,
    )
    free = _free_names(how, free, degree, record)
    forced = scenario == "step" and base.get("force_amplitude", 0.0) != 0.0
    force = base.get("force_amplitude", 0.0) if forced else 0.0
    how.check_free(free, nuisance, base, forced, record.signal)
    if len(free) + 2 > record.time.size:
        raise BadInputError(
            f"{record.time.size} samples cannot fit {len(free)} parameters; a fit needs at least {len(free) + 2}"
        )
    modal = bool(set(free) & set(MODAL)) or scene == "kinematics"
    fixed = dict(nuisance) | {k: base[k] for k in ("x0", "v0") if k in parameters and k in base}
    if scene != "kinematics":
        # an initial state neither fitted nor given: the first sample, at rest
        if "x0" not in free and "x0" not in fixed:
            fixed["x0"] = float(record.values[0]) if record.signal == "pos" else how.equilibrium(base)
        if "v0" not in free and "v0" not in fixed:
            fixed["v0"] = 0.0
    start_values = _start(how, record, base, fixed, free, force)
    problem = _Problem(how, chosen, base, record, free, start_values, modal, force)
    solved = _solve(problem, record)
    # the grid was set for the start; if the estimate is faster, refine it once
    estimate = problem.values(solved["x"])
    if problem.fastest_rate(estimate) * problem.dt > 1.5 * OMEGA_DT:
        problem.start = dict(estimate)
        problem.set_grid(estimate)
        solved = _solve(problem, record)
    return _finish(problem, solved, run_scene)


def _start(how: SceneFit, record, base, fixed, free, force) -> dict[str, float]:
    """Start values; with a free delay, from the part after the detected release, shifted to it."""
    if "delay" not in free:
        return how.start(record, base, fixed, free, force)
    release = fit_data.find_release(record.time, record.values)
    delay = 0.0 if release is None else release - record.origin
    after = record.time >= record.origin + delay
    shifted = dataclasses.replace(
        record, time=record.time[after], values=record.values[after], origin=record.origin + delay
    )
    values = how.start(shifted, base, fixed, free, force)
    values["delay"] = delay
    return values


def _free_names(how: SceneFit, free, degree, record) -> list[str]:
    if degree is not None:
        if how.scene != "kinematics":
            raise BadInputError("--degree applies to kinematics only (its polynomial); other scenes take --free")
        if not isinstance(degree, int) or not 0 <= degree <= 3:
            raise BadInputError(
                f"--degree must be 0, 1, 2 or 3 (the scene drives up to a constant jerk), got {degree!r}"
            )
        names = ["x0", "v0", "a0", "jerk"][: degree + 1]
        lost = {"vel": 1, "acc": 2}.get(record.signal, 0)
        return names[lost:] if len(names) > lost else names
    if free is None or len(free) == 0:
        names = list(how.default_free)
        if how.scene == "kinematics":
            names = names[{"vel": 1, "acc": 2}.get(record.signal, 0) :]
        return names
    names = []
    for item in free:
        for name in str(item).split(","):
            name = _canonical(name.strip())
            if name and name not in names:
                names.append(name)
    if not names:
        raise BadInputError("--free needs at least one name")
    return names


def _finish(problem: _Problem, solved: dict[str, Any], run_scene: bool) -> FitResult:
    """Intervals, derived quantities, cross-check, verdict and the identified scene's run."""
    from mujoco import sysid

    how, record, free = problem.how, problem.record, problem.free
    x, jacobian = solved["x"], solved["jacobian"]
    _identifiability(problem, jacobian)
    # in parameters scaled to O(1): sysid's zero-eigenvalue threshold is relative, and k ~ 1e6 N/m beside
    # an offset ~ 1e-3 m would otherwise look singular
    scale = np.array(solved["scale"])
    covariance, half = sysid.calculate_intervals(solved["residuals"], jacobian * scale)
    covariance = np.asarray(covariance, float) * np.outer(scale, scale)
    half = np.asarray(half, float) * scale
    n, p = record.time.size, len(free)
    dof = n - p
    residual = np.concatenate(solved["residuals"]) * problem.scale
    fitted = record.values + residual
    values = problem.values(x)
    units = how.units()
    estimates = {}
    for i, name in enumerate(free):
        unit = record.unit if name == "offset" else units[name]
        estimates[name] = {
            "value": float(x[i]),
            "ci95": fit_results.interval(float(x[i]), float(half[i])),
            "unit": unit,
        }
    sd = np.sqrt(np.clip(np.diag(covariance), 1e-300, None))
    correlation = covariance / np.outer(sd, sd)
    quantile = fit_results.t_quantile(dof)
    derived = fit_results.delta_intervals(
        lambda v: fit_results.derived_quantities(how, problem, problem.values(v)), x, covariance, quantile
    )
    same = {"omega_n_rad_s": "omega_n", "damping_ratio": "zeta"}
    derived = {k: v for k, v in derived.items() if k not in free and same.get(k) not in free}
    params = how.scene_params(values, problem.base, problem.modal)
    curves = _curves(problem, x, covariance, quantile) if how.scene == "kinematics" else {}
    cross = fit_results.cross_check(problem, x, half, fitted)
    converged = solved["status"] in ("norm(dx) < tol", "norm(gradient) < tol")
    level = values["offset"] + (how.equilibrium(params) if record.signal == "pos" else 0.0)
    amplitude = float(np.ptp(fitted)) if how.scene == "kinematics" else float(np.max(np.abs(fitted - level)))
    result = FitResult(
        scene=how.scene,
        scenario=problem.scenario.name,
        record=record,
        free=list(free),
        estimates=estimates,
        derived=derived,
        correlation=correlation,
        covariance=covariance,
        residual_rms=float(np.sqrt(np.mean(residual**2))),
        dof=dof,
        parameters=params,
        fitted=fitted,
        cross_check=cross,
        optimizer={
            "method": "mujoco.sysid.optimize (mujoco.minimize Levenberg-Marquardt), MuJoCo RK4 rollouts",
            "status": solved["status"],
            "iterations": solved["iterations"],
            "rollouts": problem.rollouts,
            "rollout_time_s": problem.rollout_time,
            "time_per_rollout_s": problem.rollout_time / max(problem.rollouts, 1),
            "wall_time_s": solved["wall_time_s"],
            "dt": problem.dt,
            "steps": problem.steps,
            "integrator": "rk4",
        },
        converged=converged,
        curves=curves,
        amplitude=amplitude,
    )
    result.verdict = fit_results.verdict(result)
    if run_scene:
        v0 = estimates.get("v0")
        moving = v0 is not None and not v0["ci95"][0] <= 0.0 <= v0["ci95"][1]  # v0 = 0 is not plausible
        result.run, result.run_note = _scene_run(problem, values, params, moving)
    return result


def _curves(problem: _Problem, x, covariance, quantile) -> dict[str, Any]:
    """Kinematics: x(t), v(t), a(t) with 95 % bands on 41 times over the record."""
    t = np.linspace(0.0, float(problem.t[-1]), 41)
    out: dict[str, Any] = {"time_s": (t + problem.record.origin).tolist()}
    for signal in ("pos", "vel", "acc"):

        def curve(vector, signal=signal):
            values = problem.values(vector)
            y = problem.how.closed_form(t, problem.base, values, signal)
            return {str(i): float(v) for i, v in enumerate(y)}

        bands = fit_results.delta_intervals(curve, x, covariance, quantile)
        key = {"pos": "x_m", "vel": "v_m_s", "acc": "a_m_s2"}[signal]
        out[key] = [bands[str(i)]["value"] for i in range(t.size)]
        out[key + "_ci95_halfwidth"] = [bands[str(i)]["ci95"][1] - bands[str(i)]["value"] for i in range(t.size)]
    return out


def _scene_run(problem: _Problem, values: dict[str, float], params: dict[str, float], moving: bool):
    """The identified scene's own run over the record's span, or (None, why not)."""
    how, scene = problem.how, problem.scene
    chosen = problem.scenario
    overrides = {k: v for k, v in params.items() if k in scene.parameters}
    note = ""
    if how.scene == "car":
        g = scene.gravity()
        overrides["push_mass"] = (params["clearance"] - values["x0"]) * params["stiffness"] / g
        overrides.pop("damping_ratio", None)
        if moving:
            note = f"the car scene starts at rest; the fitted v0 = {values['v0']:.3g} m/s is not in its run"
    elif how.scene == "printer_head":
        total = params["carriage_mass"] + params["motor_mass"]
        overrides["deflection"] = -values["x0"] * total / params["motor_mass"]
        if moving:
            note = f"the printer_head scene starts at rest; the fitted v0 = {values['v0']:.3g} m/s is not in its run"
    try:
        run = api.run(how.scene, chosen.name, duration=float(problem.t[-1]), **overrides)
    except SpringlabError as error:
        return None, f"the identified scene could not be run: {error}"
    return run, note


def write(result: FitResult, directory: str | os.PathLike) -> list:
    """Write fit.json and the identified scene's trajectory.csv / summary.json into `directory` (all or none)."""
    from . import outputs

    files = {"fit.json": outputs.dumps(result.as_dict()) + "\n"}
    if result.run is not None:
        files["trajectory.csv"] = outputs.csv_text(result.run.columns())
        files["summary.json"] = outputs.dumps(result.run.summary) + "\n"
    return outputs.write_text_files(directory, files)
