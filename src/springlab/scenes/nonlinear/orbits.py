"""The non-linear spring's conservative part, pure NumPy: potential, equilibria, turning points, and
the energy-integral periods and transit times by tanh-sinh quadrature (module nonlinear's docstring).

    V(x) = k1 x^2 / 2 + k3 x^4 / 4 [J],   E = m v^2 / 2 + V(x)
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np


def potential(x: float | np.ndarray, k1: float, k3: float) -> np.ndarray:
    """Spring potential energy V(x) = k1 x^2 / 2 + k3 x^4 / 4 [J] at stretch x [m]."""
    x = np.asarray(x, float)
    return 0.5 * k1 * x**2 + 0.25 * k3 * x**4


def spring_force(x: float | np.ndarray, k1: float, k3: float) -> np.ndarray:
    """Spring force on the block -(k1 x + k3 x^3) [N] at stretch x [m]."""
    x = np.asarray(x, float)
    return -(k1 * x + k3 * x**3)


def curvature(x: float | np.ndarray, k1: float, k3: float) -> np.ndarray:
    """V''(x) = k1 + 3 k3 x^2 [N/m]: the spring's local stiffness at stretch x [m]."""
    return k1 + 3.0 * k3 * np.asarray(x, float) ** 2


def energy(x: float | np.ndarray, v: float | np.ndarray, mass: float, k1: float, k3: float) -> np.ndarray:
    """Mechanical energy m v^2 / 2 + V(x) [J] at position x [m] and velocity v [m/s]."""
    return 0.5 * mass * np.asarray(v, float) ** 2 + potential(x, k1, k3)


def equilibrium_positions(k1: float, k3: float) -> np.ndarray:
    """Where the spring force vanishes [m], ascending: 0, and +-sqrt(-k1/k3) when k1 k3 < 0."""
    if k1 * k3 < 0:
        side = math.sqrt(-k1 / k3)
        return np.array([-side, 0.0, side])
    return np.array([0.0])


def linear_eigenvalues(mass: float, local_stiffness: float, damping: float) -> tuple[complex, complex]:
    """Roots s [1/s] of m s^2 + d s + V''(x_e) = 0, the linearization about an equilibrium."""
    disc = np.sqrt(complex(damping**2 - 4.0 * mass * local_stiffness))
    return (-damping + disc) / (2.0 * mass), (-damping - disc) / (2.0 * mass)


def equilibrium_kind(eigenvalues: tuple[complex, complex]) -> str:
    """'center', 'stable focus', 'stable node', 'saddle', 'unstable focus/node' or 'degenerate'
    from the two eigenvalues [1/s] of the linearization."""
    s1, s2 = eigenvalues
    scale = max(abs(s1), abs(s2))
    if scale == 0:
        return "degenerate"
    real = [z.real if abs(z.real) > 1e-12 * scale else 0.0 for z in (s1, s2)]
    oscillating = abs(s1.imag) > 1e-12 * scale
    if real[0] * real[1] < 0:
        return "saddle"
    if max(real) == 0 and oscillating:
        return "center"
    if max(real) == 0:
        return "degenerate"
    if max(real) < 0:
        return "stable focus" if oscillating else "stable node"
    return "unstable focus" if oscillating else "unstable node"


def _squared_roots(level: float, k1: float, k3: float) -> tuple[complex, complex]:
    """Roots u of k3 u^2 / 4 + k1 u / 2 - level = 0 (u = x^2 where V(x) = level), without cancellation."""
    a, b, c = 0.25 * k3, 0.5 * k1, -level
    disc = b * b - 4 * a * c
    if disc >= 0:
        q = -0.5 * (b + math.copysign(math.sqrt(disc), b if b != 0 else 1.0))
        if q == 0:
            return 0j, 0j
        return complex(q / a), complex(c / q)
    root = complex(-b, math.sqrt(-disc)) / (2 * a)
    return root, root.conjugate()


