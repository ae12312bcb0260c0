"""Banded Cholesky with cached unit-vector solves (pantocosim.core.banded)."""

import numpy as np
import scipy.linalg as sla

from pantocosim.core.banded import BandedCholesky


def _spd_band(n=60, kd=4, seed=0):
    rng = np.random.default_rng(seed)
    A = np.zeros((n, n))
    for k in range(1, kd + 1):
        d = rng.standard_normal(n - k)
        A += np.diag(d, k) + np.diag(d, -k)
    A += np.diag(2.0 * kd + 1.0 + rng.random(n))
    ab = np.zeros((kd + 1, n))
    for k in range(kd + 1):
        ab[k, :n - k] = np.diag(A, -k)
    return A, ab


def test_solves_and_cached_columns_match_a_dense_solve():
    A, ab = _spd_band()
    solve = BandedCholesky.factor(ab)
    rng = np.random.default_rng(1)
    r = rng.standard_normal(A.shape[0])
    assert np.allclose(solve(r), sla.solve(A, r), rtol=1e-12, atol=1e-13)
    dofs = np.array([3, 17, 40])
    Ainv = np.linalg.inv(A)
    for j in dofs:
        assert np.allclose(solve.solve_sparse([j], [1.0]), Ainv[:, j], atol=1e-13)
    w = np.array([0.5, -2.0, 1.5])
    assert np.allclose(solve.solve_sparse(dofs, w), Ainv[:, dofs] @ w, atol=1e-13)
    # the cache is bounded (least recently used out) and stays exact
    solve.cache_size = 4
    for j in range(10):
        solve.solve_sparse([j], [1.0])
    assert len(solve._columns) == 4 and list(solve._columns) == [6, 7, 8, 9]
    assert np.allclose(solve.solve_sparse([9, 0], [1.0, 0.0]), Ainv[:, 9], atol=1e-13)
    assert np.allclose(solve.solve_sparse([9, 0], [0.0, 1.0]), Ainv[:, 0], atol=1e-13)


def test_not_positive_definite_gives_none():
    A, ab = _spd_band()
    ab[0, 5] = -100.0
    assert BandedCholesky.factor(ab) is None


def test_band_solve_every_shape_against_lapack():
    """The two-rows-at-a-time substitution on even and odd sizes, band widths 1 to n + 2."""
    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 5, 8, 13):
        for kd in range(0, n + 2):
            kd_eff = min(kd, n - 1)
            A, ab = _spd_band(n, kd_eff, seed=n + kd)
            solve = BandedCholesky.factor(ab)
            r = rng.standard_normal(n)
            assert np.allclose(solve(r), sla.solve(A, r), rtol=1e-12, atol=1e-13), (n, kd)
            x = r.copy()
            solve.solve_into(x, x)                  # in place
            assert np.allclose(x, sla.solve(A, r), rtol=1e-12, atol=1e-13), (n, kd)
