"""Exact solutions of linear time-invariant systems: z' = A z + B u(t), u piecewise constant.

The reference for every multi-DOF scene (the car's pitch and heave, the printer head's belt) and
for single-DOF runs with forcing generators in the state.  Over a step h of constant input the
exact map is read off one matrix exponential of an augmented matrix,
``expm([[A h, I], [0, 0]]) = [[e^{A h}, phi1(A h)], [0, I]]``, so no inverse of A is needed
and singular A (rigid-body modes, harmonic generators) is exact.  The exponential is
scipy.linalg.expm (scaling and squaring with Padé approximants, Al-Mohy & Higham 2009);
what springlab adds is *how* it is used: e^{A h} - I is carried apart from the identity, so
slow modes (a stiff damper's creep -k/d, rigid-body drift) survive 1e5 reuses of one step.

Units: A [1/s], B [state units / (input units s)], times [s].  Multi-DOF mechanics
``M q'' + C q' + K q = f`` enter through :func:`state_matrix` / :func:`linear_response`
with M [kg], C [N s/m], K [N/m], q [m], q' [m/s], f [N].
"""

from __future__ import annotations

import collections
import hashlib
import math
from collections.abc import Callable, Hashable
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

__all__ = ["state_matrix", "generator_system", "lti_response", "linear_response", "expm_minus_identity"]


#: BLAS's thread pools, found on first use (`single_threaded_blas`)
_BLAS_POOLS: Any = None
#: the last few eigen-decompositions (`eigen`), by matrix
_EIGEN: collections.OrderedDict[tuple, tuple[np.ndarray, ...]] = collections.OrderedDict()
#: how many `_EIGEN` keeps: a scene's state matrices of one case and the next
KEPT_EIGEN = 16


def single_threaded_blas() -> Any:
    """A context in which BLAS (numpy's and scipy's OpenBLAS) runs on one thread (threadpoolctl).

    For the dense eigenproblems of a few hundred unknowns springlab solves, BLAS's threads cost more than they
    save, and on a machine the rollouts or the test workers already fill they oversubscribe the cores: a 200 x
    200 `scipy.linalg.eig` took 0.09 s on one thread and 0.75 s on two busy cores with OpenBLAS's own.
    """
    global _BLAS_POOLS
    if _BLAS_POOLS is None:
        from threadpoolctl import ThreadpoolController  # here: importing springlab loads no thread pools

        _BLAS_POOLS = ThreadpoolController()
    return _BLAS_POOLS.limit(limits=1, user_api="blas")


def eigen(a: np.ndarray, *, vectors: bool = False) -> tuple[np.ndarray, ...]:
    """scipy.linalg.eig of a square matrix on one BLAS thread, kept for the last KEPT_EIGEN matrices.

    Parameters
    ----------
    a
        (n, n) real or complex matrix (e.g. a state matrix A [1/s]).
    vectors
        also the left and right eigenvectors.

    Returns
    -------
    tuple of np.ndarray
        (values,) or (values, left, right) as scipy.linalg.eig returns them, read-only (they are shared).
    """
    matrix = np.ascontiguousarray(a)

    def decompose() -> tuple[np.ndarray, ...]:
        with single_threaded_blas():
            if vectors:
                return tuple(scipy.linalg.eig(matrix, left=True, right=True))
            return (scipy.linalg.eigvals(matrix),)

    return kept_by_matrix(_EIGEN, KEPT_EIGEN, matrix, decompose, vectors)


