"""A taut cable (a string under tension) and its N-element lumped model, exactly: modes, a damper, rain-wind.

The cable: tension T [N], mass per length m [kg/m], length L [m] between two fixed anchors, transverse
deflection y(x, t) small (m y_tt = T y_xx); wave speed c = sqrt(T / m), impedance sqrt(T m) [N s/m].

* **Continuum modes**: y_n = sin(n pi x / L), omega_n = n pi c / L, f_n = n / (2 L) sqrt(T / m).
* **The N-element model** (the MJCF the scene generates): N moving masses m dx at x_j = j dx, j = 1 ... N,
  dx = L / (N + 1) (the anchors are the nodes 0 and N + 1), neighbours joined by springs T / dx (the string's
  restoring force, T times the difference of slopes, lumped at the nodes). K = (T / dx) tridiag(-1, 2, -1).
  The discrete sines phi_k(j) = sin(j k pi / (N + 1)) are its exact modes (they sample the continuum's), with
  omega_k = (2 c / dx) sin(k pi / (2 (N + 1))): lumped / continuum = sin(theta) / theta with
  theta = k pi / (2 (N + 1)), an error -theta^2 / 6 = -(k pi)^2 / (24 (N + 1)^2) + O(N^-4).
* **A viscous damper** of coefficient c_d [N s/m] at distance a from the anchor x = 0: the string on both sides
  of it, y = A sin(beta x) for x < a and B sin(beta (L - x)) for x > a, continuous at a, with the slope jump
  T [y_x(a+) - y_x(a-)] = c_d y_t(a). With y ~ exp(lambda t), lambda = i c beta, and eta = c_d / sqrt(T m):
  sin(beta L) + i eta sin(beta a) sin(beta (L - a)) = 0 (docs/scenes/stay_cable.md derives it). Its root
  x = beta L near n pi is mode n: lambda_n = i c x / L, damping ratio zeta_n = Im(x) / |x|. Rearranged exactly,
  tan(delta) = i eta sin^2(eps) / (1 + i eta sin(eps) cos(eps)), x = n pi + delta, eps = (a / L) x; for small
  a / L this gives the universal curve zeta_n / (a / L) = kappa / (1 + kappa^2), kappa = eta n pi a / L
  (Pacheco, Fujino and Sulekh 1993; Krenk 2000): the best damper kappa = 1, c_opt = sqrt(T m) L / (n pi a),
  gives zeta_max = a / (2 L). Carried one order further (derived in the docs) the curve gains
  (a / L) 4 kappa^3 / (1 + kappa^2)^3: the universal maximum is low by the relative amount a / L, and the
  optimum's position moves only at second order.
* **Damping in the N-element model**: intrinsic damping uniform along the cable (a viscous force per unit
  length c_s = 2 m zeta_s omega_1 towards the still air, omega_1 the continuum's: mode 1 has the ratio zeta_s,
  mode n about zeta_s / n); the damper at the node nearest a; rain-wind's aerodynamic damping as a modal
  damping of ratio zeta_a (negative) on each of the first modes (`aero_mode_damping`).

Pure numpy / scipy: the MuJoCo side (springlab.scenes.stay_cable.build) writes these values into the MJCF
and the comparisons read them back from the compiled model.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence

import numpy as np

from springlab.errors import ParameterError

from . import linear

_EPS = float(np.finfo(float).eps)
#: Newton steps allowed per continuation point of the damped root (it converges quadratically in 3-6)
_NEWTON_STEPS = 60
#: continuation points from a tiny damper up to the asked one (geometric in eta)
_CONTINUATION_POINTS = 48
#: a Newton step on the lumped determinant this small (relative) is followed by one more, the last
_CLOSE = 1e-9


def _optimize():  # noqa: ANN202 - the module
    """scipy.optimize, imported on first use: the scene registry imports this module, and every command the registry."""
    import scipy.optimize

    return scipy.optimize


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ParameterError(f"{name} must be a finite number > 0, got {value!r}")
    return value


def whole_elements(n_elements: float) -> int:
    """N as an int, or ParameterError if it is not a whole number >= 2."""
    if not (math.isfinite(n_elements) and int(n_elements) == n_elements and n_elements >= 2):
        raise ParameterError(f"n_elements must be a whole number >= 2, got {n_elements!r}")
    return int(n_elements)


@dataclasses.dataclass(frozen=True)
class TautCable:
    """A taut string: length [m], tension [N], mass per length [kg/m] (all finite, > 0).

    Raises
    ------
    ParameterError
        a value that is not a finite number > 0.
    """

    length: float
    tension: float
    mass_per_length: float

    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):
            _positive(field.name, getattr(self, field.name))

    @property
    def wave_speed(self) -> float:
        """c = sqrt(T / m) [m/s]."""
        return math.sqrt(self.tension / self.mass_per_length)

    @property
    def impedance(self) -> float:
        """sqrt(T m) [N s/m]: the damper coefficient that absorbs a travelling wave completely."""
        return math.sqrt(self.tension * self.mass_per_length)

    def omega(self, modes: int) -> np.ndarray:
        """omega_n = n pi c / L [rad/s] of the continuum, n = 1 ... modes."""
        return np.arange(1, modes + 1) * math.pi * self.wave_speed / self.length

    def frequencies_hz(self, modes: int) -> np.ndarray:
        """f_n = n / (2 L) sqrt(T / m) [Hz], n = 1 ... modes."""
        return np.arange(1, modes + 1) * self.wave_speed / (2.0 * self.length)

    # -- the N-element model ------------------------------------------------------------------

    def spacing(self, n_elements: int) -> float:
        """dx = L / (N + 1) [m]: N moving nodes between the two anchors."""
        return self.length / (whole_elements(n_elements) + 1)

    def node_positions(self, n_elements: int) -> np.ndarray:
        """x_j = j dx [m], j = 1 ... N."""
        return np.arange(1, whole_elements(n_elements) + 1) * self.spacing(n_elements)

    def node_mass(self, n_elements: int) -> float:
        """m dx [kg]: every moving node's share of the cable."""
        return self.mass_per_length * self.spacing(n_elements)

    def segment_stiffness(self, n_elements: int) -> float:
        """T / dx [N/m]: the spring between neighbouring nodes (and between an anchor and its node)."""
        return self.tension / self.spacing(n_elements)

    def lumped_matrices(self, n_elements: int) -> tuple[np.ndarray, np.ndarray]:
        """(mass (N,) [kg], K (N, N) [N/m]) of the N-element model: M = m dx I, K = (T / dx) tridiag(-1, 2, -1)."""
        n = whole_elements(n_elements)
        k = self.segment_stiffness(n)
        stiffness = 2.0 * k * np.eye(n) - k * np.eye(n, k=1) - k * np.eye(n, k=-1)
        return np.full(n, self.node_mass(n)), stiffness

    def lumped_omega(self, n_elements: int, modes: int | None = None) -> np.ndarray:
        """omega_k = (2 c / dx) sin(k pi / (2 (N + 1))) [rad/s], k = 1 ... modes (default N): the closed form."""
        n = whole_elements(n_elements)
        k = np.arange(1, (n if modes is None else modes) + 1)
        return 2.0 * self.wave_speed / self.spacing(n) * np.sin(k * math.pi / (2.0 * (n + 1)))

    def damper_node(self, n_elements: int, position: float) -> int:
        """The node (1 ... N) nearest `position` [m from the anchor x = 0], where the model puts the damper.

        Raises
        ------
        ParameterError
            a position not strictly inside the cable (0 < a < L).
        """
        position = float(position)
        if not (math.isfinite(position) and 0.0 < position < self.length):
            raise ParameterError(
                f"damper_position must lie inside the cable, 0 < a < {self.length:g} m, got {position!r}"
            )
        n = whole_elements(n_elements)
        return int(min(max(round(position / self.spacing(n)), 1), n))

    def structural_node_damping(self, n_elements: int, ratio: float) -> float:
        """Each node's viscous damping [N s/m] for the intrinsic ratio `ratio` of mode 1.

        c_s dx with c_s = 2 m zeta_s omega_1 (omega_1 the continuum's) per unit length: a damping
        proportional to mass, so mode k of the model has the ratio zeta_s omega_1 / omega_k.
        """
        return 2.0 * float(ratio) * self.mass_per_length * float(self.omega(1)[0]) * self.spacing(n_elements)

    def aero_mode_damping(self, n_elements: int, ratio: float, mode: int) -> float:
        """The damping [N s/m] of a tendon with coefficients sin(j k pi / (N + 1)) that gives mode k the ratio `ratio`.

        With mass-normalized modes phi_k = s_k / sqrt(m dx (N + 1) / 2) (sum_j sin^2 = (N + 1) / 2), the modal
        damping 2 zeta omega_k M phi_k phi_k^T M is d s_k s_k^T with d = 4 zeta omega_k m dx / (N + 1), omega_k the
        model's own (closed form): in the model without other damping, mode k decays (or grows) at exactly zeta.
        """
        n = whole_elements(n_elements)
        omega = float(self.lumped_omega(n, mode)[mode - 1])
        return 4.0 * float(ratio) * omega * self.node_mass(n) / (n + 1)


