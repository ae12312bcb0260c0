"""Stand-alone pantograph simulation under a prescribed contact force (thesis 2.3)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from pantocosim.core.errors import ParameterError
from pantocosim.core.hht import DEFAULT_ALPHA, HHTIntegrator, HHTSettings
from pantocosim.core.linear_model import LinearModel
from pantocosim.pantograph.base import PantographModel
from pantocosim.master.expression import compile_formula
from pantocosim.master.interrupt import interrupted_at


#: largest prescribed contact force [N]: a hundred times any pantograph's contact force
MAX_FORCE_N = 1e5


def force_expression(expr: str, field: str = "--force") -> Callable[[float], float]:
    """The force law F(t) [N] of a formula in ``t`` such as ``120 + 30*sin(4*pi*t)``
    (:func:`pantocosim.master.expression.compile_formula`, within +/- :data:`MAX_FORCE_N`),
    checked at t = 0."""
    force = compile_formula(expr, field, "t", max_abs=MAX_FORCE_N, unit=" N")
    force(0.0)
    return force


@dataclass
class StandaloneResult:
    time: np.ndarray
    contact_force: np.ndarray
    contact_height: np.ndarray
    contact_velocity: np.ndarray
    q: np.ndarray
    iterations: np.ndarray
    #: an :class:`~pantocosim.core.errors.Interrupted` naming where a stopped run stopped
    stopped: Exception | None = None

    def columns(self, dof_names) -> dict:
        cols = {"time": self.time, "contact_force": self.contact_force,
                "contact_height": self.contact_height, "contact_velocity": self.contact_velocity}
        for i, name in enumerate(dof_names):
            cols["q_" + name.replace(" ", "_")] = self.q[:, i]
        return cols


def simulate_pantograph(model: PantographModel, force: Callable[[float], float],
                        duration: float, dt: float = 1e-3, alpha: float = DEFAULT_ALPHA,
                        q0=None, linear: bool = False, stop=None) -> StandaloneResult:
    """Integrate the pantograph from static equilibrium under F(0) at its working height.

    With ``linear=True`` the linearised model (M, C, K about that equilibrium, thesis 2.1.2)
    is integrated instead, driven by F(t) - F(0). A ``stop`` request
    (:class:`~pantocosim.master.interrupt.StopRequest`) ends the run after the step in flight
    (the result's ``stopped`` says where).
    """
    if not (duration > 0 and dt > 0):
        raise ParameterError("duration", duration, "duration and time step must be > 0")
    F0 = force(0.0)
    if q0 is None:
        q0 = model.static_equilibrium(F0)
    n_steps = int(round(duration / dt))
    grad = np.asarray(model.contact_height_gradient(q0), dtype=float)
    if linear:
        M, C, K = model.linearize(q0, F0)
        system = LinearModel(M, C, K, input_matrix=-grad[:, None], q_ref=q0)
        to_input = lambda t: np.array([force(t) - F0])
    else:
        system = model
        to_input = lambda t: np.array([force(t)])
    integ = HHTIntegrator(system, HHTSettings(alpha=alpha))
    integ.initialize(0.0, q0, np.zeros(model.n_dofs), to_input(0.0))
    n = n_steps + 1
    time = np.arange(n) * dt
    qs = np.empty((n, model.n_dofs))
    heights = np.empty(n)
    vels = np.empty(n)
    forces = np.empty(n)
    iters = np.zeros(n, dtype=int)
    for i in range(n):
        if i > 0:
            iters[i] = integ.step(dt, to_input(time[i])).iterations
        qs[i] = integ.q
        forces[i] = force(time[i])
        if linear:
            heights[i] = model.contact_height(q0) + grad @ (integ.q - q0)
            vels[i] = grad @ integ.v
        else:
            heights[i] = model.contact_height(integ.q)
            vels[i] = model.contact_velocity(integ.q, integ.v)
        if stop is not None and stop.requested and i < n - 1:   # Ctrl-C: keep steps 0..i

            k = i + 1
            return StandaloneResult(time[:k], forces[:k], heights[:k], vels[:k], qs[:k],
                                    iters[:k], stopped=interrupted_at(time[i], i, n_steps))
    return StandaloneResult(time, forces, heights, vels, qs, iters)
