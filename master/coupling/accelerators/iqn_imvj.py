"""Interface quasi-Newton with a multi-vector inverse Jacobian (IQN-IMVJ, Lindner, Mehl &
Uekermann 2015)."""

from __future__ import annotations

import numpy as np

from .iqn_ils import IQNILS


class IQNIMVJ(IQNILS):
    """Interface quasi-Newton with a multi-vector inverse Jacobian (IQN-IMVJ, Lindner, Mehl
    & Uekermann 2015, as in preCICE): the IQN-ILS least-squares update applied on top of the
    inverse Jacobian of the previous time step, which is kept and carried forward,

        J = J_prev + (W - J_prev V) V^+,     x_{k+1} = x~_k - J r_k.

    The interface of a pantograph-catenary co-simulation has one unknown per pantograph, so
    J is stored whole (n x n). Its first update in a step is then already a Newton step with
    the previous step's Jacobian, where IQN-ILS starts from a plain relaxation."""

    name = "iqn-imvj"

    def __init__(self, initial_relaxation: float = 0.5, **_):
        self.J_prev: np.ndarray | None = None
        self.J: np.ndarray | None = None
        super().__init__(initial_relaxation)

    def reset(self):
        if self.J is not None:
            self.J_prev = self.J
        self.J = None
        self._new_step()

    def _jacobian(self, n: int) -> np.ndarray | None:
        """J_prev + (W - J_prev V) V^+ with the step's secants so far (J_prev before the
        first; None while no Jacobian is known)."""
        if not self.V:
            return self.J_prev
        Vm = np.column_stack(self.V)
        Wm = np.column_stack(self.W)
        J0 = np.zeros((n, n)) if self.J_prev is None else self.J_prev
        return J0 + (Wm - J0 @ Vm) @ np.linalg.pinv(Vm, rcond=1e-12)

    def update(self, x: np.ndarray, x_tilde: np.ndarray) -> np.ndarray:
        r = self._residual(x, x_tilde)
        self.J = self._jacobian(r.size)
        if self.J is None:
            return x + self.omega0 * r
        return x_tilde - self.J @ r

    def converged(self, x, x_tilde):
        """The last secant of the step enters the Jacobian carried to the next step."""
        if self.r_prev is not None:
            self._residual(x, x_tilde)
            self.J = self._jacobian(x.size)