def mode_shape(n_elements: int, mode: int) -> np.ndarray:
    """sin(j k pi / (N + 1)) [-], j = 1 ... N: mode k of the N-element model (and the continuum's, sampled)."""
    n = whole_elements(n_elements)
    return np.sin(np.arange(1, n + 1) * mode * math.pi / (n + 1))


def lumped_relative_error(n_elements: int, mode: int) -> float:
    """omega_k(N) / omega_k(continuum) - 1 = sin(theta) / theta - 1, theta = k pi / (2 (N + 1)) [-], exactly."""
    theta = mode * math.pi / (2.0 * (whole_elements(n_elements) + 1))
    return math.sin(theta) / theta - 1.0


def lumped_relative_error_leading(n_elements: int, mode: int) -> float:
    """The leading term -(k pi)^2 / (24 (N + 1)^2) of `lumped_relative_error` [-] (next term +theta^4 / 120)."""
    return -((mode * math.pi) ** 2) / (24.0 * (whole_elements(n_elements) + 1) ** 2)


# -- the N-element model with damping: complex modes ------------------------------------------------


@dataclasses.dataclass(frozen=True)
class ComplexModes:
    """The eigenvalues of a damped linear model: its oscillatory modes and its overdamped ones.

    Attributes
    ----------
    oscillatory
        lambda_k [1/s] with Im > 0 (one per complex pair), slowest first: mode k is oscillatory[k - 1].
    overdamped
        the real eigenvalues [1/s] (a damper stiff enough pins a node and makes a local overdamped motion
        beside it; the continuum has one too once eta > 2), most negative last.
    """

    oscillatory: np.ndarray
    overdamped: np.ndarray

    @property
    def frequencies_hz(self) -> np.ndarray:
        """|lambda| / (2 pi) [Hz]: the natural frequency of each oscillatory mode."""
        return np.abs(self.oscillatory) / (2.0 * math.pi)

    @property
    def damping_ratios(self) -> np.ndarray:
        """-Re(lambda) / |lambda| [-] of each oscillatory mode."""
        return -self.oscillatory.real / np.abs(self.oscillatory)

    @property
    def growth_rate(self) -> float:
        """max Re(lambda) [1/s] over every mode: > 0 grows."""
        return float(max(np.max(self.oscillatory.real, initial=-math.inf), np.max(self.overdamped, initial=-math.inf)))