def kept_by_matrix(
    store: collections.OrderedDict[tuple, tuple[np.ndarray, ...]],
    limit: int,
    matrix: np.ndarray,
    compute: Callable[[], tuple[np.ndarray, ...]],
    *options: Hashable,
) -> tuple[np.ndarray, ...]:
    """`compute()`'s arrays for `matrix` (and `options`), kept read-only in `store` for its last `limit` keys.

    The key is the matrix's dtype, shape and a digest of its bytes, so an equal matrix built anew finds them:
    the exact side's decompositions (`eigen`, random_vibration's bilinear maps) are asked again for the same
    parameters by each scenario and setting. The arrays are shared, hence read-only.
    """
    matrix = np.ascontiguousarray(matrix)
    key = (matrix.dtype.str, matrix.shape, hashlib.blake2b(matrix.tobytes(), digest_size=16).digest(), *options)
    kept = store.get(key)
    if kept is None:
        kept = compute()
        for array in kept:
            array.setflags(write=False)
        store[key] = kept
        while len(store) > limit:
            store.popitem(last=False)
    else:
        store.move_to_end(key)
    return kept


def _onenorm(a: np.ndarray) -> float:
    """Induced 1-norm (largest absolute column sum) of `a`, 0 for an empty matrix."""
    return float(np.abs(a).sum(axis=0).max()) if a.size else 0.0


#: ||X||_1 at which exp(X) - I is taken from the Padé approximant before squaring (scipy picks
#: degree <= 7 there, no squaring of its own)
_SCALED_NORM = 0.5


def expm_minus_identity(x: np.ndarray) -> np.ndarray:
    """exp(X) - I, accurate relative to its own (possibly small) size.

    Forming exp(X) and subtracting I rounds every mode with exp(lambda) ~ 1 (a stiff damper's
    creep, a rigid-body mode, a short step) to 1 +- ulp first, and squaring exp(X) amplifies that
    by 2^s.  So the scaling and squaring is carried on D = exp(X) - I itself: scale X by 2^-s
    until ||X 2^-s||_1 <= 1/2, take D there from one scipy.linalg.expm of a block matrix,
    exp([[Y, Y], [0, 0]]) = [[e^Y, e^Y - I], [0, I]] (the upper-right block is
    sum_{j>=1} Y^j / j!, no I subtracted), then square s times as D <- 2 D + D^2.
    (scipy's own squaring of the block, F <- E F + F, loses the creep mode of m = 1 kg,
    k = 1 N/m, d = 1e9 N s/m over h = 5e5 s to 2.5e-4 relative; this form keeps it to ~1e-15.)

    Parameters
    ----------
    x : ndarray, shape (n, n)
        Finite square matrix, dimensionless (e.g. A [1/s] times h [s]).

    Returns
    -------
    ndarray, shape (n, n)
        exp(X) - I.
    """
    n = x.shape[0]
    if n == 1:
        return np.expm1(x)
    norm = _onenorm(x)
    squarings = max(0, math.ceil(math.log2(norm / _SCALED_NORM))) if norm > 0.0 else 0
    y = x * 2.0**-squarings
    block = np.zeros((2 * n, 2 * n), dtype=np.result_type(x.dtype, np.float64))
    block[:n, :n] = y
    block[:n, n:] = y
    d = scipy.linalg.expm(block)[:n, n:]
    for _ in range(squarings):
        d = 2.0 * d + d @ d
    return d


