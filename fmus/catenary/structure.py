"""Finite-element structure in absolute nodal coordinates: assembly of cables, bars, point
masses and ground springs into sparse global vectors and matrices (thesis 3.1, 3.3.3).

DOFs are numbered by the mesh builder (:mod:`pantocosim.catenary.mesh`) along the track; the
"full" vector holds every coordinate, fixed ones included, and the "free" vector ``q`` the
unknowns. Global matrices live on one CSR pattern over the free DOFs (the union of all
element couplings), so mass, damping, stiffness and the Newton matrix share ``indices`` and
``indptr`` and are combined by adding their ``data`` arrays. Element loops and scatters are
numba kernels; nothing loops over elements in Python.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numba import njit

from . import ancf_cable, bar


@njit(cache=True)
def scatter_add(out, idx, vals):
    """out[idx[i]] += vals[i] for idx[i] >= 0 (idx and vals flattened alike)."""
    for i in range(idx.shape[0]):
        k = idx[i]
        if k >= 0:
            out[k] += vals[i]


class Structure:
    """Cables, bars, point masses and ground springs on a set of full DOFs.

    Built by setting the array attributes below and calling :meth:`finalize`.
    """

    def __init__(self, n_full: int, gravity: float = 9.81):
        self.n_full = int(n_full)
        self.gravity = float(gravity)
        #: coordinates are stored relative to ``offset`` (the station x on x-position DOFs,
        #: zero elsewhere): absolute = x_full + offset. Fixed DOFs keep their x_full value.
        self.x_full = np.zeros(self.n_full)
        self.offset = np.zeros(self.n_full)
        self.fixed = np.zeros(self.n_full, dtype=bool)
        self.zpos = np.zeros(self.n_full, dtype=bool)  # z-position DOFs (weight acts on them)
        # cables
        self.cable_dofs = np.zeros((0, 12), dtype=np.int64)
        self.cable_Le = np.zeros(0)
        self.cable_mu = np.zeros(0)
        self.cable_EA = np.zeros(0)
        self.cable_EI = np.zeros(0)
        self.cable_group = np.zeros(0, dtype=np.int64)  # index into N0_group
        self.N0_group = np.zeros(0)
        # bars
        self.bar_dofs = np.zeros((0, 6), dtype=np.int64)
        self.bar_l0 = np.zeros(0)
        self.bar_EA = np.zeros(0)
        self.bar_mass = np.zeros(0)
        self.bar_tension_only = np.zeros(0, dtype=np.bool_)
        # point masses (one per DOF entry) and ground springs (one DOF each)
        self.point_dofs = np.zeros(0, dtype=np.int64)
        self.point_mass = np.zeros(0)
        self.spring_dofs = np.zeros(0, dtype=np.int64)
        self.spring_k = np.zeros(0)
        self.spring_anchor = np.zeros(0)

    # ------------------------------------------------------------------ build
    def finalize(self) -> None:
        """Free numbering, CSR pattern, scatter maps, constant mass matrix and weight."""
        self.cable_dofs = np.ascontiguousarray(self.cable_dofs, dtype=np.int64)
        self.bar_dofs = np.ascontiguousarray(self.bar_dofs, dtype=np.int64)
        self.bar_tension_only = np.ascontiguousarray(self.bar_tension_only, dtype=np.bool_)
        off = self.offset
        self.cable_dX = np.ascontiguousarray(off[self.cable_dofs[:, 6:9]]
                                             - off[self.cable_dofs[:, 0:3]])
        self.bar_dX = np.ascontiguousarray(off[self.bar_dofs[:, 3:6]]
                                           - off[self.bar_dofs[:, 0:3]])
        self.free = np.flatnonzero(~self.fixed)
        self.n_free = self.free.size
        fmap = -np.ones(self.n_full, dtype=np.int64)
        fmap[self.free] = np.arange(self.n_free)
        self.fmap = fmap
        n = self.n_free

        def pairs(dofs):
            m = dofs.shape[1]
            r = np.broadcast_to(dofs[:, :, None], (dofs.shape[0], m, m)).ravel()
            c = np.broadcast_to(dofs[:, None, :], (dofs.shape[0], m, m)).ravel()
            return fmap[r], fmap[c]

        rc, cc = pairs(self.cable_dofs)
        rb, cb = pairs(self.bar_dofs)
        diag = np.arange(n)
        rows = np.concatenate([rc, rb, diag])
        cols = np.concatenate([cc, cb, diag])
        ok = (rows >= 0) & (cols >= 0)
        keys = np.where(ok, rows * n + cols, -1)
        uk, inv = np.unique(keys[ok], return_inverse=True)
        pos = -np.ones(keys.size, dtype=np.int64)
        pos[ok] = inv
        self.nnz = uk.size
        self.indices = (uk % n).astype(np.int32)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(uk // n, minlength=n))]
                                     ).astype(np.int32)
        # lower band storage of the symmetric pattern (for banded Cholesky)
        ur, uc = uk // n, uk % n
        low = ur >= uc
        self.bandwidth = int(np.max(ur - uc)) if uk.size else 0
        self.band_src = np.flatnonzero(low)
        self.band_dst = ((ur[low] - uc[low]) * n + uc[low]).astype(np.int64)
        nc, nb = rc.size, rb.size
        self.pos_cable = pos[:nc]
        self.pos_bar = pos[nc:nc + nb]
        self.pos_diag = pos[nc + nb:]              # position of (i, i)
        self.pos_bar_blocks = self.pos_bar.reshape(-1, 36)
        # mass matrix and weight
        M = np.zeros(self.nnz)
        fg = np.zeros(self.n_full)
        nc_el = self.cable_dofs.shape[0]
        if nc_el:
            Me = np.empty((nc_el, 12, 12))
            ge = np.empty((nc_el, 12))
            for e in range(nc_el):   # build-time only
                Me[e] = ancf_cable.mass_matrix(self.cable_mu[e], self.cable_Le[e])
                ge[e] = ancf_cable.gravity_vector(self.cable_mu[e], self.cable_Le[e],
                                                  self.gravity)
            scatter_add(M, self.pos_cable, Me.ravel())
            scatter_add(fg, self.cable_dofs.ravel(), ge.ravel())
        nb_el = self.bar_dofs.shape[0]
        if nb_el:
            Mb = self.bar_mass[:, None, None] * bar.mass_matrix(1.0)[None]
            gb = self.bar_mass[:, None] * bar.gravity_vector(1.0, self.gravity)[None]
            scatter_add(M, self.pos_bar, Mb.ravel())
            scatter_add(fg, self.bar_dofs.ravel(), gb.ravel())
        if self.point_dofs.size:
            fr = fmap[self.point_dofs]
            scatter_add(M, np.where(fr >= 0, self.pos_diag[np.maximum(fr, 0)], -1),
                        self.point_mass)
            np.add.at(fg, self.point_dofs, -self.gravity * self.point_mass * self.zpos[
                self.point_dofs])
        self.M_data = M
        self.f_weight_full = fg
        fs = fmap[self.spring_dofs]
        self.pos_spring = np.where(fs >= 0, self.pos_diag[np.maximum(fs, 0)], -1)
        self._fc = np.empty((nc_el, 12))
        self._Kc = np.empty((nc_el, 12, 12))
        self._fb = np.empty((nb_el, 6))
        self._Kb = np.empty((nb_el, 6, 6))
        self._slack = np.zeros(nb_el, dtype=np.bool_)
        self._bilateral = np.zeros(nb_el, dtype=np.bool_)

    # ------------------------------------------------------------------ helpers
    def csr(self, data) -> sp.csr_matrix:
        """A CSR matrix on the shared pattern (no copy of ``data``)."""
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n_free,) * 2)

    def absolute(self, x_full: np.ndarray) -> np.ndarray:
        """Absolute coordinates of a full vector."""
        return x_full + self.offset

    def full(self, q: np.ndarray) -> np.ndarray:
        x = self.x_full.copy()
        x[self.free] = q
        return x

    def lower_band(self, data) -> np.ndarray:
        """(bandwidth + 1, n) lower band storage (LAPACK 'L') of pattern data."""
        ab = np.zeros((self.bandwidth + 1) * self.n_free)
        ab[self.band_dst] = data[self.band_src]
        return ab.reshape(self.bandwidth + 1, self.n_free)

    @property
    def mass(self) -> sp.csr_matrix:
        return self.csr(self.M_data)

    @property
    def weight(self) -> np.ndarray:
        """External weight on the free DOFs (the gravity vector, negative z)."""
        return self.f_weight_full[self.free]

    def cable_N0(self) -> np.ndarray:
        return self.N0_group[self.cable_group]

    # ------------------------------------------------------------------ forces
    def internal(self, x_full: np.ndarray, want_K: bool = True, tension_only: bool = True):
        """Elastic forces (full vector), tangent data on the pattern (or None) and the
        slack flags of the bars. ``tension_only=False`` treats every bar as bilateral."""
        E = x_full[self.cable_dofs]
        X = x_full[self.bar_dofs]
        fc, Kc, fb, Kb, slack = self._fc, self._Kc, self._fb, self._Kb, self._slack
        ancf_cable.cable_forces(E, self.cable_dX, self.cable_Le, self.cable_EA, self.cable_EI,
                                self.cable_N0(), ancf_cable.GAUSS_XI, ancf_cable.GAUSS_W,
                                want_K, fc, Kc)
        bar.bar_forces(X, self.bar_dX, self.bar_l0, self.bar_EA,
                       self.bar_tension_only if tension_only else self._bilateral,
                       want_K, fb, Kb, slack)
        f = np.zeros(self.n_full)
        scatter_add(f, self.cable_dofs.ravel(), fc.ravel())
        scatter_add(f, self.bar_dofs.ravel(), fb.ravel())
        if self.spring_dofs.size:
            np.add.at(f, self.spring_dofs,
                      self.spring_k * (x_full[self.spring_dofs] - self.spring_anchor))
        K = None
        if want_K:
            K = np.zeros(self.nnz)
            scatter_add(K, self.pos_cable, Kc.ravel())
            scatter_add(K, self.pos_bar, Kb.ravel())
            scatter_add(K, self.pos_spring, self.spring_k)
        return f, K, slack.copy()

    def bar_tangent_blocks(self, x_full: np.ndarray, tension_only: bool = False):
        """Per-bar 6x6 tangents and forces at x_full (for damping and reports)."""
        X = x_full[self.bar_dofs]
        nb = X.shape[0]
        f = np.empty((nb, 6))
        K = np.empty((nb, 6, 6))
        s = np.empty(nb, dtype=np.bool_)
        bar.bar_forces(X, self.bar_dX, self.bar_l0, self.bar_EA,
                       self.bar_tension_only if tension_only else self._bilateral,
                       True, f, K, s)
        return f, K, s

    def bar_axial_forces(self, x_full: np.ndarray, tension_only: bool = True) -> np.ndarray:
        X = x_full[self.bar_dofs]
        d = X[:, 3:] - X[:, :3] + self.bar_dX
        ln = np.linalg.norm(d, axis=1)
        N = self.bar_EA * (ln - self.bar_l0) / self.bar_l0
        if tension_only:
            N = np.where(self.bar_tension_only & (N < 0), 0.0, N)
        return N
