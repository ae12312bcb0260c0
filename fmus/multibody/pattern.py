"""One CSR pattern for every matrix of a multibody system (mass, damping, stiffness, Newton
matrix), fixed at assembly: the union of the couplings the components declare. Matrices on
it differ only in their ``data`` arrays, so the Newton matrix c_a M + c_f (c_v C + K) is a sum
of arrays, and components scatter their blocks into ``data`` through positions found once
(:meth:`Pattern.positions`), as the catenary's structure does.

The pattern is structurally symmetric (every block is declared with its transpose), so its
CSR arrays read as CSC are the transpose: SuperLU factorizes that and solves with
``trans="T"`` (one single-threaded sparse factorization; a dense LAPACK factorization of the
same few hundred unknowns is several times slower when BLAS threads compete for the cores).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numba import njit

from ..core.scatter import scatter_add



@njit(cache=True)
def _find(indptr, indices, rows, cols, out):
    """out[k] = position of (rows[k], cols[k]) in the CSR arrays (-1 if absent)."""
    for k in range(rows.shape[0]):
        r, c = rows[k], cols[k]
        lo, hi = indptr[r], indptr[r + 1]
        while lo < hi:
            mid = (lo + hi) // 2
            if indices[mid] < c:
                lo = mid + 1
            else:
                hi = mid
        out[k] = lo if lo < indptr[r + 1] and indices[lo] == c else -1


def factorize_csr(S):
    """solve(rhs) for a CSR matrix S: SuperLU of its arrays read as CSC (S^T, no
    conversion), solved with trans="T"."""
    At = sp.csc_matrix((S.data, S.indices, S.indptr), shape=S.shape[::-1])
    lu = spla.splu(At)
    return lambda rhs: lu.solve(np.asarray(rhs, dtype=float), trans="T")


class Pattern:
    """The CSR pattern of an n x n matrix holding the given (rows, cols) couplings and their
    transposes."""

    def __init__(self, n: int, rows, cols):
        rows = np.concatenate([np.asarray(r, np.int64).ravel() for r in rows] or [[0]])
        cols = np.concatenate([np.asarray(c, np.int64).ravel() for c in cols] or [[0]])
        r = np.concatenate([rows, cols, np.arange(n)])     # the diagonal is always there
        c = np.concatenate([cols, rows, np.arange(n)])
        m = sp.csr_matrix((np.ones(r.size), (r, c)), shape=(n, n))
        m.sum_duplicates()
        m.sort_indices()
        self.n = n
        self.indptr = m.indptr.astype(np.int64)
        self.indices = m.indices.astype(np.int64)
        self.nnz = self.indices.size

    def positions(self, rows, cols) -> np.ndarray:
        """Positions in ``data`` of the couplings (rows, cols) (broadcast together);
        ValueError if one is not in the pattern."""
        rows, cols = np.broadcast_arrays(np.asarray(rows, np.int64), np.asarray(cols, np.int64))
        out = np.empty(rows.size, np.int64)
        _find(self.indptr, self.indices, np.ascontiguousarray(rows).ravel(),
              np.ascontiguousarray(cols).ravel(), out)
        if np.any(out < 0):
            k = int(np.argmax(out < 0))
            raise ValueError(f"coupling ({rows.ravel()[k]}, {cols.ravel()[k]}) is not in the "
                             "pattern: the component must declare it (tangent_dofs)")
        return out.reshape(rows.shape)

    def matrix(self, data) -> sp.csr_matrix:
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))



class PatternMatrix:
    """A matrix being assembled on a :class:`Pattern`: ``data`` and the block-adding
    interface of :class:`~pantocosim.multibody.triplets.Triplets` (for small components;
    element sets scatter through positions they keep)."""

    def __init__(self, pattern: Pattern):
        self.pattern = pattern
        self.data = np.zeros(pattern.nnz)

    def add(self, rows, cols, block) -> None:
        """Blocks: rows (..., a), cols (..., b), block (..., a, b)."""
        block = np.asarray(block, dtype=float)
        r = np.broadcast_to(np.asarray(rows)[..., :, None], block.shape)
        c = np.broadcast_to(np.asarray(cols)[..., None, :], block.shape)
        scatter_add(self.data, self.pattern.positions(r, c).ravel(), block.ravel())

    def add_entries(self, rows, cols, vals) -> None:
        scatter_add(self.data, self.pattern.positions(rows, cols).ravel(),
                    np.asarray(vals, dtype=float).ravel())

    def tocsr(self) -> sp.csr_matrix:
        return self.pattern.matrix(self.data)

    def toarray(self) -> np.ndarray:
        return self.tocsr().toarray()
