"""Banded Cholesky factorization (LAPACK dpbtrf/dpbtrs) with cached unit-vector solves.

A factorization is reused across many Newton iterations and time steps; the solves against
unit vectors ``A^-1 e_j`` it is asked for again and again (the columns of the contact-wire
DOFs under a moving pantograph, for the low-rank contact update) are kept in a small
least-recently-used cache, so a pantograph pays one solve per DOF it meets, not per step.
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np
from scipy.linalg.lapack import dpbtrf, dpbtrs


class BandedCholesky:
    """``solve = BandedCholesky.factor(ab)``; ``solve(r)``, ``solve.solve_sparse(dofs, w)``.

    ``ab``: (bandwidth + 1, n) lower band storage (LAPACK 'L'); overwritten.
    ``factor`` returns None when the matrix is not positive definite."""

    #: unit-vector solves kept (each n floats)
    cache_size = 48

    def __init__(self, cb: np.ndarray):
        self.cb = cb
        self.n = cb.shape[1]
        self._columns: OrderedDict[int, np.ndarray] = OrderedDict()

    @classmethod
    def factor(cls, ab: np.ndarray) -> "BandedCholesky | None":
        cb, info = dpbtrf(ab, lower=1, overwrite_ab=1)
        return cls(cb) if info == 0 else None

    def __call__(self, rhs: np.ndarray) -> np.ndarray:
        x, _ = dpbtrs(self.cb, rhs, lower=1)
        return x

    def _cached(self, dofs) -> list:
        """The cached solves A^-1 e_j for j in dofs (computing the missing ones at once)."""
        cache = self._columns
        dofs = [int(j) for j in np.asarray(dofs, dtype=np.int64)]
        missing = [j for j in dofs if j not in cache]
        if missing:
            E = np.zeros((self.n, len(missing)))
            E[missing, np.arange(len(missing))] = 1.0
            X = self(E)
            for i, j in enumerate(missing):
                cache[j] = np.ascontiguousarray(X[:, i])
        out = []
        for j in dofs:
            cache.move_to_end(j)
            out.append(cache[j])
        while len(cache) > max(self.cache_size, len(dofs)):
            cache.popitem(last=False)
        return out

    def solve_sparse(self, dofs, values) -> np.ndarray:
        """A^-1 b for b with ``values`` at ``dofs`` (zero elsewhere)."""
        x = np.zeros(self.n)
        for col, w in zip(self._cached(dofs), np.asarray(values, dtype=float)):
            x += w * col
        return x
