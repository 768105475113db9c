"""The exact and the discrete responses: the linearization's H(j omega), the integrator's one-step map with
the input held, the exact zero-order hold, resonances and anti-resonances, the band within tol and each
integrator's largest dt."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from springlab.exact.linearize import FD_STEP, spectral_radius
from springlab.exact.model_at_point import ModelAtPoint

from .inputs import Probe
from .results import Resonance

#: the resonance search evaluates |H| on at least this many log-spaced points of the band
SEARCH_POINTS = 2000
#: a one-step map whose spectral radius exceeds 1 by more than this is unstable: no steady state to compare
STABLE_RADIUS = 1.0 + 1e-6
#: the smallest timestep the per-integrator search tries [s]
MIN_DT = 1e-7
#: function evaluations per step, for the cost of a setting (rk4: four forward passes)
EVALUATIONS = {"euler": 1, "implicit": 1, "implicitfast": 1, "rk4": 4, "discrete": 1}
#: a zero within this relative distance of a pole cancels it (finite differences leave ~1e-8 of a mode the
#: input does not reach)
CANCEL = 1e-5
EPS = float(np.finfo(float).eps)


def _system(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: float, dt: float | None = None):
    """A SISO python-control state-space system (continuous, or discrete with step dt [s])."""
    import control  # a dependency (pyproject: its state-space evaluation); imported here to keep import time low

    args = (a, b[:, None], c[None, :], np.array([[d]]))
    return control.ss(*args) if dt is None else control.ss(*args, dt)


def _evaluate(system, x: np.ndarray) -> np.ndarray:
    """H at complex s (or z) points: python-control's state-space evaluation, c (x I - A)^-1 b + d, solved
    per point (no polynomial of the system is ever formed, so clustered poles near z = 1 at a small dt keep
    their accuracy)."""
    return np.asarray(system.horner(np.atleast_1d(x), warn_infinite=False))[0, 0]


def continuous_response(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: float) -> Callable[[np.ndarray], np.ndarray]:
    """H(f) of the continuous system, f [Hz] -> complex."""
    system = _system(a, b, c, d)

    def response(f: np.ndarray) -> np.ndarray:
        return _evaluate(system, 2j * np.pi * np.atleast_1d(np.asarray(f, float)))

    return response


def _discrete(phi: np.ndarray, gamma: np.ndarray, c: np.ndarray, d: float, dt: float, f: np.ndarray) -> np.ndarray:
    """H_d of x_{k+1} = Phi x_k + gamma u_k, y_k = c x_k + d u_k at f [Hz], for an input sampled at mid-step
    (k + 1/2) dt and held: H_d(exp(j omega dt)) exp(j omega dt / 2)."""
    omega_dt = 2 * np.pi * np.asarray(f, float) * dt
    return _evaluate(_system(phi, gamma, c, d, dt), np.exp(1j * omega_dt)) * np.exp(0.5j * omega_dt)


def held_response(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: float, dt: float, f: np.ndarray) -> np.ndarray:
    """The exact zero-order-hold discretization's response (scipy.signal.cont2discrete), sampled as `_discrete`."""
    from scipy import signal  # scipy is a dependency; imported here to keep import time low

    phi, gamma, *_ = signal.cont2discrete((a, b[:, None], c[None, :], np.array([[d]])), dt, method="zoh")
    return _discrete(phi, gamma[:, 0], c, d, dt, f)


def find_anti_resonances(
    a: np.ndarray, b: np.ndarray, c: np.ndarray, d: float, band: tuple[float, float]
) -> tuple[Resonance, ...]:
    """The anti-resonances inside the band: complex zeros with damping below 1 / sqrt(2) (so |H| dips), not
    cancelled by a pole (a mode the input does not reach or the response does not see)."""
    system = _system(a, b, c, d)
    zeros = np.asarray(system.zeros(), complex)
    poles = np.asarray(system.poles(), complex)
    found = []
    for z in zeros[zeros.imag > 0]:
        size = abs(z)
        if poles.size and np.min(np.abs(poles - z)) <= CANCEL * size:
            continue
        zeta = -z.real / size
        f = size / (2 * np.pi)
        if zeta < 1 / math.sqrt(2) and band[0] <= f <= band[1]:
            found.append(Resonance(float(f), float(abs(_evaluate(system, np.array([1j * size]))[0])), float(zeta)))
    return tuple(sorted(found, key=lambda r: r.frequency_hz))


def find_resonances(
    response: Callable[[np.ndarray], np.ndarray], band: tuple[float, float], points: int, poles: np.ndarray
) -> tuple[Resonance, ...]:
    """The resonances inside the band: local maxima of |H| on a log grid, refined, with the half-power width.

    A maximum counts only near an oscillatory pole p (| 2 pi f - |p| | <= 2 |Re p| plus two grid steps): far
    above the modes |H| falls by orders of magnitude and round-off makes local maxima of no physics."""
    from scipy.optimize import brentq, minimize_scalar

    grid = np.geomspace(band[0], band[1], max(points, SEARCH_POINTS))
    mag = np.abs(response(grid))

    def size(f: float) -> float:
        return float(np.abs(response(np.array([f])))[0])

    peaks = []
    for i in range(1, len(grid) - 1):
        if not (mag[i] > mag[i - 1] and mag[i] >= mag[i + 1]):
            continue
        found = minimize_scalar(
            lambda f: -size(f), bounds=(grid[i - 1], grid[i + 1]), method="bounded", options={"xatol": 1e-12 * grid[i]}
        )
        f0, m0 = float(found.x), size(float(found.x))
        step = 2.0 * (grid[i + 1] / grid[i] - 1.0) * 2 * math.pi * f0
        near = [p for p in poles if p.imag > 0 and abs(2 * math.pi * f0 - abs(p)) <= 2 * abs(p.real) + step]
        if not near:
            continue
        pole = min(near, key=lambda p: abs(2 * math.pi * f0 - abs(p)))
        half = m0 / math.sqrt(2.0)
        below = mag < half
        left = np.nonzero(below[:i])[0]
        right = np.nonzero(below[i + 1 :])[0]
        zeta = None
        if left.size and right.size:
            lo_i, hi_i = int(left[-1]), i + 1 + int(right[0])
            f1 = brentq(lambda f, h=half: size(f) - h, grid[lo_i], f0)
            f2 = brentq(lambda f, h=half: size(f) - h, f0, grid[hi_i])
            zeta = (f2 - f1) / (2.0 * f0)
        peaks.append(Resonance(f0, m0, zeta, float(abs(pole) / (2 * math.pi)), float(-pole.real / abs(pole))))
    return tuple(peaks)


