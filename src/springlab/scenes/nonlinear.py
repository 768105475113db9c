"""nonlinear: a mass on a non-linear spring (chapter section 5.5, Fig. 5.20 and 5.21).

    m x'' + d x' + k1 x + k3 x^3 = F(t),   x = stretch of the spring [m], + away from the wall

The spring is MuJoCo's polynomial joint stiffness "k1 0 k3" (force
-(k1 x + k3 x^3), no Python callback). Its potential energy is
V(x) = k1 x^2 / 2 + k3 x^4 / 4 [J], so an unforced, undamped block keeps
E = m v^2 / 2 + V(x).

Parameters (SI): mass [kg], k1 [N/m], k3 [N/m^3], damping d [N s/m]
(mass, k1, k3, damping default to models/nonlinear.xml and are read back from
the compiled model), force_amplitude [N], force_frequency [Hz]
(F(t) = force_amplitude sin(2 pi force_frequency t); a constant force when the
frequency is 0), x0 [m], v0 [m/s].

Scenarios (the chapter asks for none by number; these show what it describes):

* `softening` (default): k1 = 100 N/m, k3 = -1e4 N/m^3, a spring that weakens
  with stretch (Fig. 5.20). Equilibria: 0 (stable, omega = sqrt(k1/m) =
  10 rad/s) and the saddles +-sqrt(-k1/k3) = +-0.1 m where the spring force
  vanishes again. Released at x0 = 0.09 m, inside the separatrix (the orbits
  through the saddles, energy V(0.1 m) = 0.25 J): a bounded, strongly
  anharmonic oscillation whose period comes from the energy integral.
* `softening_escape`: the same spring, launched from 0 at 0.75 m/s, i.e. with
  more energy (0.281 J) than the separatrix: the block passes the saddle and
  escapes. Under x'' = +|k3| x^3 / m it would reach infinity in finite time, so
  the run stops at the escape criterion |x| >= 3 x_saddle (0.3 m, ESCAPE_FACTOR)
  and reports the escape time; this is a result, not a divergence.
* `double_well`: k1 = -100 N/m, k3 = 1e4 N/m^3 (Duffing's double well): stable
  equilibria +-sqrt(-k1/k3) = +-0.1 m with small-oscillation frequency
  omega = sqrt(-2 k1 / m) = 14.1 rad/s, a saddle at 0 (barrier 0.25 J).
  Released at 0.13 m it oscillates inside the right-hand well.
* `forced_duffing`: the double well with damping 2.5 N s/m, forced by
  3 N sin(10 t) (Holmes' chaotic Duffing oscillator x'' + 0.25 x' - x + x^3 =
  0.3 sin t in units of 0.1 m and 0.1 s). Two runs whose initial positions
  differ by 1e-9 m separate to the size of the wells (0.1 m); the scenario
  reports the separation time, the finite-time Lyapunov exponent over it and
  the long-time largest Lyapunov exponent (renormalized pair of runs).

How the force keeps the integrator's order: as in slider.py, a sinusoidal
force comes from an MJCF-native generator, a very heavy exciter body on its
own spring at the forcing frequency, coupled to the block by a fixed tendon
spring whose stiffness is taken out of the joint's k1. The exciter is
integrated by the same integrator (RK4 stays fourth order) and the model stays
batchable. A constant force is a constant control (exact).

How it is validated (no closed-form x(t)): each scenario is held to `checks`,
scalar claims against independent references, each with its tolerance basis:

* linearization: MuJoCo's own acceleration, finite-differenced at every
  equilibrium (centred differences at two steps, Richardson-combined, which is
  exact for a cubic force), gives the linearized frequency (or saddle rate),
  checked against sqrt(|V''(x_e)| / m); tolerance 2 x the differences'
  round-off.
* energy: undamped, unforced runs conserve E; its drift relative to the
  largest kinetic energy of the run (E has an arbitrary zero) must stay within
  ENERGY_DRIFT_LIMIT = 1e-6 (the accuracy springlab promises at the default
  setting).
* period (bounded runs) or escape time (escaping runs): measured from the
  trajectory (cubic Hermite interpolation of the turning points / the escape
  crossing, O(dt^4)) against the energy integral T = 2 int dx / sqrt(2 (E - V) / m)
  by tanh-sinh quadrature with the turning-point factors (x - a)(b - x) taken
  out exactly; tolerance 2 x the Richardson error estimate of
  the measured value (from a second run at dt / 2, order p) + the quadrature's
  own error estimate + 100 eps per step.
* forced runs: the observed order of convergence from runs at dt, dt/2 and
  dt/4 over the first CONVERGENCE_WINDOW seconds (before the chaos amplifies
  the error out of the asymptotic range) against the integrator's order.

Phase plane: `phase_field` (unforced), `equilibria` (with stability from the
Jacobian) and `separatrices` (the energy level of every saddle) for plots.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from .. import exciter
from ..errors import ParameterError
from ..scene import Check, Parameter, Scenario, Scene, Setup
from ..simulate import ORDERS, Trajectory, simulate

#: escape criterion: |x| >= ESCAPE_FACTOR x the saddle distance (or x the start, whichever is larger)
ESCAPE_FACTOR = 3.0
#: promised energy conservation of undamped runs at the default setting [-]
ENERGY_DRIFT_LIMIT = 1e-6
#: initial offset of the second forced run [m]
PERTURBATION = 1e-9
#: forced runs: self-convergence is measured over the first this many seconds [s]
CONVERGENCE_WINDOW = 5.0
#: Lyapunov exponent by renormalization: transient skipped [s], averaging time [s], renormalization interval [s]
LYAPUNOV_TRANSIENT, LYAPUNOV_TIME, LYAPUNOV_INTERVAL = 10.0, 100.0, 1.0
#: accepted deviation of the observed from the formal order of convergence [-]: half an order,
#: halfway to the neighbouring orders, so a genuine loss of order (e.g. a held control) fails
CONVERGENCE_ORDER_TOLERANCE = 0.5
#: forced runs: the trajectory counts as accurate while its Richardson error estimate stays
#: below this fraction of the well size [-]
ACCURACY_FRACTION = 0.01
#: finite-difference step of the linearization, relative to the model's length scale [-]
LINEARIZATION_STEP = 1e-4
#: safety factor on estimated errors (as in springlab.compare)
SAFETY = 2.0
#: round-off allowance per step, relative (as in springlab.compare)
ROUNDOFF_PER_STEP = 100 * np.finfo(float).eps

_EPS = np.finfo(float).eps


# -- the conservative part, pure NumPy ---------------------------------------------


def potential(x, k1: float, k3: float):
    """Spring potential energy V(x) = k1 x^2 / 2 + k3 x^4 / 4 [J] at stretch x [m]."""
    x = np.asarray(x, float)
    return 0.5 * k1 * x**2 + 0.25 * k3 * x**4


def spring_force(x, k1: float, k3: float):
    """Spring force on the block -(k1 x + k3 x^3) [N] at stretch x [m]."""
    x = np.asarray(x, float)
    return -(k1 * x + k3 * x**3)


def curvature(x, k1: float, k3: float):
    """V''(x) = k1 + 3 k3 x^2 [N/m]: the spring's local stiffness at stretch x [m]."""
    return k1 + 3.0 * k3 * np.asarray(x, float) ** 2


