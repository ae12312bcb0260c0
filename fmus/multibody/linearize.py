"""Linearisation about an equilibrium and natural frequencies (Cardona & Jordi, 9.8).

With dependent coordinates and multipliers (Cardona & Jordi, eq. 112) the linearised equations
M eps'' + K eps = 0 (Cardona & Jordi, eq. 106) live on the tangent space of the constraint
manifold: with Z a basis of the null space of the constraint Jacobian G at q_eq,

    M_r = Z^T M Z,    K_r = Z^T (K + sum_j lambda_j H_j) Z,

where K is the tangent of the forces (elastic and geometric stiffness) and the multiplier
term the curvature of the constraints, which carries e.g. the gravity stiffness of a hanging
pendulum (Cardona & Jordi, eq. 108). Eigenvalues of K_r phi = omega^2 M_r phi are the squared
natural frequencies.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp


def linearize(system, q_eq, t: float = 0.0):
    """(M_r, K_r, Z) at the equilibrium ``q_eq`` (with its multipliers)."""
    nq = system.n_q
    zero = np.zeros(system.n_dofs)
    ev = system.evaluate(t, q_eq, zero, zero, tangent=True)
    S = ev.stiffness.toarray() if sp.issparse(ev.stiffness) else ev.stiffness
    K = S[:nq, :nq]
    G = S[nq:, :nq] / system.constraint_scale
    Z = sla.null_space(G)
    Mr = Z.T @ (system.M @ Z)
    Kr = Z.T @ K @ Z
    return 0.5 * (Mr + Mr.T), 0.5 * (Kr + Kr.T), Z


def natural_frequencies(system, q_eq, t: float = 0.0, n: int | None = None):
    """Angular natural frequencies (rad/s, ascending; negative for unstable directions,
    -sqrt|omega^2|) and the mode shapes in node coordinates."""
    Mr, Kr, Z = linearize(system, q_eq, t)
    w2, phi = sla.eigh(Kr, Mr)
    omega = np.sign(w2) * np.sqrt(np.abs(w2))
    if n is not None:
        omega, phi = omega[:n], phi[:, :n]
    return omega, Z @ phi