@dataclasses.dataclass(frozen=True, eq=False)
class StepMap:
    """One step of an integrator at dt as a discrete-time system at the operating point: x_{k+1} = phi x_k +
    gamma u_k, y_k = c x_k + d u_k (phi (n, n), gamma (n,), c (n,), d)."""

    phi: np.ndarray
    gamma: np.ndarray
    c: np.ndarray
    d: float


class Discretizer:
    """MuJoCo's one-step map of an integrator at dt, with the input column, as a frequency response.

    Each (integrator, dt, finite-difference step) is differenced once at the model's operating point and kept:
    the band's bisection in frequency, the sinestream and the sweep ask the same setting again and again.

    Parameters
    ----------
    at
        the model at its operating point (its `workspace` takes the integrator and timestep of each map).
    probe
        the input (its column gamma) and the response: a sensor's rows come from the step of each integrator at
        its dt (rk4's from the continuous forward pass, `c` and `d`).
    c, d
        the response's row and feedthrough in the continuous system.
    """

    def __init__(self, at: ModelAtPoint, probe: Probe, c: np.ndarray, d: float):
        self.at, self.probe, self.c, self.d = at, probe, c, d
        self._maps: dict[tuple[str, float, float], StepMap | None] = {}

    def step_map(self, integrator: str, dt: float, step: float = FD_STEP) -> StepMap | None:
        """The discrete-time system of `integrator` at `dt` [s], or None where its one-step map is unstable (no
        steady state); `step`: the maps' finite-difference step (the sensor rows keep FD_STEP)."""
        key = (integrator, float(dt), float(step))
        if key not in self._maps:
            self._maps[key] = self._differenced(integrator, dt, step)
        return self._maps[key]

    def response(self, integrator: str, dt: float, f: np.ndarray, step: float = FD_STEP) -> np.ndarray | None:
        """H_d at f [Hz], or None where the one-step map is unstable (no steady state); `step`: the maps'
        finite-difference step."""
        system = self.step_map(integrator, dt, step)
        return None if system is None else _discrete(system.phi, system.gamma, system.c, system.d, dt, f)

    def _differenced(self, integrator: str, dt: float, step: float) -> StepMap | None:
        at = self.at if step == self.at.step else dataclasses.replace(self.at, step=step)
        phi = at.one_step_map(integrator, dt, self.at.workspace)
        if spectral_radius(phi) > STABLE_RADIUS:
            return None
        gamma = at.step_input_column(integrator, self.probe.input_kind, self.probe.input_index, dt)
        c, d = self.c, self.d
        if self.probe.response_kind == "sensor" and integrator != "rk4":
            c, d = self.probe.rows(self.at, integrator, dt)
        return StepMap(phi, gamma, c, d)


def relative_error(discrete: np.ndarray | None, exact: np.ndarray) -> np.ndarray:
    if discrete is None:
        return np.full(exact.shape, np.inf)
    return np.abs(discrete / exact - 1.0)


def band_within(
    discretizer: Discretizer,
    integrator: str,
    dt: float,
    exact_of: Callable[[np.ndarray], np.ndarray],
    grid: np.ndarray,
    errors: np.ndarray,
    tol: float,
) -> tuple[float, float] | None:
    """The band (fmin, f) within tol, f refined by bisection in log f between the last good and first bad point."""
    bad = np.nonzero(~(errors <= tol))[0]
    if bad.size == 0:
        return (float(grid[0]), float(grid[-1]))
    first = int(bad[0])
    if first == 0:
        return None
    lo, hi = float(grid[first - 1]), float(grid[first])
    for _ in range(30):
        mid = math.sqrt(lo * hi)
        probe = np.array([mid])
        err = relative_error(discretizer.response(integrator, dt, probe), exact_of(probe))[0]
        lo, hi = (mid, hi) if err <= tol else (lo, mid)
        if hi / lo - 1.0 < 1e-6:
            break
    return (float(grid[0]), lo)


def max_dt(discretizer: Discretizer, integrator: str, grid: np.ndarray, exact: np.ndarray, tol: float) -> float | None:
    """The largest dt [s] below Nyquist of the band's top whose response is within tol over the grid."""

    def ok(dt: float) -> bool:
        return bool(np.all(relative_error(discretizer.response(integrator, dt, grid), exact) <= tol))

    top = 0.5 / grid[-1] * (1.0 - 1e-9)  # Nyquist of fmax
    if ok(top):
        return top
    hi = top
    lo = hi / 2.0
    while not ok(lo):
        hi, lo = lo, lo / 2.0
        if lo < MIN_DT:
            return None
    for _ in range(12):  # log bisection to 2^(1/4096): dt good to ~0.02 %
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo
