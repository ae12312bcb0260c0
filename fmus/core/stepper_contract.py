"""The stepping contract: what every time-stepping engine offers and how a model declares
which engine steps it.

A **stepper** (:class:`Stepper`) advances a model, or a structure with bodies in contact,
over time steps of HHT-alpha (3.16)-(3.24): ``initialize`` sets the start state, ``prepare(h)``
pays at set-up what the first step of size h would pay, ``step(h, inputs)`` advances and
returns a :class:`StepReport`, ``get_state``/``set_state`` save and restore everything the
next step depends on (co-simulation rollback, FMU states).
:func:`~pantocosim.interaction.stepper_factory.make_stepper` builds the stepper a model
declares; the monolithic run, the FMU slaves and in-process co-simulation all take theirs from
it.

A model **declares** its stepping with the class attribute ``stepping``: ``"newton"``
(:data:`NEWTON`, the default of :class:`~.model.SecondOrderModel`: Newton-Raphson HHT on
:meth:`~.model.SecondOrderModel.evaluate`, :mod:`.hht`) or the name of a **closed-form step**
(:class:`ClosedFormStep`) registered in :data:`CLOSED_FORM_STEPS`:

- ``"affine"``: :class:`~.affine_hht.AffineHHT` on the model's ``affine_form()`` (constant
  banded matrices and unilateral rank-one elements: the linear catenary);
- ``"modal"``: :class:`~pantocosim.catenary.modal_step.ModalHHT` (the modal catenary).

A closed-form step is affine in the loads on its moving contact points; whoever supplies the
loads (FMU inputs: :class:`~.structure_stepping.ForcedStepper`; pantographs in penalty contact
solved on the condensed interface: :class:`~pantocosim.interaction.condensed.CondensedStepper`)
finishes the step. A step is registered where it is defined; the module of a model that
declares it imports that module (``catenary/modal.py`` imports ``modal_step``), so a model
never exists without its step.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from .errors import PantocosimError, ParameterError
from .registry import Registry

#: the stepping of a model without a closed form: Newton-Raphson HHT (:mod:`.hht`)
NEWTON = "newton"


@dataclass(frozen=True)
class StepReport:
    """What one step cost.

    ``iterations``: the linear solves of the step: Newton iterations (0 for a step repeated
    from a kept result), or the passes of a closed-form step over the slack set (1 when no
    unilateral element changes state); a step of structure and bodies reports the bodies'
    Newton iterations of its last pass. ``residual``: the Newton residual max |R| [N] at
    convergence (0 in closed form). ``refactorizations``: Newton matrices factorized.
    ``settled``: False when a contact's active set gave up before it repeated (the penalty
    law condensed on the contact points, interaction/penalty_contact.py): the step's
    contact forces are then its last pass's."""

    iterations: int
    residual: float = 0.0
    refactorizations: int = 0
    settled: bool = True


class Stepper(Protocol):
    """One time-stepping engine (module docstring)."""

    #: time reached [s]
    t: float

    #: a failing step leaves the state as it was (nothing to save before a step)
    closed_form: bool

    @property
    def q(self) -> np.ndarray: ...

    @property
    def v(self) -> np.ndarray: ...

    def initialize(self, t0: float, q0, v0=None, inputs0=None) -> None: ...

    def prepare(self, h: float) -> None: ...

    def step(self, h: float, inputs=None) -> StepReport: ...

    def get_state(self) -> Any: ...

    def set_state(self, state: Any) -> None: ...


