"""A linear second-order system M a + C v + K (q - q_ref) = f(t) + B u on the model interface.

Used for the linearised pantograph (thesis 2.1.2) and as the integrator's test oracle.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from .model import Evaluation, SecondOrderModel


class LinearModel(SecondOrderModel):
    def __init__(self, M, C, K, force: Callable[[float], np.ndarray] | None = None,
                 input_matrix=None, q_ref=None):
        self.M = np.atleast_2d(np.asarray(M, dtype=float))
        self.C = np.atleast_2d(np.asarray(C, dtype=float))
        self.K = np.atleast_2d(np.asarray(K, dtype=float))
        self.n_dofs = self.M.shape[0]
        self.force = force
        self.B = None if input_matrix is None else np.atleast_2d(np.asarray(input_matrix, float))
        self.q_ref = np.zeros(self.n_dofs) if q_ref is None else np.asarray(q_ref, float)

    def evaluate(self, t, q, v, a, inputs, tangent=True):
        f_rest = self.C @ v + self.K @ (q - self.q_ref)
        if self.force is not None:
            f_rest = f_rest - np.asarray(self.force(t), dtype=float)
        if self.B is not None and inputs is not None:
            f_rest = f_rest - self.B @ np.asarray(inputs, dtype=float)
        return Evaluation(f_inertia=self.M @ a, f_rest=f_rest, mass=self.M, inertia_q=None,
                          damping=self.C, stiffness=self.K)
