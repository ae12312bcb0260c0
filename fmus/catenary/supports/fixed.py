"""``type = "fixed"``: the wire is held in place at the mast (y and z; x too for the
messenger, the contact wire slides along the track)."""

from __future__ import annotations

from dataclasses import dataclass

from . import Site, Support, register


@register("fixed")
@dataclass(frozen=True)
class FixedSupport(Support):

    @classmethod
    def from_table(cls, table, wire):
        table.unknown_keys(["type"])
        return cls()

    def attach(self, site: Site, parts) -> None:
        site.structure.fixed[site.held(vertical=True)] = True