def level_crossings(level: float, k1: float, k3: float) -> np.ndarray:
    """Real positions x [m] where V(x) = level, ascending, double roots once."""
    if k3 == 0:
        if k1 == 0 or level / k1 < 0:
            return np.array([])
        r = math.sqrt(2 * level / k1)
        return np.unique([-r, r])
    roots = []
    for u in _squared_roots(level, k1, k3):
        if abs(u.imag) <= 1e-14 * max(abs(u), 1e-300) and u.real >= 0:
            roots += [-math.sqrt(u.real), math.sqrt(u.real)]
    return np.unique(roots)


def crossings_through(x_ref: float, k1: float, k3: float) -> np.ndarray:
    """Real positions x [m] where V(x) = V(x_ref), ascending, double roots once.

    One root pair is +-x_ref itself; the other follows from Vieta (the two values of x^2 add up
    to -2 k1 / k3), so no root is lost to the ill-conditioning of a near-double root.
    """
    squares = [x_ref * x_ref] + ([-2.0 * k1 / k3 - x_ref * x_ref] if k3 != 0 else [])
    roots = [sign * math.sqrt(u) for u in squares if u >= 0 for sign in (-1.0, 1.0)]
    return np.unique(roots)


def gap_below(x_ref: float, x: float | np.ndarray, k1: float, k3: float) -> np.ndarray:
    """V(x_ref) - V(x) [J], factored as (x_ref^2 - x^2) (k1/2 + k3 (x_ref^2 + x^2) / 4): exact
    next to x_ref, and next to a saddle x_ref, where it vanishes quadratically."""
    x = np.asarray(x, float)
    return (x_ref * x_ref - x * x) * (0.5 * k1 + 0.25 * k3 * (x_ref * x_ref + x * x))


def turning_points(x0: float, v0: float, mass: float, k1: float, k3: float) -> tuple[float, float]:
    """(a, b) [m]: the turning points that bracket the motion through (x0, v0); -inf/inf when the
    motion is unbounded on that side, (x0, x0) at an equilibrium."""
    level = float(energy(x0, v0, mass, k1, k3))
    # released from rest, x0 is a turning point: take the roots through it exactly
    roots = crossings_through(x0, k1, k3) if v0 == 0 else level_crossings(level, k1, k3)
    scale = max(abs(x0), math.sqrt(abs(k1 / k3)) if k3 else 0.0, 1e-300)
    near = np.abs(roots - x0) <= 1e-9 * scale
    if v0 == 0:
        force = float(spring_force(x0, k1, k3))
        if force == 0:
            return x0, x0
        others = roots[~near]
        if force > 0:  # x0 is the left turning point
            right = others[others > x0]
            return x0, float(right[0]) if right.size else math.inf
        left = others[others < x0]
        return float(left[-1]) if left.size else -math.inf, x0
    left, right = roots[roots < x0], roots[roots > x0]
    return (float(left[-1]) if left.size else -math.inf, float(right[0]) if right.size else math.inf)


def tanh_sinh(
    integrand: Callable[[np.ndarray, np.ndarray], np.ndarray],
    half_width: float,
    rtol: float = 1e-14,
    max_level: int = 12,
) -> tuple[float, float]:
    """(integral, error estimate) of integrand(left, right) over an interval of half-width
    `half_width`, where left/right are the distances of the abscissa from the interval's ends.

    Tanh-sinh (double-exponential) quadrature: converges double-exponentially for analytic
    integrands even with integrable endpoint singularities, and passes the endpoint distances
    directly (1 -+ tanh computed as 2 / (1 + e^(+-2y))) so nothing cancels next to an end. The
    step halves until two levels agree to `rtol`; the error estimate is their difference.
    """

    def level(step: float) -> float:
        t = np.arange(-4.0, 4.0 + step / 2, step)
        y = 0.5 * math.pi * np.sinh(t)
        with np.errstate(over="ignore"):
            right = half_width * 2.0 / (1.0 + np.exp(2.0 * y))  # half_width (1 - s)
            left = half_width * 2.0 / (1.0 + np.exp(-2.0 * y))  # half_width (1 + s)
            weight = 0.5 * math.pi * np.cosh(t) / np.cosh(y) ** 2
        keep = (left > 0) & (right > 0) & (weight > 0)
        return float(step * half_width * np.sum(weight[keep] * integrand(left[keep], right[keep])))

    step, previous = 0.5, level(0.5)
    for _ in range(max_level):
        step /= 2
        value = level(step)
        error = abs(value - previous)
        if error <= rtol * abs(value):
            break
        previous = value
    return value, error


