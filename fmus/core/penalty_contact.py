"""The penalty contact law (thesis 3.2): the one place it exists.

    F = k_H * max(0, z_p - z_w) + c_H * (v_p - v_w)   while in contact, clipped at F >= 0,

with z_p the pantograph contact height, z_w the contact-wire height at the contact point
(Hermite interpolation in the wire element, (3.12)-(3.13)) and k_H = 50 kN/m by default.
Used by the monolithic solver, the co-simulation master and the catenary FMU (built-in
penalty option for third-party masters).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .params import check_number


#: penalty stiffness k_H of the contact [N/m] (thesis 3.2)
DEFAULT_CONTACT_STIFFNESS = 50_000.0


@dataclass(frozen=True)
class PenaltyContact:
    stiffness: float = DEFAULT_CONTACT_STIFFNESS   # k_H [N/m]
    damping: float = 0.0          # c_H [N s/m], optional contact damping

    def __post_init__(self):
        check_number("contact.stiffness", self.stiffness, positive=True)
        check_number("contact.damping", self.damping, nonnegative=True)

    def force(self, z_p: float, z_w: float, v_p: float = 0.0, v_w: float = 0.0) -> float:
        """Contact force [N] >= 0."""
        gap = z_p - z_w
        if gap <= 0.0:
            return 0.0
        f = self.stiffness * gap + self.damping * (v_p - v_w)
        return f if f > 0.0 else 0.0

    def force_and_derivatives(self, z_p, z_w, v_p=0.0, v_w=0.0):
        """(F, dF/dz_p, dF/dv_p); dF/dz_w = -dF/dz_p and dF/dv_w = -dF/dv_p."""
        gap = z_p - z_w
        if gap <= 0.0:
            return 0.0, 0.0, 0.0
        f = self.stiffness * gap + self.damping * (v_p - v_w)
        if f <= 0.0:
            return 0.0, 0.0, 0.0
        return f, self.stiffness, self.damping

    def condensed(self, z_p, v_p, z0, v0, G, H):
        """The law with the wire affine in the forces, z_w = z0 + G F, v_w = v0 + H F (a
        structure condensed on its contact points, :mod:`.condensed`): (F, dF/dz_p,
        dF/dv_p). On the active set A, (I + k_H G + c_H H)_AA F_A = k_H (z_p - z0)_A
        + c_H (v_p - v0)_A; A holds the contacts whose gap and force are positive."""
        m = len(z_p)
        if m == 1:
            return self._condensed_one(z_p[0] - z0[0], v_p[0] - v0[0], G[0, 0], H[0, 0])
        dz, dv = z_p - z0, v_p - v0
        active = dz > 0.0
        F = np.zeros(m)
        Jz, Jv = np.zeros((m, m)), np.zeros((m, m))
        for _ in range(2 * m + 2):
            F[:] = 0.0
            Jz[:] = 0.0
            Jv[:] = 0.0
            A = np.flatnonzero(active)
            if A.size:
                Mi = np.linalg.inv(np.eye(A.size) + self.stiffness * G[np.ix_(A, A)]
                                   + self.damping * H[np.ix_(A, A)])
                F[A] = Mi @ (self.stiffness * dz[A] + self.damping * dv[A])
                Jz[np.ix_(A, A)] = self.stiffness * Mi
                Jv[np.ix_(A, A)] = self.damping * Mi
            gap = dz - G @ F
            trial = self.stiffness * gap + self.damping * (dv - H @ F)
            now = (gap > 0.0) & (trial > 0.0)
            if np.array_equal(now, active):
                break
            active = now
        return F, Jz, Jv

    def _condensed_one(self, dz, dv, g, h):
        """:meth:`condensed` of one contact."""
        k, c = self.stiffness, self.damping
        F = (k * dz + c * dv) / (1.0 + k * g + c * h)
        if F > 0.0 and dz - g * F > 0.0:
            d = 1.0 + k * g + c * h
            return np.array([F]), np.array([[k / d]]), np.array([[c / d]])
        z = np.zeros((1, 1))
        return np.zeros(1), z, z.copy()
