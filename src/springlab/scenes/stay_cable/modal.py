"""One complex mode of the N-element cable: the state a free run starts in, its exact motion, and what a run measures.

The model is linear, x' = A x with x = (q [m], q' [m/s]), A = [[0, I], [-M^-1 K, -M^-1 C]]. A mode is an
eigenvalue lambda [1/s] of A with its right eigenvector v (A v = lambda v) and left one w (w^H A = lambda w^H,
scaled so that w^H v = 1). A run started at x0 = Re(s v) (s complex) moves as

    x(t) = Re(s v e^{lambda t})        (exactly: A is real, so e^{At} Re(s v) = Re(s e^{At} v))

so every node rings at the mode's frequency and decays (or grows) at its rate, and its position and velocity
obey q'' - 2 Re(lambda) q' + |lambda|^2 q = 0 whatever the node: the 2 x 2 system a run's tolerance is derived
from. The modal filter z = w^H x = s e^{lambda t} / 2 (w^H conj(v) = 0: the conjugate mode is another
eigenvector) reads the mode's amplitude and phase from the whole state, so a run measures lambda as

    lambda_measured = [ln |z(T) / z(0)| + i (arg z(T) - arg z(0))] / T,

the phase unwrapped over the run. RK4's step is a polynomial of A dt, so the mode stays a mode of the run and
z_k = p(lambda dt)^k z_0 exactly: the measured lambda is ln p(lambda dt) / dt, off by lambda (lambda dt)^4 / 120
to leading order. The first-order integrators' steps are not polynomials of A once the damping is not
proportional to the mass (a damper): their modes differ from A's by O(dt), which their tolerance does not
count; the scene validates the damped scenarios with RK4.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from springlab.exact import linear
from springlab.exact.cable import LumpedCable
from springlab.sim.simulate import ORDERS

_EPS = float(np.finfo(float).eps)
#: round-off allowance per step, relative (as in springlab.runs.compare)
ROUNDOFF_PER_STEP = 100 * _EPS
#: leading local-error constants of the integrators' one-step maps (as in springlab.runs.compare)
ERROR_CONSTANTS = {name: (1.0 / 120.0 if order == 4 else 0.5) for name, order in ORDERS.items()}


@dataclasses.dataclass(frozen=True)
class Mode:
    """A complex mode of the N-element model.

    Attributes
    ----------
    number
        its place among the oscillatory modes, slowest first (1: the fundamental).
    value
        lambda [1/s] (Im > 0).
    right
        v (2N,) complex, A v = lambda v.
    left
        w (2N,) complex, w^H A = lambda w^H, w^H v = 1.
    """

    number: int
    value: complex
    right: np.ndarray
    left: np.ndarray

    @property
    def frequency_hz(self) -> float:
        """|lambda| / (2 pi) [Hz]: the natural frequency."""
        return abs(self.value) / (2.0 * math.pi)

    @property
    def damping_ratio(self) -> float:
        """-Re(lambda) / |lambda| [-]."""
        return -self.value.real / abs(self.value)

    @property
    def growth_rate(self) -> float:
        """Re(lambda) [1/s]: > 0 grows."""
        return self.value.real

    def system(self) -> np.ndarray:
        """[[0, 1], [-|lambda|^2, 2 Re(lambda)]] [1/s^2, 1/s]: every node's (q, q') in this mode."""
        return np.array([[0.0, 1.0], [-(abs(self.value) ** 2), 2.0 * self.value.real]])

    def start(self, node: int, amplitude: float) -> tuple[np.ndarray, np.ndarray, complex]:
        """(q0 [m], q0' [m/s], s): the state Re(s v) with q = `amplitude` [m] at `node` (1 ... N) at t = 0."""
        n = len(self.right) // 2
        scale = amplitude / self.right[node - 1]
        state = (scale * self.right).real
        return state[:n], state[n:], complex(scale)

    def motion(self, scale: complex, node: int, time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(q [m], q' [m/s]) of `node` at `time` [s] for the start Re(scale v): Re(s v_j e^{lambda t})."""
        phase = scale * self.right[node - 1] * np.exp(self.value * time)
        return phase.real, (self.value * phase).real


def modes(lumped: LumpedCable) -> list[Mode]:
    """The oscillatory modes of the N-element model, slowest first (by Im lambda), each with its left eigenvector."""
    values, left, right = linear.eigen(lumped.state_matrix(), vectors=True)
    scale = float(np.max(np.abs(values)))
    oscillatory = [i for i in range(len(values)) if values[i].imag > 64 * _EPS * scale]
    oscillatory.sort(key=lambda i: values[i].imag)
    out = []
    for number, i in enumerate(oscillatory, start=1):
        v, w = right[:, i], left[:, i]
        w = w / np.conj(np.vdot(w, v))  # w^H v = 1
        out.append(Mode(number, complex(values[i]), v, w))
    return out


def fastest_growing(found: list[Mode]) -> Mode:
    """The mode with the largest Re(lambda) (the first of equals)."""
    return max(found, key=lambda mode: (mode.growth_rate, -mode.number))


def measured_value(mode: Mode, qpos: np.ndarray, qvel: np.ndarray, duration: float) -> complex:
    """lambda [1/s] of `mode` measured from a run: the modal filter z = w^H x at its two ends (module docstring).

    Parameters
    ----------
    mode
        the mode, with its left eigenvector.
    qpos, qvel
        (steps + 1, N) the run's positions [m] and velocities [m/s].
    duration
        the run's length [s].
    """
    z = _modal_filter(np.conj(mode.left), qpos, qvel)
    phase = np.unwrap(np.angle(z))
    return complex(math.log(abs(z[-1]) / abs(z[0])), phase[-1] - phase[0]) / duration


#: rows of the record the modal filter takes at a time: a multiple of 4, so BLAS's complex matrix-vector product
#: meets every row in the same group of rows as in one product of the whole record (the same sums, bit for bit)
FILTER_ROWS = 4096


def _modal_filter(weights: np.ndarray, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
    """z_k = (q_k, q'_k) . weights (complex) for every row k of the record, as `concatenate([qpos, qvel]) @ weights`.

    That product casts the whole record to complex first (16 bytes a value: 76 MB for rain_wind's 24,001 x 198,
    and most of its cost was the fresh memory); here FILTER_ROWS rows at a time through one reused buffer.
    """
    rows, n = qpos.shape
    out = np.empty(rows, complex)
    buffer = np.empty((min(rows, FILTER_ROWS), 2 * n), complex)
    for start in range(0, rows, FILTER_ROWS):
        stop = min(start + FILTER_ROWS, rows)
        block = buffer[: stop - start]
        block.real[:, :n] = qpos[start:stop]
        block.real[:, n:] = qvel[start:stop]
        block.imag = 0.0
        out[start:stop] = block @ weights
    return out


def value_error_bound(mode: Mode, integrator: str, dt: float) -> float:
    """Bound [1/s] on |lambda_measured - lambda|: 2 C |lambda| (|lambda| dt)^p of an order-p step, and round-off.

    C = 1/120 for RK4 (exactly its leading term, ln p(h) = h - h^5 / 120 + ...), 1/2 for the first-order
    integrators (an upper estimate, exact in mode for a proportional damping). Round-off: the state's
    relative error grows by at most 100 eps a step, so ln |z| and arg z err by 100 eps K over K steps,
    and lambda = their change over K dt by 100 eps / dt.
    """
    size = abs(mode.value)
    order = ORDERS[integrator]
    leading = 2.0 * ERROR_CONSTANTS[integrator] * size * (size * dt) ** order
    return leading + ROUNDOFF_PER_STEP / dt


def error_basis(integrator: str) -> str:
    """The tolerance's basis in words."""
    constant = "1/120" if ORDERS[integrator] == 4 else "1/2"
    return (
        f"2 C |lambda| (|lambda| dt)^p of {integrator} (C = {constant}, p = {ORDERS[integrator]}) + 100 eps / dt"
        " (round-off); the exact lambda the N-element model's (read back from the compiled model), measured by the"
        " modal filter w^H x"
    )
