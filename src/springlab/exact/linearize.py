"""Linearizing any MuJoCo model at an operating point: M, C, K, the continuous-time A, its modes,
and every integrator's one-step map.

All matrices live in MuJoCo's tangent space: the state deviation is
x = (dq, dv, dact) with dq of length nv (a ball or free joint's rotation is a
3-vector, `mj_differentiatePos`), so every square matrix here is
n x n with n = 2 nv + na.

* `linearize`: M = df/da, C = df/dv, K = df/dq of the inverse dynamics
  f(q, v, a) (MuJoCo's `mjd_inverseFD`, actuator forces counted as internal,
  so a position servo shows as stiffness), centred by averaging MuJoCo's
  forward difference with step +h and -h; the continuous-time
  A = [[0, I], [-M^-1 K, -M^-1 C]] (plus the activation rows and columns by
  centred differences of `mj_forward`), its eigenvalues lambda [1/s] and the
  modes they make (`Mode`).
* `OperatingPoint.at(model, qpos=...)` / `operating_point(model, keyframe)`: where to linearize
  (springlab.exact.operating_point; `springlab.exact.model_at_point.ModelAtPoint` holds a model there
  with its linearization, computed once).
* `one_step_map`: Phi(dt) = d x_{n+1} / d x_n of one `mj_step` for any
  integrator: `mjd_transitionFD` (centred) where MuJoCo supports it, centred
  differences of `mj_step` in the tangent space for RK4 (which
  `mjd_transitionFD` refuses).

Finite differences cost accuracy: the derivatives are good to about
sqrt(eps)-to-eps^(2/3) relative, and a double eigenvalue (a free body, an
unsprung direction: a Jordan block) moves by the *square root* of that. So
`Linearization.growth_tolerance` [1/s] is estimated from the model itself (the
centred difference at two steps), and nothing here trusts |mu| <= 1 + 1e-9.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np

from springlab.errors import BadInputError

# where to linearize lives in operating_point.py; the names stay importable from here, as before
from springlab.exact.operating_point import OperatingPoint, operating_point
from springlab.sim.simulate import integrator_id, quiet_mujoco

__all__ = [
    "FD_STEP",
    "INPUT_KINDS",
    "Linearization",
    "Mode",
    "OperatingPoint",
    "input_column",
    "linearize",
    "modes_of",
    "one_step_map",
    "operating_point",
    "sensor_rows",
    "spectral_radius",
    "step_input_column",
]

#: finite-difference step in the tangent space [m, rad, m/s, rad/s or activation units]
FD_STEP = 1e-6
_EPS = float(np.finfo(float).eps)
_INTEGRATION = int(mujoco.mjtState.mjSTATE_INTEGRATION)


def _point_or_default(model: mujoco.MjModel, point: OperatingPoint | None) -> OperatingPoint:
    return operating_point(model, None) if point is None else point


@dataclasses.dataclass(frozen=True)
class Mode:
    """One mode of the continuous-time linearization.

    Attributes
    ----------
    eigenvalue
        lambda [1/s] (for an oscillatory pair, the one with Im > 0).
    kind
        'oscillatory' (complex pair), 'decaying' / 'growing' (real lambda < 0 / > 0),
        or 'rigid' (|lambda| within the growth tolerance of 0: a free or unsprung direction).
    frequency_hz
        natural frequency |lambda| / (2 pi) [Hz] (0 for rigid).
    damping_ratio
        -Re(lambda) / |lambda| [-] (1 for decaying, -1 for growing, None for rigid).
    physically_unstable
        Re(lambda) beyond the growth tolerance: the model's own dynamics grows
        there (an upright pendulum), which no integrator should be blamed for.
    """

    eigenvalue: complex
    kind: str
    frequency_hz: float
    damping_ratio: float | None
    physically_unstable: bool

    @property
    def rate_rad_s(self) -> float:
        """|lambda| [rad/s]: what a timestep must resolve."""
        return abs(self.eigenvalue)

    def to_dict(self) -> dict[str, Any]:
        """{"frequency_hz", "damping_ratio", "physically_unstable", "kind", "eigenvalue": [re, im] [1/s]}."""
        return {
            "frequency_hz": float(self.frequency_hz),
            "damping_ratio": None if self.damping_ratio is None else float(self.damping_ratio),
            "physically_unstable": bool(self.physically_unstable),
            "kind": self.kind,
            "eigenvalue": [float(self.eigenvalue.real), float(self.eigenvalue.imag)],
        }


def modes_of(eigenvalues: Sequence[complex] | np.ndarray, growth_tolerance: float) -> list[Mode]:
    """Modes [fastest first] from the eigenvalues [1/s] of a real continuous-time A.

    Complex pairs become one oscillatory mode; real eigenvalues one mode each.
    `growth_tolerance` [1/s]: |lambda| below it is rigid, Re(lambda) above it is growth.
    """
    modes = []
    for lam in np.asarray(eigenvalues, complex):
        size = abs(lam)
        if size <= growth_tolerance:
            modes.append(Mode(complex(lam), "rigid", 0.0, None, False))
            continue
        if abs(lam.imag) > growth_tolerance:
            if lam.imag < 0:
                continue  # its conjugate carries the mode
            kind = "oscillatory"
            zeta = -lam.real / size
        else:
            lam = complex(lam.real, 0.0)
            kind = "decaying" if lam.real < 0 else "growing"
            zeta = 1.0 if lam.real < 0 else -1.0
        modes.append(Mode(complex(lam), kind, size / (2 * math.pi), float(zeta), bool(lam.real > growth_tolerance)))
    modes.sort(key=lambda mode: -mode.rate_rad_s)
    return modes


@dataclasses.dataclass
class Linearization:
    """A model linearized at an operating point (tangent-space state x = (dq, dv, dact), n = 2 nv + na).

    Attributes
    ----------
    point
        the operating point.
    M
        (nv, nv) mass matrix df/da [kg, kg m^2].
    C
        (nv, nv) damping df/dv [N s/m, N m s/rad] (joint damping, actuator gains on velocity, contacts).
    K
        (nv, nv) stiffness df/dq [N/m, N m/rad] (springs, gravity's restoring or toppling term, servos,
        contacts).
    A
        (n, n) continuous-time system matrix, dx/dt = A x [1/s and the units above].
    eigenvalues
        (n,) eigenvalues of A [1/s].
    modes
        the modes, fastest first (`modes_of`).
    fd_error
        estimated absolute error of the entries of A from finite differences [1/s^2 in the K block].
    growth_tolerance
        [1/s] eigenvalue moves the finite differences can cause (sqrt of fd_error for a
        Jordan block, plus sqrt(eps) |A|); growth below it is not called physical.
    """

    point: OperatingPoint
    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    A: np.ndarray
    eigenvalues: np.ndarray
    modes: list[Mode]
    fd_error: float
    growth_tolerance: float

    @property
    def fastest(self) -> Mode | None:
        """The mode with the largest |lambda| that is not rigid, or None (a model with nothing but rigid motion)."""
        return next((mode for mode in self.modes if mode.kind != "rigid"), None)

    @property
    def physically_unstable(self) -> bool:
        """Whether any mode grows in the continuous dynamics itself."""
        return any(mode.physically_unstable for mode in self.modes)

    @property
    def max_growth_rate(self) -> float:
        """max Re(lambda) over the physically unstable modes [1/s], 0 if none."""
        return max((mode.eigenvalue.real for mode in self.modes if mode.physically_unstable), default=0.0)

    @functools.cached_property
    def eigenvectors(self) -> tuple[np.ndarray, np.ndarray]:
        """(values (n,) [1/s], vectors (n, n)) of A by `numpy.linalg.eig`, computed once: the mode shapes and
        the basis that sorts a one-step map's eigenvalues by mode."""
        return np.linalg.eig(self.A)

    def exact_map(self, dt: float) -> np.ndarray:
        """expm(A dt): the exact one-step map of the linearization over dt [s], (n, n)."""
        from scipy.linalg import expm  # scipy is a dependency; imported here to keep import time low

        return expm(self.A * dt)


