"""Stepping a structure alone under its inputs (:func:`stepper_under_inputs`): the HHT
integrator for a model stepped by Newton, or a closed-form step under given loads
(:class:`ForcedStepper`) for one that declares a registered closed-form step (``"affine"``,
``"modal"``, :mod:`.stepper_contract`). With pantographs in contact the one factory is
:func:`pantocosim.interaction.stepper_factory.make_stepper`, which steps a structure alone with
this one.
"""

from __future__ import annotations

import numpy as np

from . import affine_hht  # noqa: F401  (registers the "affine" closed-form step)
from .hht import HHTIntegrator
from .stepper_contract import (NEWTON, ClosedFormStep, Forwarding, Stepper, StepReport,
                               closed_form_step, declared_stepping)


class ForcedStepper(Forwarding):
    """A closed-form :class:`~.stepper_contract.ClosedFormStep` under given loads: ``step(h, F)``
    applies F (one force per contact point, at t + h) on the model's contact points
    ``points(t)`` (dofs, weights), e.g. the catenary's under forces read from FMU inputs.
    The constant step data are those of :attr:`structure`."""

    #: a step leaves the state alone until it succeeds
    closed_form = True
    wrapped = "structure"

    def __init__(self, structure: ClosedFormStep, points):
        self.structure = structure
        self.points = points

    def step(self, h: float, inputs=None) -> StepReport:
        st = self.structure
        st.begin(h, [(cp.dofs, cp.weights) for cp in self.points(st.t + h)])
        F = np.asarray(inputs, dtype=float)
        while not st.finish(F):
            pass
        return StepReport(iterations=st.passes)


def stepper_under_inputs(model, settings, *, redo: bool = False) -> Stepper:
    """The stepper of ``model`` alone under its inputs, as it declares (``stepping``):
    :class:`ForcedStepper` over its closed-form step, or the HHT integrator. ``redo``: keep what
    a step redone from the same state reuses (a co-simulation rollback redoes steps)."""
    if declared_stepping(model) != NEWTON:
        return ForcedStepper(closed_form_step(model, settings, redo), model.contact_points)
    return HHTIntegrator(model, settings)
