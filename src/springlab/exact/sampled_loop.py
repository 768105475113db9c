"""Sampled-data feedback, exact: a plant held between samples, a PID difference equation, the closed loop.

Plant. x' = A x + B u with u held constant over each controller period T [s] (zero-order hold): over one
period the exact map is x_{k+1} = Phi x_k + Gamma u_k with Phi = e^{A T} and Gamma = int_0^T e^{A tau} d tau B,
both read off one matrix exponential of the augmented matrix [[A, B], [0, 0]] T (no inverse of A: the
printer head's rigid-body mode makes A singular). The measurement is y_k = C x_k, taken at the sample.

Controller, the difference equation a firmware runs at each sample k (no computation delay: u_k is applied
from t_k to t_{k+1}):

    e_k = r_k - y_k
    I_k = I_{k-1} + T e_k                                      integral: rectangle rule including the current error
    u_k = F_k + kp e_k + kd (v_k - (y_k - y_{k-1}) / T) + ki I_k   derivative: backward difference of y

with y_{-1} = y_0 (the first difference is 0). The derivative acts on the measurement, not on the error, so a
step of the reference does not kick the force; a reference that moves (a planner's path) brings its own rate
v_k and force F_k, fed forward (`PidLaw`, which may also clip u_k to the motor's limit). For a reference that
stands still (v = F = 0) the law is the classic one, and `closed_loop`, `step_response` and the margins
describe it. From -y to u it is K(z) = kp + kd (z - 1) / (T z) + ki T z / (z - 1), and the loop transfer is
L(z) = K(z) P(z) with P(z) = C (z I - Phi)^-1 Gamma; the closed loop's characteristic equation 1 + L(z) = 0 is
the state-space closed loop's (`closed_loop`) eigenvalue problem.

Gain margin: the factor g by which kp, kd and ki together can grow before a closed-loop pole leaves the unit
circle (`critical_gain`, by bisection on the spectral radius, to 1e-12 relative), cross-checked by
python-control's `stability_margins` of L (`margins`).

Units: T [s], kp [N/m], kd [N s/m], ki [N/(m s)], positions [m], forces [N].
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

if TYPE_CHECKING:
    import control

__all__ = [
    "Pid",
    "PidLaw",
    "closed_loop",
    "critical_gain",
    "held_run",
    "held_open_run",
    "held_run_error",
    "loop_response",
    "loop_transfer",
    "margins",
    "spectral_radius",
    "step_response",
    "zoh",
]


def zoh(a: np.ndarray, b: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray]:
    """(Phi, Gamma): the exact one-period map of x' = A x + B u with u held, from one augmented exponential.

    Parameters
    ----------
    a
        State matrix A [1/s], (n, n).
    b
        Input matrix B [state units / (input units s)], (n, m).
    period
        Hold period T [s], > 0.
    """
    a, b = np.atleast_2d(np.asarray(a, dtype=float)), np.asarray(b, dtype=float).reshape(len(a), -1)
    n, m = b.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n], block[:n, n:] = a * period, b * period
    exponential = scipy.linalg.expm(block)
    return exponential[:n, :n], exponential[:n, n:]


@dataclasses.dataclass(frozen=True)
class Pid:
    """The sampled PID law of the module docstring.

    Attributes
    ----------
    kp
        Proportional gain [N/m], >= 0.
    kd
        Derivative gain [N s/m], >= 0 (on the measurement, backward difference).
    ki
        Integral gain [N/(m s)], >= 0 (rectangle rule).
    period
        Controller period T [s], > 0.
    """

    kp: float
    kd: float
    ki: float
    period: float

    def __post_init__(self) -> None:
        for name in ("kp", "kd", "ki"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if not (math.isfinite(self.period) and self.period > 0):
            raise ValueError(f"controller period must be > 0 s, got {self.period!r}")

    def scaled(self, gain: float) -> Pid:
        """The same law with kp, kd and ki multiplied by `gain` [-]."""
        return Pid(self.kp * gain, self.kd * gain, self.ki * gain, self.period)

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float]:
        """The law as a state-space system in its state w_k = (y_{k-1}, I_{k-1}), or (y_{k-1}) when ki = 0.

        Returns
        -------
        tuple
            (F, G, R, H, J, L): w_{k+1} = F w_k + G y_k + R r_k and u_k = H w_k + J y_k + L r_k, F (nw, nw);
            G, R, H (nw,); J, L floats. Without an integral term its state is left out (it would be an
            uncontrolled eigenvalue 1 of the closed loop).
        """
        t = self.period
        j = -self.kp - self.kd / t - self.ki * t
        reference_gain = self.kp + self.ki * t
        if self.ki == 0:
            return np.zeros((1, 1)), np.array([1.0]), np.array([0.0]), np.array([self.kd / t]), j, reference_gain
        f = np.array([[0.0, 0.0], [0.0, 1.0]])
        return f, np.array([1.0, -t]), np.array([0.0, t]), np.array([self.kd / t, self.ki]), j, reference_gain

    def transfer(self) -> control.TransferFunction:
        """K(z) [N/m] from -y to u: kp + kd (z - 1) / (T z) + ki T z / (z - 1) (sampled at T)."""
        import control  # here: python-control loads scipy.optimize, start-up time for every command

        t = self.period
        z = control.TransferFunction([1.0, 0.0], [1.0], t)
        law = self.kp + self.kd * (z - 1) / (t * z)
        return law + self.ki * t * z / (z - 1) if self.ki > 0 else law


class PidLaw:
    """The PID difference equation run sample by sample on measurements (a MuJoCo loop's controller).

    `update(y, r, feedforward, rate)` takes the measurement y_k [m], the reference r_k [m], the force F_k [N]
    and the reference's rate v_k [m/s] fed forward, and returns u_k [N], the module docstring's law, clipped to
    +-`limit` [N] (the motor's force limit, as MuJoCo's ctrlrange clips; no anti-windup: the integral keeps
    integrating the error). The first call takes y_{-1} = y_0. `saturated` says whether the last update was
    clipped.
    """

    def __init__(self, pid: Pid, limit: float = math.inf) -> None:
        self.pid = pid
        self.limit = limit
        self.previous: float | None = None
        self.integral = 0.0
        self.saturated = False

    def update(self, measurement: float, reference: float, feedforward: float = 0.0, rate: float = 0.0) -> float:
        """u_k [N] of y_k [m], r_k [m], F_k [N] and v_k [m/s] (class docstring)."""
        pid = self.pid
        previous = measurement if self.previous is None else self.previous
        error = reference - measurement
        self.integral += pid.period * error
        self.previous = measurement
        velocity = (measurement - previous) / pid.period
        force = feedforward + pid.kp * error + pid.kd * (rate - velocity) + pid.ki * self.integral
        self.saturated = abs(force) > self.limit
        # np.clip's selection in floats (a numpy call per sample cost more than the law itself)
        return float(min(max(force, -self.limit), self.limit))


def closed_loop(
    phi: np.ndarray, gamma: np.ndarray, output: np.ndarray, pid: Pid
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """The sampled-data closed loop in z_k = (x_k, w_k), w the law's state (`Pid.matrices`).

    Returns
    -------
    tuple
        (A_cl, B_cl, C_u, D_u): z_{k+1} = A_cl z_k + B_cl r_k and u_k = C_u z_k + D_u r_k [N]; y_k = output x_k.
    """
    c = np.asarray(output, dtype=float).reshape(-1)
    g_col = np.asarray(gamma, dtype=float).reshape(-1)
    f, g, r, h, j, r_gain = pid.matrices()
    n, nw = len(c), len(g)
    c_u = np.concatenate([j * c, h])
    a_cl = np.zeros((n + nw, n + nw))
    a_cl[:n, :n] = phi
    a_cl[:n, :] += np.outer(g_col, c_u)
    a_cl[n:, :n] = np.outer(g, c)
    a_cl[n:, n:] = f
    b_cl = np.concatenate([g_col * r_gain, r])
    return a_cl, b_cl, c_u, r_gain


def step_response(
    phi: np.ndarray, gamma: np.ndarray, output: np.ndarray, pid: Pid, reference: float, samples: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The closed loop from rest with the reference stepping to `reference` [m] at sample 0.

    Returns
    -------
    tuple
        (y [m] at samples 0..samples, u [N] held over samples 0..samples-1, states x at samples 0..samples).
    """
    a_cl, b_cl, c_u, d_u = closed_loop(phi, gamma, output, pid)
    c = np.asarray(output, dtype=float).reshape(-1)
    n = len(c)
    z = np.zeros(len(b_cl))
    states, forces = [z[:n].copy()], []
    for _ in range(samples):
        forces.append(float(c_u @ z + d_u * reference))
        z = a_cl @ z + b_cl * reference
        states.append(z[:n].copy())
    x = np.array(states)
    return x @ c, np.array(forces), x


def loop_transfer(phi: np.ndarray, gamma: np.ndarray, output: np.ndarray, pid: Pid) -> control.TransferFunction:
    """L(z) = K(z) P(z) [-], the loop broken at the plant's input (module docstring)."""
    import control  # here: python-control loads scipy.optimize, start-up time for every command

    c = np.asarray(output, dtype=float).reshape(1, -1)
    plant = control.ss(phi, np.asarray(gamma, dtype=float).reshape(-1, 1), c, 0.0, pid.period)
    return pid.transfer() * control.ss2tf(plant)


def loop_response(
    phi: np.ndarray, gamma: np.ndarray, output: np.ndarray, pid: Pid, frequency_hz: np.ndarray
) -> np.ndarray:
    """L(e^{i omega T}) [-] at `frequency_hz` [Hz]: K(z) C (z I - Phi)^-1 Gamma evaluated exactly (batched solves)."""
    z = np.exp(2j * math.pi * np.asarray(frequency_hz, dtype=float) * pid.period)
    n = len(phi)
    resolvent = np.linalg.solve(
        z[:, None, None] * np.eye(n) - phi,
        np.broadcast_to(np.asarray(gamma, dtype=complex).reshape(n, 1), (z.size, n, 1)),
    )
    plant = (np.asarray(output, dtype=float).reshape(1, n) @ resolvent)[:, 0, 0]
    return _law(pid, z) * plant


def _law(pid: Pid, z: np.ndarray) -> np.ndarray:
    """K(z) [input units / output units] of the discrete PID at the points z (derivative and integral by differences)."""
    law = pid.kp + pid.kd * (z - 1) / (pid.period * z)
    if pid.ki > 0:
        law = law + pid.ki * pid.period * z / (z - 1)
    return law


def margins(
    phi: np.ndarray, gamma: np.ndarray, output: np.ndarray, pid: Pid, *, lowest_hz: float = 0.01, points: int = 40001
) -> dict[str, float]:
    """Gain margin [dB] (as the gain rises), phase margin [deg] and their frequencies [Hz] of L(z).

    L is evaluated exactly (`loop_response`) on a logarithmic grid from `lowest_hz` to the Nyquist frequency
    1 / (2 T); each sign change of Im L with Re L < 0 (a phase crossover) and of |L| - 1 (a gain crossover) is
    refined by Brent's method. The gain margin is the smallest 1 / |L| above 1 at a phase crossover (the factor
    by which the gains can rise; `critical_gain` finds it from the poles), the phase margin the smallest angle
    between L and -1 at a gain crossover, 180 deg - |arg L| with arg L in (-180, 180] deg. Margins describe a
    stable loop; whether it is stable is the poles' answer (`spectral_radius`). (python-control's `stability_margins` reads these off its own
    frequency grid and misses the lightly damped belt's crossover by 3 % of the gain: not used.)

    Returns
    -------
    dict
        {"gain_margin_db", "phase_margin_deg", "phase_crossover_hz", "gain_crossover_hz"}; inf and nan where
        there is no crossover.
    """
    import scipy.optimize  # here: scipy.optimize costs every command start-up time (tests/cli/test_cli_usage.py)

    nyquist = 0.5 / pid.period
    grid = np.geomspace(lowest_hz, nyquist * (1 - 1e-9), points)
    values = _bracketing_response(phi, gamma, output, pid, grid)

    def response(f: float) -> complex:
        return complex(loop_response(phi, gamma, output, pid, np.array([f]))[0])

    gain_margin, phase_crossover = math.inf, math.nan
    for i in np.flatnonzero(np.sign(values.imag[:-1]) != np.sign(values.imag[1:])):
        if values.real[i] < 0 or values.real[i + 1] < 0:
            f = scipy.optimize.brentq(lambda x: response(x).imag, grid[i], grid[i + 1], xtol=1e-13 * grid[i])
            value = response(f)
            if value.real < 0 and 1 / abs(value) > 1 and 1 / abs(value) < gain_margin:
                gain_margin, phase_crossover = 1 / abs(value), f
    phase_margin, gain_crossover = math.inf, math.nan
    excess = np.abs(values) - 1
    for i in np.flatnonzero(np.sign(excess[:-1]) != np.sign(excess[1:])):
        f = scipy.optimize.brentq(lambda x: abs(response(x)) - 1, grid[i], grid[i + 1], xtol=1e-13 * grid[i])
        margin = 180.0 - abs(math.degrees(np.angle(response(f))))
        if margin < phase_margin:
            phase_margin, gain_crossover = margin, f
    return {
        "gain_margin_db": 20 * math.log10(gain_margin) if math.isfinite(gain_margin) else math.inf,
        "phase_margin_deg": phase_margin,
        "phase_crossover_hz": phase_crossover,
        "gain_crossover_hz": gain_crossover,
    }


#: how far from 0 [relative to the sizes of its terms] a value of the triangular form must be for its sign to be taken
#: without the batched solves (both are good to about cond(z I - Phi) eps of those sizes: 1e-7 at the belt's
#: rigid-body double pole on the grid's lowest frequency)
_SIGN_MARGIN = 1e-5


def _bracketing_response(
    phi: np.ndarray, gamma: np.ndarray, output: np.ndarray, pid: Pid, frequency_hz: np.ndarray
) -> np.ndarray:
    """L on `margins`' grid, good for the signs the crossings are bracketed by: `loop_response`'s own values where
    a sign is in doubt, the plant's triangular form elsewhere.

    `margins` reads the grid only for the signs of Im L, Re L and |L| - 1 (Brent's method then refines each
    crossing on `loop_response` itself). With Phi = Q T Q^H (complex Schur, T upper triangular),
    C (z I - Phi)^-1 Gamma = (C Q) (z I - T)^-1 (Q^H Gamma), the solve a back substitution: n (n + 1) / 2 array
    operations over the whole grid where the batched solves factor a 4 x 4 matrix per point, and as backward
    stable. Every point where one of the three quantities lies within `_SIGN_MARGIN` of the sizes of the terms
    summed for it is evaluated by `loop_response`, so every sign is the solves' own and the brackets, hence the
    margins, are theirs bit for bit.
    """
    f = np.asarray(frequency_hz, dtype=float)
    triangular, basis = scipy.linalg.schur(np.asarray(phi, dtype=complex), output="complex")
    row = (np.asarray(output, dtype=float).reshape(1, -1) @ basis)[0]
    column = basis.conj().T @ np.asarray(gamma, dtype=complex).reshape(-1)
    z = np.exp(2j * math.pi * f * pid.period)
    n = len(column)
    solved: list[np.ndarray] = [np.empty(0, complex)] * n
    for i in range(n - 1, -1, -1):  # (z I - T) y = Q^H Gamma from the last row up
        rest = column[i] + sum((triangular[i, j] * solved[j] for j in range(i + 1, n)), np.zeros_like(z))
        solved[i] = rest / (z - triangular[i, i])
    law = _law(pid, z)
    values = law * sum(row[i] * solved[i] for i in range(n))
    size = np.abs(law) * sum(np.abs(row[i] * solved[i]) for i in range(n))
    margin = _SIGN_MARGIN * np.maximum(size, 1.0)
    doubtful = (
        (np.abs(values.imag) <= margin) | (np.abs(values.real) <= margin) | (np.abs(np.abs(values) - 1) <= margin)
    )
    if doubtful.any():
        values[doubtful] = loop_response(phi, gamma, output, pid, f[doubtful])
    return values


def spectral_radius(phi: np.ndarray, gamma: np.ndarray, output: np.ndarray, pid: Pid) -> float:
    """Largest |pole| [-] of the closed loop (< 1: stable)."""
    return float(np.max(np.abs(np.linalg.eigvals(closed_loop(phi, gamma, output, pid)[0]))))


def critical_gain(phi: np.ndarray, gamma: np.ndarray, output: np.ndarray, pid: Pid, *, largest: float = 1e4) -> float:
    """The factor g [-] on kp, kd and ki at the nearest stability boundary from g = 1.

    Stable at g = 1: the g > 1 at which the loop first loses stability as the gains rise (the gain margin as a
    factor; inf if stable up to `largest`). Unstable at g = 1: the g < 1 below which it is stable again (0 if
    it stays unstable down to 1 / `largest`). Geometric scan (ratio 1.01) from 1, then bisection on the
    spectral radius to 1e-12 relative.
    """

    def stable(gain: float) -> bool:
        return spectral_radius(phi, gamma, output, pid.scaled(gain)) < 1.0

    rising = stable(1.0)
    ratio = 1.01 if rising else 1 / 1.01
    low, high = 1.0, ratio
    while stable(high) == rising:
        low, high = high, high * ratio
        if not (1 / largest < high < largest):
            return math.inf if rising else 0.0
    # low is on the side of g = 1, high across the boundary
    while abs(high - low) > 1e-12 * max(high, low):
        middle = 0.5 * (low + high)
        if stable(middle) == rising:
            low = middle
        else:
            high = middle
    return 0.5 * (low + high)


def held_run(
    a: np.ndarray,
    b: np.ndarray,
    dt: float,
    steps: int,
    x0: np.ndarray,
    control: Callable[[int, np.ndarray], float],
    steps_per_sample: int = 1,
) -> tuple[np.ndarray, np.ndarray]:
    """The exact motion of x' = A x + B u with u held: set from the exact state at each sample, held between.

    Every `steps_per_sample` steps of dt [s] from step 0, u_k = control(k, x) [input units] of the exact state
    x at that sample; one step is the exact map (`zoh` at dt), so the motion is exact at every step whatever
    the controller (a clipped law, a feedforward, an open-loop sequence).

    Returns
    -------
    tuple
        (x at steps 0..steps, (steps + 1, n); u held over each step, (steps,)).
    """
    phi, gamma = zoh(a, b, dt)
    phi = np.ascontiguousarray(phi)  # the same values: a contiguous matrix makes .dot BLAS's product at once
    x = np.empty((steps + 1, len(a)))
    x[0] = x0
    column = gamma[:, 0]
    forces = [0.0] * steps
    force = 0.0
    state = x[0]
    # one step per pass: phi @ x_j + gamma u_j with the state carried, not re-read from x; ndarray.dot is the same
    # BLAS product as @ (cblas_dgemv of a contiguous matrix and vector) at a third of the call's cost
    for j in range(steps):
        if j % steps_per_sample == 0:
            force = float(control(j // steps_per_sample, x[j]))
        forces[j] = force
        state = phi.dot(state) + column * force
        x[j + 1] = state
    return x, np.array(forces, dtype=float)


def held_open_run(
    a: np.ndarray, b: np.ndarray, dt: float, x0: np.ndarray, forces: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """`held_run` of an open-loop force sequence u_j [input units] held over step j: (x (m + 1, n), u (m,)).

    The same steps as `held_run(a, b, dt, len(forces), x0, lambda k, x: float(forces[k]))`, bit for bit (phi x_j
    + gamma u_j, each gamma u_j the same product), with the products formed for every step at once and no call
    per step: the loop is the step itself.
    """
    phi, gamma = zoh(a, b, dt)
    phi = np.ascontiguousarray(phi)
    u = np.asarray(forces, dtype=float)
    pushes = gamma[:, 0][None, :] * u[:, None]  # row j: column * u_j, as held_run forms it
    x = np.empty((len(u) + 1, len(a)))
    x[0] = x0
    state = x[0]
    for j, push in enumerate(pushes):
        state = phi.dot(state) + push
        x[j + 1] = state
    return x, u.copy()


def held_maximum(
    a: np.ndarray, b: np.ndarray, dt: float, states: np.ndarray, forces: np.ndarray, row: np.ndarray
) -> float:
    """The largest row . x(t) of a held motion (`held_run`) over continuous time, not only at its steps.

    Between steps the motion is exact with its held input, x(t_j + s) = Phi(s) x_j + Gamma(s) u_j; the best
    sample's two neighbouring steps are searched by a bounded Brent method on that map (a smooth peak sampled
    at many steps per oscillation lies next to its best sample).

    Parameters
    ----------
    a, b
        the plant x' = A x + B u [1/s], [state units / (input units s)].
    dt
        the step [s].
    states
        (steps + 1, n) the exact states at the steps.
    forces
        (steps,) the input held over each step [input units].
    row
        (n,) the output read, e.g. the carriage's position.

    Returns
    -------
    float
        the continuous maximum [output units].
    """
    values = states @ row
    best_step = int(np.argmax(values))
    best = float(values[best_step])
    import scipy.optimize

    for step in (best_step - 1, best_step):
        if step < 0 or step >= len(forces):
            continue

        def output(s: float, step: int = step) -> float:
            if s <= 0.0:
                return float(states[step] @ row)
            phi, gamma = zoh(a, b, s)
            return float(row @ (phi @ states[step] + gamma[:, 0] * forces[step]))

        found = scipy.optimize.minimize_scalar(
            lambda s: -output(s), bounds=(0.0, dt), method="bounded", options={"xatol": 1e-9 * dt}
        )
        best = max(best, -float(found.fun))
    return best


def held_last_exit(
    a: np.ndarray,
    b: np.ndarray,
    dt: float,
    states: np.ndarray,
    forces: np.ndarray,
    row: np.ndarray,
    level: float,
    offset: float = 0.0,
) -> float:
    """The time [s] after which |row . x(t) - offset| stays <= level for good, within the held motion's record.

    Located on the cubic Hermite interpolant of the steps (springlab.exact.events.last_exit), then found by
    Brent's method on the exact map of the step it falls in, x(t_j + s) = Phi(s) x_j + Gamma(s) u_j: a root of
    the exact motion, not of its interpolant. Arguments as `held_maximum`; 0 if it never leaves the band.
    """
    import scipy.optimize

    from springlab.exact import events

    time = dt * np.arange(len(states))
    held = np.append(forces, forces[-1] if len(forces) else 0.0)
    rates = (states @ a.T + np.outer(held, b[:, 0])) @ row
    estimate = events.last_exit(time, states @ row - offset, rates, level)
    if not math.isfinite(estimate) or estimate <= 0.0:
        return estimate
    for step in dict.fromkeys(min(max(k, 0), len(forces) - 1) for k in (int(estimate // dt), int(estimate // dt) - 1)):

        def excess(s: float, step: int = step) -> float:
            if s <= 0.0:
                return abs(float(states[step] @ row) - offset) - level
            phi, gamma = zoh(a, b, s)
            return abs(float(row @ (phi @ states[step] + gamma[:, 0] * forces[step])) - offset) - level

        if excess(0.0) > 0.0 >= excess(dt):
            return step * dt + float(scipy.optimize.brentq(excess, 0.0, dt, xtol=1e-15, rtol=1e-15))
    return estimate


def held_run_error(
    a: np.ndarray,
    b: np.ndarray,
    dt: float,
    order: int,
    constant: float,
    states: np.ndarray,
    forces: np.ndarray,
    steps_per_sample: int = 1,
    response: Callable[[int, np.ndarray], float] | None = None,
) -> np.ndarray:
    """The leading-order global error [state units] of an order-p integrator on a `held_run`, loop included.

    An order-p one-step method commits the local error -C h^(p+1) A_z^(p+1) z_j on the autonomous system
    z = (x, u), A_z = [[A, B], [0, 0]] (u held over the step: a generator state with u' = 0), C the
    integrator's constant (RK4 1/120, first-order methods 1/2; springlab.sim.simulate.ERROR_CONSTANTS). The
    errors are carried by the exact step map, e_(j+1) = Phi e_j + Gamma du_j + delta_j, and where the control
    is set from a measurement the error comes back through the law: du_k = response(k, e) [input units] at
    each sample (the law's linear response to the state error e, including its memory; 0 where it is
    clipped). Without `response` the control is open-loop (du = 0), and e is compare's C h^p t A^(p+1) z(t)
    summed exactly across the held input's switches.

    Parameters
    ----------
    a, b
        A [1/s] (n, n) and B (n, 1).
    dt
        Step h [s].
    order, constant
        The integrator's order p and local-error constant C [-].
    states, forces
        The exact run (`held_run`): x (m + 1, n) and u (m,).
    steps_per_sample
        Steps per sample of the law.
    response
        du_k = response(k, e_k) of the law at sample k, or None.

    Returns
    -------
    np.ndarray
        (m + 1, n) signed error vectors, 0 at step 0.
    """
    n = len(a)
    phi, gamma = zoh(a, b, dt)
    generator = np.zeros((n + 1, n + 1))
    generator[:n, :n], generator[:n, n] = a, np.asarray(b, dtype=float).reshape(-1)
    power = np.linalg.matrix_power(generator * dt, order + 1)[:n]  # (h A_z)^(p+1), its x rows
    augmented = np.column_stack([states[:-1], forces])
    local = -constant * augmented @ power.T
    error = np.zeros_like(states)
    phi, column = np.ascontiguousarray(phi), gamma[:, 0]
    current = error[0]
    push = column * 0.0  # Gamma du, formed where du changes (at a sample), not at every step
    for j, step_error in enumerate(local):
        if response is not None and j % steps_per_sample == 0:
            push = column * float(response(j // steps_per_sample, error[j]))
        current = phi.dot(current) + push + step_error  # as in held_run
        error[j + 1] = current
    return error
