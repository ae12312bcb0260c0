"""A kept factorization with a low-rank stiffness removal, by the Woodbury identity.

    (A - B S B^T)^-1 r = x + U (I - S B^T U)^-1 S B^T x,   x = A^-1 r,  U = A^-1 B,

with S = diag(s) (s > 0: the stiffness of elements that dropped out, e.g. slack droppers)
and B's columns sparse vectors b_j. The columns U are solved once and kept by the caller for
the whole run (:class:`ColumnCache`), so a new slack set costs an m x m solve, not a
factorization.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _dots(idx, val, x, rows, out):
    """out[r] = b_rows[r] . x (idx < 0: absent)."""
    for r in range(rows.shape[0]):
        i = rows[r]
        s = 0.0
        for k in range(idx.shape[1]):
            j = idx[i, k]
            if j >= 0:
                s += val[i, k] * x[j]
        out[r] = s


@njit(cache=True)
def _combine(idx, val, coef, rows, out):
    """out += sum_r coef[r] b_rows[r]."""
    for r in range(rows.shape[0]):
        i = rows[r]
        for k in range(idx.shape[1]):
            j = idx[i, k]
            if j >= 0:
                out[j] += coef[r] * val[i, k]


@njit(cache=True)
def _add_rows(Z, rows, c, out):
    """out += sum_r c[r] Z[rows[r]]."""
    for r in range(rows.shape[0]):
        z, cr = Z[rows[r]], c[r]
        for i in range(out.shape[0]):
            out[i] += cr * z[i]


@njit(cache=True)
def _woodbury(idx, val, rows, s, small_inv, Z, x):
    """x <- x + U small_inv (s * B_rows^T x), in place, with U = Z[rows]^T
    (:class:`LowRankSolve`)."""
    y = np.empty(rows.shape[0])
    _dots(idx, val, x, rows, y)
    _add_rows(Z, rows, small_inv @ (s * y), x)


class SparseVectors:
    """m sparse vectors of length n: ``idx`` (m, k) indices (-1 = absent), ``val`` (m, k)."""

    def __init__(self, idx: np.ndarray, val: np.ndarray, n: int):
        self.idx = np.asarray(idx, dtype=np.int64)
        self.val = np.where(self.idx >= 0, np.asarray(val, dtype=float), 0.0)
        self.n = int(n)
        self._pad_idx = np.where(self.idx >= 0, self.idx, self.n)
        self._all = np.arange(self.idx.shape[0], dtype=np.int64)

    def dots(self, x: np.ndarray, rows=None, out=None) -> np.ndarray:
        """b_j . x for every vector (or the ``rows``), into ``out`` if given."""
        rows = self._all if rows is None else np.asarray(rows, dtype=np.int64)
        out = np.empty(rows.shape[0]) if out is None else out
        _dots(self.idx, self.val, np.asarray(x, dtype=float), rows, out)
        return out

    def combine(self, coef: np.ndarray, rows, out=None) -> np.ndarray:
        """sum_j coef_j b_j over ``rows`` as a dense vector (added to ``out`` if given)."""
        out = np.zeros(self.n) if out is None else out
        _combine(self.idx, self.val, np.asarray(coef, dtype=float),
                 np.asarray(rows, dtype=np.int64), out)
        return out

    def dense(self, j: int) -> np.ndarray:
        return self.combine(np.ones(1), [j])


class ColumnCache:
    """A^-1 b_j of a kept banded factorization ``solve``
    (:class:`~pantocosim.core.banded.BandedCholesky`), computed on first use and kept as the
    rows of :attr:`Z` (the memory of every column is reserved at once; the system gives
    it page by page as columns are solved)."""

    def __init__(self, solve, vectors: SparseVectors):
        self.solve = solve
        self.vectors = vectors
        self.Z = np.zeros((vectors.idx.shape[0], vectors.n))
        self._known = np.zeros(vectors.idx.shape[0], dtype=bool)

    def ensure(self, rows) -> None:
        """Solve the columns of ``rows`` not solved yet."""
        rows = np.asarray(rows, dtype=np.int64)
        missing = rows[~self._known[rows]]
        if missing.size == 0:
            return
        for j in missing.tolist():            # each vector is short: a local solve
            idx = self.vectors.idx[j]
            idx = idx[idx >= 0]
            self.Z[j] = self.solve.solve_local(int(idx.min()), int(idx.max()),
                                               self.vectors.dense(j))
        self._known[missing] = True

    def prefill(self, rows=None) -> None:
        """Solve the columns of ``rows`` (default: every vector) now, e.g. at set-up, so
        that no step pays for them."""
        self.ensure(np.arange(self.vectors.idx.shape[0]) if rows is None else rows)


class LowRankSolve:
    """``solve(r)`` for A - sum_j s_j b_j b_j^T, with ``solve_sparse`` like the base's."""

    def __init__(self, cache: ColumnCache, rows: np.ndarray, scales: np.ndarray):
        self.base = cache.solve
        self.vectors = cache.vectors
        self.rows = np.asarray(rows, dtype=np.int64)
        self.s = np.asarray(scales, dtype=float)
        self.Z = cache.Z
        if self.rows.size:
            cache.ensure(self.rows)
            BtU = np.column_stack([self.vectors.dots(self.Z[j], self.rows)
                                   for j in self.rows.tolist()])
            self.small = np.eye(self.rows.size) - self.s[:, None] * BtU
            self._small_inv = np.linalg.inv(self.small)

    def _correct(self, x: np.ndarray) -> np.ndarray:
        """x <- x + U (I - S B^T U)^-1 S B^T x, in place."""
        if self.rows.size:
            v = self.vectors
            _woodbury(v.idx, v.val, self.rows, self.s, self._small_inv, self.Z, x)
        return x

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return self._correct(np.array(self.base(r), dtype=float))

    def solve_into(self, rhs: np.ndarray, out: np.ndarray) -> np.ndarray:
        """``out`` = solve of ``rhs`` without an n-length temporary (``out`` may be ``rhs``)."""
        self.base.solve_into(rhs, out)
        return self._correct(out)

    def solve_sparse(self, dofs, values, out=None) -> np.ndarray:
        return self._correct(self.base.solve_sparse(dofs, values, out=out))
