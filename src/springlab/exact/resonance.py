"""A resonance test as a printer runs one: an accelerometer on the carriage, a swept force, a fitted belt mode.

3D-printer firmware measures the resonance it will shape against with an accelerometer on the toolhead
during a sweep of test vibrations. Here the sweep is a linear chirp of the motor force (`chirp`), held
over each simulation step (so the record's input is exactly what the plant received), and the record is
the carriage accelerometer's, sampled every `every` steps, with the sensor's noise.

The model fitted (the printer head's, exact.positioning): the carriage's acceleration per motor force is

    G(s) = (1 / M) (2 zeta omega s + omega^2) / (s^2 + 2 zeta omega s + omega^2),

the rigid body's 1 / M at low frequency, the belt's resonance at omega, rolling off as 2 zeta omega / (M s)
above it (the belt passes no force instantly). With the force held over each step of dt the sampled
response is the exact zero-order-hold discretization of G (a 2-state system: the carriage's deviation x
from the centre of mass, x'' + 2 zeta omega x' + omega^2 x = -F / M, and the acceleration
-(omega^2 x + 2 zeta omega x')), so the fit has no leakage, window or transient error: its residuals are
the noise alone.

Estimator: nonlinear least squares of the sampled record against that response (an output-error fit) in
theta = (omega, zeta, 1 / M), started from the record's spectrum (the peak of |Y / U|). For white Gaussian
noise this is the maximum-likelihood estimate; its covariance is s^2 (J^T J)^-1, J the Jacobian of the
response at the optimum and s^2 the residuals' variance, and the 95 % interval is +-1.96 standard errors
(the record has thousands of samples: Student's t is the normal's to 1e-3).

Units: force [N], acceleration [m/s^2], times [s], frequencies [Hz] (omega [rad/s]), 1 / M [1/kg].
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.linalg

__all__ = ["ResonanceFit", "accelerance_response", "chirp", "fit_resonance"]

#: the normal distribution's two-sided 95 % quantile
Z95 = 1.959963984540054


def chirp(amplitude: float, low_hz: float, high_hz: float, duration: float, dt: float) -> np.ndarray:
    """Force [N] per step of a linear chirp from `low_hz` to `high_hz` [Hz] over `duration` [s], held per step of dt.

    F_j = amplitude sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T))) at the step's midpoint t = (j + 1/2) dt (the
    held value closest to the smooth chirp's average over the step).
    """
    if not (0 < low_hz < high_hz):
        raise ValueError(f"the chirp needs 0 < low < high, got {low_hz!r} and {high_hz!r} Hz")
    if not (0 < dt < duration):
        raise ValueError(f"the chirp needs 0 < dt < duration, got {dt!r} and {duration!r} s")
    steps = int(round(duration / dt))
    t = (np.arange(steps) + 0.5) * dt
    phase = 2 * math.pi * (low_hz * t + (high_hz - low_hz) * t * t / (2 * duration))
    return amplitude * np.sin(phase)


#: steps per block of `accelerance_response` (rounded down to a whole number of samples): the blocks' outputs are
#: one matrix product each, and the state carried from block to block is a short loop
RESPONSE_BLOCK = 512


def _state_space(omega: float, zeta: float, inverse_mass: float, dt: float) -> tuple[np.ndarray, ...]:
    """(Phi (2, 2), Gamma (2,), C (2,)) of the exact ZOH discretization of G at step dt: y_k = C x_k,
    x_{k+1} = Phi x_k + Gamma F_k (one matrix exponential of the augmented 3 x 3 block)."""
    a = np.array([[0.0, 1.0], [-(omega**2), -2 * zeta * omega]])
    block = np.zeros((3, 3))
    block[:2, :2] = a * dt
    block[1, 2] = -inverse_mass * dt
    exponential = scipy.linalg.expm(block)
    return exponential[:2, :2], exponential[:2, 2], np.array([-(omega**2), -2 * zeta * omega])


def accelerance_response(
    force: np.ndarray, dt: float, every: int, omega: float, zeta: float, inverse_mass: float
) -> np.ndarray:
    """The carriage acceleration [m/s^2] at steps 0, every, 2 every, ... of the force [N] held per step of dt [s].

    Sample j is the acceleration at t = j every dt, before that step's force acts on the carriage (the belt
    has no feedthrough), from rest: y_k = sum_{i < k} C Phi^(k-1-i) Gamma F_i of the exact ZOH map (`_state_space`).
    Computed in blocks of B steps (RESPONSE_BLOCK): inside a block, the response to its own forces is one product
    with the block's impulse responses C Phi^m Gamma (a Toeplitz matrix, only its sampled rows) and the response to
    the state it starts from one product with C Phi^m; the state is carried from block to block by Phi^B. Each
    sample is a sum of at most B products plus the carried state, so it is exact to a few B eps of the sum of
    the sizes of its terms (the step-by-step recursion's error grows with the whole record's length instead).
    """
    phi, gamma, c = _state_space(omega, zeta, inverse_mass, dt)
    force = np.asarray(force, dtype=float)
    size = len(force)
    samples = -(-size // every)
    block = every * max(1, RESPONSE_BLOCK // every)
    count = -(-size // block)
    padded = np.zeros(count * block)
    padded[:size] = force
    forces = padded.reshape(count, block)
    powers = np.empty((block + 1, 2, 2))  # Phi^m, m = 0 ... B, one product at a time (doubling loses a digit)
    powers[0] = np.eye(2)
    step = np.ascontiguousarray(phi)
    for m in range(block):
        np.dot(step, powers[m], out=powers[m + 1])  # phi @ powers[m], the same BLAS product, written in place
    rows = np.arange(0, block, every)  # the sampled steps of a block
    impulse = np.einsum("j,mjk,k->m", c, powers[:block], gamma)  # C Phi^m Gamma
    lag = rows[:, None] - 1 - np.arange(block)[None, :]  # m - 1 - i
    toeplitz = np.where(lag >= 0, impulse[np.clip(lag, 0, None)], 0.0)
    observe = np.einsum("j,mjk->mk", c, powers[rows])  # C Phi^m at the sampled rows
    injected = forces @ np.einsum("mjk,k->mj", powers[block - 1 :: -1], gamma)  # sum_i Phi^(B-1-i) Gamma F_i
    starts = np.empty((count, 2))
    state = np.zeros(2)
    for index in range(count):
        starts[index] = state
        state = powers[block] @ state + injected[index]
    return (forces @ toeplitz.T + starts @ observe.T).reshape(-1)[:samples]


@dataclasses.dataclass(frozen=True)
class ResonanceFit:
    """The belt mode measured by a resonance test.

    Attributes
    ----------
    frequency_hz, damping_ratio, inverse_mass
        Estimates of f_n [Hz], zeta [-] and 1 / M [1/kg].
    covariance
        Covariance of (omega [rad/s], zeta [-], 1 / M [1/kg]), (3, 3).
    noise
        Residual standard deviation [m/s^2] (the sensor noise as the fit sees it).
    samples
        Number of accelerometer samples fitted.
    """

    frequency_hz: float
    damping_ratio: float
    inverse_mass: float
    covariance: np.ndarray
    noise: float
    samples: int

    @property
    def frequency_ci95(self) -> tuple[float, float]:
        """95 % interval [Hz] of the natural frequency."""
        half = Z95 * math.sqrt(self.covariance[0, 0]) / (2 * math.pi)
        return self.frequency_hz - half, self.frequency_hz + half

    @property
    def damping_ci95(self) -> tuple[float, float]:
        """95 % interval [-] of the damping ratio."""
        half = Z95 * math.sqrt(self.covariance[1, 1])
        return self.damping_ratio - half, self.damping_ratio + half


def _spectral_guess(force: np.ndarray, acceleration: np.ndarray, dt: float, every: int) -> tuple[float, float, float]:
    """(omega [rad/s], zeta [-], 1 / M [1/kg]) to start from: the peak of |Y / U| and the low-frequency level."""
    held = force[: len(acceleration) * every : every]
    spectrum_u, spectrum_y = np.fft.rfft(held), np.fft.rfft(acceleration)
    frequencies = np.fft.rfftfreq(len(held), every * dt)
    strong = np.abs(spectrum_u) > 0.1 * np.abs(spectrum_u).max()  # inside the chirp's band
    ratio = np.where(strong, np.abs(spectrum_y) / np.maximum(np.abs(spectrum_u), 1e-300), 0.0)
    peak = int(np.argmax(ratio))
    level = float(np.median(ratio[strong][: max(1, strong.sum() // 10)]))  # the band's low end
    zeta = min(0.5, max(1e-3, level / (2 * ratio[peak])))  # |G| peaks at about 1 / (2 zeta M)
    return 2 * math.pi * frequencies[peak], zeta, level


def fit_resonance(
    force: np.ndarray, acceleration: np.ndarray, dt: float, every: int = 1, band_hz: tuple[float, float] | None = None
) -> ResonanceFit:
    """Fit the belt mode to a resonance test's record (module docstring).

    Parameters
    ----------
    force
        The motor force [N] held over each simulation step of dt, from rest.
    acceleration
        The accelerometer's readings [m/s^2] at steps 0, every, 2 every, ... (noise included).
    dt
        Simulation step [s].
    every
        Steps per accelerometer sample, >= 1.
    band_hz
        The swept band (low, high) [Hz]: a resonance found outside it was extrapolated, not measured.

    Raises
    ------
    ValueError
        A record too short for three parameters, a fit that leaves the physical range, or a resonance outside
        the swept band (the band missed it).
    """
    import scipy.optimize  # here: scipy.optimize costs every command start-up time (tests/cli/test_cli_usage.py)

    acceleration = np.asarray(acceleration, dtype=float)
    if acceleration.size < 10 or len(force) < (acceleration.size - 1) * every + 1:
        raise ValueError("the resonance test needs at least 10 accelerometer samples within the force record")
    force = np.asarray(force, dtype=float)[: acceleration.size * every]
    omega0, zeta0, inverse0 = _spectral_guess(force, acceleration, dt, every)
    scale = np.array([omega0, zeta0, inverse0])

    def residuals(x: np.ndarray) -> np.ndarray:
        omega, zeta, inverse = x * scale
        return accelerance_response(force, dt, every, omega, zeta, inverse)[: acceleration.size] - acceleration

    solution = scipy.optimize.least_squares(
        residuals, np.ones(3), jac="3-point", x_scale="jac", xtol=1e-14, ftol=1e-14, gtol=1e-14
    )
    omega, zeta, inverse = solution.x * scale
    if not (0 < zeta < 1 and omega > 0 and inverse > 0):
        raise ValueError(
            f"the resonance test found no belt mode in its band (fit: {omega / (2 * math.pi):.4g} Hz, zeta {zeta:.3g})"
        )
    if band_hz is not None and not (band_hz[0] <= omega / (2 * math.pi) <= band_hz[1]):
        raise ValueError(
            f"the resonance test's band {band_hz[0]:g}-{band_hz[1]:g} Hz misses the belt's resonance (the fit"
            f" extrapolates to {omega / (2 * math.pi):.4g} Hz): sweep a band that contains it"
        )
    dof = acceleration.size - 3
    variance = float(solution.fun @ solution.fun) / dof
    jacobian = solution.jac / scale  # d residual / d theta
    covariance = variance * np.linalg.inv(jacobian.T @ jacobian)
    return ResonanceFit(omega / (2 * math.pi), zeta, inverse, covariance, math.sqrt(variance), acceleration.size)