def _continuous_model(model: mujoco.MjModel) -> mujoco.MjModel:
    """A copy of `model` whose forward pass computes the continuous-time dynamics.

    The 'discrete' integrator folds dt^2 K into qacc itself and mj_inverse would then invert
    that; Euler's forward pass is the plain continuous one (its implicit damping is applied
    after the forward pass, in the step).
    """
    work = copy.copy(model)
    work.opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)
    return work


def _inverse_jacobians(model: mujoco.MjModel, data: mujoco.MjData, step: float) -> tuple[np.ndarray, ...]:
    """Centred (M, C, K) [SI] from mjd_inverseFD's forward differences at +step and -step."""
    nv = model.nv
    out = []
    for h in (step, -step):
        dfdq, dfdv, dfda = (np.zeros((nv, nv)) for _ in range(3))
        mujoco.mjd_inverseFD(model, data, h, 1, dfdq, dfdv, dfda, None, None, None, None)
        out.append((dfda.T, dfdv.T, dfdq.T))
    return tuple(0.5 * (a + b) for a, b in zip(*out))


def _forward_rates(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """(qacc, act_dot) after mj_forward at data's state."""
    mujoco.mj_forward(model, data)
    return np.concatenate([data.qacc, data.act_dot])


def _nudge(model: mujoco.MjModel, data: mujoco.MjData, j: int, delta: float) -> None:
    """Move data's state by `delta` along tangent-space coordinate j of (dq, dv, dact).

    Positions move through mj_integratePos, so quaternion joints stay unit length; `delta` is in the
    coordinate's unit (rad or m for dq, rad/s or m/s for dv, the actuator's unit for dact).
    """
    nv = model.nv
    if j < nv:
        direction = np.zeros(nv)
        direction[j] = delta
        mujoco.mj_integratePos(model, data.qpos, direction, 1.0)
    elif j < 2 * nv:
        data.qvel[j - nv] += delta
    else:
        data.act[j - 2 * nv] += delta


def _activation_blocks(model: mujoco.MjModel, data: mujoco.MjData, point: OperatingPoint, step: float) -> np.ndarray:
    """Centred d(qacc, act_dot)/d(dq, dv, dact), (nv + na, n), by mj_forward in the tangent space."""
    nv, na = model.nv, model.na
    n = 2 * nv + na
    jac = np.empty((nv + na, n))
    for j in range(n):
        sides = []
        for sign in (1.0, -1.0):
            point.load(model, data)
            _nudge(model, data, j, sign * step)
            sides.append(_forward_rates(model, data))
        jac[:, j] = (sides[0] - sides[1]) / (2 * step)
    return jac


def _system_matrix(model, data, point, step) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    point.load(model, data)
    mujoco.mj_forward(model, data)
    mass, damping, stiffness = _inverse_jacobians(model, data, step)
    nv, na = model.nv, model.na
    n = 2 * nv + na
    a = np.zeros((n, n))
    a[:nv, nv : 2 * nv] = np.eye(nv)
    try:
        a[nv : 2 * nv, :nv] = -np.linalg.solve(mass, stiffness)
        a[nv : 2 * nv, nv : 2 * nv] = -np.linalg.solve(mass, damping)
    except np.linalg.LinAlgError:
        raise BadInputError(
            "the model's mass matrix is singular at the operating point; add mass or armature"
        ) from None
    if na:
        blocks = _activation_blocks(model, data, point, step)
        a[nv : 2 * nv, 2 * nv :] = blocks[:nv, 2 * nv :]
        a[2 * nv :, :] = blocks[nv:, :]
    return mass, damping, stiffness, a


def linearize(model: mujoco.MjModel, point: OperatingPoint | None = None, *, step: float = FD_STEP) -> Linearization:
    """Linearize `model`'s continuous-time dynamics at `point` (default: `operating_point(model)`).

    M, C, K come from MuJoCo's `mjd_inverseFD` (centred: the mean of its forward differences with
    steps +step and -step), A from them (plus centred differences of `mj_forward` for actuator
    activations). The operating point need not be an equilibrium: A is then the linearization of
    the flow along the motion through it. `model` is not modified.

    Parameters
    ----------
    model
        any compiled model.
    point
        where to linearize.
    step
        finite-difference step in the tangent space [m, rad, m/s, rad/s].

    Returns
    -------
    The Linearization: M, C, K [SI], A [1/s], eigenvalues [1/s], modes (frequency [Hz], damping
    ratio, physically unstable) and the finite-difference error estimates.
    """
    point = _point_or_default(model, point)
    work = _continuous_model(model)
    data = mujoco.MjData(work)
    with quiet_mujoco():
        mass, damping, stiffness, a = _system_matrix(work, data, point, step)
        *_, a_coarse = _system_matrix(work, data, point, 2 * step)
    eigenvalues = np.linalg.eigvals(a)
    # centred differences err like step^2 (truncation) or eps/step (round-off); the two-step
    # difference bounds the finer one's error. A Jordan block's double eigenvalue moves by the
    # square root of an entry's error, an ordinary eigenvalue by sqrt(eps) |A| at worst.
    fd_error = float(np.max(np.abs(a - a_coarse))) if a.size else 0.0
    scale = float(np.max(np.abs(eigenvalues))) if a.size else 0.0
    growth_tolerance = 10.0 * math.sqrt(fd_error + _EPS * scale**2) + math.sqrt(_EPS) * scale
    return Linearization(
        point=point,
        M=mass,
        C=damping,
        K=stiffness,
        A=a,
        eigenvalues=eigenvalues,
        modes=modes_of(eigenvalues, growth_tolerance),
        fd_error=fd_error,
        growth_tolerance=growth_tolerance,
    )


def _rk4_map(model: mujoco.MjModel, data: mujoco.MjData, point: OperatingPoint, step: float) -> np.ndarray:
    """Centred differences of mj_step in the tangent space: (n, n)."""
    nv, na = model.nv, model.na
    n = 2 * nv + na
    point.load(model, data)
    mujoco.mj_forward(model, data)
    data.qacc_warmstart[:] = data.qacc
    saved = np.empty(mujoco.mj_stateSize(model, _INTEGRATION))
    mujoco.mj_getState(model, data, saved, _INTEGRATION)
    phi = np.empty((n, n))
    after: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # (qpos, qvel, act) after the + and - nudge
    for j in range(n):
        after.clear()
        for sign in (1.0, -1.0):
            mujoco.mj_setState(model, data, saved, _INTEGRATION)
            _nudge(model, data, j, sign * step)
            mujoco.mj_step(model, data)
            after.append((data.qpos.copy(), data.qvel.copy(), data.act.copy()))
        (q_plus, v_plus, a_plus), (q_minus, v_minus, a_minus) = after
        dq = np.zeros(nv)
        mujoco.mj_differentiatePos(model, dq, 2 * step, q_minus, q_plus)
        phi[:nv, j] = dq
        phi[nv : 2 * nv, j] = (v_plus - v_minus) / (2 * step)
        phi[2 * nv :, j] = (a_plus - a_minus) / (2 * step)
    return phi


def one_step_map(
    model: mujoco.MjModel,
    integrator: str,
    dt: float,
    point: OperatingPoint | None = None,
    *,
    step: float = FD_STEP,
    data: mujoco.MjData | None = None,
    copy_model: bool = True,
) -> np.ndarray:
    """MuJoCo's one-step map Phi = d x_{n+1} / d x_n of `integrator` at timestep `dt` [s], (n, n).

    x = (dq, dv, dact) in the tangent space (n = 2 nv + na); for a linear model x_{n+1} = Phi x_n
    exactly, so |eigenvalues| > 1 of Phi are growth per step [-]. Centred differences with step
    `step`: `mjd_transitionFD` for euler, implicit, implicitfast and discrete; `mj_step` differenced
    in the tangent space (`mj_integratePos` / `mj_differentiatePos`) for rk4. `model` is not
    modified (a copy takes the integrator and timestep; copy_model=False sets them on `model` itself,
    for loops that own a scratch copy: copying a large model costs more than its map); `data` is
    optional scratch.

    Raises
    ------
    UnknownNameError
        unknown integrator.
    BadInputError
        dt not a finite number > 0.
    """
    kind = integrator_id(integrator)
    point = _point_or_default(model, point)
    work = copy.copy(model) if copy_model else model
    return map_on(work, kind, dt, point, step=step, data=data)


def map_on(
    work: mujoco.MjModel,
    kind: int,
    dt: float,
    point: OperatingPoint,
    *,
    step: float = FD_STEP,
    data: mujoco.MjData | None = None,
) -> np.ndarray:
    """`one_step_map` on `work` itself (it takes MuJoCo's integrator `kind` and the timestep `dt` [s]) at
    `point`: for a caller that owns a scratch copy and has resolved the integrator's name once
    (`springlab.exact.model_at_point.ModelAtPoint.one_step_map`). `data`: optional scratch for `work`.

    Raises
    ------
    BadInputError
        dt not a finite number > 0.
    """
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise BadInputError(f"dt must be a finite number > 0 s, got {dt!r}")
    work.opt.integrator = kind
    work.opt.timestep = dt
    data = mujoco.MjData(work) if data is None else data
    n = 2 * work.nv + work.na
    with quiet_mujoco():
        if kind == int(mujoco.mjtIntegrator.mjINT_RK4):
            return _rk4_map(work, data, point, step)
        point.load(work, data)
        mujoco.mj_forward(work, data)
        data.qacc_warmstart[:] = data.qacc
        phi = np.zeros((n, n))
        mujoco.mjd_transitionFD(work, data, step, 1, phi, None, None, None)
    return phi


def spectral_radius(matrix: np.ndarray) -> float:
    """max |eigenvalue| of a square matrix [-] (0 for an empty one)."""
    return float(np.max(np.abs(np.linalg.eigvals(matrix)))) if matrix.size else 0.0


# -- inputs: a control or a generalized force, and how it enters the dynamics and one step --------------

#: input kinds: an actuator's control (held over a step, as MuJoCo applies it) or a generalized force
#: on one degree of freedom (`qfrc_applied`, also held)
INPUT_KINDS = ("ctrl", "force")


def _apply_input(data: mujoco.MjData, kind: str, index: int, delta: float) -> None:
    if kind == "ctrl":
        data.ctrl[index] += delta
    elif kind == "force":
        data.qfrc_applied[index] += delta
    else:
        raise ValueError(f"input kind is one of {INPUT_KINDS}, got {kind!r}")


def input_column(
    model: mujoco.MjModel, kind: str, index: int, point: OperatingPoint | None = None, *, step: float = FD_STEP
) -> np.ndarray:
    """b = d(dx/dt)/du [1/s per input unit], (n,): how one input enters the continuous-time dynamics.

    Centred differences of `mj_forward` (the continuous forward pass, as in `linearize`) in the input
    `kind` ('ctrl': control `index`; 'force': `qfrc_applied` of dof `index`) at `point`; the position
    rows are 0 (an input acts through forces). `model` is not modified.
    """
    point = _point_or_default(model, point)
    work = _continuous_model(model)
    data = mujoco.MjData(work)
    sides = []
    with quiet_mujoco():
        for sign in (1.0, -1.0):
            point.load(work, data)
            _apply_input(data, kind, index, sign * step)
            sides.append(_forward_rates(work, data))
    column = np.zeros(2 * model.nv + model.na)
    column[model.nv :] = (sides[0] - sides[1]) / (2 * step)
    return column


def step_input_column(
    model: mujoco.MjModel,
    integrator: str,
    kind: str,
    index: int,
    dt: float,
    point: OperatingPoint | None = None,
    *,
    step: float = FD_STEP,
) -> np.ndarray:
    """gamma = d x_{n+1} / d u [per input unit], (n,): one `mj_step` of `integrator` at `dt` [s] with the
    input held over the step (MuJoCo's zero-order hold), beside `one_step_map`'s Phi.

    Centred differences of `mj_step` in the tangent space (positions through `mj_differentiatePos`), for
    every integrator alike. `model` is not modified.
    """
    point = _point_or_default(model, point)
    work = copy.copy(model)
    work.opt.integrator = integrator_id(integrator)
    work.opt.timestep = dt
    data = mujoco.MjData(work)
    nv = work.nv
    after = []
    with quiet_mujoco():
        for sign in (1.0, -1.0):
            point.load(work, data)
            mujoco.mj_forward(work, data)
            data.qacc_warmstart[:] = data.qacc
            _apply_input(data, kind, index, sign * step)
            mujoco.mj_step(work, data)
            after.append((data.qpos.copy(), data.qvel.copy(), data.act.copy()))
    (q_plus, v_plus, a_plus), (q_minus, v_minus, a_minus) = after
    dq = np.zeros(nv)
    mujoco.mj_differentiatePos(work, dq, 2 * step, q_minus, q_plus)
    return np.concatenate([dq, (v_plus - v_minus) / (2 * step), (a_plus - a_minus) / (2 * step)])


# -- responses: a sensor's rows, as MuJoCo's step computes it ----------------------------------------------------


def sensor_rows(
    model: mujoco.MjModel,
    kind: str,
    index: int,
    point: OperatingPoint | None = None,
    *,
    integrator: str | None = None,
    dt: float | None = None,
    step: float = FD_STEP,
) -> tuple[np.ndarray, np.ndarray]:
    """(C, d): d(sensordata) = C dx + d du, (nsensordata, n) and (nsensordata,), at `point`.

    The sensors of one `mj_step`, which computes them at the step's start (x_k, u_k): C and, for a control
    input, d from MuJoCo's `mjd_transitionFD` (centred, its C and D); for a generalized force ('force', dof
    `index`) d by centred differences of `mj_forward`'s sensordata in `qfrc_applied`. `integrator` None: the
    continuous forward pass (as `linearize`; euler's forward pass is the continuous one); else that integrator
    at `dt` [s] ('discrete' reports its finite-difference acceleration to acceleration-stage sensors; rk4,
    which `mjd_transitionFD` refuses, evaluates its sensors in the continuous forward pass at the step's start,
    so it takes the continuous rows). `model` is not modified.
    """
    point = _point_or_default(model, point)
    if integrator is None or integrator == "rk4":
        work = _continuous_model(model)
    else:
        work = copy.copy(model)
        work.opt.integrator = integrator_id(integrator)
        if dt is not None:
            work.opt.timestep = dt
    data = mujoco.MjData(work)
    n = 2 * work.nv + work.na
    rows = np.zeros((work.nsensordata, n))
    controls = np.zeros((work.nsensordata, work.nu))
    with quiet_mujoco():
        point.load(work, data)
        mujoco.mj_forward(work, data)
        data.qacc_warmstart[:] = data.qacc
        mujoco.mjd_transitionFD(work, data, step, 1, None, None, rows, controls)
        if kind == "ctrl":
            return rows, controls[:, index].copy()
        sides = []
        for sign in (1.0, -1.0):
            point.load(work, data)
            _apply_input(data, kind, index, sign * step)
            mujoco.mj_forward(work, data)
            sides.append(data.sensordata.copy())
    return rows, (sides[0] - sides[1]) / (2 * step)
