"""Linear springs from one DOF to the ground (spring supports; the
:class:`~.structure.Element` protocol). Force k (x - anchor): the anchor, the spring's
ground end, is an unknown of the initial-configuration problem (3.1.3)."""

from __future__ import annotations

import numpy as np

from ..core.scatter import scatter_add



class GroundSprings:
    """dofs: full DOF of every spring, k: stiffness [N/m], anchor: ground-end coordinate."""

    def __init__(self, dofs, k, anchor):
        self.dofs = np.asarray(dofs, dtype=np.int64).reshape(-1, 1)
        self.k = np.asarray(k, dtype=float)
        self.anchor = np.asarray(anchor, dtype=float)

    def bind(self, structure, pos) -> None:
        self.pos = pos                       # diagonal positions (-1: fixed DOF)

    def add_mass(self, M, f_weight, gravity) -> None:
        pass                                 # massless

    def add_forces(self, x_full, f, K, tension_only) -> None:
        if self.k.size:
            d = self.dofs[:, 0]
            np.add.at(f, d, self.k * (x_full[d] - self.anchor))
        if K is not None:
            scatter_add(K, self.pos, self.k)

    def outputs(self, x_full) -> dict[str, np.ndarray]:
        return {"force": self.k * (x_full[self.dofs[:, 0]] - self.anchor)}
