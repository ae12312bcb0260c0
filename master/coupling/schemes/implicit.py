"""Implicit coupling with state rollback: the interface forces are iterated to the fixed
point H(F) = F with an accelerator; a converged step reproduces the monolithic HHT step
(thesis (3.16))."""

from __future__ import annotations

import numpy as np

from pantocosim.core.errors import ConvergenceError

from .base import Scheme


class Implicit(Scheme):
    name = "implicit"
    iterative = True
    restores_states = True

    def step(self, coupler, t, h, states):
        """Iterate on the interface forces, restoring ``states`` (saved at t) between
        passes."""
        s, acc = coupler.s, coupler.acc
        acc.reset()
        F = np.maximum(2.0 * coupler.forces - coupler.forces_prev, 0.0)  # extrapolation
        for it in range(1, s.max_iterations + 1):
            coupler.set_all(F)
            coupler.step_all(t, h)
            H = coupler.contact_forces()
            r = H - F
            if np.max(np.abs(r)) <= s.tolerance:
                acc.converged(F, H)
                return F, it
            coupler.restore(states)
            F = np.maximum(acc.update(F, H), 0.0)
        raise ConvergenceError(
            f"implicit coupling did not converge at t = {t + h:.6g} s: interface residual "
            f"{np.max(np.abs(r)):.3e} N after {s.max_iterations} iterations",
            time=t + h, residual=float(np.max(np.abs(r))))
