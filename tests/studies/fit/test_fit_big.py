"""Long records: the exact reductions (springlab.studies.fit.reductions) and the fit on them.

References are independent of the code under test: numpy's own products (J^T J, J^T r, |r|^2) and
numpy.linalg.lstsq on the whole matrix, per-sample sums written out below, scipy.optimize.least_squares on
every sample, and the fit of the same record forced through its per-sample path (reductions.BLOCK raised
above the record, so that nothing is reduced).

Tolerances. Householder QR of an m x k matrix A is backward stable: R is the exact factor of A + dA with
|dA|_F <= c m k eps |A|_F (Higham, Accuracy and Stability, thm 19.4; c a small constant, 1 here because the
bound is far from tight), so R^T R - A^T A is at most 2 m k eps |A|_F^2 (plus numpy's own sum's m eps
|A|_F^2). A least-squares solution moves by at most eps cond(A) (1 + cond(A) |r| / (|A| |x|)) relative
(Higham thm 20.1), times the same m k. The fits: both paths minimise the same cost, so their estimates
differ by no more than the Gauss-Newton step each reports still to go (fit.json's convergence
remaining_step) plus sysid's forward-difference Jacobian, sqrt(eps) relative per column, through the
correlation matrix's condition; half-widths by that same finite-difference error.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.optimize

from springlab.studies.fit import reductions
from springlab.studies.fit.fit import fit

EPS = np.finfo(float).eps


def qr_bound(a: np.ndarray) -> float:
    """Backward-error bound of R^T R against A^T A for A (m, k) [units of A squared] (module docstring)."""
    m, k = a.shape
    return (2 * k + 1) * m * EPS * float(np.sum(a * a))


@pytest.mark.parametrize("sizes", [(5000, 700, 3), (1, 2, 64, 3000)])
def test_triangular_holds_the_normal_equations_of_all_its_parts(sizes):
    # parts of random sizes (some with fewer rows than columns) stacked: R^T R = J^T J, R^T z = J^T r,
    # |z|^2 + rho^2 = |r|^2 for the factor [[R, z], [0, rho]] of [J | r]
    rng = np.random.default_rng(len(sizes))
    p = 5
    parts = [rng.normal(size=(m, p + 1)) * np.array([1.0, 1e3, 1e-3, 7.0, 0.5, 2.0]) for m in sizes]
    whole = np.vstack(parts)
    factor = reductions.triangular(iter(parts))
    assert factor.shape == (p + 1, p + 1)
    assert np.allclose(factor, np.triu(factor), rtol=0, atol=0), "the factor is upper triangular"
    j, r = whole[:, :p], whole[:, p]
    big_r, z, rho = factor[:p, :p], factor[:p, p], factor[p, p]
    bound = qr_bound(whole)
    assert np.max(np.abs(big_r.T @ big_r - j.T @ j)) <= bound
    assert np.max(np.abs(big_r.T @ z - j.T @ r)) <= bound
    assert abs(z @ z + rho**2 - r @ r) <= bound
    # and far from the bound's slack: dropping one row of the record breaks it
    assert np.max(np.abs(big_r.T @ big_r - j[1:].T @ j[1:])) > bound


def test_blockwise_least_squares_is_numpys_on_the_whole(monkeypatch):
    rng = np.random.default_rng(3)
    n, k = 10_007, 4
    a = rng.normal(size=(n, k)) @ np.diag([1.0, 10.0, 0.1, 3.0])
    truth = np.array([2.0, -1.0, 0.5, 3.0])
    b = a @ truth + rng.normal(0.0, 0.1, n)
    expected = np.linalg.lstsq(a, b, rcond=None)[0]
    calls = []

    def rows(start, stop):
        calls.append((start, stop))
        return a[start:stop], b[start:stop]

    monkeypatch.setattr(reductions, "BLOCK", 1000)  # 11 blocks, the last one short
    got = reductions.lstsq(n, rows)
    assert len(calls) == 11 and calls[-1] == (10_000, 10_007)
    cond = np.linalg.cond(a)
    residual = np.linalg.norm(a @ expected - b)
    relative = n * k * EPS * cond * (1 + cond * residual / (np.linalg.norm(a, 2) * np.linalg.norm(expected)))
    assert np.linalg.norm(got - expected) <= relative * np.linalg.norm(expected)


def test_a_short_least_squares_is_numpys_own(monkeypatch):
    # at most BLOCK rows: numpy.linalg.lstsq of the whole, bit for bit (small records as before)
    rng = np.random.default_rng(4)
    a, b = rng.normal(size=(300, 3)), rng.normal(size=300)
    assert np.array_equal(reductions.lstsq(300, lambda i, j: (a[i:j], b[i:j])), np.linalg.lstsq(a, b, rcond=None)[0])


def grouped_problem(seed: int, block: int, monkeypatch):
    """Random groups (sizes 1 to 12, i.e. fewer and more samples than q + 1) with a q = 4 basis per sample."""
    rng = np.random.default_rng(seed)
    sizes = rng.integers(1, 13, size=60)
    group = np.repeat(np.arange(sizes.size) * 2 + 3, sizes)  # ids need not be 0..G-1, only non-decreasing
    n, q = group.size, 4
    basis = rng.normal(size=(n, q))
    y = rng.normal(size=n)
    monkeypatch.setattr(reductions, "BLOCK", block)  # blocks that cut through groups
    reduced = reductions.Grouped(n, lambda index: (group[index], basis[index]), q, lambda index: y[index])
    return reduced, group, basis, y, sizes


@pytest.mark.parametrize("block", [7, 64, 100_000])
def test_grouped_reduction_gives_the_per_sample_sums(block, monkeypatch):
    reduced, group, basis, y, sizes = grouped_problem(block, block, monkeypatch)
    assert reduced.rows == int(np.sum(np.minimum(sizes, 5)))
    assert np.array_equal(reduced.counts, sizes)
    rng = np.random.default_rng(11)
    coefficients = rng.normal(size=(group.max() + 1, 4))
    per_sample = np.einsum("nq,nq->n", basis, coefficients[group]) - y
    residual = reduced.residual(coefficients)
    # the sum of squares, per group and in all
    bound = qr_bound(np.column_stack([basis, y])) * (1 + float(np.max(np.abs(coefficients)))) ** 2
    assert abs(residual @ residual - per_sample @ per_sample) <= bound
    for g in np.unique(group):
        rows = reduced.group == g
        assert abs(residual[rows] @ residual[rows] - per_sample[group == g] @ per_sample[group == g]) <= bound
    # the Jacobian in the coefficients (B_i in group g's columns) and another vector under the same rotations:
    # J_r^T J_r = J^T J and J_r^T (Q^T v) = J^T v
    columns = group.max() + 1

    def jacobian(groups, weights):
        out = np.zeros((groups.size, columns * 4))
        for i, (g, w) in enumerate(zip(groups, weights)):
            out[i, g * 4 : g * 4 + 4] = w
        return out

    full, small = jacobian(group, basis), jacobian(reduced.group, reduced.weights)
    v = np.sin(np.arange(group.size))
    rotated = reduced.reduce(lambda index: v[index])
    assert np.max(np.abs(small.T @ small - full.T @ full)) <= bound
    assert np.max(np.abs(small.T @ rotated - full.T @ v)) <= qr_bound(np.column_stack([basis, v]))
    assert abs(rotated @ rotated - v @ v) <= qr_bound(np.column_stack([basis, v]))  # a rotation: |Q^T v| = |v|


def test_reduced_rows_give_scipy_the_per_sample_solution(monkeypatch):
    # a damped cosine's four parameters by scipy.optimize.least_squares on every sample and on the p + 1
    # reduced rows of reductions.Reduced: the same minimum
    rng = np.random.default_rng(5)
    n = 9000
    t = np.linspace(0.0, 3.0, n)
    truth = np.array([0.02, 1.0, 20.0, 0.3])
    sigma = 1e-3

    def model(x, tt):
        return x[0] * np.exp(-x[1] * tt) * np.cos(x[2] * tt + x[3])

    def jacobian(x):
        """The model's derivatives in its four parameters, by hand."""
        decay, angle = np.exp(-x[1] * t), x[2] * t + x[3]
        c, s = decay * np.cos(angle), decay * np.sin(angle)
        return np.column_stack([c, -x[0] * t * c, -x[0] * t * s, -x[0] * s])

    y = model(truth, t) + rng.normal(0.0, sigma, n)

    def residual(x, start=0, stop=None):
        return model(x, t[start:stop]) - y[start:stop]

    start = np.array([0.021, 0.9, 20.05, 0.25])
    bounds = (np.array([0.0, 0.0, 10.0, -1.0]), np.array([1.0, 10.0, 30.0, 1.0]))
    options = {"bounds": bounds, "x_scale": "jac", "xtol": 1e-15, "ftol": 1e-15, "gtol": 1e-15}
    whole = scipy.optimize.least_squares(residual, start, **options)
    monkeypatch.setattr(reductions, "BLOCK", 1000)
    reduced = reductions.Reduced(n, residual, bounds)
    got = scipy.optimize.least_squares(reduced.fun, start, jac=reduced.jac, **options)
    assert got.fun.size == 5  # p + 1 rows, not n
    assert reduced.evaluations >= got.nfev  # one pass over the blocks per point
    assert abs(2 * got.cost - 2 * whole.cost) <= n * EPS * 2 * whole.cost
    # both stop near the same minimum (ftol: on the round-off floor of the cost): each within its own remaining
    # Gauss-Newton step (exact derivatives, by hand), plus forward differences' sqrt(eps) per column through the
    # normal matrix's condition, in standard errors
    j = jacobian(whole.x)
    standard_error = np.sqrt(np.diag(np.linalg.inv(j.T @ j)) * (2 * whole.cost / (n - 4)))
    scaled = j / np.linalg.norm(j, axis=0)
    allowed = math.sqrt(EPS) * np.linalg.cond(scaled.T @ scaled) * standard_error
    for x in (whole.x, got.x):
        allowed = allowed + np.abs(np.linalg.lstsq(jacobian(x), -residual(x), rcond=None)[0])
    assert np.all(np.abs(got.x - whole.x) <= allowed)
    assert np.all(np.abs(got.x - whole.x) <= 1e-4 * standard_error)  # and far inside the noise