@dataclasses.dataclass(frozen=True)
class LumpedCable:
    """M q'' + C q' + K q = f of the N-element model (or any model with these three matrices).

    Attributes
    ----------
    mass
        (N,) node masses [kg] (M is diagonal).
    stiffness
        (N, N) K [N/m].
    damping
        (N, N) C [N s/m].
    """

    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray

    @classmethod
    def build(
        cls,
        cable: TautCable,
        n_elements: int,
        *,
        structural_ratio: float = 0.0,
        damper_position: float | None = None,
        damper_coefficient: float = 0.0,
        aero_ratio: float = 0.0,
        aero_modes: int = 0,
    ) -> LumpedCable:
        """The N-element model of `cable` with the damping the scene's MJCF carries (module docstring)."""
        mass, stiffness = cable.lumped_matrices(n_elements)
        n = len(mass)
        damping = np.eye(n) * cable.structural_node_damping(n, structural_ratio)
        if damper_position is not None:
            node = cable.damper_node(n, damper_position)
            damping[node - 1, node - 1] += float(damper_coefficient)
        for k in range(1, int(aero_modes) + 1):
            shape = mode_shape(n, k)
            damping += cable.aero_mode_damping(n, aero_ratio, k) * np.outer(shape, shape)
        return cls(mass, stiffness, damping)

    @property
    def size(self) -> int:
        """N, the moving nodes."""
        return len(self.mass)

    def with_damper(self, node: int, coefficient: float) -> LumpedCable:
        """The same model with `coefficient` [N s/m] more damping at `node` (1 ... N)."""
        damping = self.damping.copy()
        damping[node - 1, node - 1] += float(coefficient)
        return LumpedCable(self.mass, self.stiffness, damping)

    def state_matrix(self) -> np.ndarray:
        """A = [[0, I], [-M^-1 K, -M^-1 C]] (2N, 2N) of the state (q [m], q' [m/s])."""
        n = self.size
        a = np.zeros((2 * n, 2 * n))
        a[:n, n:] = np.eye(n)
        a[n:, :n] = -self.stiffness / self.mass[:, None]
        a[n:, n:] = -self.damping / self.mass[:, None]
        return a

    def complex_modes(self) -> ComplexModes:
        """The quadratic eigenproblem (lambda^2 M + lambda C + K) phi = 0, solved as the eigenvalues of A.

        A's eigenvalues carry a backward error of a few eps |A| (LAPACK's QR algorithm); a mode of a light
        damper is well conditioned, so lambda is good to about N eps |lambda_max| absolute. An eigenvalue
        whose imaginary part is within 64 eps |lambda_max| of 0 counts as real.
        """
        (values,) = linear.eigen(self.state_matrix())
        tolerance = 64 * _EPS * float(np.max(np.abs(values)))
        real = np.abs(values.imag) <= tolerance
        oscillatory = values[~real & (values.imag > 0)]
        return ComplexModes(oscillatory[np.argsort(oscillatory.imag, kind="stable")], np.sort(values[real].real)[::-1])

    def growth_rate(self) -> float:
        """max Re(lambda) [1/s] over every mode (> 0: the model's own motion grows)."""
        return float(np.max(linear.eigen(self.state_matrix())[0].real))

    def is_tridiagonal(self, tendons: Sequence[tuple[np.ndarray, float]] = ()) -> bool:
        """Whether K is symmetric tridiagonal and C diagonal once the `tendons`' damping is taken out (`eigenvalue_near`).

        The cable with its damper is such a model with no tendons; rain-wind's modal damping adds a tendon per mode,
        w u u^T with u its coefficients on the nodes and w its damping [N s/m].
        """
        return _recurrence_parts(self, tendons) is not None

    def eigenvalue_near(self, start: complex, tendons: Sequence[tuple[np.ndarray, float]] = ()) -> complex:
        """The eigenvalue lambda [1/s] of (lambda^2 M + lambda C + K) phi = 0 that Newton's method reaches from `start`.

        With K tridiagonal and C = D + U W U^T (D diagonal, U W U^T the `tendons`: `is_tridiagonal`), write
        T(lambda) = lambda^2 M + lambda D + K. Then det Q = det T det S, S = I + lambda W U^T T^-1 U (r x r, r the
        tendons), and det T is the product of the pivots r_1 = a_1, r_j = a_j - e_(j-1)^2 / r_(j-1)
        (a_j = lambda^2 m_j + lambda d_j + k_jj, e_j = k_(j,j+1)). So d ln det Q / d lambda = sum_j r_j' / r_j
        (the same recurrence differentiated) + trace(S^-1 S'), S' = W (U^T Y - lambda Y^T T' Y), Y = T^-1 U from
        the same pivots: one Newton step lambda -= 1 / (d ln det Q / d lambda) costs O(N r), where a dense eigensolve
        of the state matrix costs O(N^3) (a fiftieth of the 198 x 198 one for the scene's 99 nodes). Newton stops
        one step after a step below `_CLOSE` |lambda|: convergence is quadratic, so what is left is below the
        determinant's own round-off (its terms a_j cancel to about (omega_1 / omega_N)^2 of their size: lambda is
        good to about (omega_N / omega_1)^2 eps relative, 3e-14 for the scene's cable, and steps of that size never
        stop). The root is the one Newton reaches, normally the nearest; a caller that needs a particular mode
        confirms it (`damper_optimum`, `stabilising_damper` against the dense eigenvalues).

        Raises
        ------
        ArithmeticError
            the model is not of that form, a pivot vanishes, or Newton's step does not fall below `_CLOSE` |lambda|
            within `_NEWTON_STEPS` steps.
        """
        parts = _recurrence_parts(self, tendons)
        if parts is None:
            raise ArithmeticError("the determinant's recurrence needs K tridiagonal and C diagonal but for its tendons")
        lam = complex(start)
        polished = False
        for _ in range(_NEWTON_STEPS):
            total = _log_det_slope(lam, *parts)
            if total == 0 or not (math.isfinite(total.real) and math.isfinite(total.imag)):
                raise ArithmeticError(f"the determinant's recurrence broke down at lambda = {lam!r}")
            step = 1.0 / total
            lam -= step
            if polished:
                return lam
            polished = abs(step) <= _CLOSE * abs(lam)
        raise ArithmeticError(f"Newton on the determinant did not converge from lambda = {complex(start)!r}")


