"""Exact reductions: least squares over millions of samples in bounded memory, with the same answer.

A least-squares fit reads, of its n residuals r and their n x p Jacobian J, only |r|^2, J^T r and J^T J: the
cost, the gradient and the Gauss-Newton matrix are what Levenberg-Marquardt (mujoco.minimize), scipy's
trust-region reflective solver, the covariance, the intervals and the convergence test use. The triangular
factor of the QR decomposition of [J | r] holds exactly these in (p + 1) x (p + 1) numbers: with
Q^T [J | r] = [[R, z], [0, rho]], R^T R = J^T J, R^T z = J^T r and |z|^2 + rho^2 = |r|^2. It can be accumulated
block by block (the factor of [factor so far; next block] is the factor of all rows so far: a tall-skinny QR),
so no n-long array of residuals or n x p Jacobian is ever held. Records of at most BLOCK samples are handled
whole, exactly as before.

* `blocks`, `triangular`, `lstsq`: blocks of samples, the accumulated factor, linear least squares over blocks
  (the fit's start, springlab.studies.fit.models).
* `Grouped`: samples in consecutive groups whose model is linear in each group's own q coefficients, the MuJoCo
  fit's reading of its grid (springlab.studies.fit.engine: within one grid step the signal at the samples is the
  cubic Hermite interpolant of the step's end states, B_i c_k). Each group's rows reduce, once and for all
  parameters, to at most q + 1 (the factor of [B_k | y_k]), and the sum of squares over the group is
  |R_k c_k - z_k|^2 + rho_k^2 exactly: the residual, cost, gradient and Gauss-Newton matrix are the per-sample
  ones, from about 5 rows per grid step instead of every sample.
* `Reduced`: a residual over blocks of samples given to scipy.optimize.least_squares as its p + 1 reduced rows
  at each point (the closed-form cross-check of a long record, springlab.studies.fit.results).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from typing import cast

import numpy as np

#: samples per block; a record of at most this many samples is handled whole (per sample, as before)
BLOCK = 65536


def blocks(n: int, size: int | None = None) -> Iterator[tuple[int, int]]:
    """(start, stop) of consecutive blocks of `size` (BLOCK) samples covering range(n)."""
    size = size or BLOCK
    for start in range(0, n, size):
        yield start, min(start + size, n)


def triangular(parts: Iterable[np.ndarray]) -> np.ndarray:
    """The (k, k) upper-triangular R with R^T R = sum of part^T part over the (m_i, k) parts: a flat tall-skinny
    QR, each part's factor by LAPACK's blocked Householder QR (dgeqrt, 6x numpy.linalg.qr's speed on a tall
    part), then the factor of the parts' factors stacked (zero rows where all parts hold fewer than k rows)."""
    from scipy.linalg import lapack  # here, not at module top: scipy.linalg costs start-up to every command

    factors = []
    for part in parts:
        m, k = part.shape
        if m > k:
            out, _, info = lapack.dgeqrt(k, np.asfortranarray(part, dtype=float))
            assert info == 0, f"dgeqrt failed ({info})"
            factors.append(np.triu(out[:k]))
        else:
            factors.append(np.asarray(part, float))
    assert factors, "triangular needs at least one part"
    factor = _r(np.vstack(factors))
    k = factor.shape[1]
    if factor.shape[0] < k:
        factor = np.vstack([factor, np.zeros((k - factor.shape[0], k))])
    return factor


def _r(a: np.ndarray) -> np.ndarray:
    """The R of numpy.linalg.qr (stacked: one per matrix of a 3-d array), its mode 'r'."""
    return cast(np.ndarray, np.linalg.qr(a, mode="r"))


