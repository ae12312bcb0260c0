"""Planar joint: a node's body moves in a fixed plane (normal n through its reference
position): n . x = n . X0 and the body vector along n stays along n (perpendicular to the
two in-plane directions p, r). Three equations; the body keeps two translations and the
rotation about n. It holds a planar mechanism in its plane when its links are
:class:`~pantocosim.multibody.distance.Distance` constraints (massless bars with spherical
ends), which would otherwise let it leave the plane.
"""

from __future__ import annotations

import numpy as np

from .constraint_set import ConstraintSet
from .joints import Joint, _perpendicular_pair


class Planar(Joint):
    kind = "planar"

    def __init__(self, node: int, normal=(0.0, 0.0, 1.0)):
        super().__init__(node, None)
        self.normal = np.asarray(normal, float) / np.linalg.norm(normal)
        p, r = _perpendicular_pair(self.normal)
        self.perpendicular = [(self.normal, p), (self.normal, r)]

    def constraints(self, system) -> list[ConstraintSet]:
        n = self.normal
        normal = ConstraintSet(system.x_dofs(self.a)[None, :], np.zeros((1, 3, 3)), n[None],
                               np.array([-n @ system.X0[self.a]]), name=f"{self.kind} plane")
        return [normal, self._perpendicularity(system)]
