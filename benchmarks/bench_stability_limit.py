"""Cost of the RK4 stability limit, the scalar scan it was against the vectorised one it is.

The stability chart draws the theory boundary at 201 damping ratios per
integrator. The old rk4 limit scanned up to 3000 omega*dt values one Python
call at a time, then bisected (about 3000 calls per zeta, 605k for the chart);
simulate.stability_limit now evaluates the scan as one array and bisects with
one call per step. Both give the same limit (printed: largest relative difference).

Run: python benchmarks/bench_stability_limit.py
"""

from __future__ import annotations

import math

import numpy as np

from springlab.exact.limits import _rk4_amplification, stability_limit
from timing import best_of

ZETAS = np.concatenate([[0.0], np.geomspace(1e-2, 100.0, 200)])


def scalar_rk4_limit(zeta: float) -> float:
    """The previous implementation: a Python loop over the scan grid."""
    disc = np.sqrt(complex(zeta * zeta - 1))
    roots = np.array([-zeta + disc, -zeta - disc])

    def unstable(h: float) -> bool:
        return bool(np.max(np.abs(_rk4_amplification(h * roots))) > 1 + 1e-13)

    grid = np.linspace(1e-3, 3.0, 3000) / max(1.0, zeta + math.sqrt(max(zeta * zeta - 1, 0)))
    first = next((h for h in grid if unstable(h)), None)
    if first is None:
        return math.inf
    low, high = first - (grid[1] - grid[0]), first
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (low, mid) if unstable(mid) else (mid, high)
    return low


def main() -> None:
    old = best_of(lambda: [scalar_rk4_limit(float(z)) for z in ZETAS], repeat=3)
    new = best_of(lambda: [stability_limit("rk4", float(z)) for z in ZETAS], repeat=3)
    difference = max(
        abs(stability_limit("rk4", float(z)) - scalar_rk4_limit(float(z))) / scalar_rk4_limit(float(z)) for z in ZETAS
    )
    print(f"rk4 stability limit at {ZETAS.size} damping ratios (one chart panel)")
    print(f"  scalar scan   {old:8.3f} s")
    print(f"  vectorised    {new:8.3f} s   ratio {old / new:.0f}x")
    print(f"  largest relative difference of the limits: {difference:.1e}")


if __name__ == "__main__":
    main()
