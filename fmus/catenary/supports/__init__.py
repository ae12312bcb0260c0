"""Supports of the wires at the intermediate masts: one class per TOML ``type``, one file
each, behind the registry :data:`SUPPORTS` (see ``docs/architecture.md``).

A support class validates its own table (``[contact_support]`` or ``[messenger_support]``)
with :class:`~pantocosim.core.params.Table` and, when the mesh is built, attaches itself to
one wire at one mast (a :class:`Site`): it fixes DOFs, adds elements to the
:class:`~pantocosim.catenary.parts.MeshParts` and declares the unknowns of the
initial-configuration problem (:class:`~pantocosim.catenary.parts.Anchor`). The two line ends
are anchored (x, y, z of both wires fixed) by the mesh itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ...core.params import Table

#: support classes by their TOML ``type`` string
SUPPORTS: dict[str, type["Support"]] = {}


def register(name: str):
    """Class decorator: make a support class available as ``type = "<name>"``."""
    def deco(cls):
        cls.type_name = name
        SUPPORTS[name] = cls
        return cls
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


# registration: one import per support type
from . import fixed, spring, steady_arm  # noqa: E402,F401
