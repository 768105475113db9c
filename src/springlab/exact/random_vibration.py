"""Stationary response of a linear model to white noise, exactly, and the scatter of an RMS from a finite record.

The model x' = A x + B w(t), w white with intensity W (E[w(t) w(s)^T] = W delta(t - s), W [input^2 s]).

* **Continuous**: the stationary covariance P solves A P + P A^T + B W B^T = 0 (`continuous_covariance`;
  Bartels-Stewart through scipy, or `second_order_covariance` for M q'' + C q' + K q = F w with C = alpha M
  plus a damping of low rank: a damper, a few modal terms. That one works in the undamped modes, where
  the Lyapunov operator of alpha M is diagonal, and adds the low-rank damping through a linear system of
  2 N r unknowns (r the rank): N = 400 in a fraction of a second where Bartels-Stewart takes seconds).
* **Held**: MuJoCo holds a control over each step, so the load a simulation applies is w_k ~ N(0, W / dt)
  held on [k dt, (k + 1) dt) (the same low-frequency spectral density W). The exact state at the steps is
  x_{k+1} = Phi x_k + Gamma w_k, Phi = e^{A dt}, Gamma = int_0^dt e^{A s} ds B (the zero-order hold, one matrix
  exponential), and its stationary covariance solves P = Phi P Phi^T + Gamma (W / dt) Gamma^T
  (`held_covariance`). P_held - P_continuous is the hold's own effect, whatever the integrator.
* **The integrator's own**: a one-step map x_{k+1} = F x_k + G w_k read from MuJoCo's linearization gives
  P = F P F^T + G (W / dt) G^T (`discrete_covariance`); P_integrator - P_held is the integrator's bias.
* **A finite record**: the sample variance s^2 = (1/K) sum_k y_k^2 of y = c^T x over K steps (zero mean) has
  Var(s^2) = (2 / K^2) sum_{j,k} R_{j-k}^2 for a Gaussian process with autocovariance R_k = c^T Phi^k P c. The
  sums sum_k R_k^2 and sum_k k R_k^2 are quadratic forms of discrete Lyapunov solutions (`record_variance`),
  exact (the tail beyond K included); the continuous record of length T the same with integrals
  (`record_variance_continuous`): Var(s^2) = (4 / T) int_0^T (1 - tau / T) R(tau)^2 dtau, about (2 / T)
  int R^2 over the whole line. `variance_interval` turns it into an interval at a stated confidence level
  (a scaled chi-square with nu = 2 sigma^4 / Var(s^2) degrees of freedom: the skew of a short record kept).
"""

from __future__ import annotations

import collections
import dataclasses
import math
import warnings
from collections.abc import Sequence

import numpy as np
import scipy.linalg

from springlab.errors import BadInputError
from springlab.exact.linear import kept_by_matrix

_EPS = float(np.finfo(float).eps)
#: the bilinear transform and real Schur form of the last few one-step maps (`_bilinear`), by matrix
_BILINEAR: collections.OrderedDict[tuple, tuple[np.ndarray, ...]] = collections.OrderedDict()
#: how many `_BILINEAR` keeps: a case's held map and MuJoCo's map at one setting, and the next setting's
KEPT_BILINEAR = 4


def _stable(a: np.ndarray, what: str) -> None:
    worst = float(np.max(scipy.linalg.eigvals(a).real))
    if not worst < 0.0:
        raise BadInputError(
            f"{what} has no stationary covariance: a mode does not decay (max Re lambda = {worst:.6g} 1/s >= 0)"
        )


def continuous_covariance(a: np.ndarray, noise: np.ndarray) -> np.ndarray:
    """P with A P + P A^T + noise = 0 [state units^2], noise = B W B^T [state units^2 / s] (Bartels-Stewart).

    scipy.linalg.solve_continuous_lyapunov's operations in its order, its real Schur form of A read for the decay
    too (Re(lambda) on its diagonal: LAPACK standardizes a 2 x 2 block to equal diagonal entries), so a stable A
    costs no eigensolve of its own; A's eigenvalues are asked only to word a failure.

    Raises
    ------
    BadInputError
        A has a mode that does not decay.
    """
    a = np.atleast_2d(np.asarray_chkfinite(a))
    q = np.atleast_2d(np.asarray_chkfinite(-np.asarray(noise, float)))
    if a.ndim != 2 or a.shape != q.shape or a.shape[0] != a.shape[1] or a.size == 0 or np.iscomplexobj(a):
        _stable(a, "the model")
        p = scipy.linalg.solve_continuous_lyapunov(a, q)
        return 0.5 * (p + p.T)
    schur_form, schur_basis = scipy.linalg.schur(a, output="real")
    if not float(np.max(np.diag(schur_form))) < 0.0:
        _stable(a, "the model")
    p = _bartels_stewart(schur_form, schur_basis, q, "the model has an eigenvalue pair whose sum is about 0")
    return 0.5 * (p + p.T)


