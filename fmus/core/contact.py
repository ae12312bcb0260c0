"""The penalty contact law (thesis 3.2): the one place it exists.

    F = k_H * max(0, z_p - z_w) + c_H * (v_p - v_w)   while in contact, clipped at F >= 0,

with z_p the pantograph contact height, z_w the contact-wire height at the contact point
(Hermite interpolation in the wire element, (3.12)-(3.13)) and k_H = 50 kN/m by default.
Used by the monolithic solver, the co-simulation master and the catenary FMU (built-in
penalty option for third-party masters).
"""

from __future__ import annotations

from dataclasses import dataclass

from .params import check_number


@dataclass(frozen=True)
class PenaltyContact:
    stiffness: float = 50_000.0   # k_H [N/m]
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