class Forwarding:
    """What a stepper wrapping another engine forwards to it: ``t``, ``q``, ``v``,
    ``initialize``, ``prepare``, ``get_state``, ``set_state``. The wrapper names the
    attribute holding the engine in :attr:`wrapped` and adds its own ``step``."""

    #: the attribute that holds the wrapped engine
    wrapped: str

    @property
    def t(self) -> float:
        return getattr(self, self.wrapped).t

    @property
    def q(self) -> np.ndarray:
        return getattr(self, self.wrapped).q

    @property
    def v(self) -> np.ndarray:
        return getattr(self, self.wrapped).v

    def initialize(self, t0: float, q0, v0=None, inputs0=None) -> None:
        getattr(self, self.wrapped).initialize(t0, q0, v0, inputs0)

    def prepare(self, h: float) -> None:
        getattr(self, self.wrapped).prepare(h)

    def get_state(self) -> Any:
        return getattr(self, self.wrapped).get_state()

    def set_state(self, state: Any) -> None:
        getattr(self, self.wrapped).set_state(state)


class CoupledStepper(Stepper, Protocol):
    """A stepper of a structure with bodies (pantographs) in contact, q = [structure |
    body 1 | ...]: what a monolithic run reads after each step."""

    @property
    def structure_q(self) -> np.ndarray: ...

    def contacts(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(contact forces, contact heights, wire heights), one per body."""
        ...


class ClosedFormStep(Protocol):
    """A closed-form HHT-alpha step of a structure loaded on moving points, in two halves:
    ``begin(h, loads)`` (loads: (dofs, weights) of each load vector n_k(t + h)) predicts and
    solves the free response :attr:`delta_free` and the load responses :attr:`W` (one row
    per load, Delta = delta_free + sum_k F_k W_k on top of the Newmark predictors
    :attr:`q_p`, :attr:`v_p`); ``finish(F)`` takes the step with the loads F, or returns
    False when the set of slack unilateral elements changed (the responses were solved
    again: supply F again). :attr:`c_v` is dv/dq of the step begun (3.18), :attr:`passes`
    the solves of the step, :attr:`committed` the slack set the step ended with."""

    t: float
    n_steps: int
    q: np.ndarray
    v: np.ndarray
    q_p: np.ndarray
    v_p: np.ndarray
    delta_free: np.ndarray
    W: np.ndarray
    passes: int
    committed: np.ndarray

    @property
    def c_v(self) -> float: ...

    def initialize(self, t0: float, q0, v0=None, F0=None) -> None: ...

    def prepare(self, h: float) -> None: ...

    def begin(self, h: float, loads) -> None: ...

    def finish(self, F) -> bool: ...

    def get_state(self) -> dict: ...

    def set_state(self, state: dict) -> None: ...


#: name -> factory(model, settings, redo) of a :class:`ClosedFormStep`; ``redo``: keep what a
#: step redone from the same state reuses (co-simulation rollback)
CLOSED_FORM_STEPS = Registry("closed-form step", "stepping")


def register_closed_form_step(name: str):
    """Class or function decorator: the factory of the closed-form step ``name``."""
    return CLOSED_FORM_STEPS.register(name)


def declared_stepping(model) -> str:
    """The stepping ``model`` declares (its ``stepping``), checked against the registry; an
    unknown one is refused with what to import."""
    name = type(model).stepping
    if name != NEWTON and name not in CLOSED_FORM_STEPS:
        raise ParameterError(
            "stepping", name, f"{type(model).__name__} declares a stepping no imported module "
            f"registers (known: {', '.join([NEWTON, *CLOSED_FORM_STEPS])}): import the module "
            f"with @register_closed_form_step({name!r}) in the module of "
            f"{type(model).__name__} ({type(model).__module__})")
    return name


def closed_form_step(model, settings, redo: bool = False) -> ClosedFormStep:
    """The closed-form step ``model`` declares (not for :data:`NEWTON`)."""
    return CLOSED_FORM_STEPS[declared_stepping(model)](model, settings, redo)


def warm_up(stepper, h: float, inputs=None) -> None:
    """Take one step of ``h`` and put the state back: what a first step pays once (numba
    loading its compiled kernels, the factorization for h, the first unit-vector solves) is
    paid at set-up, not inside a paced loop. A failing step is left for the run to
    report."""
    state = stepper.get_state()
    try:
        stepper.step(h, inputs)
    except PantocosimError:
        pass
    finally:
        stepper.set_state(state)