def _bartels_stewart(schur_form: np.ndarray, schur_basis: np.ndarray, q: np.ndarray, pair: str) -> np.ndarray:
    """X with A X + X A^H = Q given A = U T U^H (real Schur: T `schur_form`, U `schur_basis`): the tail of
    scipy.linalg.solve_continuous_lyapunov past its Schur form, its operations in its order. `pair` words the
    warning LAPACK's ?TRSYL raises for a near-singular equation (an eigenvalue pair summing to about 0)."""
    f = schur_basis.conj().T.dot(q.dot(schur_basis))
    (trsyl,) = scipy.linalg.get_lapack_funcs(("trsyl",), (schur_form, f))
    y, scale, info = trsyl(schur_form, schur_form, f, tranb="T")
    if info < 0:
        raise ValueError(f"?TRSYL exited with the internal error illegal value in argument number {-info}.")
    if info == 1:
        warnings.warn(
            f"{pair}: the Lyapunov solution is obtained via perturbing the coefficients", RuntimeWarning, stacklevel=3
        )
    y *= scale
    return schur_basis.dot(y).dot(schur_basis.conj().T)


def zero_order_hold(a: np.ndarray, b: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(Phi, Gamma): the exact step of x' = A x + B u with u held over dt [s]; one expm of [[A, B], [0, 0]] dt."""
    n, m = a.shape[0], b.shape[1]
    block = np.zeros((n + m, n + m))
    block[:n, :n] = a * dt
    block[:n, n:] = b * dt
    e = scipy.linalg.expm(block)
    return e[:n, :n], e[:n, n:]


def discrete_covariance(transition: np.ndarray, noise: np.ndarray) -> np.ndarray:
    """P with P = F P F^T + noise (the stationary covariance of x_{k+1} = F x_k + e_k, Cov e_k = noise).

    Raises
    ------
    BadInputError
        F has an eigenvalue on or outside the unit circle (read off the Schur form the solve takes, else F's
        eigenvalues: `_decays_by_schur`).
    """
    if not _decays_by_schur(transition):
        worst = float(np.max(np.abs(scipy.linalg.eigvals(transition))))
        if not worst < 1.0:
            raise BadInputError(f"the one-step map has no stationary covariance: |mu| = {worst:.15g} >= 1")
    p = solve_discrete_lyapunov(transition, np.asarray(noise, float))
    return 0.5 * (p + p.T)


def _decays_by_schur(transition: np.ndarray) -> bool:
    """Whether every eigenvalue mu of F has |mu| < 1, read off the Schur form `solve_discrete_lyapunov` takes anyway.

    Its bilinear transform B^H = (F + I)^-1 (F - I) has the eigenvalues (mu - 1) / (mu + 1), inside the left half
    plane exactly when |mu| < 1, and the real Schur form's diagonal holds their real parts (LAPACK standardizes a
    2 x 2 block to equal diagonal entries): a dense eigensolve of F fewer. False (so the caller asks the eigenvalues)
    where the form is not the one the solve uses (under 10 states, complex) or cannot be formed (F + I singular).
    """
    a = np.asarray(transition)
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] < 10 or np.iscomplexobj(a):
        return False
    try:
        schur_form = _bilinear(a)[2]
    except (np.linalg.LinAlgError, ValueError):
        return False
    return bool(np.max(np.diag(schur_form)) < 0.0)


