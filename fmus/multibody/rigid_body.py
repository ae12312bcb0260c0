"""A rigid body carried by one node (the rigid solids of Cardona & Jordi's mechanisms).

A point of the body sits at x + sum_i xi_i d_i (xi its body components, d_i the node's
directors), so the kinetic energy of the body is

    T = 1/2 m |x'|^2 + m x' . sum_i c_i d_i' + 1/2 sum_ij J_ij d_i' . d_j',

with m its mass, c the body components of its centre of mass relative to the node and
J = int rho xi xi^T dV the Euler tensor about the node, J = 1/2 tr(I_G) 1 - I_G + m c c^T
from the central inertia tensor I_G. The mass matrix is constant (no gyroscopic terms: they
come out of the orthonormality constraints of the directors), and the weight M u_g of
:class:`~pantocosim.multibody.loads.Gravity` is exactly the weight of the body at its centre
of mass. Several bodies on one node add up (e.g. a bar and a particle fixed to it).
"""

from __future__ import annotations

import numpy as np
from .component import Component


class RigidBody(Component):
    """``mass`` with its centre ``center`` and central inertia tensor ``inertia`` (spatial
    components in the reference configuration; default: the node's position and zero, a
    particle), carried by ``node``."""

    def __init__(self, node: int, mass: float, inertia=None, center=None, name: str = "body"):
        self.node = int(node)
        self.mass = float(mass)
        self.inertia = np.zeros((3, 3)) if inertia is None else np.asarray(inertia, float)
        self.center = None if center is None else np.asarray(center, float)
        self.name = name
        if not self.mass >= 0.0:
            raise ValueError(f"{name}: mass must be >= 0, got {mass}")
        if self.inertia.shape != (3, 3) or not np.allclose(self.inertia, self.inertia.T):
            raise ValueError(f"{name}: the inertia tensor must be a symmetric 3 x 3 matrix")

    def bind(self, system) -> None:
        R0 = system.R0[self.node]
        X0 = system.X0[self.node]
        c = np.zeros(3) if self.center is None else R0.T @ (self.center - X0)
        IG = R0.T @ self.inertia @ R0
        J = 0.5 * np.trace(IG) * np.eye(3) - IG + self.mass * np.outer(c, c)
        if np.min(np.linalg.eigvalsh(0.5 * np.trace(IG) * np.eye(3) - IG)) < -1e-12 * max(
                1.0, np.trace(IG)):
            raise ValueError(f"{self.name}: the inertia tensor violates the triangle "
                             "inequality (no real mass distribution has it)")
        m = np.zeros((4, 4))
        m[0, 0] = self.mass
        m[0, 1:] = m[1:, 0] = self.mass * c
        m[1:, 1:] = J
        self.block = np.kron(m, np.eye(3))
        self.dofs = system.node_dofs(self.node)

    def add_mass(self, M) -> None:
        M.add(self.dofs, self.dofs, self.block)
