"""The growing lists of one mesh build: bars, point masses, ground springs and the unknowns
of the initial-configuration problem, filled by the mesh stages and by the supports
(:mod:`pantocosim.catenary.supports`), then handed to the structure as element sets."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bar import BarSet
from .ground_spring import GroundSprings
from .point_mass import PointMasses


@dataclass
class Anchor:
    """A support whose height is an unknown of the initial-configuration problem: the pin of
    a steady arm (``kind='pin'``, ``index`` = full DOF of the pin coordinate ``comp``: 1 for
    y, 2 for z) or the ground end of a spring (``kind='spring'``, ``index`` = spring
    number), chosen so that the supported coordinate (full DOF ``target``) takes the
    ``design`` value (stagger or height)."""

    kind: str
    index: int
    target: int
    design: float
    bar: int = -1
    comp: int = 2


class MeshParts:
    """Bars, point masses and springs added one by one; :meth:`add_to` makes their element sets."""

    def __init__(self):
        self._bars: list[tuple] = []
        self._points: list[tuple] = []
        self._springs: list[tuple] = []
        self.anchors: list[Anchor] = []
        self.arms: list[tuple] = []      # (bar, pin node, wire node, design y)

    def bar(self, dofs, l0: float, EA: float, mass: float, tension_only: bool) -> int:
        """Add a bar between two nodes (dofs: 3 + 3 full position DOFs); its number."""
        self._bars.append((list(dofs), l0, EA, mass, tension_only))
        return len(self._bars) - 1

    def point_masses(self, dofs, mass: float) -> None:
        """A mass moving with each of ``dofs`` (dropped later when zero)."""
        self._points += [(int(k), mass) for k in dofs]

    def spring(self, dof: int, k: float, anchor: float) -> int:
        """A ground spring on one DOF; its number."""
        self._springs.append((dof, k, anchor))
        return len(self._springs) - 1

    def add_to(self, structure) -> None:
        """Register bars, point masses and springs (in this order) with the structure."""
        dofs, l0, EA, mass, tonly = (list(c) for c in zip(*self._bars)) if self._bars \
            else ([], [], [], [], [])
        structure.add("bars", BarSet(np.array(dofs, dtype=np.int64).reshape(-1, 6),
                                     np.array(l0), np.array(EA), np.array(mass),
                                     np.array(tonly, dtype=np.bool_)))
        pd = np.array([p[0] for p in self._points], dtype=np.int64)
        pm = np.array([p[1] for p in self._points])
        keep = pm > 0
        structure.add("points", PointMasses(pd[keep], pm[keep]))
        structure.add("springs", GroundSprings(
            np.array([s[0] for s in self._springs], dtype=np.int64),
            np.array([s[1] for s in self._springs], dtype=float),
            np.array([s[2] for s in self._springs], dtype=float)))