def _recurrence_parts(model: LumpedCable, tendons: Sequence[tuple[np.ndarray, float]]) -> tuple | None:
    """(m, k_jj, k_(j,j+1)^2, d, U's columns, w) as lists for `_log_det_slope`, or None if the model is not of the form
    K tridiagonal, C = D + sum_k w_k u_k u_k^T with D diagonal (the off-diagonal rest within round-off of 0)."""
    k, c = model.stiffness, model.damping
    upper, lower = np.diag(k, 1), np.diag(k, -1)
    if not (
        np.array_equal(upper, lower) and np.array_equal(k, np.diag(np.diag(k)) + np.diag(upper, 1) + np.diag(lower, -1))
    ):
        return None
    low_rank = np.zeros_like(c)
    for vector, weight in tendons:  # in the read-back's order, so the sums are its own
        low_rank += float(weight) * np.outer(vector, vector)
    rest = c - low_rank
    off = rest - np.diag(np.diag(rest))
    if np.max(np.abs(off), initial=0.0) > 4 * len(tendons) * _EPS * np.max(np.abs(c), initial=0.0):
        return None
    return (
        model.mass.tolist(),
        np.diag(k).tolist(),
        (upper**2).tolist(),
        upper.tolist(),
        np.diag(rest).tolist(),
        [np.asarray(vector, float).tolist() for vector, _ in tendons],
        np.array([float(weight) for _, weight in tendons]),
    )


