"""Joints between two nodes, or between a node and the ground, as quadratic constraints.

A vector fixed in the body of a node is u = sum_i alpha_i d_i with alpha = R0^T u0 (its
components in the reference triad). The joints combine two kinds of equations (the pendulum paper
treats its joints as constraints with multipliers, eq. 15):

- coincidence of positions x_A - x_B = 0 (linear; B may be a fixed point),
- perpendicularity of body vectors u_A . w_B = 0 (bilinear in the directors; w_B may be a
  fixed vector of the ground).

| joint      | equations                                    | relative freedoms      |
|------------|----------------------------------------------|------------------------|
| universal  | 3 coincidence + a_A . b_B = 0                | 2 rotations (a_A, b_B) |
| revolute   | 3 coincidence + a_A . p_B = 0, a_A . r_B = 0 | rotation about a       |
| clamp      | 3 coincidence + 3 perpendicularities         | none                   |

With the six orthonormality equations of each node the counts are independent (the clamp
uses d1.e2 = d1.e3 = d2.e3 = 0, not nine director equations, so nothing is redundant).
The multipliers of the coincidence equations are the joint forces (Cardona & Jordi, 9.7).
"""

from __future__ import annotations

import numpy as np

from .component import Component
from .constraint_set import ConstraintSet


def _perpendicular_pair(a):
    a = np.asarray(a, float) / np.linalg.norm(a)
    trial = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    p = trial - (trial @ a) * a
    p /= np.linalg.norm(p)
    return p, np.cross(a, p)


class Joint(Component):
    """A set of coincidence and perpendicularity equations between node A and node B (or
    the ground when B is None)."""

    kind = "joint"

    def __init__(self, node_a: int, node_b: int | None = None, point=None):
        self.a = node_a
        self.b = node_b
        self.point = point
        self.perpendicular: list[tuple[np.ndarray, np.ndarray]] = []  # (u0 in A, w0 in B)

    def constraints(self, system) -> list[ConstraintSet]:
        sets = [self._coincidence(system)]
        if self.perpendicular:
            sets.append(self._perpendicularity(system))
        return sets

    def _coincidence(self, system) -> ConstraintSet:
        xa = system.x_dofs(self.a)
        eye = np.eye(3)
        if self.b is None:
            p = system.X0[self.a] if self.point is None else np.asarray(self.point, float)
            return ConstraintSet(np.tile(xa, (3, 1)), np.zeros((3, 3, 3)), eye, -p,
                                 name=f"{self.kind} position")
        xb = system.x_dofs(self.b)
        idx = np.tile(np.concatenate([xa, xb]), (3, 1))
        return ConstraintSet(idx, np.zeros((3, 6, 6)), np.hstack([eye, -eye]), np.zeros(3),
                             name=f"{self.kind} position")

    def _perpendicularity(self, system) -> ConstraintSet:
        m = len(self.perpendicular)
        da = system.d_dofs(self.a)
        RA = system.R0[self.a]
        eye = np.eye(3)
        if self.b is None:
            idx = np.tile(da, (m, 1))
            b = np.array([np.kron(RA.T @ u0, w0) for u0, w0 in self.perpendicular])
            return ConstraintSet(idx, np.zeros((m, 9, 9)), b, np.zeros(m),
                                 name=f"{self.kind} axes")
        db = system.d_dofs(self.b)
        RB = system.R0[self.b]
        H = np.zeros((m, 18, 18))
        for k, (u0, w0) in enumerate(self.perpendicular):
            Cm = np.kron(np.outer(RA.T @ u0, RB.T @ w0), eye)
            H[k, :9, 9:] = Cm
            H[k, 9:, :9] = Cm.T
        return ConstraintSet(np.tile(np.concatenate([da, db]), (m, 1)), H,
                             np.zeros((m, 18)), np.zeros(m), name=f"{self.kind} axes")


class Universal(Joint):
    """Cross axes: ``axis_a`` fixed in A, ``axis_b`` fixed in B, perpendicular in the
    reference configuration; B turns about both."""

    kind = "universal"

    def __init__(self, node_a, node_b, axis_a, axis_b):
        super().__init__(node_a, node_b)
        axis_a = np.asarray(axis_a, float)
        axis_b = np.asarray(axis_b, float)
        if abs(axis_a @ axis_b) > 1e-12 * np.linalg.norm(axis_a) * np.linalg.norm(axis_b):
            raise ValueError("universal joint: the cross axes must be perpendicular")
        self.perpendicular = [(axis_a, axis_b)]


class Revolute(Joint):
    """Rotation about ``axis`` only (node_b None: about a fixed axis through the node)."""

    kind = "revolute"

    def __init__(self, node_a, node_b=None, axis=(0.0, 0.0, 1.0), point=None):
        super().__init__(node_a, node_b, point)
        axis = np.asarray(axis, float)
        p, r = _perpendicular_pair(axis)
        self.perpendicular = [(axis, p), (axis, r)]


class Clamp(Joint):
    """Node fixed to the ground in position and orientation (its reference triad)."""

    kind = "clamp"

    def __init__(self, node_a, point=None):
        super().__init__(node_a, None, point)

    def constraints(self, system):
        R = system.R0[self.a]
        e1, e2, e3 = R.T
        self.perpendicular = [(e1, e2), (e1, e3), (e2, e3)]
        return super().constraints(system)