def energy(x, v, mass: float, k1: float, k3: float):
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


def equilibrium_kind(eigenvalues) -> str:
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


def gap_below(x_ref: float, x, k1: float, k3: float):
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


def tanh_sinh(integrand, half_width: float, rtol: float = 1e-14, max_level: int = 12) -> tuple[float, float]:
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

    Raises:
      ValueError: the block turns back before reaching x_to.
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


# -- measuring the trajectory ---------------------------------------------------------


def _label(x: float) -> str:
    """A position [m] for a quantity name: '+0.1', '-0.1', '0'."""
    return "0" if x == 0 else f"{x:+.4g}"


def _hermite_root(t0, t1, y0, y1, dy0, dy1, target=0.0) -> float:
    """Time in [t0, t1] [s] where the cubic Hermite interpolant of y (slopes dy) equals target."""
    h = t1 - t0
    p0, p1, m0, m1 = y0 - target, y1 - target, dy0 * h, dy1 * h
    # cubic in s: (2s^3 - 3s^2 + 1) p0 + (s^3 - 2s^2 + s) m0 + (-2s^3 + 3s^2) p1 + (s^3 - s^2) m1
    coefficients = [2 * p0 + m0 - 2 * p1 + m1, -3 * p0 - 2 * m0 + 3 * p1 - m1, m0, p0]
    roots = np.roots(coefficients) if any(coefficients[:3]) else np.array([])
    real = [r.real for r in roots if abs(r.imag) < 1e-9 and -1e-9 <= r.real <= 1 + 1e-9]
    if not real:  # fall back to the linear interpolant
        s = p0 / (p0 - p1) if p0 != p1 else 0.0
    else:
        s = min(real, key=lambda r: abs(r - p0 / (p0 - p1)) if p0 != p1 else r)
    return t0 + s * h