def _log_det_slope(
    lam: complex,
    mass: list[float],
    diagonal: list[float],
    coupling: list[float],
    upper: list[float],
    damping: list[float],
    vectors: list[list[float]],
    weights: np.ndarray,
) -> complex:
    """d ln det(lambda^2 M + lambda C + K) / d lambda at `lam` (`LumpedCable.eigenvalue_near`)."""
    n = len(mass)
    pivot = lam * lam * mass[0] + lam * damping[0] + diagonal[0]
    slope = 2.0 * lam * mass[0] + damping[0]
    pivots = [pivot]
    total = slope / pivot
    for j in range(1, n):
        a = lam * lam * mass[j] + lam * damping[j] + diagonal[j]
        da = 2.0 * lam * mass[j] + damping[j]
        e2 = coupling[j - 1]
        pivot, slope = a - e2 / pivot, da + e2 * slope / (pivot * pivot)
        pivots.append(pivot)
        total += slope / pivot
    if not vectors:
        return total
    # Y = T^-1 U through T = L diag(r) L^T, L unit lower bidiagonal with L_(j+1, j) = e_j / r_j
    columns = []
    for u in vectors:
        z = [complex(u[0])]
        for j in range(1, n):
            z.append(u[j] - upper[j - 1] / pivots[j - 1] * z[j - 1])
        y = [0j] * n
        y[n - 1] = z[n - 1] / pivots[n - 1]
        for j in range(n - 2, -1, -1):
            y[j] = (z[j] - upper[j] * y[j + 1]) / pivots[j]
        columns.append(y)
    ys = np.array(columns).T  # (N, r)
    us = np.array(vectors).T
    rates = 2.0 * lam * np.array(mass) + np.array(damping)  # T' = diag(2 lambda m + d)
    gram = us.T @ ys
    gram_slope = -(ys.T * rates) @ ys
    weights_diag = np.diag(weights)
    s = np.eye(len(vectors)) + lam * weights_diag @ gram
    s_slope = weights_diag @ (gram + lam * gram_slope)
    return total + complex(np.trace(np.linalg.solve(s, s_slope)))


