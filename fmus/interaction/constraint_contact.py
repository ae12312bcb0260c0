"""The constraint contact law: a rigid, unilateral contact with a Lagrange multiplier
(``[contact] law = "constraint"``; derivation in docs/en50318-validation.md, "The constraint
contact").

Contact k has the gap (penetration) g_k(q, t) = z_p(q_p) - z_w(q_c, t) (3.9)-(3.13), its rate
g'_k = v_p - v_w (the wire's convective term included) and the force lambda_k, acting as
lambda_k u_k with u_k = dg_k/dq (+ the pantograph's contact-height gradient, - the wire's
Hermite weights). The step enforces the complementarity on the gap a time tau ahead,

    c_k = g_k + tau g'_k,   lambda_k >= 0,   c_k <= 0,   lambda_k c_k = 0,

with tau = LOOKAHEAD / c_v (about one step; c_v = gamma / (beta h) of (3.18)). tau = 0 would
be the gap itself (index 3), whose Newmark velocities flip the sign of g' every step in
contact, so the head leaves the wire and hits it again step after step; with tau g'
the relative velocity of a closed contact decays by (tau - h/2) / (tau + h/2) per step
(trapezoidal rule), a gap left by an impact within a few steps, and a closed contact holds
g = g' = 0: the rigid contact, to which the solution converges as h -> 0. The condition is
solved in the same Newton-Raphson iteration as the HHT equations (3.16): with
dR/dlambda = c_f U and dc/dq = j U^T, j = 1 + tau c_v, a correction of (q, lambda) on the
active set A (primal-dual active set: A = {k : lambda_k + kappa_k c_k > 0}) is

    x = S^-1 (R + c_f U dlambda),
    c_f (U_A^T S^-1 U_A) dlambda_A = c_A / j - U_A^T S^-1 R - c_f U_A^T S^-1 U_I dlambda_I,
    dlambda_k = -lambda_k off A,

with the system's own factorization of S (no contact term in it). The residual the
integrator checks carries the complementarity error phi_k = lambda_k - max(0, lambda_k +
kappa_k c_k) as a force phi_k u_k, so a step converges only when each contact is closed or
open as it must be; a converged step that still violates it by more than
:attr:`ConstraintContact.gap_tolerance` raises :class:`~.errors.ConvergenceError`.

A separation at a dropper clamp that lasts one step or a few keeps its number of steps as h
shrinks: that part of the loss of contact is the step's (docs/en50318-validation.md, "Loss of
contact and the step").

The law has no stiffness: there is no contact mode, the wire and the head move together
while in contact. It needs the assembled monolithic solver; a force-height exchange through
FMU ports cannot hold it (docs/en50318-validation.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import ConvergenceError
from ..core.params import check_number
from .contact_registry import register

#: scale kappa [N/m] of the complementarity function before the first Newton matrix gives
#: the step's own stiffness at the contact point (it changes no converged result)
DEFAULT_KAPPA = 1.0e7
#: tau c_v: the look-ahead of the enforced gap in units of 1 / c_v (about one step)
LOOKAHEAD = 2.0


@register("constraint")
@dataclass(frozen=True)
class ConstraintContact:
    #: largest violation [m] of c = g + tau g' a converged step may leave: while in contact,
    #: or penetration while the force is zero
    gap_tolerance: float = 1.0e-6

    compliance = 0.0
    condensable = False
    across_ports = False
    #: the scenario's [contact] values the law takes: none (a rigid contact)
    fields = ()

    def __post_init__(self):
        check_number("contact.gap_tolerance", self.gap_tolerance, positive=True)

    @classmethod
    def from_fields(cls, stiffness: float, damping: float) -> "ConstraintContact":
        """The constraint law takes neither value (the scenario loader refuses them)."""
        return cls()

    def bind(self, system) -> "ConstraintInSystem":
        return ConstraintInSystem(self, system)


def _unit(system, k, cp, g) -> np.ndarray:
    """u_k = dg_k/dq as a vector of the system."""
    u = np.zeros(system.n_dofs)
    o = system.offsets[k]
    u[o:o + g.size] = g
    np.add.at(u, cp.dofs, -cp.weights)
    return u


class ConstraintInSystem:
    """The multipliers of an assembled system's contacts (:mod:`.coupled`)."""

    def __init__(self, law: ConstraintContact, system):
        self.law, self.system = law, system
        m = len(system.pantographs)
        self.lam = np.zeros(m)
        self.kappa = np.full(m, DEFAULT_KAPPA)
        self.tau = 0.0              # look-ahead [s] (0 in a static solve)
        self._last = None           # (time, c, multipliers) of the last evaluation

    def force(self, k, z_p, z_w, v_p, v_w):
        """(lambda_k, 0, 0): the force is an unknown, not a function of the gap."""
        return float(self.lam[k]), 0.0, 0.0

    def add_residual(self, ev, states, f_rest) -> None:
        """phi_k u_k into ``f_rest``; the gaps and unit vectors into ``ev.constraint``."""
        sys_ = self.system
        gaps = np.array([s[1] - s[2] + self.tau * (s[3] - s[4]) for s in states])
        phi = self.lam - np.maximum(0.0, self.lam + self.kappa * gaps)
        units = [_unit(sys_, k, s[5], s[6]) for k, s in enumerate(states)]
        for u, p in zip(units, phi):
            f_rest += p * u
        ev.constraint = (units, gaps, phi)
        self._last = (ev.contact_lin[0], gaps, self.lam.copy())

    def newton_solve(self, solve, ev, rhs):
        """The Newton correction of q (returned) and of the multipliers (applied)."""
        units, gaps, phi = ev.constraint
        t = ev.contact_lin[0]
        c_f, c_v = solve.c_f, solve.c_v
        R = np.asarray(rhs, dtype=float) - c_f * sum(p * u for p, u in zip(phi, units))
        x0 = solve(R, (t, []))
        if c_f == 0.0:              # acceleration at the start: the multipliers stay
            return x0
        self.tau = LOOKAHEAD / c_v if c_v > 0.0 else 0.0
        j = 1.0 + self.tau * c_v
        Y = np.column_stack([solve(u, (t, [])) for u in units])
        U = np.column_stack(units)
        W = U.T @ Y
        self.kappa = 1.0 / (j * c_f * np.maximum(np.diag(W), 1e-300))
        active = self.lam + self.kappa * gaps > 0.0
        dlam = -self.lam.copy()
        if active.any():
            A = np.flatnonzero(active)
            I = np.flatnonzero(~active)
            b = gaps[A] / j - U[:, A].T @ x0 - c_f * W[np.ix_(A, I)] @ dlam[I]
            try:
                dlam[A] = np.linalg.solve(c_f * W[np.ix_(A, A)], b)
            except np.linalg.LinAlgError:
                raise ConvergenceError(f"constraint contact: singular contact system at "
                                       f"t = {t:.6g} s (two contacts on one point of the "
                                       "wire?)", time=t) from None
        self.lam = self.lam + dlam
        return x0 + c_f * (Y @ dlam)

    def commit(self) -> None:
        """Check the complementarity of the step just converged: a step that leaves a
        contact open under a force or closed beyond the tolerance is an error, never a
        result."""
        if self._last is None:
            return
        t, gaps, lam = self._last
        tol = self.law.gap_tolerance
        closed = lam > 0.0
        bad = (gaps > tol) | (closed & (np.abs(gaps) > tol)) | (lam < -self.kappa * tol)
        if bad.any():
            k = int(np.argmax(bad))
            raise ConvergenceError(
                f"constraint contact {k + 1} not satisfied at the end of a step"
                f"{'' if t is None else f' (t = {t:.6g} s)'}: gap {gaps[k]:.3g} m (a time "
                f"tau = {self.tau:.3g} s ahead), force "
                f"{lam[k]:.4g} N (tolerance {tol:g} m); a smaller simulation.dt or "
                "newton_rtol", time=float("nan") if t is None else t)

    def get_state(self):
        return self.lam.copy(), self.kappa.copy(), self.tau

    def set_state(self, state) -> None:
        if state is not None:
            self.lam, self.kappa, self.tau = state[0].copy(), state[1].copy(), state[2]
