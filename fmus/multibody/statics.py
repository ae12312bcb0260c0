"""Static equilibrium of a multibody system: Newton-Raphson on
f(q) + s G^T lambda = 0, s g(q) = 0 (the rest condition of Cardona & Jordi, eq. 102, with the
multipliers of eq. 112), with the loads ramped in ``steps`` equal increments.

Large rotations: a Newton correction moves the directors along the tangent of the rotation
group and breaks their orthonormality at second order, which the stiff axial and shear terms
turn into large residuals. The corrections of a node's directors are therefore applied as a
rotation, d_i <- exp(dtheta) d_i with dtheta = 1/2 sum_i d_i x dd_i (the spatial incremental
rotation of the pendulum paper, eq. 4), which keeps every triad orthonormal."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial.transform import Rotation

from pantocosim.core.errors import ConvergenceError


def solve_static(system, q=None, loads=(), steps: int = 1, t: float = 0.0,
                 rtol: float = 1e-10, max_iterations: int = 40, rotate: bool = True,
                 shift: float = 0.0):
    """Equilibrium from ``q`` (default the reference) with every load of ``loads`` scaled
    k/steps at increment k (their ``scale``). Returns q with the multipliers.

    ``shift`` > 0 adds shift * 10^-k M to the Newton matrix at iteration k (pseudo-transient
    continuation: the mass regularises mechanisms whose stiffness only appears under load,
    e.g. a pendulum released from the unstretched reference, and steers Newton to the stable
    equilibrium; the converged solution does not depend on it)."""
    q = system.reference() if q is None else np.array(q, dtype=float)
    zero = np.zeros(system.n_dofs)
    nq = system.n_q
    if not np.any(q[nq:]):
        # multipliers balancing the full loads in the least-squares sense, so that the first
        # tangent already holds the geometric stiffness of the constraint forces (without
        # it a pendulum's first Newton step is unbounded)
        for load in loads:
            load.scale = 1.0
        f, _, _ = system.forces(t, q, zero, tangent=False)
        _, G = system.constraint_jacobian(q)
        q[nq:] = spla.lsqr(G.T, -f, atol=1e-14, btol=1e-14)[0] / system.constraint_scale
    for k in range(1, steps + 1):
        for load in loads:
            load.scale = k / steps
        dq_max = np.inf
        for it in range(max_iterations):
            ev = system.evaluate(t, q, zero, zero, tangent=True)
            r = ev.f_rest
            if it == 0:
                f_scale_0 = max(np.max(np.abs(r[:system.n_q])), 1e-300)
            elif (np.max(np.abs(r)) <= rtol * f_scale_0
                  or dq_max <= 1e-13 * max(1.0, np.max(np.abs(q[:system.n_q])))):
                break
            S = ev.stiffness
            if shift > 0.0 and shift * 10.0 ** -it > 1e-12:
                S = S + (shift * 10.0 ** -it) * ev.mass
            dq = (spla.splu(sp.csc_matrix(S)).solve(r) if sp.issparse(S)
                  else sla.solve(S, r))
            dq_max = np.max(np.abs(dq[:system.n_q]))
            q = update(system, q, -dq) if rotate else q - dq
        else:
            raise ConvergenceError(f"static equilibrium: no convergence at load step {k}",
                                   time=t, step=k, residual=float(np.max(np.abs(r))))
    return q


def update(system, q, dq):
    """q + dq with each node's director increments applied as a finite rotation."""
    n_nodes = system.n_q // 12
    out = q + dq
    qd = q[:system.n_q].reshape(n_nodes, 12)
    dd = dq[:system.n_q].reshape(n_nodes, 12)
    D = qd[:, 3:].reshape(n_nodes, 3, 3)          # rows d1, d2, d3
    dD = dd[:, 3:].reshape(n_nodes, 3, 3)
    theta = 0.5 * np.cross(D, dD).sum(axis=1)    # (n_nodes, 3)
    Rot = Rotation.from_rotvec(theta).as_matrix()
    newD = np.einsum("nij,nkj->nki", Rot, D)
    out[:system.n_q].reshape(n_nodes, 12)[:, 3:] = newD.reshape(n_nodes, 9)
    return out
