"""Banded Cholesky factorization in one compiled pass, on the factor's columns as rows.

LAPACK's ``dpbtrf`` takes a band narrower than its block size (32) column by column, one BLAS
call (``dsyr``) per column: on the catenary's Newton matrix (7689 DOFs, band width 19) that
is 2.4 ms, mostly call overhead. The same right-looking elimination written as one loop

    L_jj = sqrt(A_jj),   L_ij = A_ij / L_jj,   A_il -= L_ij L_lj   (j < l <= i < j + w),

over storage ``LT[j, k] = A[j + k, j]`` (the lower band, a column per row: every update runs
over contiguous memory) takes about a sixth of it. It leaves the layout
:class:`~.banded.BandedCholesky` solves with: ``LT[j, 0] = 1 / L_jj``, ``LT[j, k] =
L_{j+k, j}``, and fills the factor's rows ``R[j, k] = L_{j, j-k}`` the back substitution
reads.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def lower_columns(data, src, dst, n, w):
    """(n, w) band columns as rows ``LT[j, k] = A[j + k, j]`` of a matrix given on a sparse
    pattern: ``data[src[i]]`` goes to flat position ``dst[i]`` (zero elsewhere)."""
    out = np.zeros(n * w)
    for i in range(src.shape[0]):
        out[dst[i]] = data[src[i]]
    return out.reshape(n, w)


@njit(cache=True)
def factor_columns(LT):
    """Cholesky factor of the band ``LT`` in place (layout above); True on success, False
    when a pivot is not positive (the matrix is not positive definite, or not finite)."""
    n, w = LT.shape
    for j in range(n):
        d = LT[j, 0]
        if not d > 0.0:
            return False
        inv = 1.0 / np.sqrt(d)
        LT[j, 0] = inv
        m = min(w - 1, n - 1 - j)
        for k in range(1, m + 1):
            LT[j, k] *= inv
        for k in range(1, m + 1):
            lk = LT[j, k]
            row = j + k
            for l in range(k, m + 1):
                LT[row, l - k] -= LT[j, l] * lk
    return True


@njit(cache=True)
def factor_rows(LT, R):
    """R[j, k] = L_{j, j-k} (zero for j < k), R[j, 0] = 1 / L_jj, from the factor ``LT``."""
    n, w = LT.shape
    for j in range(n):
        R[j, 0] = LT[j, 0]
        for k in range(1, w):
            R[j, k] = LT[j - k, k] if j >= k else 0.0
