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

from ..core.scatter import scatter_add



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


class BarSet:
    """All bars of a structure (the :class:`~.structure.Element` protocol): droppers
    (tension-only) and steady arms. dofs: (n, 6) full DOFs [r_i, r_j]; per bar the
    unstretched length ``l0``, ``EA``, total ``mass`` and ``tension_only``. After each force
    evaluation ``slack`` holds the bars that carried no force."""

    def __init__(self, dofs, l0, EA, mass, tension_only):
        self.dofs = np.ascontiguousarray(np.asarray(dofs, dtype=np.int64).reshape(-1, 6))
        self.l0 = np.asarray(l0, dtype=float)
        self.EA = np.asarray(EA, dtype=float)
        self.mass = np.asarray(mass, dtype=float)
        self.tension_only = np.ascontiguousarray(tension_only, dtype=np.bool_)

    def __len__(self) -> int:
        return self.dofs.shape[0]

    def bind(self, structure, pos) -> None:
        off = structure.offset
        self.dX = np.ascontiguousarray(off[self.dofs[:, 3:6]] - off[self.dofs[:, 0:3]])
        self.pos = pos
        self.pos_blocks = pos.reshape(-1, 36)
        n = len(self)
        self._f = np.empty((n, 6))
        self._K = np.empty((n, 6, 6))
        self.slack = np.zeros(n, dtype=np.bool_)
        self._bilateral = np.zeros(n, dtype=np.bool_)

    def _law(self, tension_only: bool) -> np.ndarray:
        return self.tension_only if tension_only else self._bilateral

    def add_mass(self, M, f_weight, gravity) -> None:
        if not len(self):
            return
        Mb = self.mass[:, None, None] * mass_matrix(1.0)[None]
        gb = self.mass[:, None] * gravity_vector(1.0, gravity)[None]
        scatter_add(M, self.pos, Mb.ravel())
        scatter_add(f_weight, self.dofs.ravel(), gb.ravel())

    def add_forces(self, x_full, f, K, tension_only) -> None:
        bar_forces(x_full[self.dofs], self.dX, self.l0, self.EA, self._law(tension_only),
                   K is not None, self._f, self._K, self.slack)
        scatter_add(f, self.dofs.ravel(), self._f.ravel())
        if K is not None:
            scatter_add(K, self.pos, self._K.ravel())

    def tangent_blocks(self, x_full, tension_only: bool = False):
        """Per-bar 6x6 tangents and forces at x_full (for damping and reports)."""
        n = len(self)
        f, K, s = np.empty((n, 6)), np.empty((n, 6, 6)), np.empty(n, dtype=np.bool_)
        bar_forces(x_full[self.dofs], self.dX, self.l0, self.EA, self._law(tension_only),
                   True, f, K, s)
        return f, K, s

    def axial_forces(self, x_full, tension_only: bool = True) -> np.ndarray:
        """Axial force N of every bar (tension positive; zero when slack if tension_only)."""
        X = x_full[self.dofs]
        d = X[:, 3:] - X[:, :3] + self.dX
        ln = np.linalg.norm(d, axis=1)
        N = self.EA * (ln - self.l0) / self.l0
        if tension_only:
            N = np.where(self.tension_only & (N < 0), 0.0, N)
        return N

    def outputs(self, x_full) -> dict[str, np.ndarray]:
        return {"axial_force": self.axial_forces(x_full)}
