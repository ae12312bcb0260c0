"""The registry of contact laws (:data:`CONTACT_LAWS`), the :class:`ContactLaw` protocol they
follow and the decorator they register with (:func:`register`); the laws themselves, and the
list of their modules, are in :mod:`.contact_laws`."""

from __future__ import annotations

from typing import Any, Protocol

from ..core.registry import Registry

#: contact laws by their scenario name
CONTACT_LAWS = Registry("contact law", "contact.law")
#: the law of a scenario that names none
DEFAULT_LAW = "penalty"


class ContactLaw(Protocol):
    name: str
    compliance: float
    condensable: bool
    across_ports: bool
    fields: tuple

    def bind(self, system) -> Any:
        """The law's part in an assembled :class:`~.coupled.CoupledSystem`."""


def register(name: str):
    """Class decorator: make a law available as ``law = "<name>"``."""
    def deco(cls):
        cls.name = name
        return CONTACT_LAWS.add(name, cls)
    return deco
