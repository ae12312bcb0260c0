"""The contact laws between a pantograph and the contact wire, by the name a scenario gives
them (``[contact] law``): one module per law, behind the registry :data:`CONTACT_LAWS`.

A law declares what the solvers need to know of it (:class:`ContactLaw`):

- ``compliance``: static compression of the contact per newton [m/N] (1 / k_H for the
  penalty law, 0 for a rigid contact); the static start places the pantograph with it;
- ``condensable``: the law can be solved on a structure condensed on its contact points
  (:mod:`.condensed`, the linear and modal catenaries' closed-form path);
- ``across_ports``: the law is a force of the two sides' heights, so it can be evaluated on
  one side of an FMU interface (the co-simulation couplings and the catenary FMU);
- ``fields``: the scenario's ``[contact]`` values it takes (the loader refuses the others);
- ``bind(system)``: its part in the assembled monolithic system (:mod:`.coupled`): the force of
  each contact, any term it adds to the residual, the Newton correction with the system's
  factorization, and its own state (a multiplier's value) across steps.
"""

from __future__ import annotations

# registration: one import per law
from . import constraint_contact, penalty_contact  # noqa: F401
from .contact_registry import CONTACT_LAWS, DEFAULT_LAW, ContactLaw, register

__all__ = ["CONTACT_LAWS", "DEFAULT_LAW", "ContactLaw", "make_contact", "register"]


def make_contact(law: str, stiffness: float, damping: float):
    """The law ``law`` with the scenario's ``[contact]`` values (each law takes those it uses,
    ``from_fields``)."""
    return CONTACT_LAWS[law].from_fields(stiffness=stiffness, damping=damping)
