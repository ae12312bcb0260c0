"""Small dense systems inside numba kernels (a few contacts, a few slack droppers): no LAPACK
call, no allocation."""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def gauss_jordan(A, m) -> bool:
    """Reduce the leading m x m block of A (m x (m + k)) to the identity by row operations
    on whole rows, with partial pivoting, so the last k columns end as that block's inverse
    times what they held. Returns False (A partly reduced) when the block is singular."""
    width = A.shape[1]
    for col in range(m):
        p = col
        for r in range(col + 1, m):
            if abs(A[r, col]) > abs(A[p, col]):
                p = r
        if A[p, col] == 0.0:
            return False
        if p != col:
            for j in range(width):
                A[col, j], A[p, j] = A[p, j], A[col, j]
        inv = 1.0 / A[col, col]
        for j in range(width):
            A[col, j] *= inv
        for r in range(m):
            if r != col and A[r, col] != 0.0:
                f = A[r, col]
                for j in range(width):
                    A[r, j] -= f * A[col, j]
    return True