def turning_times(time: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray) -> np.ndarray:
    """Times [s] of the position maxima (v crossing zero downwards), to O(dt^4) by cubic Hermite
    interpolation of v with its derivative a [m/s^2]."""
    down = np.flatnonzero((velocity[:-1] > 0) & (velocity[1:] <= 0))
    return np.array(
        [
            _hermite_root(time[i], time[i + 1], velocity[i], velocity[i + 1], acceleration[i], acceleration[i + 1])
            for i in down
        ]
    )


def measured_period(time, position, velocity, acceleration) -> float:
    """Mean spacing of successive position maxima [s] (nan with fewer than two)."""
    peaks = turning_times(time, velocity, acceleration)
    if len(peaks) < 2:
        return math.nan
    return float((peaks[-1] - peaks[0]) / (len(peaks) - 1))


def crossing_time(time, position, velocity, radius: float) -> float:
    """First time [s] |x| reaches `radius` [m], to O(dt^4) by cubic Hermite interpolation (nan: never)."""
    beyond = np.flatnonzero(np.abs(position) >= radius)
    if not beyond.size or beyond[0] == 0:
        return math.nan if not beyond.size else float(time[0])
    i = int(beyond[0]) - 1
    target = math.copysign(radius, position[i + 1])
    return _hermite_root(time[i], time[i + 1], position[i], position[i + 1], velocity[i], velocity[i + 1], target)


# -- the scene -------------------------------------------------------------------------------


_UNFORCED = {"force_amplitude": 0.0, "damping": 0.0}
_DOUBLE_WELL = {"k1": -100.0, "k3": 1e4}


