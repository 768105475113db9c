"""The stay cable's exact layer, measured: the stationary covariance at N = 400 and the universal curve's range.

1. The exact covariance of the N-element cable under a uniform white wind (a damper at 6 m, 0.1 % intrinsic
   damping): springlab.exact.random_vibration.second_order_covariance (the undamped modes plus the damper's
   low-rank term) against scipy's Bartels-Stewart (solve_continuous_lyapunov) on the same state matrix, timed
   alternately (best of several), N = 100, 200, 400; each one's error against the integral of the impulse
   responses (Van Loan's exponential and doubling, the tests' reference) where that is affordable (N <= 100).
   The held covariance (the same wind held over 10 ms steps: expm and solve_discrete_lyapunov) beside them.
2. The universal curve against the transcendental equation: the exact optimum damper and the largest damping
   ratio of modes 1-3 over a / L = 0.005 ... 0.1, the relative errors of the curve's a / (2L) and
   sqrt(T m) L / (n pi a).

Run: python benchmarks/bench_stay_cable.py
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from springlab.exact import cable as cb
from springlab.exact import random_vibration as rv
from timing import best_of

CABLE = cb.TautCable(300.0, 6.1e6, 70.0)
DAMPER_POSITION, DAMPER, STRUCTURAL, INTENSITY = 6.0, 3.3e5, 0.001, 30.0


def _problem(n: int):
    model = cb.LumpedCable.build(
        CABLE, n, structural_ratio=STRUCTURAL, damper_position=DAMPER_POSITION, damper_coefficient=DAMPER
    )
    b = np.zeros((2 * n, 1))
    b[n:, 0] = CABLE.spacing(n) / model.mass
    alpha = CABLE.structural_node_damping(n, STRUCTURAL) / model.mass[0]
    factor = np.zeros((n, 1))
    factor[CABLE.damper_node(n, DAMPER_POSITION) - 1, 0] = 1.0
    return model, b, alpha, factor


def _doubling(a: np.ndarray, noise: np.ndarray) -> np.ndarray:
    n = a.shape[0]
    h = 1e-3
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n], block[:n, n:], block[n:, n:] = -a * h, noise * h, a.T * h
    e = scipy.linalg.expm(block)
    phi = e[n:, n:].T
    p = phi @ e[:n, n:]
    t = h
    while t < 1e5:
        p, phi, t = p + phi @ p @ phi.T, phi @ phi, 2 * t
    return 0.5 * (p + p.T)


def covariance_timings() -> None:
    print("exact covariance of the N-element cable (uniform white wind, damper at 6 m, 0.1 % intrinsic)")
    print(f"{'N':>5} {'structured [s]':>15} {'scipy [s]':>10} {'ratio':>7} {'held 10 ms [s]':>15}  errors vs integral")
    for n in (100, 200, 400):
        model, b, alpha, factor = _problem(n)
        a, w = model.state_matrix(), np.array([[INTENSITY]])
        structured = best_of(
            lambda m=model, b=b, al=alpha, f=factor: rv.second_order_covariance(
                m.mass, m.stiffness, al, f, np.array([DAMPER]), b, w
            ),
            repeat=5,
        )
        bartels = best_of(lambda a=a, b=b: rv.continuous_covariance(a, b @ w @ b.T), repeat=3)
        held = best_of(lambda a=a, b=b: rv.held_covariance(a, b, w, 0.01), repeat=1)
        errors = ""
        if n <= 100:
            brute = _doubling(a, b @ w @ b.T)
            scale = np.sqrt(np.outer(np.diag(brute), np.diag(brute)))
            p1 = rv.second_order_covariance(model.mass, model.stiffness, alpha, factor, np.array([DAMPER]), b, w)
            p2 = rv.continuous_covariance(a, b @ w @ b.T)
            errors = (
                f"structured {np.max(np.abs(p1 - brute) / scale):.1e}, scipy {np.max(np.abs(p2 - brute) / scale):.1e}"
            )
        print(f"{n:>5} {structured:>15.3f} {bartels:>10.3f} {bartels / structured:>7.1f} {held:>15.3f}  {errors}")


def universal_range() -> None:
    print("\nthe universal curve against the transcendental equation (exact / curve - 1)")
    print(f"{'a/L':>7} {'mode':>5} {'zeta_max':>12} {'curve a/2L':>11} {'error':>9} {'eta_opt error':>14}")
    for ratio in (0.005, 0.01, 0.02, 0.05, 0.1):
        for mode in (1, 2, 3):
            eta_opt, zeta_max = cb.exact_optimum(mode, ratio)
            eta_u, zeta_u = cb.universal_optimum(mode, ratio)
            print(
                f"{ratio:>7g} {mode:>5} {zeta_max:>12.6g} {zeta_u:>11.6g} {zeta_max / zeta_u - 1:>9.2e}"
                f" {eta_opt / eta_u - 1:>14.2e}"
            )


if __name__ == "__main__":
    covariance_timings()
    universal_range()
    print(
        f"\n(mode 1 of the default stay: f1 = {CABLE.frequencies_hz(1)[0]:.4f} Hz, sqrt(T m) = {CABLE.impedance:.0f} N s/m,"
        f" the universal optimum at 6 m: {CABLE.impedance / (math.pi * DAMPER_POSITION / CABLE.length):.0f} N s/m)"
    )
