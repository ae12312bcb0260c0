"""Dynamic Aitken under-relaxation of the interface forces."""

from __future__ import annotations

import numpy as np

from .base import Accelerator


class Aitken(Accelerator):
    """Dynamic Aitken under-relaxation on the interface forces (Irons-Tuck / Kuttler-Wall)."""

    name = "aitken"

    def __init__(self, initial_relaxation: float = 0.5, **_):
        super().__init__(initial_relaxation)
        self.reset()

    def reset(self):
        self.omega = self.omega0
        self.r_prev = None

    def update(self, x: np.ndarray, x_tilde: np.ndarray) -> np.ndarray:
        r = x_tilde - x
        if self.r_prev is not None:
            dr = r - self.r_prev
            denom = float(dr @ dr)
            if denom > 0.0:
                self.omega = -self.omega * float(self.r_prev @ dr) / denom
        self.r_prev = r
        return x + self.omega * r
