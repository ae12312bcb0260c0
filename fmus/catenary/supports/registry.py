"""The registry of support types (:data:`SUPPORTS`), the :class:`Support` base they derive
from and the :class:`Site` the mesh offers them; the types register themselves with
:func:`register` (see ``docs/architecture.md``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ...core.params import Table
from ...core.registry import Registry

#: support classes by their TOML ``type`` string
SUPPORTS = Registry("support type", "type")


def register(name: str):
    """Class decorator: make a support class available as ``type = "<name>"``."""
    def deco(cls):
        cls.type_name = name
        return SUPPORTS.add(name, cls)
    return deco


@dataclass
class Site:
    """One wire at one intermediate mast, as the mesh offers it to a support."""

    wire: str                  # "contact" or "messenger"
    number: int                # support number along the line (0: the first line end)
    node: int                  # the wire's node at the mast
    dofs: np.ndarray           # its full DOFs (x, y, z, slopes)
    height: float              # design height of the wire there [m]
    slides: bool               # the wire may slide along the track (x left free)
    preload: float             # vertical load assumed on a spring for its first anchor [N]
    own_nodes: list            # the support's own nodes (Support.n_own_nodes of them)
    own_dofs: np.ndarray       # their position DOFs, (own_nodes, 3)
    structure: Any             # the Structure being built (x_full, offset, fixed)
    definition: Any            # the CatenaryDefinition

    def held(self, vertical: bool) -> np.ndarray:
        """Position DOFs a support holds: y (and z if ``vertical``), plus x unless the wire
        slides along the track."""
        return self.dofs[(1 if self.slides else 0):(3 if vertical else 2)]


class Support:
    """Base of the support types: see :mod:`.fixed` for the smallest one."""

    type_name: ClassVar[str] = ""
    #: wires the type may hold
    wires: ClassVar[tuple[str, ...]] = ("contact", "messenger")
    #: nodes of its own per mast (3 position DOFs each, numbered after the wire nodes)
    n_own_nodes: ClassVar[int] = 0
    #: the fields of its table besides ``type`` (a :class:`~pantocosim.core.schema.Section`,
    #: read by ``from_table`` and listed in the catenary format's reference)
    FIELDS: ClassVar[Any] = None

    @classmethod
    def from_table(cls, table: Table, wire: str) -> "Support":
        """Validate the support's TOML table (ParameterError naming file, field, value)."""
        raise NotImplementedError

    def check_line(self, stagger: list[float], n_spans: int, source: str | None) -> None:
        """Checks against the rest of the definition (default: none)."""

    def attach(self, site: Site, parts) -> None:
        """Hold ``site``'s wire: fix DOFs, add elements and anchors to ``parts``."""
        raise NotImplementedError


def parse_support(table: Table, wire: str) -> Support:
    """The support described by ``table``, its class chosen by ``type``."""
    name = table.string("type", choices=[n for n, c in SUPPORTS.items() if wire in c.wires])
    return SUPPORTS[name].from_table(table, wire)

