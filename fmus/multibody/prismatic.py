"""Prismatic joint: node B's body slides along an axis fixed in node A's body and does not
turn relative to it (the guide of the block of Cardona & Jordi, Fig. 35).

Five quadratic constraints (joints.py explains the two kinds of equation of the other joints):

- relative orientation locked: a_1 . b_2 = a_1 . b_3 = a_2 . b_3 = 0, with a_i fixed in A and
  b_i fixed in B, both equal to A's reference triad (the three equations of a clamp, between
  two bodies);
- transverse position: (x_B - x_A) . w_A = (X0_B - X0_A) . w0 for the two body vectors w of A
  perpendicular to the axis (bilinear in x and A's directors).

The multipliers of the transverse equations are the guide's normal forces; the motion along
the axis is left free (a :class:`~pantocosim.multibody.distance.Distance` can impose it).
"""

from __future__ import annotations

import numpy as np

from .constraint_set import ConstraintSet
from .joints import Joint, _perpendicular_pair


class Prismatic(Joint):
    kind = "prismatic"

    def __init__(self, node_a: int, node_b: int, axis=(1.0, 0.0, 0.0)):
        super().__init__(node_a, node_b)
        self.axis = np.asarray(axis, float) / np.linalg.norm(axis)

    def constraints(self, system) -> list[ConstraintSet]:
        e1, e2, e3 = system.R0[self.a].T
        self.perpendicular = [(e1, e2), (e1, e3), (e2, e3)]
        return [self._perpendicularity(system), self._transverse(system)]

    def _transverse(self, system) -> ConstraintSet:
        xa, xb = system.x_dofs(self.a), system.x_dofs(self.b)
        da = system.d_dofs(self.a)
        RA = system.R0[self.a]
        offset = system.X0[self.b] - system.X0[self.a]
        eye = np.eye(3)
        H, c = np.zeros((2, 15, 15)), np.zeros(2)
        for k, w0 in enumerate(_perpendicular_pair(self.axis)):
            beta = RA.T @ w0                       # w_A = sum_i beta_i d_i
            C = np.kron(beta[None, :], eye)        # (3, 9): d(w_A)/d(directors)
            H[k, 3:6, 6:] = C                      # x_B . w_A
            H[k, 0:3, 6:] = -C                     # -x_A . w_A
            H[k] = H[k] + H[k].T
            c[k] = -offset @ w0
        idx = np.tile(np.concatenate([xa, xb, da]), (2, 1))
        return ConstraintSet(idx, H, np.zeros((2, 15)), c, name=f"{self.kind} guide")
