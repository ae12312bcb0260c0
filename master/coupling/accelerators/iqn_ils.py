"""Interface quasi-Newton with inverse-Jacobian least squares (IQN-ILS, Degroote et al.
2009)."""

from __future__ import annotations

import numpy as np

from .base import Accelerator


class IQNILS(Accelerator):
    """Interface quasi-Newton with inverse-Jacobian least squares (IQN-ILS)."""

    name = "iqn-ils"

    def __init__(self, initial_relaxation: float = 0.5, reuse_steps: int = 0, **_):
        super().__init__(initial_relaxation)
        self.reuse = reuse_steps
        self.old_V: list[np.ndarray] = []
        self.old_W: list[np.ndarray] = []
        self.reset()

    def reset(self):
        # keep columns of previous time steps when reuse > 0
        if getattr(self, "V", None):
            self.old_V = (self.old_V + self.V)[-self.reuse * 8:] if self.reuse else []
            self.old_W = (self.old_W + self.W)[-self.reuse * 8:] if self.reuse else []
        self._new_step()

    def _new_step(self):
        """Forget the secants of the step (V: residual differences, W: x~ differences)."""
        self.V: list[np.ndarray] = []
        self.W: list[np.ndarray] = []
        self.r_prev = None
        self.xt_prev = None

    def _residual(self, x: np.ndarray, x_tilde: np.ndarray) -> np.ndarray:
        """r = x~ - x; records the secant pair to the previous iterate of the step."""
        r = x_tilde - x
        if self.r_prev is not None:
            self.V.append(r - self.r_prev)
            self.W.append(x_tilde - self.xt_prev)
        self.r_prev, self.xt_prev = r.copy(), x_tilde.copy()
        return r

    def update(self, x: np.ndarray, x_tilde: np.ndarray) -> np.ndarray:
        r = self._residual(x, x_tilde)
        V = self.V + self.old_V
        W = self.W + self.old_W
        if not V:
            return x + self.omega0 * r
        Vm = np.column_stack(V)
        Wm = np.column_stack(W)
        c, *_ = np.linalg.lstsq(Vm, -r, rcond=1e-12)
        return x_tilde + Wm @ c
