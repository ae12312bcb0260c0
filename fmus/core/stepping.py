"""The one stepper factory (:func:`make_stepper`) and the steppers it builds besides the HHT
integrator and the condensed step: a closed-form structure step under given loads
(:class:`ForcedStepper`) and Newton-Raphson on structure, bodies and contacts assembled
(:class:`AssembledStepper`).

============================  ===================================  ==========================
the model declares            under its inputs                     with bodies in contact
============================  ===================================  ==========================
``stepping = "newton"``       :class:`~.hht.HHTIntegrator`         :class:`AssembledStepper`
a registered structure step   :class:`ForcedStepper`               :class:`~.condensed.
(``"affine"``, ``"modal"``)                                        CondensedStepper`
============================  ===================================  ==========================

The monolithic run, the catenary FMU and in-process co-simulation all take their stepper from
:func:`make_stepper`, so a model is stepped the same way everywhere.
"""

from __future__ import annotations

import numpy as np

from . import affine_hht  # noqa: F401  (registers the "affine" structure step)
from .condensed import CondensedStepper
from .coupled import CoupledSystem
from .hht import HHTIntegrator
from .stepper import NEWTON, CoupledStepper, Stepper, StepReport, StructureStep, \
    declared_stepping, structure_step


class ForcedStepper:
    """A closed-form :class:`~.stepper.StructureStep` under given loads: ``step(h, F)``
    applies F (one force per contact point, at t + h) on the model's contact points
    ``points(t)`` (dofs, weights), e.g. the catenary's under forces read from FMU inputs.
    The constant step data are those of :attr:`structure`."""

    #: a step leaves the state alone until it succeeds
    closed_form = True

    def __init__(self, structure: StructureStep, points):
        self.structure = structure
        self.points = points

    @property
    def t(self) -> float:
        return self.structure.t

    @property
    def q(self) -> np.ndarray:
        return self.structure.q

    @property
    def v(self) -> np.ndarray:
        return self.structure.v

    def initialize(self, t0: float, q0, v0=None, inputs0=None) -> None:
        self.structure.initialize(t0, q0, v0, inputs0)

    def prepare(self, h: float) -> None:
        self.structure.prepare(h)

    def step(self, h: float, inputs=None) -> StepReport:
        st = self.structure
        st.begin(h, [(cp.dofs, cp.weights) for cp in self.points(st.t + h)])
        F = np.asarray(inputs, dtype=float)
        while not st.finish(F):
            pass
        return StepReport(iterations=st.passes)

    def get_state(self) -> dict:
        return self.structure.get_state()

    def set_state(self, state: dict) -> None:
        self.structure.set_state(state)


class AssembledStepper:
    """Newton-Raphson HHT on a structure, bodies and their penalty contacts assembled into one
    model (:class:`~.coupled.CoupledSystem`, DOFs [structure | body 1 | ...]): any model."""

    closed_form = False

    def __init__(self, structure, bodies, contact, settings, contact_state=None):
        self.system = CoupledSystem(structure, bodies, contact)
        self.system.law.set_state(contact_state)
        self.integ = HHTIntegrator(self.system, settings)

    @property
    def t(self) -> float:
        return self.integ.t

    @property
    def q(self) -> np.ndarray:
        return self.integ.q

    @property
    def v(self) -> np.ndarray:
        return self.integ.v

    @property
    def structure_q(self) -> np.ndarray:
        """The structure's coordinates."""
        return self.integ.q[:self.system.n_cat]

    def initialize(self, t0: float, q0, v0=None, inputs0=None) -> None:
        self.integ.initialize(t0, q0, v0, inputs0)

    def prepare(self, h: float) -> None:
        self.integ.prepare(h)

    def step(self, h: float, inputs=None) -> StepReport:
        return self.integ.step(h, inputs)

    def contacts(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(contact forces, contact heights, wire heights), one per body."""
        st = self.system.contact_state(self.integ.t, self.integ.q, self.integ.v)
        return tuple(np.array([c[i] for c in st]) for i in range(3))

    def get_state(self) -> dict:
        return self.integ.get_state()

    def set_state(self, state: dict) -> None:
        self.integ.set_state(state)


def make_stepper(model, settings, bodies=(), contact=None, *, redo: bool = False,
                 contact_state=None) -> Stepper | CoupledStepper:
    """The stepper of ``model`` under its inputs, or with ``bodies`` (pantographs) in
    ``contact`` (a law of :mod:`.contact_laws`, in ``contact_state``: the static start's),
    as the model declares (``stepping``, :mod:`.stepper`; table
    above). ``redo``: keep what a step redone from the same state reuses (a co-simulation
    rollback redoes steps). A law that cannot be condensed on the contact points
    (``condensable``) is stepped on the assembled system. Initialize it with ``initialize(t0, q0, v0, inputs0)``; with
    bodies it is a :class:`~.stepper.CoupledStepper`, q0 = [structure | body 1 | ...] at
    rest."""
    closed = declared_stepping(model) != NEWTON
    if bodies:
        if closed and contact.condensable:
            return CondensedStepper(structure_step(model, settings, redo), model.contact_points,
                                    bodies, contact, settings, speed=model.speed)
        return AssembledStepper(model, bodies, contact, settings, contact_state)
    if closed:
        return ForcedStepper(structure_step(model, settings, redo), model.contact_points)
    return HHTIntegrator(model, settings)
