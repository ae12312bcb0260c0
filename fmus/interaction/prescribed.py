"""A pantograph stand-in without degrees of freedom: its contact height and velocity are
prescribed (set from outside before each step).

Used by the catenary FMU's built-in penalty option (``contact_mode`` = 1): the FMU couples its
catenary to one :class:`PrescribedPantograph` per pantograph through
:class:`~pantocosim.interaction.coupled.CoupledSystem` and
:class:`~pantocosim.interaction.penalty_contact.PenaltyContact`, so the penalty force is solved
implicitly with the wire inside the catenary's HHT step, the pantograph's height and
velocity being the values at the end of the step.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..core.model import Evaluation, SecondOrderModel

_EMPTY = np.zeros(0)


class PrescribedPantograph(SecondOrderModel):
    """0-DOF pantograph whose contact point is at ``height`` moving at ``velocity``."""

    n_dofs = 0

    def __init__(self, height: float = 0.0, velocity: float = 0.0):
        self.height = float(height)
        self.velocity = float(velocity)

    def set(self, height: float, velocity: float) -> None:
        self.height = float(height)
        self.velocity = float(velocity)

    # ------------------------------------------------------------------ contact interface
    def contact_height(self, q) -> float:
        return self.height

    def contact_height_gradient(self, q) -> np.ndarray:
        return _EMPTY

    def contact_velocity(self, q, v) -> float:
        return self.velocity

    # ------------------------------------------------------------------ model interface
    def evaluate(self, t, q, v, a, inputs, tangent=True) -> Evaluation:
        ev = Evaluation(f_inertia=np.zeros(0), f_rest=np.zeros(0), structure_key=None)
        if tangent:
            empty = sp.csr_matrix((0, 0))
            ev.mass = ev.damping = ev.stiffness = empty
        return ev

    def effective_matrix(self, ev, c_a, c_v, c_f):
        return np.zeros((0, 0))

    def factorize(self, S):
        return lambda r: np.zeros(0)

    def get_internal_state(self):
        return (self.height, self.velocity)

    def set_internal_state(self, state) -> None:
        if state is not None:
            self.height, self.velocity = float(state[0]), float(state[1])
