"""``type = "spring"``: a vertical ground spring of ``stiffness`` [N/m] under the wire (y
held; x too for the messenger), with a point ``mass`` [kg] on the wire (a steady arm's or a
cantilever's mass moving with it). The spring's ground end is an unknown of the initial
configuration: the wire sits at its design height."""

from __future__ import annotations

from dataclasses import dataclass

from ...core.schema import Field, Section
from ..parts import Anchor
from .registry import Site, Support, register


@register("spring")
@dataclass(frozen=True)
class SpringSupport(Support):
    stiffness: float
    mass: float = 0.0

    FIELDS = Section("", [
        Field("stiffness", unit="N/m", positive=True, doc="vertical spring under the wire"),
        Field("mass", unit="kg", default=0.0, nonnegative=True,
              doc="point mass on the wire (steady arm, cantilever)"),
    ], extra=("type",))

    @classmethod
    def from_table(cls, table, wire):
        cls.FIELDS.check_keys(table)
        return cls(**{f.name: f.read(table) for f in cls.FIELDS.fields})

    def attach(self, site: Site, parts) -> None:
        site.structure.fixed[site.held(vertical=False)] = True
        z = site.dofs[2]
        k = parts.spring(z, self.stiffness, site.height + site.preload / self.stiffness)
        parts.anchors.append(Anchor("spring", k, int(z), site.height))
        if self.mass > 0:
            parts.point_masses(site.dofs[:3], self.mass)