def stabilising_damper(
    model: LumpedCable,
    node: int,
    *,
    guess: float,
    rtol: float = 1e-12,
    tendons: Sequence[tuple[np.ndarray, float]] = (),
) -> float:
    """The smallest damper [N s/m] at `node` that stops every mode of `model` from growing.

    The growth rate g(c) = max Re(lambda) falls from g(0) as the damper grows, and rises again once the damper
    pins the cable (a node at the damper). The answer is the lower root of g(c) = 0: bracketed by walking up
    from guess / 2 in steps of 1.25 until g < 0 (from far below when g(guess / 2) < 0 already), then Brent's
    method to `rtol`. Returns 0 if the model does not grow, nan if no damper up to 3000 times the nodes'
    impedance stops it.

    Where the model is tridiagonal but for its `tendons` (`LumpedCable.is_tridiagonal`), g follows the modes that
    grow without the damper, each by Newton on the determinant (`LumpedCable.eigenvalue_near`, from its root at the
    nearest damper tried so far), a fiftieth of a dense eigensolve each; the root is then confirmed against the
    dense eigenvalues there (their fastest-growing mode is a followed one, within their error N eps |lambda_max|),
    and else, as for any other model, g is the dense eigenvalues' largest real part throughout.

    Parameters
    ----------
    guess
        a damper [N s/m] near the answer, e.g. the universal curve's estimate (nan: start the walk far below).
    tendons
        the damping that is not diagonal, as (u, w) pairs: C = D + sum w u u^T (rain-wind's modal tendons).
    """
    if model.growth_rate() <= 0.0:
        return 0.0
    if model.is_tridiagonal(tendons):
        followed = _FollowedGrowth(model, node, tendons)
        try:
            log_c = _lower_root(model, followed, guess, rtol)
            followed.confirm(log_c)
            return math.exp(log_c)
        except ArithmeticError:
            pass  # Newton failed or followed another mode: the dense eigenvalues decide

    def growth(log_c: float) -> float:
        return model.with_damper(node, math.exp(log_c)).growth_rate()

    return math.exp(_lower_root(model, growth, guess, rtol))