def ring_down(n: int, seed: int = 1) -> dict[str, np.ndarray]:
    """A 20 mm release of a 20 rad/s, zeta = 0.05 mode over 3 s, 1 mm noise (closed form written out)."""
    t = np.linspace(0.0, 3.0, n)
    omega, zeta, x0 = 20.0, 0.05, 0.02
    wd = omega * math.sqrt(1 - zeta**2)
    x = x0 * np.exp(-zeta * omega * t) * (np.cos(wd * t) + zeta * omega / wd * np.sin(wd * t))
    return {"time": t, "slider_pos": x + np.random.default_rng(seed).normal(0.0, 1e-3, n)}


def reductions_made(monkeypatch) -> list[str]:
    """Which reductions a fit builds (the grouped one of the MuJoCo fit, the cross-check's)."""
    made: list[str] = []
    for cls in (reductions.Grouped, reductions.Reduced):
        original = cls.__init__

        def spy(self, *args, _original=original, _name=cls.__name__, **kwargs):
            made.append(_name)
            _original(self, *args, **kwargs)

        monkeypatch.setattr(cls, "__init__", spy)
    return made


@pytest.mark.slow  # two fits of 69 000 samples (about 2 s and 3 s on one core)
def test_a_record_above_the_block_size_gives_the_per_sample_fit(monkeypatch):
    data = ring_down(reductions.BLOCK + 4000)
    made = reductions_made(monkeypatch)
    reduced = fit("slider", data, mass=2.0, start=0.0, run_scene=False, show_progress=False)
    assert made == ["Grouped", "Reduced"], "the long record is fitted on its reduced rows"
    monkeypatch.setattr(reductions, "BLOCK", 10**9)
    made.clear()
    per_sample = fit("slider", data, mass=2.0, start=0.0, run_scene=False, show_progress=False)
    assert made == [], "the reference fit is the per-sample one"
    assert reduced.dof == per_sample.dof == data["time"].size - 5
    said = [note for note in reduced.record.notes if "rows that reduce the" in note]
    assert len(said) == 1 and not any("rows that reduce the" in note for note in per_sample.record.notes)
    assert reduced.converged and per_sample.converged
    condition = np.linalg.cond(per_sample.correlation)
    finite_differences = math.sqrt(EPS) * condition
    for name in per_sample.free:
        a, b = reduced.estimates[name], per_sample.estimates[name]
        half = b["ci95"][1] - b["value"]
        to_go = abs(reduced.convergence["remaining_step"][name]) + abs(per_sample.convergence["remaining_step"][name])
        assert abs(a["value"] - b["value"]) <= to_go + finite_differences * half, name
        assert abs((a["ci95"][1] - a["value"]) / half - 1) <= finite_differences, name
    assert abs(reduced.residual_rms / per_sample.residual_rms - 1) <= finite_differences
    # the fitted signal at every sample: one rollout at (nearly) the same estimate
    size = float(np.max(np.abs(data["slider_pos"])))
    assert np.max(np.abs(reduced.fitted - per_sample.fitted)) <= 1e-6 * size
    assert reduced.cross_check["agrees"] and per_sample.cross_check["agrees"]


