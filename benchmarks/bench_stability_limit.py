"""Cost of the RK4 stability limit, the scalar scan it was against the vectorised one it is.

The stability chart draws the theory boundary at 201 damping ratios per
integrator. The old rk4 limit scanned up to 3000 omega*dt values one Python
call at a time, then bisected (about 3000 calls per zeta, 605k for the chart);
simulate.stability_limit now evaluates the scan as one array and bisects with
one call per step. Both give the same limit (printed: largest relative difference).

Its row, `stability limit rk4`, is the vectorised limit per damping ratio against the same scan and bisection done
as one numpy computation over every damping ratio (the bare numpy cost of the same answer). Not in `make bench`'s
default run: the table's `stability` row times the whole command that draws these limits (`bench.py --only
bench_stability_limit` runs it).

Run: python benchmarks/bench_stability_limit.py
"""

from __future__ import annotations

import math

import numpy as np

import measure
from springlab.exact.limits import _rk4_amplification, _unit_oscillator_roots, stability_limit
from timing import best_of

ZETAS = np.concatenate([[0.0], np.geomspace(1e-2, 100.0, 200)])
#: one call per damping ratio against all of them at once: the same arithmetic (each call's scan is one array), and
#: per call its Python and 60 bisection steps of numpy on one value (12,000 small calls over the panel, about as much
#: time again as the arithmetic): within 3x
LIMIT_BUDGET = 3.0


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


def all_at_once(zetas: np.ndarray) -> np.ndarray:
    """The same limits as one numpy computation over every zeta: the scan as one (zetas, 3000, 2) array, then the
    60 bisection steps each one array operation over the zetas (the bare numpy cost of the same answer)."""
    roots = np.array([_unit_oscillator_roots(float(z)) for z in zetas])
    fastest = np.maximum(1.0, np.max(np.abs(roots), axis=1))

    def unstable(h: np.ndarray) -> np.ndarray:
        return np.max(np.abs(_rk4_amplification(h[..., None] * roots[:, None, :])), axis=-1) > 1 + 1e-13

    grid = np.linspace(1e-3, 3.0, 3000)[None, :] / fastest[:, None]
    hits = unstable(grid)
    found = hits.any(axis=1)
    first = grid[np.arange(len(zetas)), np.argmax(hits, axis=1)]
    low, high = first - (grid[:, 1] - grid[:, 0]), first
    for _ in range(60):
        mid = 0.5 * (low + high)
        bad = unstable(mid[:, None])[:, 0]
        low, high = np.where(bad, low, mid), np.where(bad, mid, high)
    return np.where(found, low, np.inf)


def main() -> None:
    old = best_of(lambda: [scalar_rk4_limit(float(z)) for z in ZETAS], repeat=3)
    (new, new_cpu), (floor_wall, floor_cpu) = measure.side_by_side(
        [lambda: [stability_limit("rk4", float(z)) for z in ZETAS], lambda: all_at_once(ZETAS)], 3
    )
    limits = np.array([stability_limit("rk4", float(z)) for z in ZETAS])
    assert np.allclose(all_at_once(ZETAS), limits, rtol=1e-12), "the floor computes another answer"
    difference = max(
        abs(stability_limit("rk4", float(z)) - scalar_rk4_limit(float(z))) / scalar_rk4_limit(float(z)) for z in ZETAS
    )
    print(f"rk4 stability limit at {ZETAS.size} damping ratios (one chart panel)")
    print(f"  scalar scan   {old:8.3f} s")
    print(f"  vectorised    {new:8.3f} s   ratio {old / new:.0f}x")
    print(f"  largest relative difference of the limits: {difference:.1e}")

    measure.emit(
        measure.Row(
            "stability limit rk4",
            f"RK4's stability limit at {ZETAS.size} damping ratios (one chart panel)",
            new,
            new_cpu,
            "numpy",
            floor_wall,
            floor_cpu,
            LIMIT_BUDGET,
            "(set)",
            "bench_stability_limit.py: springlab.exact.limits.stability_limit per damping ratio against the same"
            f" scan and bisection as one numpy computation over all of them; the scalar scan it replaced {old:.3g} s",
        )
    )


if __name__ == "__main__":
    main()