def oscillation_period(mass: float, k1: float, k3: float, x0: float, v0: float) -> tuple[float, float]:
    """Period [s] of the undamped, unforced motion through (x0, v0) from the energy integral,
    T = 2 int_a^b dx / sqrt(2 (E - V(x)) / m), and its quadrature error estimate [s].

    With the turning points a < b, E - V(x) = (x - a)(b - x) R(x) exactly (R a quadratic, or
    k1/2), so the integrand is 1 / sqrt(2 (x - a)(b - x) R(x) / m): the square-root endpoint
    singularities are factored out and handled by tanh-sinh quadrature, which is also robust
    near the separatrix, where R nearly vanishes at an end and the period grows like a logarithm.
    inf when the motion is unbounded, nan at an equilibrium.
    """
    a, b = turning_points(x0, v0, mass, k1, k3)
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.inf, 0.0
    if a == b:
        return math.nan, 0.0
    if k3 == 0:

        def reduced(x):
            return np.full_like(x, 0.5 * k1)
    else:
        s, p = a + b, a * b
        c = 2.0 * k1 / k3 + s * s - p

        def reduced(x):
            return 0.25 * k3 * (x * x + s * x + c)

    def integrand(left, right):
        x = np.where(left <= right, a + left, b - right)
        return 1.0 / np.sqrt(2.0 * left * right * reduced(x) / mass)

    value, error = tanh_sinh(integrand, 0.5 * (b - a))
    return 2.0 * value, 2.0 * error


def transit_time(mass: float, k1: float, k3: float, x_from: float, v_from: float, x_to: float) -> tuple[float, float]:
    """Time [s] the undamped, unforced block needs from x_from (velocity v_from [m/s], heading for
    x_to) to x_to [m], t = int dx / |v(x)|, and its quadrature error estimate [s].

    v(x)^2 = v_from^2 + 2 (x - x_from) D(x) / m with D the exact divided difference of V, so a
    start at a turning point (v_from = 0) is an integrable 1/sqrt singularity, which the
    tanh-sinh quadrature handles.

    Raises
    ------
    ValueError
        The block turns back before reaching x_to.
    """
    length = x_to - x_from
    if length == 0:
        return 0.0, 0.0

    def divided(x):  # (V(x_from) - V(x)) / (x - x_from), exactly
        return -(x + x_from) * (0.5 * k1 + 0.25 * k3 * (x * x + x_from * x_from))

    def speed_squared(travelled):  # travelled = |x - x_from|
        x = x_from + math.copysign(1.0, length) * travelled
        return v_from**2 + 2.0 * math.copysign(1.0, length) * travelled * divided(x) / mass

    probe = abs(length) * np.linspace(0.0, 1.0, 4001)[1:]
    if np.any(speed_squared(probe) <= 0):
        raise ValueError(f"the block turns back before reaching x = {x_to:g} m")

    def integrand(left, right):
        return 1.0 / np.sqrt(speed_squared(np.where(left <= right, left, abs(length) - right)))

    return tanh_sinh(integrand, 0.5 * abs(length))


