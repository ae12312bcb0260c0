"""Banded Cholesky with cached unit-vector solves (pantocosim.core.banded)."""

import numpy as np
import pytest
import scipy.linalg as sla

from pantocosim.core import band_window
from pantocosim.core.banded import BandedCholesky


def same_solution(x, expected, A, kd):
    """x agrees with ``expected`` (both backward-stable solves of A x = b, or columns of A^-1)
    within twice the forward error bound of one, cond(A) 8 (kd + 1) eps of max|expected|: the
    bound of a banded Cholesky solve, rows of kd + 1 terms (cond(A) from Gershgorin's discs
    where A is diagonally dominant, else computed)."""
    d = np.abs(np.diag(A))
    off = np.abs(A).sum(axis=1) - d
    cond = ((d + off).max() / (d - off).min() if np.all(d > off)
            else np.linalg.cond(A))
    tol = 2 * cond * 8 * (kd + 1) * np.finfo(float).eps * np.abs(expected).max()
    return np.abs(np.asarray(x) - expected).max() <= tol


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
    assert same_solution(solve(r), sla.solve(A, r), A, 4)
    dofs = np.array([3, 17, 40])
    Ainv = np.linalg.inv(A)
    for j in dofs:
        assert same_solution(solve.solve_sparse([j], [1.0]), Ainv[:, j], A, 4)
    w = np.array([0.5, -2.0, 1.5])
    assert same_solution(solve.solve_sparse(dofs, w), Ainv[:, dofs] @ w, A, 4)
    # the cache is bounded (least recently used out) and stays exact
    solve.cache_size = 4
    for j in range(10):
        solve.solve_sparse([j], [1.0])
    assert len(solve._slots) == 4 and list(solve._slots) == [6, 7, 8, 9]
    assert same_solution(solve.solve_sparse([9, 0], [1.0, 0.0]), Ainv[:, 9], A, 4)
    assert same_solution(solve.solve_sparse([9, 0], [0.0, 1.0]), Ainv[:, 0], A, 4)


def test_not_positive_definite_gives_none():
    A, ab = _spd_band()
    ab[0, 5] = -100.0
    assert BandedCholesky.factor(ab) is None


def test_factor_layout_rows_and_several_right_hand_sides():
    """The kept factor: LT[j, 0] = 1 / L[j, j], LT[j, k] = L[j + k, j], and its rows
    R[j, k] = L[j, j - k] for the back substitution, on sizes below, at and above the band
    width; a block of right-hand sides is solved as each alone."""
    rng = np.random.default_rng(5)
    for n, kd in ((1, 0), (2, 1), (7, 3), (60, 4), (300, 18)):
        A, ab = _spd_band(n, kd, seed=n)
        solve = BandedCholesky.factor(ab)
        L = np.linalg.cholesky(A)
        tol = 1e-13 * np.abs(L).max()
        for j in range(n):
            assert abs(1.0 / solve.LT[j, 0] - L[j, j]) <= tol
            k = min(kd, n - 1 - j)
            assert np.abs(solve.LT[j, 1:k + 1] - L[j + 1:j + k + 1, j]).max(initial=0.0) <= tol
            if solve.R is not None:
                m = min(j, kd)
                expected = np.array([L[j, j - k] for k in range(1, m + 1)])
                assert np.abs(solve.R[j, 1:m + 1] - expected).max(initial=0.0) <= tol
                assert not solve.R[j, m + 1:].any()
        R2 = rng.standard_normal((n, 3))
        assert same_solution(solve(R2), sla.solve(A, R2), A, kd)