def solve_discrete_lyapunov(transition: np.ndarray, noise: np.ndarray) -> np.ndarray:
    """X with F X F^T - X + Q = 0: scipy.linalg.solve_discrete_lyapunov(F, Q), the same operations in the same
    order, with F's part kept (`_bilinear`) for the next Q.

    For n >= 10 scipy maps the equation to the continuous B^H X + X B = -C, B = (F^H - I)(F^H + I)^-1,
    C = 2 (F + I)^-1 Q (F^H + I)^-1, and solves that by Bartels-Stewart on B^H's real Schur form: the inverses
    and the Schur form depend on F alone and cost nine tenths of a solve of 198 states. A held covariance and
    its record's two sums (`record_variances`) solve with one F: they compute them once. Below 10 states
    scipy's direct method, unchanged.
    """
    a = np.asarray(transition)
    q = np.asarray(noise)
    if a.ndim != 2 or a.shape[0] < 10 or a.shape != q.shape or np.iscomplexobj(a) or np.iscomplexobj(q):
        return scipy.linalg.solve_discrete_lyapunov(a, q)
    plus_inverse, plus_h_inverse, schur_form, schur_basis = _bilinear(a)
    # scipy's _solve_discrete_lyapunov_bilinear, then solve_continuous_lyapunov(B^H, -C) past its Schur form
    c = 2 * np.dot(np.dot(plus_inverse, q), plus_h_inverse)
    q_continuous = np.atleast_2d(np.asarray_chkfinite(-c))
    pair = "the one-step map has an eigenvalue pair whose bilinear images sum to about 0"
    return _bartels_stewart(schur_form, schur_basis, q_continuous, pair)


def _bilinear(a: np.ndarray) -> tuple[np.ndarray, ...]:
    """((F + I)^-1, (F^H + I)^-1, T, U) with B^H = U T U^T (real Schur) of `solve_discrete_lyapunov`, kept per F."""

    def transform() -> tuple[np.ndarray, ...]:
        eye = np.eye(a.shape[0])
        a_h = a.conj().transpose()
        plus_h_inverse = np.linalg.inv(a_h + eye)
        b = np.dot(a_h - eye, plus_h_inverse)
        b_h = np.atleast_2d(np.asarray_chkfinite(b.conj().transpose()))
        schur_form, schur_basis = scipy.linalg.schur(b_h, output="real")
        return np.linalg.inv(a + eye), plus_h_inverse, schur_form, schur_basis

    return kept_by_matrix(_BILINEAR, KEPT_BILINEAR, a, transform)


