"""The interface update of the implicit coupling (one accelerator per module, behind
:data:`pantocosim.master.coupling.accelerators.ACCELERATORS`)."""

from __future__ import annotations

import numpy as np


class Accelerator:
    """``update(x, H(x))`` gives the next interface forces; ``converged(x, H(x))`` is told
    the converged pair of a step; ``reset()`` starts a step."""

    #: registry name (``--accelerator``)
    name = ""

    def __init__(self, initial_relaxation: float = 0.5, **_):
        self.omega0 = initial_relaxation

    def reset(self) -> None:
        """Start a time step."""

    def update(self, x: np.ndarray, x_tilde: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def converged(self, x: np.ndarray, x_tilde: np.ndarray) -> None:
        """Nothing to keep by default."""