def test_band_solve_every_shape_against_lapack():
    """The two-rows-at-a-time substitution on even and odd sizes, band widths 1, 2, 3, about
    half and all of n, and beyond n (each width compiles a kernel: not every one between)."""
    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 5, 8, 13):
        for kd in sorted({0, 1, 2, n // 2, n - 1, n, n + 1}):
            kd_eff = min(kd, n - 1)
            A, ab = _spd_band(n, kd_eff, seed=n + kd)
            solve = BandedCholesky.factor(ab)
            r = rng.standard_normal(n)
            assert same_solution(solve(r), sla.solve(A, r), A, kd_eff), (n, kd)
            x = r.copy()
            solve.solve_into(x, x)                  # in place
            assert same_solution(x, sla.solve(A, r), A, kd_eff), (n, kd)


def test_local_solves_equal_full_solves_on_a_long_band():
    """A unit vector's solve decays away from its entry; the local solve stops where it is
    below 1e-20 of its peak and must agree with the full solve to round-off."""
    n, kd = 3000, 7
    A, ab = _spd_band(n, kd, seed=4)
    ab[0] += 40.0                       # a mass-dominated step matrix: fast decay
    A += 40.0 * np.eye(n)
    solve = BandedCholesky.factor(ab.copy())
    for j in (0, 1, 1500, n - 2, n - 1):
        e = np.zeros(n)
        e[j] = 1.0
        full = sla.solve_banded((kd, kd), _general_band(A, kd), e)
        local = solve.solve_local(j, j)
        assert same_solution(local, full, A, kd), j
        assert np.count_nonzero(local) < n / 3          # it did stop early
    b = np.zeros(n)
    b[[700, 703, 709]] = [1.0, -2.0, 0.5]
    x = solve.solve_local(700, 709, b)
    assert same_solution(x, sla.solve(A, b), A, kd)


def _general_band(A, kd):
    n = A.shape[0]
    out = np.zeros((2 * kd + 1, n))
    for k in range(-kd, kd + 1):
        d = np.diag(A, k)
        if k >= 0:
            out[kd - k, k:] = d
        else:
            out[kd - k, :n + k] = d
    return out


def test_window_substitution_of_every_kind_of_width_against_lapack():
    """The generated kernels (pending sums in registers) on widths from a diagonal matrix
    to the widest given a kernel; wider bands keep the array substitution."""
    rng = np.random.default_rng(5)
    n = 70
    for w in (1, 2, 3, 5, 8, 19, band_window.MAX_WIDTH, band_window.MAX_WIDTH + 1):
        A, ab = _spd_band(n, w - 1, seed=w)
        solve = BandedCholesky.factor(ab)
        assert (solve._window is None) == (w > band_window.MAX_WIDTH), w
        r = rng.standard_normal(n)
        expected = sla.solve(A, r)
        assert same_solution(solve(r), expected, A, w - 1), w
        x = r.copy()
        solve.solve_into(x, x)                      # in place
        assert same_solution(x, expected, A, w - 1), w


@pytest.fixture
def kernel_folder(monkeypatch, tmp_path):
    """A kernel folder of the test's own, and :func:`band_window.solver` forgetting what it
    loaded before and after the test."""
    monkeypatch.setenv(band_window.FOLDER_VARIABLE, str(tmp_path))
    band_window.solver.cache_clear()
    yield tmp_path
    band_window.solver.cache_clear()


def _solves_like_lapack(kernels, n, kd, seed):
    A, ab = _spd_band(n, kd, seed=seed)
    chol = BandedCholesky.factor(ab)
    r = np.random.default_rng(seed + 1).standard_normal(n)
    x = np.empty(n)
    kernels.solve(chol.LT, chol.R, r, x)
    return same_solution(x, sla.solve(A, r), A, kd)


def test_window_kernel_compiled_in_memory_where_no_folder_is_writable(monkeypatch,
                                                                       kernel_folder):
    blocked = kernel_folder / "file"
    blocked.write_text("")                          # a file where a folder should be
    monkeypatch.setattr(band_window, "_folders", lambda: iter([blocked / "kernels"]))
    assert _solves_like_lapack(band_window.solver(4), 30, 3, seed=8)
    assert not (blocked / "kernels").exists()


def test_window_kernel_module_is_written_once(kernel_folder):
    band_window.solver(6)
    written = list(kernel_folder.glob("band_window_w6_*.py"))
    assert len(written) == 1
    stamp = written[0].stat().st_mtime_ns
    band_window.solver.cache_clear()
    band_window.solver(6)                            # found, not written again
    assert written[0].stat().st_mtime_ns == stamp


def test_window_kernel_compiled_in_memory_when_its_file_cannot_be_loaded(kernel_folder):
    band_window.solver(7)
    (written,) = kernel_folder.glob("band_window_w7_*.py")
    written.write_text("raise ImportError('damaged')\n")   # same name, other content
    band_window.solver.cache_clear()
    assert _solves_like_lapack(band_window.solver(7), 40, 6, seed=11)