def held_covariance(
    a: np.ndarray,
    b: np.ndarray,
    intensity: np.ndarray,
    dt: float,
    hold: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """P at the steps of x' = A x + B w under white noise of intensity W held over each step of dt [s].

    The held sample w_k ~ N(0, W / dt), so P = Phi P Phi^T + Gamma (W / dt) Gamma^T (module docstring). `hold`:
    (Phi, Gamma) of `zero_order_hold(a, b, dt)` when the caller has them already (None: computed here).

    Raises
    ------
    BadInputError
        A has a mode that does not decay: Phi = e^(A dt) has |mu| = e^(Re(lambda) dt) >= 1 there, read off the
        Schur form the Lyapunov solve takes (`_decays_by_schur`); A's eigenvalues are asked only to word it.
    """
    phi, gamma = zero_order_hold(a, b, dt) if hold is None else hold
    if not _decays_by_schur(phi):
        _stable(a, "the model")
    return discrete_covariance(phi, gamma @ (np.atleast_2d(intensity) / dt) @ gamma.T)


def map_bias(held: np.ndarray, transition: np.ndarray, input_map: np.ndarray, step_noise: np.ndarray) -> np.ndarray:
    """P_map - P_held [state units^2]: how far a one-step map's stationary covariance is from the held exact one.

    D solves D = F D F^T + (F P F^T - P + G W_k G^T) with P the held covariance (`held_covariance`), F, G the map
    (x_{k+1} = F x_k + G w_k) and W_k = W / dt the held sample's covariance: the difference's own Lyapunov
    equation, whose right side is as small as the map's error, so D keeps its digits where P_map - P_held
    computed apart would lose them to the two solutions' round-off.
    """
    g = np.atleast_2d(input_map)
    rhs = transition @ held @ transition.T - held + g @ np.atleast_2d(step_noise) @ g.T
    return discrete_covariance(transition, 0.5 * (rhs + rhs.T))


# -- the structured solver: M q'' + (alpha M + U D U^T) q' + K q = F w ---------------------------------------


def second_order_covariance(
    mass: np.ndarray,
    stiffness: np.ndarray,
    background: float,
    factors: np.ndarray,
    weights: np.ndarray,
    noise_factor: np.ndarray,
    intensity: np.ndarray,
) -> np.ndarray:
    """The stationary covariance of (q, q') for M q'' + C q' + K q = (input), C = alpha M + U diag(d) U^T.

    Works in the undamped modes (K Phi = M Phi Omega^2, Phi^T M Phi = I), where the model with C = alpha M is
    diagonal with eigenvalues -alpha/2 +- i sqrt(omega^2 - alpha^2/4) and known eigenvectors X, so its Lyapunov
    operator L0(P) = A0 P + P A0^T is diagonal in X's coordinates. The full A = A0 - U~ V~^T (U~ = [0; M^-1 U D],
    V~ = [0; U]) turns A P + P A^T + Q = 0 into L0(P) = -Q + U~ Y^T + Y U~^T with Y = P V~ (2N x r unknowns), one
    linear system; then P = X H X^T. Cost O(N^3) in real matrix products plus a (2 N r)^2 complex solve.

    Parameters
    ----------
    mass
        (N,) diagonal of M [kg].
    stiffness
        (N, N) K [N/m], symmetric positive definite.
    background
        alpha [1/s]: C's part alpha M (nonzero; it may be negative if the low-rank part makes the whole stable).
    factors, weights
        U (N, r) and d (r,) [N s/m per unit of U^2] of the low-rank damping U diag(d) U^T.
    noise_factor
        B (2N, p): how the noise enters the state (q, q') [state units / (input units s)].
    intensity
        W (p, p) [input^2 s].

    Returns
    -------
    P (2N, 2N) [m^2, m^2/s, m^2/s^2 by block].

    Raises
    ------
    BadInputError
        the background damping is 0, a mode of A0 is critically damped, or the whole model does not decay.
    """
    mass = np.asarray(mass, float)
    n = len(mass)
    squared, shapes = scipy.linalg.eigh(stiffness, np.diag(mass))
    if background == 0.0 or not np.all(squared > 0):
        raise BadInputError("the structured covariance needs a positive-definite K and a background damping alpha != 0")
    mu = np.sqrt(squared - background**2 / 4.0 + 0j)
    plus, minus = -background / 2.0 + 1j * mu, -background / 2.0 - 1j * mu
    gap = minus - plus
    if np.min(np.abs(gap)) <= 1e-8 * np.max(np.abs(plus)):
        raise BadInputError("a mode of the background damping is critically damped: use continuous_covariance")
    lam = np.concatenate([plus, minus])
    inverse_sum = 1.0 / (lam[:, None] + lam[None, :])

    def to_eigen(columns: np.ndarray) -> np.ndarray:
        """X^-1 columns for a (2N, p) state block: per mode [lambda- eta - eta', -lambda+ eta + eta'] / gap."""
        eta = shapes.T @ (mass[:, None] * columns[:n])
        rate = shapes.T @ (mass[:, None] * columns[n:])
        return np.concatenate(
            [(minus[:, None] * eta - rate) / gap[:, None], (rate - plus[:, None] * eta) / gap[:, None]]
        )

    u_matrix = np.asarray(factors, float).reshape(n, -1)
    r = u_matrix.shape[1]
    w_modal = shapes.T @ u_matrix  # Phi^T U (N, r)
    u_hat = to_eigen(np.concatenate([np.zeros((n, r)), (u_matrix * np.asarray(weights, float)) / mass[:, None]]))
    v_hat = np.concatenate([plus[:, None] * w_modal, minus[:, None] * w_modal])  # X^T V~
    b_hat = to_eigen(np.asarray(noise_factor, float))
    q_hat = b_hat @ np.atleast_2d(intensity) @ b_hat.T
    # Y^ (2N, r): Y^_pi - sum_{q,k} U^_pk T_pq V^_qi Y^_qk - sum_k Y^_pk (T (U^_k o V^_i))_p = -((Q^ o T) V^)_pi
    size = 2 * n
    system = np.eye(size * r, dtype=complex)
    coupling = np.einsum("pk,pq,qi->piqk", u_hat, inverse_sum, v_hat).reshape(size * r, size * r)
    system -= coupling
    local = np.einsum("pq,qk,qi->pik", inverse_sum, u_hat, v_hat)  # (2N, r, r)
    base = np.arange(size)[:, None, None] * r
    row_index = np.broadcast_to(base + np.arange(r)[None, :, None], local.shape)
    column_index = np.broadcast_to(base + np.arange(r)[None, None, :], local.shape)
    system[row_index.ravel(), column_index.ravel()] -= local.ravel()
    rhs = -((q_hat * inverse_sum) @ v_hat)
    y_hat = np.linalg.solve(system, rhs.reshape(-1)).reshape(size, r)
    h = (-q_hat + u_hat @ y_hat.T + y_hat @ u_hat.T) * inverse_sum
    # back to the modal coordinates (eta, eta'): Z H Z^T with Z = [[I, I], [Lambda+, Lambda-]], then q = Phi eta
    h11, h12, h21, h22 = h[:n, :n], h[:n, n:], h[n:, :n], h[n:, n:]
    eta_eta = (h11 + h12 + h21 + h22).real
    eta_rate = (h11 * plus[None, :] + h12 * minus[None, :] + h21 * plus[None, :] + h22 * minus[None, :]).real
    rate_rate = (
        plus[:, None] * h11 * plus[None, :]
        + plus[:, None] * h12 * minus[None, :]
        + minus[:, None] * h21 * plus[None, :]
        + minus[:, None] * h22 * minus[None, :]
    ).real
    p = np.empty((size, size))
    p[:n, :n] = shapes @ eta_eta @ shapes.T
    p[:n, n:] = shapes @ eta_rate @ shapes.T
    p[n:, :n] = p[:n, n:].T
    p[n:, n:] = shapes @ rate_rate @ shapes.T
    return 0.5 * (p + p.T)


# -- the scatter of an estimated variance -----------------------------------------------------------------------


def record_variance(covariance: np.ndarray, transition: np.ndarray, output: np.ndarray, samples: int) -> float:
    """Var(s^2) [output^4] of s^2 = (1/K) sum_{k<K} y_k^2, y_k = c^T x_k of the stationary chain x_{k+1} = F x_k + e_k.

    For a Gaussian chain, Var(s^2) = (2 / K^2) [K R_0^2 + 2 sum_{k=1}^{K-1} (K - k) R_k^2], R_k = c^T F^k P c.
    With v = P c, S0 = sum_{k>=0} R_k^2 = c^T X c (X = F X F^T + v v^T) and S1 = sum_k k R_k^2 = c^T Z c
    (Z = F Z F^T + X - v v^T), the finite sum is K (S0 - R_0^2) - S1 + c_K^T Z c_K with c_K = (F^K)^T c (the
    tail beyond K, exactly), so Var(s^2) = (2 / K^2) [K (2 S0 - R_0^2) - 2 S1 + 2 c_K^T Z c_K].

    Parameters
    ----------
    covariance
        P, the chain's stationary covariance.
    transition
        F, its one-step map.
    output
        c (n,): y = c^T x.
    samples
        K, the record's length in steps.
    """
    return float(record_variances(covariance, transition, output, [samples])[0])


def record_variances(
    covariance: np.ndarray, transition: np.ndarray, output: np.ndarray, samples: Sequence[int]
) -> np.ndarray:
    """`record_variance` [output^4] for each record length K in `samples` (ascending or not), the two discrete
    Lyapunov solutions shared: (len(samples),)."""
    c = np.asarray(output, float)
    v = covariance @ c
    r0 = float(c @ v)
    x = solve_discrete_lyapunov(transition, np.outer(v, v))
    z = solve_discrete_lyapunov(transition, x - np.outer(v, v))
    s0, s1 = float(c @ x @ c), float(c @ z @ c)
    out = np.empty(len(samples))
    for i, count in enumerate(samples):
        c_k = np.linalg.matrix_power(transition.T, int(count)) @ c
        total = count * (2.0 * s0 - r0**2) - 2.0 * s1 + 2.0 * float(c_k @ z @ c_k)
        out[i] = 2.0 * total / count**2
    return out


def record_variance_continuous(covariance: np.ndarray, a: np.ndarray, output: np.ndarray, duration: float) -> float:
    """Var(s^2) [output^4] of s^2 = (1/T) int_0^T y^2 dt, y = c^T x of the stationary process x' = A x + noise.

    Var(s^2) = (4 / T) int_0^T (1 - tau / T) R(tau)^2 dtau, R(tau) = c^T e^{A tau} P c; with v = P c,
    int_0^inf R^2 = c^T Y0 c (A Y0 + Y0 A^T + v v^T = 0), int_0^inf tau R^2 = c^T Y1 c (A Y1 + Y1 A^T + Y0 = 0),
    and the tail beyond T exactly through c_T = e^{A^T T} c: Var = (4 / T) [S0 - S1 / T + c_T^T Y1 c_T / T].
    """
    c = np.asarray(output, float)
    v = covariance @ c
    y0 = scipy.linalg.solve_continuous_lyapunov(a, -np.outer(v, v))
    y1 = scipy.linalg.solve_continuous_lyapunov(a, -y0)
    c_t = scipy.linalg.expm(a.T * duration) @ c
    return 4.0 / duration * (float(c @ y0 @ c) - float(c @ y1 @ c) / duration + float(c_t @ y1 @ c_t) / duration)


@dataclasses.dataclass(frozen=True)
class VarianceInterval:
    """Where an estimated variance falls, at a confidence level, around the exact one.

    Attributes
    ----------
    variance
        the exact variance sigma^2 [output^2].
    spread
        sqrt(Var(s^2)) [output^2]: the estimate's standard deviation.
    level
        the confidence level [-] (0.99: 99 %).
    low, high
        the interval for s^2 [output^2]: sigma^2 chi2_nu(q) / nu at q = (1 - level)/2 and (1 + level)/2,
        nu = 2 sigma^4 / Var(s^2) (Satterthwaite's scaled chi-square: the mean and variance of s^2 matched).
    """

    variance: float
    spread: float
    level: float
    low: float
    high: float

    @property
    def degrees_of_freedom(self) -> float:
        """nu = 2 sigma^4 / Var(s^2) [-]: the record's worth in independent squared samples."""
        return 2.0 * self.variance**2 / self.spread**2

    def contains(self, estimate: float) -> bool:
        """Whether `estimate` [output^2] lies inside [low, high]."""
        return self.low <= estimate <= self.high

    def rms_interval(self) -> tuple[float, float]:
        """[sqrt(low), sqrt(high)] [output]: the same interval for the RMS."""
        return math.sqrt(self.low), math.sqrt(self.high)

    def true_variance_interval(self, estimate: float) -> tuple[float, float]:
        """[low, high] [output^2] for the true variance given an estimate s^2 (the same chi-square inverted)."""
        return estimate * self.variance / self.high, estimate * self.variance / self.low


def _chi2_ppf(probability: float, degrees_of_freedom: float) -> float:
    """The chi-square quantile [-]: 2 P^-1(nu/2, q), the regularized gamma's inverse, as scipy.stats.chi2.ppf computes
    it (the same bits) without importing scipy.stats (a quarter to most of a second of a cold validate)."""
    import scipy.special  # here, as before scipy.stats: the scene registry imports this module

    return float(2.0 * scipy.special.gammaincinv(degrees_of_freedom / 2.0, probability))


def variance_interval(variance: float, spread: float, level: float) -> VarianceInterval:
    """The `level` interval of an estimated variance whose exact value is `variance` and scatter `spread`.

    Parameters
    ----------
    variance
        sigma^2 [output^2], > 0.
    spread
        sqrt(Var(s^2)) [output^2], > 0 (`record_variance`).
    level
        confidence level in (0, 1).
    """
    if not (0.0 < level < 1.0):
        raise BadInputError(f"the confidence level must lie in (0, 1), got {level!r}")
    nu = 2.0 * variance**2 / spread**2
    low = variance * _chi2_ppf((1.0 - level) / 2.0, nu) / nu
    high = variance * _chi2_ppf((1.0 + level) / 2.0, nu) / nu
    return VarianceInterval(float(variance), float(spread), float(level), low, high)


def rms_along(covariance: np.ndarray, nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """(RMS of q, RMS of q') [m, m/s] at every node from a (2N, 2N) covariance of (q, q')."""
    diagonal = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    return diagonal[:nodes], diagonal[nodes : 2 * nodes]