def test_a_record_of_block_size_is_fitted_per_sample(monkeypatch):
    # small records exactly as before: nothing reduced, numpy and scipy on every sample
    monkeypatch.setattr(reductions, "BLOCK", 2000)
    made = reductions_made(monkeypatch)
    result = fit("slider", ring_down(2000), mass=2.0, start=0.0, run_scene=False, show_progress=False)
    assert made == [] and result.converged and result.dof == 2000 - 5


def test_above_the_block_size_but_sparse_against_the_grid_is_fitted_per_sample(monkeypatch):
    # fewer than COMPRESS_PER_STEP samples per simulation step: the reduction would not shrink the problem
    monkeypatch.setattr(reductions, "BLOCK", 500)
    made = reductions_made(monkeypatch)
    result = fit("slider", ring_down(1000), mass=2.0, start=0.0, run_scene=False, show_progress=False)
    assert "Grouped" not in made and result.converged


@pytest.mark.slow  # four starts' fits of 69 000 samples (about 2 s and 5 s on one core)
def test_multi_start_on_a_long_record_gives_the_per_sample_fit(monkeypatch):
    # each start rebuilds the problem from plain data (springlab.studies.fit.starts) and reduces it again on its
    # own grid: the best start's reduced residuals must be the main problem's
    data = ring_down(reductions.BLOCK + 4000, seed=2)
    made = reductions_made(monkeypatch)
    reduced = fit("slider", data, mass=2.0, start=0.0, run_scene=False, starts=2, show_progress=False)
    assert "Grouped" in made
    monkeypatch.setattr(reductions, "BLOCK", 10**9)
    per_sample = fit("slider", data, mass=2.0, start=0.0, run_scene=False, starts=2, show_progress=False)
    assert reduced.converged and per_sample.converged
    finite_differences = math.sqrt(EPS) * np.linalg.cond(per_sample.correlation)
    for name in per_sample.free:
        a, b = reduced.estimates[name], per_sample.estimates[name]
        half = b["ci95"][1] - b["value"]
        to_go = abs(reduced.convergence["remaining_step"][name]) + abs(per_sample.convergence["remaining_step"][name])
        assert abs(a["value"] - b["value"]) <= to_go + finite_differences * half, name
        assert abs((a["ci95"][1] - a["value"]) / half - 1) <= finite_differences, name
