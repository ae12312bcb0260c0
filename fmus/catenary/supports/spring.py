"""``type = "spring"``: a vertical ground spring of ``stiffness`` [N/m] under the wire (y
held; x too for the messenger), with a point ``mass`` [kg] on the wire (a steady arm's or a
cantilever's mass moving with it). The spring's ground end is an unknown of the initial
configuration: the wire sits at its design height."""

from __future__ import annotations

from dataclasses import dataclass

from ..parts import Anchor
from . import Site, Support, register


@register("spring")
@dataclass(frozen=True)
class SpringSupport(Support):
    stiffness: float
    mass: float = 0.0

    @classmethod
    def from_table(cls, table, wire):
        table.unknown_keys(["type", "stiffness", "mass"])
        return cls(stiffness=table.number("stiffness", positive=True),
                   mass=table.number("mass", 0.0, nonnegative=True))

    def attach(self, site: Site, parts) -> None:
        site.structure.fixed[site.held(vertical=False)] = True
        z = site.dofs[2]
        k = parts.spring(z, self.stiffness, site.height + site.preload / self.stiffness)
        parts.anchors.append(Anchor("spring", k, int(z), site.height))
        if self.mass > 0:
            parts.point_masses(site.dofs[:3], self.mass)