def _lower_root(model: LumpedCable, growth: Callable[[float], float], guess: float, rtol: float) -> float:
    """ln c [ln N s/m] of the lower root of `growth` (of ln c) for `stabilising_damper`; nan if none up to its top."""
    # the damper's scale: sqrt(k m) of a node, times N (the impedance sqrt(T m) is (N + 1) of these)
    log_scale = math.log(math.sqrt(float(model.stiffness[0, 0]) * float(model.mass[0])) * model.size)
    far_below, top = log_scale - 40.0, log_scale + 8.0
    low = math.log(guess / 2.0) if math.isfinite(guess) and guess > 0 else log_scale - 12.0
    step = math.log(1.25) if math.isfinite(guess) and guess > 0 else math.log(2.0)
    if growth(low) <= 0.0:
        low, high = far_below, low
    else:
        high = low + step
        while growth(high) > 0.0:
            if high > top:
                return math.nan
            low, high = high, high + step
    return float(_optimize().brentq(growth, low, high, xtol=1e-14, rtol=max(rtol, 4 * _EPS)))


class _FollowedGrowth:
    """g(ln c) of `stabilising_damper` from the modes that grow without the damper, each followed by Newton."""

    def __init__(self, model: LumpedCable, node: int, tendons: Sequence[tuple[np.ndarray, float]]):
        self.model, self.node, self.tendons = model, node, tendons
        (values,) = linear.eigen(model.state_matrix())
        growing = values[(values.real > 0.0) & (values.imag >= 0.0)]
        self.roots: dict[float, np.ndarray] = {-math.inf: growing}  # ln c -> the followed eigenvalues [1/s]

    def __call__(self, log_c: float) -> float:
        nearest = min(self.roots, key=lambda tried: abs(tried - log_c))
        damped = self.model.with_damper(self.node, math.exp(log_c))
        found = np.array([damped.eigenvalue_near(start, self.tendons) for start in self.roots[nearest]])
        self.roots[log_c] = found
        return float(np.max(found.real))

    def confirm(self, log_c: float) -> None:
        """ArithmeticError unless the dense eigenvalues' fastest-growing mode at ln c is a followed one."""
        if not math.isfinite(log_c):
            return  # no damper stops the followed modes, so none stops the model
        (values,) = linear.eigen(self.model.with_damper(self.node, math.exp(log_c)).state_matrix())
        top = values[np.argmax(values.real)]
        followed = self.roots.get(log_c, np.array([], complex))
        error = self.model.size * _EPS * float(np.max(np.abs(values)))
        if not followed.size or np.min(np.abs(followed - complex(top.real, abs(top.imag)))) > error:
            raise ArithmeticError(f"the fastest-growing mode {top!r} at the root is not a followed one")


# -- the continuum with a damper: the transcendental equation ---------------------------------------------------


def _residual(x: complex, ratio: float, eta: float) -> complex:
    return complex(np.sin(x) + 1j * eta * np.sin(ratio * x) * np.sin((1.0 - ratio) * x))


def _slope(x: complex, ratio: float, eta: float) -> complex:
    rest = 1.0 - ratio
    inner = ratio * np.cos(ratio * x) * np.sin(rest * x) + rest * np.sin(ratio * x) * np.cos(rest * x)
    return complex(np.cos(x) + 1j * eta * inner)


def _newton(x: complex, ratio: float, eta: float) -> complex:
    for _ in range(_NEWTON_STEPS):
        slope = _slope(x, ratio, eta)
        if slope == 0:
            raise ArithmeticError("the damped cable's roots coalesce here (overdamped mode): no Newton step")
        step = _residual(x, ratio, eta) / slope
        x -= step
        if abs(step) <= 2 * _EPS * abs(x):
            return x
    raise ArithmeticError(f"Newton did not converge on the damped cable's root (eta {eta:g}, a/L {ratio:g})")


def universal_start(mode: int, ratio: float, eta: float) -> complex:
    """The asymptotic root x = n pi + eps i kappa / (1 + i kappa), eps = n pi a / L, kappa = eta eps [-]."""
    eps = mode * math.pi * ratio
    kappa = eta * eps
    return mode * math.pi + eps * 1j * kappa / (1.0 + 1j * kappa)