def _matrix(name: str, value, n: int | None = None) -> np.ndarray:
    arr = np.atleast_2d(np.asarray(value, dtype=float))
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1]:
        raise ValueError(f"{name} must be a square matrix, got shape {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise ValueError(f"{name} must be {n}x{n}, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return arr


def state_matrix(mass_matrix: ArrayLike, damping_matrix: ArrayLike, stiffness_matrix: ArrayLike) -> np.ndarray:
    """First-order state matrix of M q'' + C q' + K q = f.

    Parameters
    ----------
    mass_matrix
        M (n, n) [kg], symmetric positive definite.
    damping_matrix
        C (n, n) [N s/m].
    stiffness_matrix
        K (n, n) [N/m] (may be singular, e.g. rigid-body modes).

    Returns
    -------
    ndarray
        A = [[0, I], [-M^-1 K, -M^-1 C]] (2n, 2n) for the state z = (q, q')
        (upper-right block dimensionless, lower blocks [1/s^2] and [1/s]).

    Raises
    ------
    ValueError
        For non-finite or mis-shaped matrices or an M that is not
        symmetric positive definite.
    """
    mm = _matrix("mass_matrix", mass_matrix)
    n = mm.shape[0]
    cc = _matrix("damping_matrix", damping_matrix, n)
    kk = _matrix("stiffness_matrix", stiffness_matrix, n)
    _check_spd(mm)
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -np.linalg.solve(mm, kk)
    a[n:, n:] = -np.linalg.solve(mm, cc)
    return a


def generator_system(
    mass_matrix: ArrayLike,
    damping_matrix: ArrayLike,
    stiffness_matrix: ArrayLike,
    forcing: ArrayLike,
    generator: ArrayLike,
) -> np.ndarray:
    """State matrix of M q'' + C q' + K q = F g with the inputs g as states of their own, g' = G g.

    The autonomous form a scene's reference and its error bound share: a constant force or
    preload is a generator state with G = [[0]] (g = 1), a sinusoid a pair with
    G = [[0, omega], [-omega, 0]].

    Parameters
    ----------
    mass_matrix, damping_matrix, stiffness_matrix
        M [kg], C [N s/m], K [N/m], (n, n) (see :func:`state_matrix`).
    forcing
        F (n, m): generalized force per unit of each generator state [N per unit].
    generator
        G (m, m) [1/s].

    Returns
    -------
    ndarray
        A (2n + m, 2n + m) [1/s] of z = (q, q', g): [[state_matrix, [0; M^-1 F]], [0, G]].
    """
    top = state_matrix(mass_matrix, damping_matrix, stiffness_matrix)
    n = top.shape[0] // 2
    ff = np.asarray(forcing, float).reshape(n, -1)
    gg = np.asarray(generator, float).reshape(ff.shape[1], ff.shape[1])
    a = np.zeros((2 * n + gg.shape[0],) * 2)
    a[: 2 * n, : 2 * n] = top
    a[n : 2 * n, 2 * n :] = np.linalg.solve(np.asarray(mass_matrix, float), ff)
    a[2 * n :, 2 * n :] = gg
    return a


def _check_spd(mm: np.ndarray) -> None:
    scale = float(np.abs(mm).max()) if mm.size else 0.0
    if not np.allclose(mm, mm.T, rtol=0.0, atol=1e-12 * scale):
        raise ValueError("mass_matrix must be symmetric")
    try:
        np.linalg.cholesky(mm)
    except np.linalg.LinAlgError:
        raise ValueError("mass_matrix must be positive definite") from None


class _Propagator:
    """Exact one-step maps for z' = A z + B u with u constant over the step.

    A step of length h maps z -> e^{A h} z + G u with G = int_0^h e^{A s} ds B.
    Two representations of e^{A h} are used:

    * ``z + (D z + G u)`` with D = e^{A h} - I from :func:`expm_minus_identity`
      for ordinary steps.  Keeping D apart from the identity means reusing the
      same step 1e5 times does not accumulate the rounding of I + small, and
      slow modes of stiff systems stay exact.
    * ``Phi z + G u`` with Phi = e^{A h} from scipy.linalg.expm when the step is
      strongly contracting (||Phi||_1 <= 1/2), where I + D would keep only
      absolute accuracy while Phi keeps the decaying state relatively exact.
    """

    def __init__(self, a: np.ndarray, b: np.ndarray):
        self.a = a
        self.b = b
        self.n = a.shape[0]
        self.norm_a = _onenorm(a)
        self._cache: dict = {}

    def maps(self, h: float):
        """(contracting, M, G) for step h [s]; M is Phi if contracting else D."""
        hit = self._cache.get(h)
        if hit is not None:
            return hit
        n = self.n
        if h == 0.0:
            out = (False, np.zeros((n, n)), np.zeros_like(self.b))
        else:
            aug = np.zeros((2 * n, 2 * n))
            aug[:n, :n] = h * self.a
            aug[:n, n:] = np.eye(n)
            # exp([[hA, I], [0, 0]]) = [[e^{hA}, phi1(hA)], [0, I]],
            # phi1(hA) = sum (hA)^j / (j+1)!, so G = h phi1(hA) B.
            dx = expm_minus_identity(aug)
            gmat = h * (dx[:n, n:] @ self.b)
            phi = scipy.linalg.expm(aug[:n, :n])
            if _onenorm(phi) <= 0.5:
                out = (True, phi, gmat)
            else:
                out = (False, dx[:n, :n], gmat)
        self._cache[h] = out
        return out

    def step(self, z: np.ndarray, h: float, u: np.ndarray) -> np.ndarray:
        if h == 0.0:
            return z
        contracting, mmat, gmat = self.maps(h)
        if contracting:
            return mmat @ z + gmat @ u
        return z + (mmat @ z + gmat @ u)

    def run(self, z_start: np.ndarray, s_start: float, s: np.ndarray, u: np.ndarray) -> np.ndarray:
        """States at the non-decreasing times s >= s_start, from z(s_start)."""
        n_out = s.size
        out = np.empty((n_out, self.n))
        if n_out == 0:
            return out
        bu = self.b @ u
        span = s[-1] - s_start
        h = span / n_out
        grid = s_start + h * np.arange(1, n_out + 1)
        delta = s - grid
        max_delta = float(np.abs(delta).max())
        if n_out >= 8 and max_delta * self.norm_a <= 1e-4:
            self._run_uniform(out, z_start, h, u)
            if max_delta > 0.0:
                # Times deviate from the uniform grid by ulps: exact Taylor
                # correction z(g + delta) (the 4th-order term is < 1e-17).
                zd = out @ self.a.T + bu
                z2 = zd @ self.a.T
                z3 = z2 @ self.a.T
                dl = delta[:, None]
                out += dl * (zd + dl / 2.0 * (z2 + dl / 3.0 * z3))
            return out
        # Irregular grid: exact step by step, one exponential per distinct step.
        z = z_start
        prev = s_start
        for i in range(n_out):
            z = self.step(z, float(s[i] - prev), u)
            prev = s[i]
            out[i] = z
        return out

    def _run_uniform(self, out: np.ndarray, z_start: np.ndarray, h: float, u: np.ndarray) -> None:
        n_out = out.shape[0]
        block = min(n_out, 256)
        contracting, mmat, gmat = self.maps(h)
        # Maps for 1..block steps by doubling (j steps followed by L steps):
        #   Phi form: Phi_{j+L} = Phi_L Phi_j,          g_{j+L} = Phi_L g_j + g_L
        #   D form:   D_{j+L} = D_j + D_L + D_L D_j,    g_{j+L} = g_j + g_L + D_L g_j
        ms = mmat[None, :, :].copy()
        gs = (gmat @ u)[None, :].copy()
        while ms.shape[0] < block:
            ml, gl = ms[-1], gs[-1]
            if contracting:
                ms = np.concatenate([ms, ml @ ms])
                gs = np.concatenate([gs, gs @ ml.T + gl])
            else:
                ms = np.concatenate([ms, ms + ml + ml @ ms])
                gs = np.concatenate([gs, gs + gl + gs @ ml.T])
        ms, gs = ms[:block], gs[:block]
        if not contracting:
            # z + D_j z is only relatively exact while e^{A j h} = I + D_j has
            # not contracted the state; cap the block before that happens.
            norms = np.abs(ms + np.eye(self.n)).sum(axis=1).max(axis=1)
            small = np.flatnonzero(norms < 0.5)
            if small.size:
                block = max(1, int(small[0]))
                ms, gs = ms[:block], gs[:block]
        zb = z_start
        for b0 in range(0, n_out, block):
            cnt = min(block, n_out - b0)
            if contracting:
                out[b0 : b0 + cnt] = ms[:cnt] @ zb + gs[:cnt]
            else:
                out[b0 : b0 + cnt] = zb + (ms[:cnt] @ zb + gs[:cnt])
            zb = out[b0 + cnt - 1]


def _output_times(t) -> np.ndarray:
    times = np.atleast_1d(np.asarray(t, dtype=float))
    if times.ndim != 1:
        raise ValueError(f"t must be a 1-D array of times [s], got shape {times.shape}")
    if not np.all(np.isfinite(times)):
        raise ValueError("t must contain only finite times [s]")
    if times.size and times[0] < 0.0:
        raise ValueError("t must start at t[0] >= 0 [s]")
    if np.any(np.diff(times) < 0.0):
        raise ValueError("t must be non-decreasing")
    return times


def _parse_input(b, u, n: int):
    """-> (B (n, p), breakpoints (K,), values (K, p))."""
    if u is None:
        return np.zeros((n, 0)), np.zeros(1), np.zeros((1, 0))
    if b is None:
        raise ValueError("an input u needs an input matrix b")
    bmat = np.asarray(b, dtype=float)
    if bmat.ndim == 1:
        bmat = bmat[:, None]
    if bmat.ndim != 2 or bmat.shape[0] != n:
        raise ValueError(f"b must have shape ({n}, p), got {bmat.shape}")
    if not np.all(np.isfinite(bmat)):
        raise ValueError("b must be finite")
    p = bmat.shape[1]
    if isinstance(u, tuple) and len(u) == 2 and np.ndim(u[0]) == 1:
        bp = np.asarray(u[0], dtype=float)
        vals = np.asarray(u[1], dtype=float)
        if vals.ndim == 1 and p == 1:
            vals = vals[:, None]
        if bp.size == 0 or not np.all(np.isfinite(bp)):
            raise ValueError("breakpoints must be a non-empty finite 1-D array [s]")
        if bp[0] != 0.0:
            raise ValueError("the first breakpoint must be 0 [s]")
        if np.any(np.diff(bp) < 0.0):
            raise ValueError("breakpoints must be sorted")
        if vals.shape != (bp.size, p):
            raise ValueError(f"input values must have shape ({bp.size}, {p}), got {vals.shape}")
    else:
        vals = np.atleast_1d(np.asarray(u, dtype=float))
        if vals.shape != (p,):
            raise ValueError(f"constant input must have shape ({p},), got {vals.shape}")
        bp = np.zeros(1)
        vals = vals[None, :]
    if not np.all(np.isfinite(vals)):
        raise ValueError("input values must be finite")
    return bmat, bp, vals


def lti_response(
    t: ArrayLike,
    a: ArrayLike,
    z0: ArrayLike,
    b: ArrayLike | None = None,
    u: ArrayLike | tuple[ArrayLike, ArrayLike] | None = None,
) -> np.ndarray:
    """Exact solution of z' = A z + B u(t) with piecewise-constant input.

    Over each interval of constant input the exact map is read off
    expm([[A h, I], [0, 0]]) = [[e^{A h}, phi1(A h)], [0, I]], with
    int_0^h e^{A s} ds B = h phi1(A h) B; this needs no inverse of A, so
    singular A (rigid-body modes, harmonic generators) is exact.  The state is
    propagated segment by segment and between output times.  Runs of
    (near-)uniformly spaced output times reuse one exponential: maps for
    1..256 steps are built by doubling and applied block-wise (vectorised),
    and times that deviate from the uniform grid by roundoff are corrected
    with an exact short Taylor step.  Irregular grids take one exponential
    per distinct step size (slow if every step differs).

    Parameters
    ----------
    t
        Output times [s], 1-D, non-decreasing, t[0] >= 0 (need not be uniform).
    a
        State matrix A (N, N) [1/s].
    z0
        State at t = 0, shape (N,).
    b
        Input matrix B (N, p); required iff u is given.
    u
        None (no input), a constant input (p,) applied for t >= 0, or a
        tuple ``(breakpoints, values)``: sorted switch times (K,) [s] with
        breakpoints[0] == 0, and values (K, p), value i acting on
        [breakpoints[i], breakpoints[i+1]).

    Returns
    -------
    ndarray
        z: states at the output times, shape (len(t), N).

    Raises
    ------
    ValueError
        For mis-shaped or non-finite input, unsorted times or
        breakpoints, or a first breakpoint other than 0.
    """
    times = _output_times(t)
    amat = _matrix("a", a)
    n = amat.shape[0]
    z = np.asarray(z0, dtype=float).reshape(-1)
    if z.shape != (n,):
        raise ValueError(f"z0 must have shape ({n},), got {np.shape(z0)}")
    if not np.all(np.isfinite(z)):
        raise ValueError("z0 must be finite")
    bmat, bp, vals = _parse_input(b, u, n)
    prop = _Propagator(amat, bmat)
    out = np.empty((times.size, n))
    if times.size == 0:
        return out

    tau = 0.0
    j = 0
    n_seg = bp.size
    for seg in range(n_seg):
        u_seg = vals[seg]
        last = seg == n_seg - 1
        j2 = times.size if last else int(np.searchsorted(times, bp[seg + 1], side="left"))
        if j2 > j:
            # First output of the segment separately, so the rest can form a
            # uniform run even when the breakpoint is off the output grid.
            z = prop.step(z, float(times[j] - tau), u_seg)
            out[j] = z
            if j2 > j + 1:
                out[j + 1 : j2] = prop.run(z, float(times[j]), times[j + 1 : j2], u_seg)
            z = out[j2 - 1]
            tau = float(times[j2 - 1])
            j = j2
        if j >= times.size or last:
            break
        z = prop.step(z, float(bp[seg + 1] - tau), u_seg)
        tau = float(bp[seg + 1])
    return out


def linear_response(
    t: ArrayLike,
    mass_matrix: ArrayLike,
    damping_matrix: ArrayLike,
    stiffness_matrix: ArrayLike,
    q0: ArrayLike,
    v0: ArrayLike,
    force: ArrayLike | tuple[ArrayLike, ArrayLike] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Exact response of M q'' + C q' + K q = f(t) for an n-DOF linear system.

    Thin wrapper over :func:`lti_response` with A from :func:`state_matrix`
    and B = [[0], [M^-1]], so singular K (free rigid-body modes) is exact.

    Parameters
    ----------
    t
        Output times [s], 1-D, non-decreasing, t[0] >= 0.
    mass_matrix
        M (n, n) [kg], symmetric positive definite.
    damping_matrix
        C (n, n) [N s/m].
    stiffness_matrix
        K (n, n) [N/m].
    q0
        Initial displacements (n,) [m] at t = 0.
    v0
        Initial velocities (n,) [m/s] at t = 0.
    force
        None (free vibration), a constant force vector (n,) [N] for
        t >= 0 (pass an array or list), or ``(breakpoints, values)`` with
        breakpoints (K,) [s] starting at 0 and values (K, n) [N], value i
        acting on [breakpoints[i], breakpoints[i+1]).

    Returns
    -------
    tuple[ndarray, ndarray]
        (q, v): displacements [m] and velocities [m/s], each (len(t), n).

    Raises
    ------
    ValueError
        For non-physical, mis-shaped or non-finite input.
    """
    amat = state_matrix(mass_matrix, damping_matrix, stiffness_matrix)
    n = amat.shape[0] // 2
    q0 = np.asarray(q0, dtype=float).reshape(-1)
    v0 = np.asarray(v0, dtype=float).reshape(-1)
    if q0.shape != (n,) or v0.shape != (n,):
        raise ValueError(f"q0 and v0 must have shape ({n},)")
    bmat = None
    if force is not None:
        mm = np.atleast_2d(np.asarray(mass_matrix, dtype=float))
        bmat = np.zeros((2 * n, n))
        bmat[n:] = np.linalg.inv(mm)
    z = lti_response(t, amat, np.concatenate([q0, v0]), bmat, force)
    return z[:, :n], z[:, n:]
