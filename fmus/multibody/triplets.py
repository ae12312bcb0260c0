"""Sparse assembly by (row, column, value) triplets: components add element blocks, the
system turns the lot into one CSR matrix (duplicates summed)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


class Triplets:
    def __init__(self, n: int, m: int | None = None):
        self.shape = (n, n if m is None else m)
        self.rows: list[np.ndarray] = []
        self.cols: list[np.ndarray] = []
        self.vals: list[np.ndarray] = []

    def add(self, rows, cols, block) -> None:
        """Blocks: rows (..., a), cols (..., b), block (..., a, b)."""
        rows = np.asarray(rows)
        cols = np.asarray(cols)
        block = np.asarray(block, dtype=float)
        r = np.broadcast_to(rows[..., :, None], block.shape)
        c = np.broadcast_to(cols[..., None, :], block.shape)
        self.rows.append(r.reshape(-1))
        self.cols.append(c.reshape(-1))
        self.vals.append(block.reshape(-1))

    def add_entries(self, rows, cols, vals) -> None:
        self.rows.append(np.asarray(rows).reshape(-1))
        self.cols.append(np.asarray(cols).reshape(-1))
        self.vals.append(np.asarray(vals, dtype=float).reshape(-1))

    def tocsr(self) -> sp.csr_matrix:
        if not self.rows:
            return sp.csr_matrix(self.shape)
        return sp.csr_matrix((np.concatenate(self.vals),
                              (np.concatenate(self.rows), np.concatenate(self.cols))),
                             shape=self.shape)

    def toarray(self) -> np.ndarray:
        """Dense sum of the triplets (np.bincount: much cheaper than a CSR for small
        systems)."""
        n, m = self.shape
        if not self.rows:
            return np.zeros(self.shape)
        flat = np.concatenate(self.rows) * m + np.concatenate(self.cols)
        return np.bincount(flat, weights=np.concatenate(self.vals),
                           minlength=n * m).reshape(n, m)
