"""Penalty-damper contact of a node with a rigid plane (the cam-follower element of the
pendulum paper, eq. 17): with the normal gap q_n = n . x - h,

    F = k q_n + c q_n'   while q_n < 0,   zero otherwise,

pushing the node along +n. The elastic part derives from the pseudo-elastic potential
1/2 k q_n^2 (the pendulum paper, after eq. 16), the damping part from the Rayleigh function
1/2 c q_n'^2, whose rate c q_n'^2 the energy account reports as contact dissipation. As in
the paper the force is not clipped: while the node leaves the plane fast the damper may pull.
"""

from __future__ import annotations

import numpy as np

from ..core.scatter import scatter_add
from .component import Component


class GroundContact(Component):
    def __init__(self, node: int, normal=(0.0, 1.0, 0.0), offset: float = 0.0,
                 stiffness: float = 1.0e6, damping: float = 0.0):
        n = np.asarray(normal, dtype=float)
        self.n = n / np.linalg.norm(n)
        self.node = node
        self.offset = float(offset)
        self.k = float(stiffness)
        self.c = float(damping)

    def bind(self, system) -> None:
        self.dofs = system.x_dofs(self.node)

    def tangent_dofs(self) -> np.ndarray:
        return self.dofs[None, :]

    def locate(self, pattern) -> None:
        self.pos = pattern.positions(self.dofs[:, None], self.dofs[None, :]).ravel()

    def state_key(self, q) -> bool:
        """In contact or not: the tangent changes with it (an integrator reusing a
        factorization refactorizes)."""
        return self.gap(q) < 0.0

    def gap(self, q) -> float:
        return float(self.n @ q[self.dofs] - self.offset)

    def force(self, q, v) -> float:
        """Normal force on the node (positive pushes it out of the plane)."""
        qn = self.gap(q)
        if qn >= 0.0:
            return 0.0
        return -(self.k * qn + self.c * float(self.n @ v[self.dofs]))

    def add_forces(self, t, q, v, f, K, C) -> None:
        qn = self.gap(q)
        if qn >= 0.0:
            return
        vn = float(self.n @ v[self.dofs])
        f[self.dofs] += (self.k * qn + self.c * vn) * self.n
        if K is not None:
            nn = np.outer(self.n, self.n).ravel()
            scatter_add(K.data, self.pos, self.k * nn)
            scatter_add(C.data, self.pos, self.c * nn)

    def energy(self, t, q, v) -> dict:
        qn = self.gap(q)
        return {"contact": 0.5 * self.k * qn * qn if qn < 0.0 else 0.0}

    def powers(self, t, q, v) -> dict:
        qn = self.gap(q)
        vn = float(self.n @ v[self.dofs])
        return {"dissipation": self.c * vn * vn if qn < 0.0 else 0.0}
