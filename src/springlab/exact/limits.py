"""Where MuJoCo's integrators stop being stable on a damped oscillator, exactly.

For the test mode x'' + 2 zeta omega x' + omega^2 x = 0 each fixed-step method is a linear
map of the state per step; the largest omega*dt [-] at which its spectral radius stays <= 1 is
the stability limit. Euler, implicit and implicitfast treat joint damping implicitly and the
spring explicitly (closed form); RK4 is fully explicit (its amplification polynomial, scanned
and bisected); `discrete` is never unstable.
"""

from __future__ import annotations

import math

import numpy as np

from springlab.sim.simulate import integrator_id


def _rk4_amplification(z: np.ndarray) -> np.ndarray:
    return 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24


def stability_limit(integrator: str, zeta: float) -> float:
    """Largest omega_n*dt [-] at which `integrator` is stable on m x'' + d x' + k x = 0.

    euler, implicit and implicitfast treat joint damping implicitly and springs
    explicitly: stable while omega*dt < 2 zeta + 2 sqrt(zeta^2 + 1).
    rk4 is explicit in both: the bound where a root's hλ leaves RK4's stability
    region (2.83 at zeta = 0, shrinking like 2.79/(2 zeta) for heavy damping).
    discrete makes springs implicit: unconditionally stable (inf).

    Parameters
    ----------
    integrator
        one of INTEGRATORS.
    zeta
        damping ratio [-], >= 0.
    """
    integrator_id(integrator)
    if integrator == "discrete":
        return math.inf
    if integrator != "rk4":
        return 2 * zeta + 2 * math.hypot(zeta, 1.0)  # hypot: no overflow for huge zeta
    # roots of s^2 + 2 zeta s + 1 (omega_n = 1), in units where omega_n dt = h
    return rk4_limit(_unit_oscillator_roots(zeta))


def rk4_limit(roots: np.ndarray) -> float:
    """Largest h [-] at which RK4 is stable on every mode exp(s t), s in `roots` [-]: the first h whose
    amplification |R(h s)| leaves the unit disc (by more than 1e-13), found by a scan and a bisection.

    Parameters
    ----------
    roots
        complex eigenvalues in units of the timestep's scale (e.g. divided by omega_n, so h = omega_n dt);
        the scan covers h up to 3 / max(1, max |s|).

    Returns
    -------
    h [-], or inf when no h in the scan is unstable.
    """

    def unstable(h: np.ndarray) -> np.ndarray:
        # one vectorised evaluation per scan or bisection step (charts ask for hundreds of zetas)
        return np.max(np.abs(_rk4_amplification(np.multiply.outer(h, roots))), axis=-1) > 1 + 1e-13

    fastest = float(np.max(np.abs(roots)))  # zeta + sqrt(zeta^2 - 1) when overdamped, else 1
    grid = np.linspace(1e-3, 3.0, 3000) / max(1.0, fastest)
    hits = np.flatnonzero(unstable(grid))
    if not hits.size:
        return math.inf
    first = float(grid[hits[0]])
    low, high = first - (grid[1] - grid[0]), first
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (low, mid) if unstable(np.array(mid)) else (mid, high)
    return float(low)


def _unit_oscillator_roots(zeta: float) -> np.ndarray:
    """Roots of s^2 + 2 zeta s + 1 [-], without overflow for huge zeta (e.g. damping = 1e300)."""
    if zeta <= 1.0:
        disc = np.sqrt(complex(zeta * zeta - 1))
        return np.array([-zeta + disc, -zeta - disc])
    # zeta (1 + sqrt(1 - 1/zeta^2)) never squares zeta; the slow root is 1 / the fast one (product 1)
    fast = -zeta * (1.0 + math.sqrt((1.0 - 1.0 / zeta) * (1.0 + 1.0 / zeta)))
    return np.array([1.0 / fast, fast], dtype=complex)
