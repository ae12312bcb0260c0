"""``type = "fixed"``: the wire is held in place at the mast (y and z; x too for the
messenger, the contact wire slides along the track)."""

from __future__ import annotations

from dataclasses import dataclass

from ...core.schema import Section
from .registry import Site, Support, register


@register("fixed")
@dataclass(frozen=True)
class FixedSupport(Support):

    FIELDS = Section("", [], extra=("type",))

    @classmethod
    def from_table(cls, table, wire):
        cls.FIELDS.check_keys(table)
        return cls()

    def attach(self, site: Site, parts) -> None:
        site.structure.fixed[site.held(vertical=True)] = True
