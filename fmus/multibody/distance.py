"""Distance between two body points: a massless rigid link with spherical ends (constant
length) or a linear actuator (length imposed as a function of time; Cardona & Jordi, 9.6: "a linear
actuator imposes only the distance between two points").

A point attached to node A's body sits at p_A = x_A + sum_i alpha_i d_i = T_A q_A (alpha its
body components), linear in the node coordinates, so

    g = |p_B - p_A|^2 - L(t)^2 = 0

is one quadratic constraint (B a second body point, or a fixed point). Its multiplier gives
the force of the link or actuator: the constraint force on B is -s lambda dg/dp_B =
-2 s lambda (p_B - p_A), i.e. a push of -2 s lambda L along p_B - p_A (:meth:`Distance.force`).
"""

from __future__ import annotations

import numpy as np

from .component import Component
from .constraint_set import ConstraintSet


def body_point(system, node: int, point=None):
    """(dofs (12,), T (3, 12)) with p = T q[dofs] the point ``point`` (spatial coordinates in
    the reference configuration; default the node itself) of the node's body."""
    X0, R0 = system.X0[node], system.R0[node]
    alpha = np.zeros(3) if point is None else R0.T @ (np.asarray(point, float) - X0)
    T = np.kron(np.concatenate([[1.0], alpha])[None, :], np.eye(3))
    return system.node_dofs(node), T


def _squared(law):
    """The drive -L(t)^2 of g and its time derivatives, from (L, L', L'')."""
    def drive(t):
        L, Ld, Ldd = law(t)
        return -L * L, -2.0 * L * Ld, -2.0 * (Ld * Ld + L * Ldd)
    return drive


class Distance(Component):
    """|p_B - p_A| = L between ``point_a`` of node A's body and ``point_b`` of node B's body
    (``node_b`` None: ``point_b`` is a fixed point). ``length``: None (the reference
    distance), a number, or a function t -> (L, L', L'') (an actuator)."""

    kind = "distance"

    def __init__(self, node_a: int, point_a=None, node_b: int | None = None, point_b=None,
                 length=None):
        if node_b is None and point_b is None:
            raise ValueError("distance to the ground needs point_b")
        self.a, self.point_a = int(node_a), point_a
        self.b, self.point_b = (None if node_b is None else int(node_b)), point_b
        self.length = length

    def _difference(self, system):
        """(dofs, D, p) with p_B - p_A = D q[dofs] + p (p the fixed point, or 0)."""
        da, Ta = body_point(system, self.a, self.point_a)
        if self.b is None:
            return da, -Ta, np.asarray(self.point_b, float)
        db, Tb = body_point(system, self.b, self.point_b)
        return np.concatenate([da, db]), np.hstack([-Ta, Tb]), np.zeros(3)

    def reference_length(self, system) -> float:
        dofs, D, p = self._difference(system)
        return float(np.linalg.norm(D @ system.reference()[dofs] + p))

    def constraints(self, system) -> list[ConstraintSet]:
        dofs, D, p = self._difference(system)
        H = 2.0 * D.T @ D
        b = 2.0 * D.T @ p
        c = p @ p
        drive = _squared(self.length) if callable(self.length) else None
        if drive is None:
            L = self.reference_length(system) if self.length is None else float(self.length)
            if not L > 0.0:
                raise ValueError(f"distance: length must be > 0, got {L}")
            c -= L * L
        self._map = (dofs, D, p)
        return [ConstraintSet(dofs[None, :], H[None], b[None], np.array([c]), name=self.kind,
                              drive=drive)]

    def current_length(self, q) -> float:
        dofs, D, p = self._map
        return float(np.linalg.norm(D @ q[dofs] + p))

    def force(self, system, q) -> float:
        """The push of the link or actuator along p_B - p_A (positive: it pushes the points
        apart, the link is compressed), from its multiplier in ``q``."""
        return float(-2.0 * system.multipliers(q, self)[0] * self.current_length(q))
