"""Point masses on single DOFs: the clamps of the droppers and the masses of spring supports
(the :class:`~.structure.Element` protocol). A mass is entered once per coordinate it moves
with (three entries for a mass at a node); its weight acts on z-position DOFs only."""

from __future__ import annotations

import numpy as np

from ..core.scatter import scatter_add



class PointMasses:
    """dofs: full DOF of every entry, mass: its mass [kg]."""

    def __init__(self, dofs, mass):
        self.dofs = np.asarray(dofs, dtype=np.int64).reshape(-1, 1)
        self.mass = np.asarray(mass, dtype=float)

    def bind(self, structure, pos) -> None:
        self.pos = pos                       # diagonal positions (-1: fixed DOF)
        self._zpos = structure.zpos

    def add_mass(self, M, f_weight, gravity) -> None:
        if not self.mass.size:
            return
        d = self.dofs[:, 0]
        scatter_add(M, self.pos, self.mass)
        np.add.at(f_weight, d, -gravity * self.mass * self._zpos[d])

    def add_forces(self, x_full, f, K, tension_only) -> None:
        pass                                 # inertia only

    def outputs(self, x_full) -> dict[str, np.ndarray]:
        return {}