class Nonlinear(Scene):
    name = "nonlinear"
    title = "mass on a non-linear spring: equilibria, separatrices, escape, chaos (section 5.5)"
    joints = ("block",)
    camera = "side"
    # RK4 at 1 ms: omega dt <= 0.05 everywhere the scenarios go (the stiffest point is the
    # escape radius, |V''|/m = 2600 1/s^2); energy drift stays below 1e-6 of the exchanged energy.
    integrator = "rk4"
    dt = 1e-3
    default_scenario = "softening"
    parameters = {
        p.name: p
        for p in (
            Parameter("mass", "kg", "mass of the block", minimum=0.0, minimum_inclusive=False),
            Parameter("k1", "N/m", "linear spring coefficient (spring force k1 x + k3 x^3)"),
            Parameter("k3", "N/m^3", "cubic spring coefficient (< 0 softening, > 0 hardening)"),
            Parameter("damping", "N s/m", "damper coefficient d", minimum=0.0),
            Parameter("force_amplitude", "N", "amplitude of the applied force", default=0.0),
            Parameter(
                "force_frequency",
                "Hz",
                "frequency of the sinusoidal force (0: constant force)",
                minimum=0.0,
                default=5.0 / math.pi,
            ),
            Parameter("x0", "m", "initial stretch of the spring", default=0.09),
            Parameter("v0", "m/s", "initial velocity", default=0.0),
        )
    }
    scenarios = {
        s.name: s
        for s in (
            Scenario(
                "softening",
                "softening spring released inside the separatrix: bounded, anharmonic",
                5.0,
                {**_UNFORCED, "x0": 0.09, "v0": 0.0},
            ),
            Scenario(
                "softening_escape",
                "softening spring launched above the saddle energy: escapes",
                5.0,
                {**_UNFORCED, "x0": 0.0, "v0": 0.75},
            ),
            Scenario(
                "double_well",
                "Duffing double well (k1 < 0 < k3): oscillation inside one well",
                5.0,
                {**_UNFORCED, **_DOUBLE_WELL, "x0": 0.13, "v0": 0.0},
            ),
            Scenario(
                "forced_duffing",
                "damped, sinusoidally forced double well: chaos, 1e-9 m grows to the wells",
                40.0,
                {
                    **_DOUBLE_WELL,
                    "damping": 2.5,
                    "force_amplitude": 3.0,
                    "force_frequency": 5.0 / math.pi,
                    "x0": 0.1,
                    "v0": 0.0,
                },
            ),
        )
    }

    # -- model ---------------------------------------------------------------

    def model_defaults(self, model: mujoco.MjModel) -> dict[str, float]:
        joint = model.joint("block")
        return {
            "mass": float(model.body("block").mass[0]),
            "k1": float(joint.stiffness[0]),
            "k3": float(model.jnt_stiffnesspoly[joint.id][1]),
            "damping": float(model.dof_damping[joint.dofadr[0]]),
        }

    @staticmethod
    def _forcing(params: dict[str, float]) -> str:
        """'harmonic', 'constant' or 'none' for these parameters."""
        if params["force_amplitude"] == 0.0:
            return "none"
        return "harmonic" if params["force_frequency"] > 0 else "constant"

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], scenario: Scenario) -> None:
        spec.body("block").mass = params["mass"]
        joint = spec.joint("block")
        joint.stiffness = [params["k1"], 0.0, params["k3"]]
        joint.damping = [params["damping"], 0.0, 0.0]
        if self._forcing(params) == "harmonic":
            self._add_exciter(spec, params)

    def _add_exciter(self, spec: mujoco.MjSpec, params: dict[str, float]) -> None:
        """The sinusoidal force generator (springlab.exciter)."""
        omega = 2 * math.pi * params["force_frequency"]
        # everything the exciter drives, as a stiffness scale: the spring at the escape radius too
        reach = ESCAPE_FACTOR * max(abs(params["x0"]), self._length_scale(params))
        driven = (
            abs(params["k1"]) + 3 * abs(params["k3"]) * reach**2 + params["mass"] * omega**2 + params["damping"] * omega
        )
        exciter.add(
            spec,
            "block",
            force_amplitude=params["force_amplitude"],
            force_frequency=params["force_frequency"],
            driven_stiffness=driven,
        )

    @staticmethod
    def _length_scale(params: dict[str, float]) -> float:
        """sqrt(|k1/k3|) [m], the distance of the non-trivial equilibria (0 when k1 or k3 is 0)."""
        return math.sqrt(abs(params["k1"] / params["k3"])) if params["k3"] and params["k1"] else 0.0

    def setup(self, model, params, scenario, steps, dt) -> Setup:
        return self._setup(model, params, params["x0"], params["v0"])

    def _setup(self, model, params, x0: float, v0: float) -> Setup:
        qpos = np.zeros(model.nq)
        qvel = np.zeros(model.nv)
        qpos[model.joint("block").qposadr[0]] = x0
        qvel[model.joint("block").dofadr[0]] = v0
        forcing = self._forcing(params)
        if forcing == "harmonic":
            exciter.start(model, qvel, params["force_frequency"])
        control = np.array([params["force_amplitude"] if forcing == "constant" else 0.0])
        return Setup(qpos=qpos, qvel=qvel, control=control)

    # -- physics read back from the compiled model --------------------------

    @staticmethod
    def physical(model: mujoco.MjModel) -> tuple[float, float, float, float]:
        """(mass [kg], k1 [N/m], k3 [N/m^3], damping [N s/m]) the block sees in `model`.

        k1 includes a coupling tendon's share when the exciter is present.
        """
        joint = model.joint("block")
        # the coupling tendon's coefficient on the block is 1
        k1 = float(joint.stiffness[0]) + exciter.coupling_stiffness(model)
        k2, k3 = (float(c) for c in model.jnt_stiffnesspoly[joint.id])
        if k2 != 0:
            raise ParameterError("the nonlinear scene's spring has no x^2 term (jnt_stiffnesspoly[0] must be 0)")
        return float(model.body("block").mass[0]), k1, k3, float(model.dof_damping[joint.dofadr[0]])

    def escape_radius(self, model: mujoco.MjModel, params: dict[str, float]) -> float:
        """|x| [m] at which a softening spring's block counts as escaped (inf: it cannot escape)."""
        m, k1, k3, d = self.physical(model)
        if k3 >= 0:
            return math.inf
        reach = max(self._length_scale({"k1": k1, "k3": k3}), abs(params["x0"]))
        return ESCAPE_FACTOR * reach if reach > 0 else math.inf

    def can_escape(self, model: mujoco.MjModel, params: dict[str, float]) -> bool:
        """Whether the block can physically reach the escape radius: not if the run is unforced
        and the undamped orbit through (x0, v0) is bounded (damping only lowers the energy)."""
        if not math.isfinite(self.escape_radius(model, params)):
            return False
        if self._forcing(params) != "none":
            return True
        m, k1, k3, d = self.physical(model)
        a, b = turning_points(params["x0"], params["v0"], m, k1, k3)
        return not (math.isfinite(a) and math.isfinite(b))

    def stop_condition(self, model, params, scenario):
        # a bounded orbit that reaches the radius is a numerical blow-up, left to divergence detection
        if not self.can_escape(model, params):
            return None
        radius = self.escape_radius(model, params)
        column = model.joint("block").qposadr[0]
        return lambda qpos, qvel: np.abs(qpos[:, column]) >= radius

    def modes(self, model, params, scenario) -> list[tuple[float, float]]:
        m, k1, k3, d = self.physical(model)
        modes = []
        for x_e in equilibrium_positions(k1, k3):
            stiffness = abs(float(curvature(x_e, k1, k3)))
            if stiffness > 0:
                modes.append((math.sqrt(stiffness / m), d / (2 * math.sqrt(stiffness * m))))
        # the stiffest point the block can reach: the escape radius, or the bounded orbit's turning points
        if self.can_escape(model, params):
            reach = self.escape_radius(model, params)
        else:
            a, b = turning_points(params["x0"], params["v0"], m, k1, k3)
            bounded = math.isfinite(a) and math.isfinite(b)
            reach = max(abs(a), abs(b)) if bounded else 1.5 * max(abs(params["x0"]), self._length_scale(params))
        stiffness = abs(float(curvature(reach, k1, k3)))
        if stiffness > 0:
            modes.append((math.sqrt(stiffness / m), d / (2 * math.sqrt(stiffness * m))))
        if self._forcing(params) == "harmonic":
            modes.append((2 * math.pi * params["force_frequency"], 0.0))  # the exciter
        return modes

    # -- phase plane -----------------------------------------------------------

    def phase_field(self, model, params, scenario):
        m, k1, k3, d = self.physical(model)

        def field(x, v):
            x, v = np.asarray(x, float), np.asarray(v, float)
            return v + 0.0 * x, (spring_force(x, k1, k3) - d * v) / m

        return field

    def equilibria(self, model, params, scenario) -> list[dict]:
        """Every equilibrium with its linearization: x [m], stable, kind, eigenvalues_per_s
        ([real, imaginary] pairs [1/s] of the roots of m s^2 + d s + V''(x) = 0), and omega_rad_s = sqrt(V''/m) (small-oscillation frequency
        without damping, where V'' > 0) or saddle_rate_per_s = sqrt(-V''/m) (where V'' < 0: the
        undamped growth rate, and the slope dv/dx of the separatrices through the saddle)."""
        m, k1, k3, d = self.physical(model)
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

    def separatrices(self, model, params, scenario, points: int = 401) -> list[tuple[np.ndarray, np.ndarray]]:
        """The energy level of every saddle, E = V(x_saddle), as (x [m], v [m/s]) curves: upper
        (v >= 0) and lower branches of each interval where the level lies above V, out to twice
        the farthest equilibrium or level crossing (the branches that leave a softening spring's
        saddles are cut there)."""
        m, k1, k3, d = self.physical(model)
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

    # -- linearization through MuJoCo ---------------------------------------------

    def mujoco_jacobian(self, model: mujoco.MjModel, x_e: float, step: float) -> np.ndarray:
        """[[0, 1], [da/dx, da/dv]] [1/s^2, 1/s]: MuJoCo's block acceleration a = qacc linearized at
        (x_e [m], v = 0), an exciter (if any) at rest.

        da/dx: centred differences with steps `step` and step/2 [m], Richardson-combined, which is
        exact (to round-off) for a force polynomial of degree <= 4; da/dv: a centred difference
        (exact for linear damping).
        """
        data = mujoco.MjData(model)
        qpos_adr, dof = model.joint("block").qposadr[0], model.joint("block").dofadr[0]

        def acceleration(x, v):
            data.qpos[:] = 0.0
            data.qvel[:] = 0.0
            data.qpos[qpos_adr], data.qvel[dof] = x, v
            mujoco.mj_forward(model, data)
            return float(data.qacc[dof])

        def centred(h):
            return (acceleration(x_e + h, 0.0) - acceleration(x_e - h, 0.0)) / (2 * h)

        # the 'discrete' integrator folds h^2 K into qacc itself; the continuous dynamics is
        # what every explicit setting's forward pass computes
        integrator = model.opt.integrator
        model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
        try:
            da_dx = (4 * centred(step / 2) - centred(step)) / 3
            velocity_step = 1.0  # [m/s]; the damping force is linear in v
            da_dv = (acceleration(x_e, velocity_step) - acceleration(x_e, -velocity_step)) / (2 * velocity_step)
        finally:
            model.opt.integrator = integrator
        return np.array([[0.0, 1.0], [da_dx, da_dv]])

    def _linearization_checks(self, model, params) -> list[Check]:
        m, k1, k3, d = self.physical(model)
        scale = max(self._length_scale({"k1": k1, "k3": k3}), abs(params["x0"]), 1e-3)
        step = LINEARIZATION_STEP * scale
        checks = []
        for x_e in equilibrium_positions(k1, k3):
            stiffness = float(curvature(x_e, k1, k3))
            if stiffness == 0:
                continue
            jacobian = self.mujoco_jacobian(model, x_e, step)
            # round-off of the Richardson-combined differences: (4 x 2 / h + 2 / h) / 3 = 10/3 eps |a| / h,
            # |a| the largest acceleration at the probes; allow 10 eps per evaluation of MuJoCo's force
            probe = abs(x_e) + step
            largest = (abs(k1) * probe + abs(k3) * probe**3) / m
            relative = 10 * (10 / 3) * _EPS * largest / step / (abs(stiffness) / m) + 100 * _EPS
            name = f"omega_at_{_label(x_e)}_m_rad_s" if stiffness > 0 else f"saddle_rate_at_{_label(x_e)}_m_per_s"
            checks.append(
                Check(
                    name=name,
                    value=math.sqrt(abs(jacobian[1, 0])),
                    reference=math.sqrt(abs(stiffness) / m),
                    # a square root halves a relative error
                    tolerance=SAFETY * 0.5 * relative,
                    basis="MuJoCo's qacc linearized by Richardson-combined centred differences (exact for a cubic"
                    " force): 2 x its round-off, against sqrt(|k1 + 3 k3 x^2| / m)",
                )
            )
        return checks

    # -- re-running for error estimates -------------------------------------------

    def _rerun(
        self,
        params,
        scenario,
        integrator: str,
        dt: float,
        duration: float,
        x0: float | None = None,
        v0: float | None = None,
        state: tuple | None = None,
        model: mujoco.MjModel | None = None,
    ) -> Trajectory:
        """Another run of the same scene, optionally from another block state or from a full
        (qpos, qvel) state; on a fresh model unless one is given (simulate sets its timestep)."""
        model = self.build(params, scenario) if model is None else model
        if state is not None:
            qpos, qvel = state
            setup = Setup(qpos=qpos, qvel=qvel, control=self._setup(model, params, 0.0, 0.0).control)
        else:
            setup = self._setup(model, params, params["x0"] if x0 is None else x0, params["v0"] if v0 is None else v0)
        return simulate(
            model,
            integrator=integrator,
            dt=dt,
            duration=duration,
            qpos=setup.qpos,
            qvel=setup.qvel,
            control=setup.control,
            stop=self.stop_condition(model, params, scenario),
        )

    def _block(self, model, trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]:
        j = model.joint("block")
        return trajectory.qpos[:, j.qposadr[0]], trajectory.qvel[:, j.dofadr[0]]

    # -- results -------------------------------------------------------------

    def _orbit(self, model, params) -> dict:
        """What the unforced, undamped motion through (x0, v0) is: energies, turning points, period."""
        m, k1, k3, d = self.physical(model)
        x0, v0 = params["x0"], params["v0"]
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

    def quantities(self, model, params, scenario, trajectory: Trajectory) -> dict:
        m, k1, k3, d = self.physical(model)
        x, v = self._block(model, trajectory)
        equilibria = self.equilibria(model, params, scenario)
        out: dict = {
            "equilibria_m": [e["x"] for e in equilibria],
            "equilibrium_kinds": [e["kind"] for e in equilibria],
            "stable_equilibria_m": [e["x"] for e in equilibria if e["stable"]],
        }
        for e in equilibria:
            if "omega_rad_s" in e:
                out[f"omega_at_{_label(e['x'])}_m_rad_s"] = e["omega_rad_s"]
            if "saddle_rate_per_s" in e:
                out[f"saddle_rate_at_{_label(e['x'])}_m_per_s"] = e["saddle_rate_per_s"]
        if k3 != 0 and k1 != 0:
            out["saddle_or_well_distance_m"] = self._length_scale({"k1": k1, "k3": k3})
        if k3 < 0 < k1:
            # the softening spring's force peaks where V'' = 0 (Fig. 5.20)
            x_peak = math.sqrt(k1 / (-3 * k3))
            out["peak_spring_force_N"] = float(-spring_force(x_peak, k1, k3))
            out["peak_force_stretch_m"] = x_peak
        unforced = d == 0 and self._forcing(params) == "none"
        if unforced:
            out.update(self._orbit(model, params))
            if out["motion"] == "bounded":
                out["period_simulated_s"] = measured_period(trajectory.time, x, v, self._acceleration(model, x, v))
            e = energy(x, v, m, k1, k3)
            out["energy_drift_relative"] = float(np.max(np.abs(e - e[0])) / max(np.max(0.5 * m * v**2), 1e-300))
        out["max_displacement_m"] = float(np.max(np.abs(x)))
        radius = self.escape_radius(model, params)
        if math.isfinite(radius):
            out["escape_radius_m"] = radius
            out["escaped"] = bool(trajectory.stopped)
            if trajectory.stopped:
                out["escape_time_s"] = crossing_time(trajectory.time, x, v, radius)
                if unforced:
                    try:
                        out["escape_time_quadrature_s"] = transit_time(
                            m, k1, k3, params["x0"], params["v0"], math.copysign(radius, x[-1])
                        )[0]
                    except ValueError:
                        pass
        if self._forcing(params) == "harmonic" and d > 0:
            out.update(self._chaos(model, params, scenario, trajectory))
        return out

    def _acceleration(self, model, x, v):
        m, k1, k3, d = self.physical(model)
        return (spring_force(x, k1, k3) - d * v) / m

    def _well_size(self, params: dict[str, float], model) -> float:
        """The distance from the saddle to a well [m] (or the largest displacement without wells)."""
        m, k1, k3, d = self.physical(model)
        return self._length_scale({"k1": k1, "k3": k3}) or max(abs(params["x0"]), 1e-3)

    def _chaos(self, model, params, scenario, trajectory: Trajectory) -> dict:
        """Sensitivity to initial conditions: a second run from x0 + PERTURBATION."""
        m, k1, k3, d = self.physical(model)
        x, v = self._block(model, trajectory)
        duration = float(trajectory.time[-1])
        twin = self._rerun(
            params, scenario, trajectory.integrator, trajectory.dt, duration, x0=params["x0"] + PERTURBATION
        )
        x2, v2 = self._block(model, twin)
        n = min(len(x), len(x2))
        well = self._well_size(params, model)
        omega = math.sqrt(abs(float(curvature(well, k1, k3))) / m) or 1.0
        separation = np.abs(x2[:n] - x[:n])
        distance = np.hypot(x2[:n] - x[:n], (v2[:n] - v[:n]) / omega)
        out = {"perturbation_m": PERTURBATION, "well_size_m": well}
        apart = np.flatnonzero(separation >= well)
        if apart.size:
            i = int(apart[0])
            t_sep = float(trajectory.time[i])
            out["separation_time_s"] = t_sep
            out["ftle_per_s"] = float(math.log(distance[i] / PERTURBATION) / t_sep)
        else:
            out["separation_time_s"] = math.inf
        # how long this trajectory itself is right: Richardson estimate from a run at dt/2
        order = ORDERS[trajectory.integrator]
        half = self._rerun(params, scenario, trajectory.integrator, trajectory.dt / 2, duration)
        xh = self._block(model, half)[0][::2]
        n = min(len(x), len(xh))
        estimate = 2**order / (2**order - 1) * np.abs(x[:n] - xh[:n])
        wrong = np.flatnonzero(estimate > ACCURACY_FRACTION * well)
        out["accurate_until_s"] = float(trajectory.time[wrong[0]]) if wrong.size else float(trajectory.time[n - 1])
        out["lyapunov_exponent_per_s"], out["lyapunov_standard_error_per_s"] = self.lyapunov_exponent(
            params, scenario, trajectory.integrator, trajectory.dt
        )
        return out

    def lyapunov_exponent(
        self,
        params,
        scenario,
        integrator: str,
        dt: float,
        transient: float = LYAPUNOV_TRANSIENT,
        total: float = LYAPUNOV_TIME,
        interval: float = LYAPUNOV_INTERVAL,
    ) -> tuple[float, float]:
        """Largest Lyapunov exponent [1/s] by Benettin's renormalization, and its standard error [1/s].

        A companion run PERTURBATION away (in the block's (x, v / omega) plane) is pulled back
        to that distance every `interval` [s]; the exponent is the mean log growth per second
        over `total` [s] after `transient` [s]. The standard error treats the segments' growth
        rates as independent, so it is a statistical uncertainty of a finite average, not a bound.
        """
        model = self.build(params, scenario)
        m, k1, k3, d = self.physical(model)
        omega = math.sqrt(abs(float(curvature(self._well_size(params, model), k1, k3))) / m) or 1.0
        qpos_adr, dof = model.joint("block").qposadr[0], model.joint("block").dofadr[0]
        lead = self._rerun(params, scenario, integrator, dt, transient)
        state = (lead.qpos[-1].copy(), lead.qvel[-1].copy())
        twin = (state[0].copy(), state[1].copy())
        twin[0][qpos_adr] += PERTURBATION
        rates = []
        segments = max(1, round(total / interval))
        for _ in range(segments):
            lead = self._rerun(params, scenario, integrator, dt, interval, state=state, model=model)
            follow = self._rerun(params, scenario, integrator, dt, interval, state=twin, model=model)
            state = (lead.qpos[-1].copy(), lead.qvel[-1].copy())
            dx = follow.qpos[-1][qpos_adr] - state[0][qpos_adr]
            dv = follow.qvel[-1][dof] - state[1][dof]
            distance = math.hypot(dx, dv / omega)
            rates.append(math.log(distance / PERTURBATION) / interval)
            # the companion restarts on the same exciter state, PERTURBATION away along the current direction
            twin = (state[0].copy(), state[1].copy())
            twin[0][qpos_adr] += dx * PERTURBATION / distance
            twin[1][dof] += dv * PERTURBATION / distance
        rates = np.array(rates)
        return float(np.mean(rates)), float(np.std(rates, ddof=1) / math.sqrt(len(rates))) if len(
            rates
        ) > 1 else math.inf

    # -- validation ------------------------------------------------------------------

    def checks(self, model, params, scenario, trajectory: Trajectory) -> list[Check]:
        m, k1, k3, d = self.physical(model)
        out = self._linearization_checks(model, params)
        integrator, dt = trajectory.integrator, trajectory.dt
        order = ORDERS[integrator]
        richardson = 2**order / (2**order - 1)
        floor = ROUNDOFF_PER_STEP * trajectory.steps
        unforced = d == 0 and self._forcing(params) == "none"
        x, v = self._block(model, trajectory)
        if unforced:
            e = energy(x, v, m, k1, k3)
            drift = float(np.max(np.abs(e - e[0])) / max(np.max(0.5 * m * v**2), 1e-300))
            out.append(
                Check(
                    "energy_drift_relative",
                    drift,
                    0.0,
                    ENERGY_DRIFT_LIMIT,
                    "springlab's promise for undamped runs at the default setting: |E - E0| <="
                    " 1e-6 x the largest kinetic energy",
                )
            )
            orbit = self._orbit(model, params)
            duration = float(trajectory.time[-1])
            if orbit["motion"] == "bounded":
                period = measured_period(trajectory.time, x, v, self._acceleration(model, x, v))
                half = self._rerun(params, scenario, integrator, dt / 2, duration)
                xh, vh = self._block(model, half)
                period_half = measured_period(half.time, xh, vh, self._acceleration(model, xh, vh))
                estimate = richardson * abs(period - period_half)
                reference = orbit["period_quadrature_s"]
                if not math.isfinite(period):  # fewer than two maxima in the run: nothing to measure
                    return out
                out.append(
                    Check(
                        "period_s",
                        period,
                        reference,
                        (SAFETY * estimate + orbit["period_quadrature_error_s"]) / reference + floor,
                        f"2 x the Richardson error estimate of the measured period (runs at dt and dt/2, order {order})"
                        " + quadrature error + 100 eps per step, against the energy integral by quadrature",
                    )
                )
            if trajectory.stopped:
                radius = self.escape_radius(model, params)
                escape = crossing_time(trajectory.time, x, v, radius)
                half = self._rerun(params, scenario, integrator, dt / 2, duration)
                xh, vh = self._block(model, half)
                escape_half = crossing_time(half.time, xh, vh, radius)
                try:
                    reference, quad_error = transit_time(
                        m, k1, k3, params["x0"], params["v0"], math.copysign(radius, x[-1])
                    )
                except ValueError:
                    reference, quad_error = math.nan, 0.0
                out.append(
                    Check(
                        "escape_time_s",
                        escape,
                        reference,
                        (SAFETY * richardson * abs(escape - escape_half) + quad_error) / reference + floor,
                        f"2 x the Richardson error estimate of the measured escape time (dt and dt/2, order {order})"
                        " + quadrature error + 100 eps per step, against int dx / v(x) by quadrature",
                    )
                )
        elif self._forcing(params) != "none":
            out.append(self._convergence_check(params, scenario, integrator, dt, float(trajectory.time[-1])))
        return out

    def _convergence_check(self, params, scenario, integrator: str, dt: float, duration: float) -> Check:
        """Observed order of convergence from runs at dt, dt/2 and dt/4 over CONVERGENCE_WINDOW."""
        window = min(CONVERGENCE_WINDOW, duration)
        runs = [self._rerun(params, scenario, integrator, dt / 2**i, window) for i in range(3)]
        model = self.build(params, scenario)
        positions = [self._block(model, run)[0][:: 2**i] for i, run in enumerate(runs)]
        n = min(len(p) for p in positions)
        coarse = float(np.max(np.abs(positions[0][:n] - positions[1][:n])))
        fine = float(np.max(np.abs(positions[1][:n] - positions[2][:n])))
        observed = math.log2(coarse / fine) if fine > 0 and coarse > 0 else math.nan
        order = ORDERS[integrator]
        return Check(
            "observed_order",
            observed,
            float(order),
            CONVERGENCE_ORDER_TOLERANCE / order,
            f"no closed form: |x(dt) - x(dt/2)| / |x(dt/2) - x(dt/4)| over the first {window:g} s must"
            f" show the integrator's order {order} within +-{CONVERGENCE_ORDER_TOLERANCE:g}",
            certifies_error=False,  # a diagnostic of convergence, not an error of the motion
        )


SCENE = Nonlinear()