def damped_wavenumber(mode: int, ratio: float, eta: float) -> complex:
    """x = beta L [-] of mode `mode` of the continuum with a damper at a = ratio L, eta = c_d / sqrt(T m).

    The root of sin x + i eta sin(ratio x) sin((1 - ratio) x) = 0 that starts at n pi when eta = 0, followed
    by continuation in eta (48 geometric steps from a damper 1e-6 of the optimum, each polished by Newton in
    complex arithmetic from the previous root; the first start is the asymptotic solution, exact to O(eps^3)
    there): Newton's last step is below 2 eps |x|, so x is the root to machine precision.

    Raises
    ------
    ParameterError
        ratio outside (0, 1), eta negative or not finite.
    ArithmeticError
        two roots coalesce on the path (a damper near mid-span can make a mode overdamped).
    """
    if not (0.0 < ratio < 1.0):
        raise ParameterError(f"the damper's a / L must lie in (0, 1), got {ratio!r}")
    if not (math.isfinite(eta) and eta >= 0.0):
        raise ParameterError(f"the damper coefficient must be finite and >= 0, got eta = {eta!r}")
    if eta == 0.0:
        return complex(mode * math.pi)
    tiny = 1e-6 / (mode * math.pi * ratio)
    path = np.geomspace(tiny, eta, _CONTINUATION_POINTS) if eta > tiny else np.array([eta])
    x = universal_start(mode, ratio, float(path[0]))
    for value in path:
        x = _newton(x, ratio, float(value))
    return x


def damped_eigenvalue(cable: TautCable, mode: int, damper_position: float, damper_coefficient: float) -> complex:
    """lambda_n = i c beta_n [1/s] of the continuum with a damper c_d [N s/m] at a [m]."""
    x = damped_wavenumber(mode, damper_position / cable.length, damper_coefficient / cable.impedance)
    return 1j * cable.wave_speed * x / cable.length


def damping_ratio_of(x: complex) -> float:
    """zeta = Im(x) / |x| [-] of a root x = beta L."""
    return float(x.imag / abs(x))


def universal_damping_ratio(mode: int, ratio: float, eta: float) -> float:
    """The asymptotic curve zeta_n = (a / L) kappa / (1 + kappa^2), kappa = eta n pi a / L [-]."""
    kappa = eta * mode * math.pi * ratio
    return ratio * kappa / (1.0 + kappa**2)


def universal_correction(mode: int, ratio: float, eta: float) -> float:
    """The next term of the curve, (a / L)^2 4 kappa^3 / (1 + kappa^2)^3 [-] (docs/scenes/stay_cable.md).

    The curve plus this term leaves an error O((n pi a / L)^2) relative.
    """
    kappa = eta * mode * math.pi * ratio
    return ratio**2 * 4.0 * kappa**3 / (1.0 + kappa**2) ** 3


def universal_optimum(mode: int, ratio: float) -> tuple[float, float]:
    """(eta_opt, zeta_max) of the universal curve: eta = 1 / (n pi a / L), zeta = a / (2 L)."""
    return 1.0 / (mode * math.pi * ratio), ratio / 2.0


def exact_optimum(mode: int, ratio: float, *, xatol: float = 1e-9) -> tuple[float, float]:
    """(eta_opt, zeta_max) of mode `mode` from the transcendental equation: the damper that damps it most.

    A bounded scalar search (Brent) on log eta over a factor 30 either side of the universal optimum,
    maximizing zeta_n(eta) = Im x / |x|; zeta is flat at its maximum, so zeta_max is good to about eps and
    eta_opt to about sqrt(xatol).
    """
    guess, _ = universal_optimum(mode, ratio)

    def negative_ratio(log_eta: float) -> float:
        return -damping_ratio_of(damped_wavenumber(mode, ratio, math.exp(log_eta)))

    span = math.log(30.0)
    found = _optimize().minimize_scalar(
        negative_ratio,
        bounds=(math.log(guess) - span, math.log(guess) + span),
        method="bounded",
        options={"xatol": xatol},
    )
    return math.exp(float(found.x)), -float(found.fun)


def curve(mode: int, ratio: float, etas: np.ndarray) -> np.ndarray:
    """zeta_n(eta) [-] from the transcendental equation at each eta (each root solved on its own)."""
    return np.array([damping_ratio_of(damped_wavenumber(mode, ratio, float(eta))) for eta in etas])