def lstsq(n: int, part: Callable[[int, int], tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """min |A x - b| over n rows given by blocks: part(start, stop) -> (A rows (m, k), b rows (m,)).

    numpy.linalg.lstsq of the whole when n <= BLOCK; otherwise of the accumulated factor of [A | b], whose
    normal equations are the whole's (the same minimum-norm solution, rank cut-off eps x n as lstsq's).
    """
    if n <= BLOCK:
        a, b = part(0, n)
        return np.linalg.lstsq(a, b, rcond=None)[0]
    factor = triangular(np.column_stack(part(start, stop)) for start, stop in blocks(n))
    k = factor.shape[1] - 1
    return np.linalg.lstsq(factor[:k, :k], factor[:k, k], rcond=np.finfo(float).eps * n)[0]


class Grouped:
    """A per-sample least-squares problem whose model is linear in each group's own coefficients, reduced exactly.

    Samples 0..n-1 fall into consecutive groups (ids non-decreasing with the sample); the model at sample i is
    B_i . c_g(i), with B_i the sample's q basis values and c_g the group's q coefficients (the parameters move only
    c). Per group, the Householder factor of [B_g | y_g] gives min(n_g, q + 1) rows [W | z]: for every c,
    sum over the group of (B_i . c - y_i)^2 = |W c - z|^2 (the last row of a group of more than q samples has
    W = 0 and z = the part of y no c reaches). `residual(c)` is that reduced residual; `reduce(v)` reduces
    another per-sample vector with the same rotations (Q^T v), so that J^+ v is the reduced problem's.

    Parameters
    ----------
    n
        Samples.
    locate
        locate(index) -> (group ids (m,), basis (m, q)) of the samples `index` (an int array).
    q
        Coefficients per group.
    values
        values(index) -> (m,) the data at the samples `index`.
    """

    def __init__(
        self,
        n: int,
        locate: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
        q: int,
        values: Callable[[np.ndarray], np.ndarray],
    ):
        self.samples, self.q, self._locate = n, q, locate
        starts, ids = [], []
        last = None
        for start, stop in blocks(n):
            group, _ = locate(np.arange(start, stop))
            new = np.flatnonzero(np.diff(group, prepend=-1 if last is None else last) != 0)
            starts.append(start + new)
            ids.append(group[new])
            last = group[-1]
        #: first sample, size and id of each group
        self.starts = np.concatenate(starts)
        self.counts = np.diff(np.append(self.starts, n))
        self.ids = np.concatenate(ids)
        kept = np.minimum(self.counts, q + 1)
        #: first reduced row of each group, and the group id of every reduced row
        self.offsets = np.concatenate([[0], np.cumsum(kept)[:-1]])
        self.group = np.repeat(self.ids, kept)
        self.weights, self.data = self._factor(values)

    @property
    def rows(self) -> int:
        """Reduced rows (at most q + 1 per group)."""
        return int(self.group.size)

    def model(self, coefficients: np.ndarray) -> np.ndarray:
        """(rows,) W c for coefficients indexed by group id ((groups, q)): the model in the reduced rows."""
        return np.einsum("rq,rq->r", self.weights, coefficients[self.group])

    def residual(self, coefficients: np.ndarray) -> np.ndarray:
        """(rows,) W c - z: its squares sum to the per-sample sum of (B_i . c - y_i)^2."""
        return self.model(coefficients) - self.data

    def reduce(self, values: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """(rows,) another per-sample vector v (values(index) -> v at those samples) under the same rotations,
        Q^T v: |Q^T v| = |v|, and the reduced Jacobian's J_r^T (Q^T v) is the per-sample J^T v, so that
        J_r^+ (Q^T v) = J^+ v."""
        return self._factor(values)[1]

    def _factor(self, values: Callable[[np.ndarray], np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """(W (rows, q), z (rows,)): the groups' factors of [B | v], batched by group size."""
        q = self.q
        weights, data = np.zeros((self.rows, q)), np.zeros(self.rows)
        for count in np.unique(self.counts):
            which = np.flatnonzero(self.counts == count)
            per = max(1, BLOCK // int(count))
            for first in range(0, which.size, per):
                chosen = which[first : first + per]
                index = (self.starts[chosen][:, None] + np.arange(count)).ravel()
                _, basis = self._locate(index)
                stacked = np.column_stack([basis, values(index)]).reshape(chosen.size, int(count), q + 1)
                factor = _r(stacked)  # (groups, min(count, q + 1), q + 1)
                rows = (self.offsets[chosen][:, None] + np.arange(factor.shape[1])).ravel()
                weights[rows] = factor[:, :, :q].reshape(-1, q)
                data[rows] = factor[:, :, q].ravel()
        return weights, data


class Reduced:
    """A least-squares residual over blocks of samples, given to scipy.optimize.least_squares as p + 1 rows.

    At each point x, one pass over the blocks evaluates the residual and its forward-difference Jacobian
    (scipy's '2-point' steps: sqrt(eps) max(1, |x_j|), turned back at an upper bound) and accumulates the
    factor [[R, z], [0, rho]] of [J | r]; `fun` returns (z, rho) and `jac` R stacked on a zero row. The solver
    then sees the per-sample problem's cost, gradient, Gauss-Newton matrix and column norms (x_scale='jac')
    exactly, and nothing else of it is read by its trust-region steps: the same iterates, from p + 1 rows.

    Parameters
    ----------
    n
        Samples.
    residual
        residual(x, start, stop) -> (stop - start,) the residual of samples start..stop-1 at parameters x.
    bounds
        (low, high) arrays of the parameters' box bounds.
    """

    def __init__(
        self,
        n: int,
        residual: Callable[[np.ndarray, int, int], np.ndarray],
        bounds: tuple[np.ndarray, np.ndarray],
    ):
        self.n, self._residual = n, residual
        self.low, self.high = (np.asarray(b, float) for b in bounds)
        self._at: bytes | None = None
        self._jacobian = np.empty((0, 0))
        self.evaluations = 0

    def steps(self, x: np.ndarray) -> np.ndarray:
        """The forward-difference steps at x: scipy's '2-point' rule (approx_derivative), reversed where the
        step would leave the bounds and the reverse one fits."""
        step = math.sqrt(np.finfo(float).eps) * np.where(x >= 0, 1.0, -1.0) * np.maximum(1.0, np.abs(x))
        outside = (x + step < self.low) | (x + step > self.high)
        fits = np.abs(step) <= np.maximum(x - self.low, self.high - x)
        return np.where(outside & fits, -step, step)

    def fun(self, x: np.ndarray) -> np.ndarray:
        """(p + 1,) the reduced residual (z, rho) at x; inf where the residual is not finite."""
        x = np.asarray(x, float)
        step = self.steps(x)
        moved = [x + step[j] * np.eye(x.size)[j] for j in range(x.size)]
        dx = np.array([moved[j][j] - x[j] for j in range(x.size)])

        def parts() -> Iterator[np.ndarray]:
            for start, stop in blocks(self.n):
                base = self._residual(x, start, stop)
                columns = [(self._residual(m, start, stop) - base) / dx[j] for j, m in enumerate(moved)]
                yield np.column_stack([*columns, base])

        self.evaluations += 1
        with np.errstate(all="ignore"):
            factor = triangular(parts())
        p = x.size
        if not np.all(np.isfinite(factor)):
            self._at, self._jacobian = None, np.full((p + 1, p), np.nan)
            return np.full(p + 1, np.inf)
        self._at = x.tobytes()
        self._jacobian = np.vstack([factor[:p, :p], np.zeros((1, p))])
        return factor[:, p].copy()

    def jac(self, x: np.ndarray) -> np.ndarray:
        """(p + 1, p) the reduced Jacobian at x (from the `fun` call at x, which the solver always makes first)."""
        if self._at != np.asarray(x, float).tobytes():
            self.fun(x)
        return self._jacobian
