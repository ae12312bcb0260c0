"""Quadratic holonomic constraints, vectorised.

Every constraint of the multibody core -- director orthonormality, joints, clamps -- is a
polynomial of degree at most two in the nodal coordinates, because a node's orientation is
carried by its three directors (no rotation parameters). One constraint j acts on a few local
coordinates q_l = q[idx_j]:

    g_j(q) = 1/2 q_l^T H_j q_l + b_j . q_l + c_j,
    grad g_j = H_j q_l + b_j,          Hessian = H_j (constant),

so the constraint Jacobian is exact and the multiplier term sum_j lambda_j H_j of the tangent
is exact too. The equations of motion are the Lagrange equations with multipliers
(Cardona & Jordi, eq. 112): M a + f(q, v) + G^T lambda = 0, g(q) = 0.

Rheonomic constraints (an actuator imposing a motion, Cardona & Jordi, 9.6) add a known function of
time, g_j(q, t) = ... + r_j(t): a set's ``drive`` returns (r, r', r'') at t, and the second
time derivative of g_j becomes G_j a + v^T H_j v + r_j''(t).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _constraint_kernel(q, lam, s, idx, H, b, c, f, g, kdata, pos_h, pos_g, pos_gt, want_k,
                       grad):
    """g_j, f += s lambda_j grad g_j and, if ``want_k``, s lambda_j H_j and the rows and
    columns s grad g_j of the Newton matrix at their pattern positions (-1: none)."""
    m, nl = idx.shape
    for j in range(m):
        val = c[j]
        for a in range(nl):
            acc = b[j, a]
            for k in range(nl):
                if H[j, a, k] != 0.0:
                    acc += H[j, a, k] * q[idx[j, k]]
            grad[a] = acc
            val += (0.5 * (acc - b[j, a]) + b[j, a]) * q[idx[j, a]]
        g[j] = val
        sl = s * lam[j]
        for a in range(nl):
            f[idx[j, a]] += sl * grad[a]
        if want_k:
            for a in range(nl):
                for k in range(nl):
                    p = pos_h[j, a * nl + k]
                    if p >= 0:
                        kdata[p] += sl * H[j, a, k]
                p = pos_g[j, a]
                if p >= 0:
                    kdata[p] += s * grad[a]
                    kdata[pos_gt[j, a]] += s * grad[a]


class ConstraintSet:
    """``m`` constraints on ``nl`` local coordinates each (idx (m, nl) into the global q).

    ``drive``: None, or a function t -> (r, r', r'') (each broadcastable to (m,)) added to c.
    """

    def __init__(self, idx, H, b, c, name: str = "", drive=None):
        self.idx = np.ascontiguousarray(idx, dtype=np.int64)
        m, nl = self.idx.shape
        self.H = np.ascontiguousarray(np.broadcast_to(H, (m, nl, nl)), dtype=float)
        self.b = np.ascontiguousarray(np.broadcast_to(b, (m, nl)), dtype=float)
        self.c = np.ascontiguousarray(np.broadcast_to(c, (m,)), dtype=float)
        self.name = name
        #: (first row, number of rows, drive) of the driven rows
        self.drives = [] if drive is None else [(0, m, drive)]

    @property
    def size(self) -> int:
        return self.idx.shape[0]

    def values(self, q, t: float = 0.0):
        ql = q[self.idx]
        g = 0.5 * np.einsum("mi,mij,mj->m", ql, self.H, ql) + np.einsum("mi,mi->m", self.b,
                                                                          ql) + self.c
        if self.drives:
            g += self.time_terms(t)[0]
        return g

    def time_terms(self, t: float):
        """(r, r', r''): the driven part of the constraints and its time derivatives at t
        (zero on the rows without a drive)."""
        out = np.zeros((3, self.size))
        for start, m, drive in self.drives:
            for k, val in enumerate(drive(t)):
                out[k, start:start + m] = val
        return out

    def gradients(self, q):
        """(m, nl) local rows of the Jacobian."""
        ql = q[self.idx]
        return np.einsum("mij,mj->mi", self.H, ql) + self.b

    def curvature(self, v):
        """v^T H_j v: the velocity term of the second time derivative of g_j."""
        vl = v[self.idx]
        return np.einsum("mi,mij,mj->m", vl, self.H, vl)

    # ------------------------------------------------------------------ system kernel
    def couplings(self, n_q: int):
        """(rows, cols) of the Newton-matrix entries the constraints fill: the nonzero H_j
        entries and, for the coordinates a constraint involves, its row n_q + j and column."""
        j, a, k = np.nonzero(self.H)
        active = np.any(self.H != 0.0, axis=2) | (self.b != 0.0)
        jj, aa = np.nonzero(active)
        rows = [self.idx[j, a], n_q + jj]
        cols = [self.idx[j, k], self.idx[jj, aa]]
        return rows, cols

    def locate(self, pattern, n_q: int) -> None:
        """Keep the pattern positions of :meth:`couplings` (-1 where nothing is filled)."""
        m, nl = self.idx.shape
        self._pos_h = np.full((m, nl * nl), -1, np.int64)
        self._pos_g = np.full((m, nl), -1, np.int64)
        self._pos_gt = np.full((m, nl), -1, np.int64)
        j, a, k = np.nonzero(self.H)
        self._pos_h[j, a * nl + k] = pattern.positions(self.idx[j, a], self.idx[j, k])
        jj, aa = np.nonzero(np.any(self.H != 0.0, axis=2) | (self.b != 0.0))
        self._pos_g[jj, aa] = pattern.positions(n_q + jj, self.idx[jj, aa])
        self._pos_gt[jj, aa] = pattern.positions(self.idx[jj, aa], n_q + jj)
        self._grad = np.empty(nl)

    def add_forces(self, t, q, lam, s, f, kdata=None):
        """g(q, t), with f += s G^T lambda and the constraint entries of the Newton matrix
        added to ``kdata`` (pattern data; None: no tangent)."""
        g = np.empty(self.size)
        want_k = kdata is not None
        _constraint_kernel(q, lam, s, self.idx, self.H, self.b, self.c, f, g,
                           kdata if want_k else np.zeros(1), self._pos_h, self._pos_g,
                           self._pos_gt, want_k, self._grad)
        if self.drives:
            g += self.time_terms(t)[0]
        return g

    @staticmethod
    def concatenate(sets: list["ConstraintSet"]) -> "ConstraintSet":
        """One set of all constraints of ``sets`` (padded to the widest local size)."""
        sets = [s for s in sets if s.size]
        nl = max(s.idx.shape[1] for s in sets)
        idx, H, b, c, drives = [], [], [], [], []
        start = 0
        for s in sets:
            m, k = s.idx.shape
            drives.extend((start + i, n, d) for i, n, d in s.drives)
            start += m
            pad = nl - k
            # padding points at coordinate 0 with zero coefficients
            idx.append(np.hstack([s.idx, np.zeros((m, pad), np.int64)]))
            Hp = np.zeros((m, nl, nl))
            Hp[:, :k, :k] = s.H
            H.append(Hp)
            b.append(np.hstack([s.b, np.zeros((m, pad))]))
            c.append(s.c)
        out = ConstraintSet(np.vstack(idx), np.concatenate(H), np.vstack(b), np.concatenate(c))
        out.drives = drives
        return out


def orthonormality(director_dofs) -> ConstraintSet:
    """d_i . d_j = delta_ij at each node: 6 constraints on its 9 director coordinates.

    ``director_dofs``: (n, 9) global indices of [d1, d2, d3] of each node."""
    dd = np.asarray(director_dofs, dtype=np.int64)
    n = dd.shape[0]
    pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
    H = np.zeros((6, 9, 9))
    c = np.zeros(6)
    eye = np.eye(3)
    for k, (i, j) in enumerate(pairs):
        H[k, 3 * i:3 * i + 3, 3 * j:3 * j + 3] += eye
        H[k, 3 * j:3 * j + 3, 3 * i:3 * i + 3] += eye
        if i == j:
            c[k] = -1.0
    idx = np.repeat(dd, 6, axis=0)
    return ConstraintSet(idx, np.tile(H, (n, 1, 1)), np.zeros((6 * n, 9)), np.tile(c, n),
                         name="orthonormality")
