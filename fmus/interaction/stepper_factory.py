"""The one stepper factory (:func:`make_stepper`) and the stepper it builds besides the HHT
integrator, the condensed step and the closed-form step under given loads
(:class:`~pantocosim.core.structure_stepping.ForcedStepper`): Newton-Raphson on structure,
bodies and contacts assembled (:class:`AssembledStepper`).

==========================  =======================  ===================================
the model declares          under its inputs         with bodies in contact
==========================  =======================  ===================================
``stepping = "newton"``     ``HHTIntegrator``        :class:`AssembledStepper`
a registered structure      ``ForcedStepper``        :class:`~.condensed.CondensedStepper`
step (``"affine"``,         (``stepper_under_inputs``,  (a law that cannot be condensed:
``"modal"``)                ``core.structure_stepping``)       :class:`AssembledStepper`)
==========================  =======================  ===================================

The monolithic run, the catenary FMU and in-process co-simulation all take their stepper from
:func:`make_stepper`, so a model is stepped the same way everywhere.
"""

from __future__ import annotations

import numpy as np

from ..core.hht import HHTIntegrator
from ..core.stepper_contract import (NEWTON, CoupledStepper, Forwarding, Stepper, StepReport,
                                     closed_form_step, declared_stepping)
from ..core.structure_stepping import stepper_under_inputs
from .condensed import CondensedStepper
from .coupled import CoupledSystem


class AssembledStepper(Forwarding):
    """Newton-Raphson HHT on a structure, bodies and their penalty contacts assembled into one
    model (:class:`~.coupled.CoupledSystem`, DOFs [structure | body 1 | ...]): any model."""

    closed_form = False
    wrapped = "integ"

    def __init__(self, structure, bodies, contact, settings, contact_state=None):
        self.system = CoupledSystem(structure, bodies, contact)
        self.system.law.set_state(contact_state)
        self.integ = HHTIntegrator(self.system, settings)

    @property
    def structure_q(self) -> np.ndarray:
        """The structure's coordinates."""
        return self.integ.q[:self.system.n_cat]

    def step(self, h: float, inputs=None) -> StepReport:
        return self.integ.step(h, inputs)

    def contacts(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(contact forces, contact heights, wire heights), one per body."""
        st = self.system.contact_state(self.integ.t, self.integ.q, self.integ.v)
        return tuple(np.array([c[i] for c in st]) for i in range(3))


def make_stepper(model, settings, bodies=(), contact=None, *, redo: bool = False,
                 contact_state=None) -> Stepper | CoupledStepper:
    """The stepper of ``model`` under its inputs, or with ``bodies`` (pantographs) in
    ``contact`` (a law of :mod:`.contact_laws`, in ``contact_state``: the static start's),
    as the model declares (``stepping``, :mod:`pantocosim.core.stepper_contract`; table
    above). ``redo``: keep what a step redone from the same state reuses (a co-simulation
    rollback redoes steps). A law that cannot be condensed on the contact points
    (``condensable``) is stepped on the assembled system. Initialize it with
    ``initialize(t0, q0, v0, inputs0)``; with bodies it is a
    :class:`~pantocosim.core.stepper_contract.CoupledStepper`, q0 = [structure | body 1 | ...] at
    rest."""
    closed = declared_stepping(model) != NEWTON
    if bodies:
        if closed and contact.condensable:
            return CondensedStepper(closed_form_step(model, settings, redo), model.contact_points,
                                    bodies, contact, settings, speed=model.speed)
        return AssembledStepper(model, bodies, contact, settings, contact_state)
    return stepper_under_inputs(model, settings, redo=redo)
