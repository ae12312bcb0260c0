"""Two-node bar element, 6 DOF (thesis 3.1.2, eq. (3.4)), optionally tension-only.

Coordinates [x_i, y_i, z_i, x_j, y_j, z_j]; axial force N = EA (l - l0) / l0 (engineering
strain on the unstretched length l0). A tension-only bar (dropper) whose length is below l0
carries no force and has zero stiffness ("slack"), the first criterion of thesis 3.1.2
taken with the unstretched length: the force is continuous through the switch.
Linear shape functions give a constant consistent mass matrix and gravity vector.
"""

from __future__ import annotations

import numpy as np
from numba import njit


def mass_matrix(mass: float) -> np.ndarray:
    """Consistent 6x6 mass matrix of a bar of total mass ``mass``."""
    return mass / 6.0 * np.kron(np.array([[2.0, 1.0], [1.0, 2.0]]), np.eye(3))


def gravity_vector(mass: float, g: float) -> np.ndarray:
    f = np.zeros(6)
    f[[2, 5]] = -0.5 * mass * g
    return f


@njit(cache=True)
def bar_forces(X, dX, l0, EA, tension_only, want_K, f_out, K_out, slack_out):
    """Internal forces (nb x 6), tangents (nb x 6 x 6) and slack flags of all bars.

    X: coordinates relative to node offsets whose difference (j - i) is dX (nb x 3)."""
    nb = X.shape[0]
    for b in range(nb):
        d0 = X[b, 3] - X[b, 0] + dX[b, 0]
        d1 = X[b, 4] - X[b, 1] + dX[b, 1]
        d2 = X[b, 5] - X[b, 2] + dX[b, 2]
        ln = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        u = (d0 / ln, d1 / ln, d2 / ln)
        N = EA[b] * (ln - l0[b]) / l0[b]
        slack = tension_only[b] and N < 0.0
        slack_out[b] = slack
        if slack:
            N = 0.0
        for k in range(3):
            f_out[b, k] = -N * u[k]
            f_out[b, 3 + k] = N * u[k]
        if want_K:
            ka = 0.0 if slack else EA[b] / l0[b]
            kg = N / ln
            for k in range(3):
                for l in range(3):
                    v = (ka - kg) * u[k] * u[l]
                    if k == l:
                        v += kg
                    K_out[b, k, l] = v
                    K_out[b, 3 + k, 3 + l] = v
                    K_out[b, k, 3 + l] = -v
                    K_out[b, 3 + k, l] = -v


def element_forces(X, l0, EA, tension_only=False, want_K=True):
    """Convenience wrapper: (f, K, slack) for arrays of bars."""
    X = np.ascontiguousarray(X, dtype=float).reshape(-1, 6)
    nb = X.shape[0]
    arr = lambda x, t=float: np.ascontiguousarray(np.broadcast_to(np.asarray(x, t), (nb,)))
    f = np.empty((nb, 6))
    K = np.empty((nb, 6, 6) if want_K else (1, 6, 6))
    slack = np.empty(nb, dtype=np.bool_)
    bar_forces(X, np.zeros((nb, 3)), arr(l0), arr(EA), arr(tension_only, np.bool_), want_K, f, K, slack)
    return f, (K if want_K else None), slack
