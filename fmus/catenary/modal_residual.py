"""The residual flexibility of a truncated modal basis at the catenary's interfaces.

With the modes Phi below the cutoff (K0 Phi = M Phi Omega^2, Phi^T M Phi = I), the static
response the truncated modes miss is (modal truncation with static correction, thesis 3.3)

    R = K0^-1 - Phi Omega^-2 Phi^T,    R K0 Phi = 0,   Phi^T M R = 0.

Two kinds of loads meet the catenary at points the modes cannot resolve:

- the droppers, fixed in space: when a dropper slackens, its axial force b_d N_d leaves the
  structure. Their residual shapes R B (B = [b_1 .. b_nd]) are made K0-orthogonal,
  Q = sqrt(k) R B L^-T with B^T R B = L L^T (Q^T K0 Q = k I, k a dropper stiffness scale so
  that the coordinates are metres and their rows newtons);
- the contact points, moving with the pantographs: their residual shape is what is left of
  R N(t) once the droppers' part is taken out, psi(t) = R_perp N(t),
  R_perp = R - Q Q^T / k, which leaves every dropper's length alone (B^T R_perp = 0).

Everything the dynamics needs at a position is a small product of tables kept here: the
rows of K0^-1, Phi and Q at the contact-wire DOFs S (heights and slopes, where the
interpolation (3.13) reads) and at the supports. K0^-1 on S x S is kept in a band wide
enough for the pantographs' separations. The set-up solves the kept banded factorization of
K0 once per DOF of S and per dropper; nothing per step scales with the DOFs.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

#: right-hand sides per banded solve block during the set-up
_CHUNK = 256


class InterfaceFlexibility:
    """Tables of the residual flexibility of ``lin`` (:class:`~.linear.LinearCatenary`)
    with the modes ``Phi`` (n, m) of squared circular frequencies ``omega2``.

    ``separations``: the distances between pantographs [m] the contact tables must cover;
    ``residual=False`` (a complete basis): the modal rows only.
    """

    def __init__(self, lin, Phi: np.ndarray, omega2: np.ndarray, separations=(),
                 residual: bool = True):
        n = lin.n_dofs
        solve = lin._factor_cache(0.0, 0.0, 1.0).solve          # banded Cholesky of K0
        self.omega2 = np.asarray(omega2, float)
        loc = lin.locator
        zf = loc.z_free                                           # (elements, 4), -1 fixed
        self.S = np.unique(zf[zf >= 0])                           # sorted along the track
        s_of = np.full(n, -1, dtype=np.int64)
        s_of[self.S] = np.arange(self.S.size)
        #: per contact element, the S index of its 4 interpolated DOFs (-1: fixed)
        self.elem_s = np.where(zf >= 0, s_of[np.maximum(zf, 0)], -1)
        dz = lin.mesh.node_dofs[lin.mesh.support_contact_nodes, 2]
        self.sup = lin.structure.fmap[dz]                          # -1 at the anchored ends
        sup = np.maximum(self.sup, 0)
        supmask = (self.sup >= 0)[:, None]
        self.Phi_S = np.ascontiguousarray(Phi[self.S])
        self.Phi_sup = np.where(supmask, Phi[sup], 0.0)
        self._droppers(lin, solve, Phi, sup, supmask, residual)
        self.C_sup = np.zeros((sup.size, 0))
        if residual:
            self._contact(lin, solve, separations, sup, supmask)

    # ------------------------------------------------------------------ droppers
    def _droppers(self, lin, solve, Phi, sup, supmask, residual):
        vec = lin.droppers.vectors
        n, nd = lin.n_dofs, len(lin.droppers)
        self.n_droppers = nd
        B = np.zeros((n, nd))
        for d in range(nd):
            ok = vec.idx[d] >= 0
            B[vec.idx[d][ok], d] = vec.val[d][ok]
        #: b_d . phi_j (nd, m): the droppers' elongation per unit modal coordinate
        self.B_phi = np.ascontiguousarray(B.T @ Phi)
        self.kbar = 0.0
        if nd == 0 or not residual:
            self.Q_S = np.zeros((self.S.size, 0))
            self.Q_sup = np.zeros((sup.size, 0))
            self.B_Q = np.zeros((nd, 0))
            self.Q_r0 = np.zeros(0)
            return
        RB = np.asarray(solve(B)).reshape(n, nd) - Phi @ (self.B_phi.T / self.omega2[:, None])
        Gd = B.T @ RB
        Gd = 0.5 * (Gd + Gd.T)
        L = sla.cholesky(Gd, lower=True)
        self.kbar = float(1.0 / np.mean(np.diag(Gd)))
        Q = np.sqrt(self.kbar) * sla.solve_triangular(L, RB.T, lower=True).T      # (n, nd)
        self.Q_S = np.ascontiguousarray(Q[self.S])
        self.Q_sup = np.where(supmask, Q[sup], 0.0)
        #: b_d . Q (nd, nd) = sqrt(k) L: the droppers' elongation per unit residual coordinate
        self.B_Q = np.ascontiguousarray(np.sqrt(self.kbar) * L)
        #: Q^T r0: the initial configuration's round-off on the residual coordinates
        self.Q_r0 = Q.T @ lin.r0
        self._B, self._L = B, L

    def Q_full(self, lin, Phi) -> np.ndarray:
        """Q on every DOF (n, nd) (for checks: one banded solve per dropper)."""
        if self.n_droppers == 0:
            return np.zeros((lin.n_dofs, 0))
        solve = lin._factor_cache(0.0, 0.0, 1.0).solve
        RB = np.asarray(solve(self._B)).reshape(lin.n_dofs, -1) - Phi @ (
            self.B_phi.T / self.omega2[:, None])
        return np.sqrt(self.kbar) * sla.solve_triangular(self._L, RB.T, lower=True).T

    # ------------------------------------------------------------------ contact wire
    def _contact(self, lin, solve, separations, sup, supmask):
        """K0^-1 on S x S within the band of the separations, and K0^-1 at the supports x S."""
        x = self._s_positions(lin, self.S)
        reach = max([0.0] + [abs(float(s)) for s in separations])
        reach += 2.0 * float(np.max(lin.locator.Le))
        # half bandwidth in S indices: every pair of S DOFs within ``reach`` along the track
        j = np.searchsorted(x, x + reach, side="right") - 1
        self.band = int(max(3, np.max(j - np.arange(x.size))))
        nS, bw = self.S.size, self.band
        n = lin.n_dofs
        self.C_band = np.zeros((nS, 2 * bw + 1))     # C_band[a, b - a + bw] = K0^-1[S_a, S_b]
        self.C_sup = np.zeros((sup.size, nS))
        for a0 in range(0, nS, _CHUNK):
            a1 = min(nS, a0 + _CHUNK)
            E = np.zeros((n, a1 - a0))
            E[self.S[a0:a1], np.arange(a1 - a0)] = 1.0
            X = np.asarray(solve(E)).reshape(n, a1 - a0)
            lo, hi = max(0, a0 - bw), min(nS, a1 + bw)
            rows = X[self.S[lo:hi]]                                  # (hi - lo, a1 - a0)
            for i, a in enumerate(range(a0, a1)):
                b0, b1 = max(0, a - bw), min(nS, a + bw + 1)
                self.C_band[a, b0 - a + bw:b1 - a + bw] = rows[b0 - lo:b1 - lo, i]
            self.C_sup[:, a0:a1] = np.where(supmask, X[sup], 0.0)

    @staticmethod
    def _s_positions(lin, S):
        """Track position of every S DOF (its node's reference x)."""
        loc = lin.locator
        zf = loc.z_free
        pos = np.empty(S.size)
        xs = np.stack([loc.x_start, loc.x_start, loc.x_end, loc.x_end], axis=1)
        ok = zf >= 0
        idx = np.searchsorted(S, zf[ok])
        pos[idx] = xs[ok]
        return pos

    # ------------------------------------------------------------------ per position
    def point(self, element: int, weights: np.ndarray, dweights: np.ndarray):
        """(s, w, dw): the S indices of contact element ``element`` (position in the chain)
        and the interpolation weights on them (fixed DOFs dropped)."""
        s = self.elem_s[element]
        ok = s >= 0
        return s[ok], weights[ok], dweights[ok]