def equilibria(m: float, k1: float, k3: float, d: float) -> list[dict]:
    """Every equilibrium with its linearization: x [m], stable, kind, eigenvalues_per_s
    ([real, imaginary] pairs [1/s] of the roots of m s^2 + d s + V''(x) = 0), and omega_rad_s = sqrt(V''/m) (small-oscillation frequency
    without damping, where V'' > 0) or saddle_rate_per_s = sqrt(-V''/m) (where V'' < 0: the
    undamped growth rate, and the slope dv/dx of the separatrices through the saddle)."""
    out = []
    for x_e in equilibrium_positions(k1, k3):
        stiffness = float(curvature(x_e, k1, k3))
        eigenvalues = linear_eigenvalues(m, stiffness, d)
        kind = equilibrium_kind(eigenvalues)
        entry = {
            "x": float(x_e),
            "stable": kind in ("center", "stable focus", "stable node"),
            "kind": kind,
            "eigenvalues_per_s": [[float(s.real), float(s.imag)] for s in eigenvalues],
        }
        if stiffness > 0:
            entry["omega_rad_s"] = math.sqrt(stiffness / m)
        elif stiffness < 0:
            entry["saddle_rate_per_s"] = math.sqrt(-stiffness / m)
        out.append(entry)
    return out


def separatrices(m: float, k1: float, k3: float, points: int = 401) -> list[tuple[np.ndarray, np.ndarray]]:
    """The energy level of every saddle, E = V(x_saddle), as (x [m], v [m/s]) curves: upper
    (v >= 0) and lower branches of each interval where the level lies above V, out to twice
    the farthest equilibrium or level crossing (the branches that leave a softening spring's
    saddles are cut there)."""
    saddles = [x for x in equilibrium_positions(k1, k3) if curvature(x, k1, k3) < 0]
    curves = []
    done: list[float] = []
    for saddle in saddles:
        level = float(potential(saddle, k1, k3))
        if any(abs(level - other) <= 1e-12 * max(abs(level), 1e-300) for other in done):
            continue  # symmetric saddles share one level set
        done.append(level)
        crossings = crossings_through(saddle, k1, k3)
        extent = 2.0 * max(np.max(np.abs(crossings)), np.max(np.abs(equilibrium_positions(k1, k3))))
        edges = np.unique(np.concatenate([[-extent, extent], crossings]))
        for low, high in zip(edges[:-1], edges[1:]):
            if gap_below(saddle, 0.5 * (low + high), k1, k3) <= 0:
                continue
            # cosine spacing: dense where the branch meets the axis
            x = low + (high - low) * 0.5 * (1 - np.cos(np.linspace(0, math.pi, points)))
            x[0], x[-1] = low, high
            v = np.sqrt(np.maximum(2.0 * gap_below(saddle, x, k1, k3) / m, 0.0))
            curves.append((x, v))
            curves.append((x.copy(), -v))
    return curves


def orbit(m: float, k1: float, k3: float, x0: float, v0: float) -> dict:
    """What the unforced, undamped motion through (x0, v0) is: energies, turning points, period."""
    e0 = float(energy(x0, v0, m, k1, k3))
    saddle_levels = [float(potential(x, k1, k3)) for x in equilibrium_positions(k1, k3) if curvature(x, k1, k3) < 0]
    a, b = turning_points(x0, v0, m, k1, k3)
    orbit = {"energy_J": e0, "turning_points_m": [a, b]}
    if saddle_levels:
        orbit["separatrix_energy_J"] = min(saddle_levels, key=lambda s: abs(s - e0))
        wells = [float(potential(x, k1, k3)) for x in equilibrium_positions(k1, k3) if curvature(x, k1, k3) > 0]
        if wells:
            # how much energy a block resting in a well needs to get over the lowest saddle
            orbit["barrier_height_J"] = min(saddle_levels) - min(wells)
    if math.isfinite(a) and math.isfinite(b) and a != b:
        orbit["motion"] = "bounded"
        orbit["period_quadrature_s"], orbit["period_quadrature_error_s"] = oscillation_period(m, k1, k3, x0, v0)
    elif a == b:
        orbit["motion"] = "equilibrium"
    else:
        orbit["motion"] = "unbounded"
    return orbit
