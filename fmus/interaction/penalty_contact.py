"""The penalty contact law (thesis 3.2): the one place it exists.

    F = k_H * max(0, z_p - z_w) + c_H * (v_p - v_w)   while in contact, clipped at F >= 0,

with z_p the pantograph contact height, z_w the contact-wire height at the contact point
(Hermite interpolation in the wire element, (3.12)-(3.13)) and k_H = 50 kN/m by default.
Used by the monolithic solver, the co-simulation master and the catenary FMU (built-in
penalty option for third-party masters). The scenario's default law (``[contact] law =
"penalty"``, :mod:`.contact_laws`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..core.params import check_number
from ..core.small_dense import gauss_jordan
from .contact_registry import register

#: penalty stiffness k_H of the contact [N/m] (thesis 3.2)
DEFAULT_CONTACT_STIFFNESS = 50_000.0


@njit(cache=True)
def max_passes(m: int) -> int:
    """The passes of the active-set search over m contacts before it gives up: 2 m + 2."""
    return 2 * m + 2


@njit(cache=True)
def condensed_forces(k, c, dz, dv, G, H, active, trial, A, F):
    """F of the law with the wire affine in the forces (:meth:`PenaltyContact.condensed`),
    in place: on the active set, (I + k G + c H)_AA F_A = k dz_A + c dv_A
    (:func:`~.small_dense.gauss_jordan`; ``A``: m x (m + 1) work, or m x (2 m + 1) to end
    with the inverse of that matrix, the inactive rows and columns of the identity, in
    A[:, m + 1:]), then the set of positive gaps and forces (``trial``) until it repeats, at
    most :func:`max_passes` (m). ``active`` ends as the set F was solved on; F is NaN if that
    system is singular. Returns whether the set settled (False: it still changed after the
    last pass, and F is that pass's)."""
    m = dz.shape[0]
    for i in range(m):
        active[i] = dz[i] > 0.0
    last = max_passes(m) - 1
    for it in range(last + 1):
        for i in range(m):                      # inactive rows: F_i = 0
            for j in range(m):
                A[i, j] = 0.0
            if active[i]:
                for j in range(m):
                    if active[j]:
                        A[i, j] = k * G[i, j] + c * H[i, j]
                A[i, i] += 1.0
                A[i, m] = k * dz[i] + c * dv[i]
            else:
                A[i, i] = 1.0
                A[i, m] = 0.0
            for j in range(m + 1, A.shape[1]):
                A[i, j] = 1.0 if j == m + 1 + i else 0.0
        if not gauss_jordan(A, m):
            F[:] = np.nan
            return True                         # settled on a singular system: F flags it
        for i in range(m):
            F[i] = A[i, m]
        changed = False
        for i in range(m):
            gap = dz[i]
            rel = dv[i]
            for j in range(m):
                gap -= G[i, j] * F[j]
                rel -= H[i, j] * F[j]
            trial[i] = gap > 0.0 and k * gap + c * rel > 0.0
            changed = changed or trial[i] != active[i]
        if not changed:
            return True
        if it == last:
            return False
        for i in range(m):
            active[i] = trial[i]
    return False


@register("penalty")
@dataclass(frozen=True)
class PenaltyContact:
    stiffness: float = DEFAULT_CONTACT_STIFFNESS   # k_H [N/m]
    damping: float = 0.0          # c_H [N s/m], optional contact damping

    condensable = True
    across_ports = True
    #: the scenario's [contact] values the law takes
    fields = ("stiffness", "damping")

    def __post_init__(self):
        check_number("contact.stiffness", self.stiffness, positive=True)
        check_number("contact.damping", self.damping, nonnegative=True)

    @classmethod
    def from_fields(cls, stiffness: float, damping: float) -> "PenaltyContact":
        return cls(stiffness, damping)

    @property
    def compliance(self) -> float:
        """1 / k_H [m/N]."""
        return 1.0 / self.stiffness

    def bind(self, system) -> "PenaltyInSystem":
        return PenaltyInSystem(self)

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
        dF/dv_p, settled). On the active set A, (I + k_H G + c_H H)_AA F_A = k_H (z_p - z0)_A
        + c_H (v_p - v0)_A; A holds the contacts whose gap and force are positive; settled
        is False when the search over A gave up (:func:`condensed_forces`)."""
        dz = np.asarray(z_p, float) - z0
        dv = np.asarray(v_p, float) - v0
        m = dz.size
        active = np.zeros(m, dtype=np.bool_)
        A = np.empty((m, 2 * m + 1))
        F = np.empty(m)
        settled = condensed_forces(self.stiffness, self.damping, dz, dv,
                                   np.ascontiguousarray(G), np.ascontiguousarray(H), active,
                                   active.copy(), A, F)
        Mi = A[:, m + 1:] * np.outer(active, active)
        return F, self.stiffness * Mi, self.damping * Mi, bool(settled)


class PenaltyInSystem:
    """The penalty law in an assembled system (:mod:`.coupled`): a force of the gap, its
    linearisation added to the Newton matrix by the system's low-rank update; no state."""

    def __init__(self, law: PenaltyContact):
        self.law = law

    def force(self, k, z_p, z_w, v_p, v_w):
        """(F, dF/dgap, dF/dvrel) of contact ``k``."""
        return self.law.force_and_derivatives(z_p, z_w, v_p, v_w)

    def add_residual(self, ev, states, f_rest) -> None:
        """Nothing: the force is all the law puts in the residual."""

    def newton_solve(self, solve, ev, rhs):
        return solve(rhs, ev.contact_lin)

    def commit(self) -> None:
        pass

    def get_state(self):
        return None

    def set_state(self, state) -> None:
        pass
