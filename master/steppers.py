"""The monolithic integrators of a run, behind one small interface (``pantocosim run
--coupling monolithic``): ``step(h)`` returns the Newton iterations of the step and
``observe(row)`` writes (F, z_p, z_w) per pantograph and the support uplifts.

- :class:`AssembledStepper`: Newton-Raphson on catenary + pantographs + contacts assembled
  (:class:`~pantocosim.core.coupled.CoupledSystem`), for every catenary model;
- :class:`CondensedRunStepper`: a catenary with an affine form (constant matrices, e.g. the
  linear model) or its own closed-form stepper (``closed_form``, the modal model) in closed
  form, condensed on the contact points
  (:mod:`pantocosim.core.condensed`): the same solution, one solve per step.
"""

from __future__ import annotations

import numpy as np

from pantocosim.core.errors import PantocosimError
from pantocosim.core.hht import HHTIntegrator


class AssembledStepper:
    def __init__(self, prep, settings):
        from pantocosim.core.coupled import CoupledSystem

        self.prep = prep
        self.system = CoupledSystem(prep.catenary, prep.pantographs, prep.contact)
        self.system.law.set_state(prep.extra.get("contact_law_state"))   # static start's
        self.integ = HHTIntegrator(self.system, settings)
        q0 = np.concatenate([prep.q_cat0] + list(prep.q_pan0))
        self.integ.initialize(0.0, q0, np.zeros(self.system.n_dofs), None)

    @property
    def t(self) -> float:
        return self.integ.t

    def step(self, h: float) -> int:
        return self.integ.step(h).iterations

    def warm_up(self, h: float) -> None:
        """:func:`warm_up` of :attr:`integ`."""
        warm_up(self.integ, h)

    def observe(self):
        """([(F, z_p, z_w) per pantograph], support uplifts) at the current state."""
        integ = self.integ
        st = self.system.contact_state(integ.t, integ.q, integ.v)
        return ([(c[0], c[1], c[2]) for c in st],
                self.prep.catenary.support_uplift(integ.q[:self.system.n_cat]))


class CondensedRunStepper:
    def __init__(self, prep, settings):
        from pantocosim.core.affine_hht import AffineHHT
        from pantocosim.core.condensed import CondensedStepper

        cat = self.catenary = prep.catenary
        self.structure = (cat.closed_form(settings) if hasattr(cat, "closed_form")
                          else AffineHHT(cat.affine_form(), settings))
        self.stepper = CondensedStepper(self.structure, cat.contact_points, prep.pantographs,
                                        prep.contact, settings, speed=cat.speed)
        self.stepper.initialize(0.0, prep.q_cat0, prep.q_pan0)

    @property
    def t(self) -> float:
        return self.structure.t

    def step(self, h: float) -> int:
        return self.stepper.step(h)

    def warm_up(self, h: float) -> None:
        """The structure's set-up for steps of h (``prepare``), then :func:`warm_up`."""
        if hasattr(self.structure, "prepare"):
            self.structure.prepare(h)
        warm_up(self.stepper, h)

    def observe(self):
        c = self.stepper.bodies
        return (list(zip(c.forces, c.heights, c.wire_heights)),
                self.catenary.support_uplift(self.structure.q))


def warm_up(stepper, h: float) -> None:
    """Take one step of ``h`` and put the state back: what a first step pays once (numba
    loading its compiled kernels, the factorization for h, the first unit-vector solves) is
    paid at set-up, not inside the paced loop. A failing step is left for the run to
    report."""
    state = stepper.get_state()
    try:
        stepper.step(h)
    except PantocosimError:
        pass
    finally:
        stepper.set_state(state)


def make_stepper(prep, settings):
    """The monolithic integrator for ``prep``'s catenary model (assembled when the contact
    law cannot be condensed)."""
    if prep.contact.condensable and (hasattr(prep.catenary, "affine_form")
                                     or hasattr(prep.catenary, "closed_form")):
        return CondensedRunStepper(prep, settings)
    return AssembledStepper(prep, settings)
