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

from .registry import SUPPORTS, Site, Support, parse_support, register

# registration: one import per support type
from . import fixed, spring, steady_arm  # noqa: E402,F401

__all__ = ["SUPPORTS", "Site", "Support", "parse_support", "register"]
