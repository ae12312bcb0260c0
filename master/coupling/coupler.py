"""The coupler of a co-simulation: the participants (one catenary, n pantographs), their
states for rollback, the discard-and-halve step, the contact law on the interface. How a step
couples them is its scheme (:mod:`.schemes`: explicit Jacobi or Gauss-Seidel, implicit with
rollback), and the implicit update its accelerator (:mod:`.accelerators`: Aitken, IQN-ILS,
IQN-IMVJ), as in preCICE and Kratos CoSimulation.

The master knows only ports. Each pantograph k has an input force F_k and outputs
(z_p, v_p); the catenary has inputs F_1..F_n and outputs (z_w, v_w) per pantograph. The
interface unknowns are the contact forces; the fixed-point map is

    H(F) = law(z_p(t+h; F), z_w(t+h; F), v_p, v_w),   residual r = H(F) - F,

and a converged implicit step reproduces the monolithic HHT step (thesis (3.16)).
Runs stop the iteration at ``coupling_rtol`` (scenario) times the mean contact force.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from pantocosim.core.errors import ConvergenceError, ParameterError, PantocosimError

from .accelerators import ACCELERATORS, DEFAULT_ACCELERATOR
from .rollback import JournaledParticipant, Rollback
from .schemes import SCHEME_NAMES, scheme_named


@dataclass
class CouplingSettings:
    scheme: str = "jacobi"            # a name of schemes.SCHEMES (or an alias)
    accelerator: str = DEFAULT_ACCELERATOR   # a name of accelerators.ACCELERATORS
    tolerance: float = 1e-7           # N, max |H(F) - F| at convergence (implicit)
    max_iterations: int = 50
    initial_relaxation: float = 0.5
    #: IQN-ILS: time steps whose secant information is reused (0: none; measured on
    #: en50318-300, reuse costs iterations: 4.0 per step with 1-4 steps against 3.0 without)
    reuse_steps: int = 0
    min_step: float = 1e-6            # s, floor of the step halving after a discard
    #: schemes that do not restore states themselves: steps between checkpoints of the
    #: participants' states (a discarded step is rolled back by replay, :mod:`.rollback`)
    checkpoint_steps: int = 32
    extrapolate: bool = True          # explicit schemes: linear extrapolation of the forces

    def validate(self):
        if self.scheme not in SCHEME_NAMES:
            raise ParameterError("coupling", self.scheme,
                                 "must be one of " + ", ".join(SCHEME_NAMES))
        if self.accelerator not in ACCELERATORS:
            raise ParameterError("accelerator", self.accelerator,
                                 f"must be one of {sorted(ACCELERATORS)}")
        if not self.tolerance > 0:
            raise ParameterError("tolerance", self.tolerance, "must be > 0")
        if not (isinstance(self.checkpoint_steps, int) and self.checkpoint_steps >= 1):
            raise ParameterError("checkpoint_steps", self.checkpoint_steps,
                                 "must be an integer >= 1")


class Subsystem:
    """What the coupling needs of one participant (an FMU, or a model in-process)."""

    def set_forces(self, forces: np.ndarray) -> None: ...
    def step(self, t: float, h: float) -> None: ...
    def outputs(self) -> tuple[np.ndarray, np.ndarray]: ...   # heights, velocities
    def get_state(self): ...
    def set_state(self, state) -> None: ...
    def free_state(self, state) -> None: ...
    def newton_iterations(self) -> float: ...   # catenary: Newton iterations of its last step


class Coupler:
    """Advances one catenary and n pantographs over communication steps."""

    def __init__(self, catenary: Subsystem, pantographs: list[Subsystem], law,
                 settings: CouplingSettings):
        settings.validate()
        self.law = law
        self.s = settings
        self.scheme = scheme_named(settings.scheme)
        period = 1 if self.scheme.restores_states else settings.checkpoint_steps
        self.rollback = Rollback(self._save, self.restore, self._free, period)
        self.cat = JournaledParticipant(catenary, self.rollback.journal)
        self.pans = [JournaledParticipant(p, self.rollback.journal) for p in pantographs]
        self.acc = ACCELERATORS[settings.accelerator](
            initial_relaxation=settings.initial_relaxation, reuse_steps=settings.reuse_steps)
        self.forces = np.zeros(len(pantographs))
        self.forces_prev = np.zeros(len(pantographs))
        self._law_prev = None
        self._law_now = None
        self.iterations: list[int] = []
        #: Newton iterations of the catenary per step (summed over coupling iterations)
        self.catenary_newton_iterations: list[float] = []
        self._newton = 0.0
        #: communication steps halved after a discard
        self.halvings = 0

    def interface(self):
        """(z_p, v_p, z_w, v_w): each a list of one float per pantograph."""
        zw, vw = self.cat.outputs()
        zp, vp = [], []
        for p in self.pans:
            h, v = p.outputs()
            zp.append(float(h[0]))
            vp.append(float(v[0]))
        return zp, vp, np.asarray(zw, float).tolist(), np.asarray(vw, float).tolist()

    def contact_forces(self, predict_h: float = 0.0) -> np.ndarray:
        """The contact law at the participants' outputs, the pantographs' heights taken
        ``predict_h`` ahead with their velocities."""
        zp, vp, zw, vw = self.interface()
        force = self.law.force
        return np.array([force(zp[k] + predict_h * vp[k], zw[k], vp[k], vw[k])
                         for k in range(len(zp))])

    def predicted_forces(self, t: float, h: float) -> np.ndarray:
        """Explicit prediction of the contact forces at t + h: linear extrapolation of the
        law's values at the last two communication points (first-order hold), or F(t) with
        ``extrapolate`` off. The value at t is remembered once the step succeeds."""
        F = self.contact_forces()
        self._law_now = (t, F)
        if self.s.extrapolate and self._law_prev is not None and self._law_prev[0] < t:
            t0, F0 = self._law_prev
            return np.maximum(F + (F - F0) * (h / (t - t0)), 0.0)
        return F

    def initialise(self, forces: np.ndarray) -> None:
        self.forces = np.array(forces, dtype=float)
        self.forces_prev = self.forces.copy()

    def set_all(self, forces):
        self.cat.set_forces(forces)
        for k, p in enumerate(self.pans):
            p.set_forces(forces[k:k + 1])

    def step_catenary(self, t, h):
        self.cat.step(t, h)
        self._newton += self.cat.newton_iterations()

    def step_all(self, t, h):
        self.step_catenary(t, h)
        for p in self.pans:
            p.step(t, h)

    def _save(self):
        return [self.cat.get_state()] + [p.get_state() for p in self.pans]

    def restore(self, states):
        self.cat.set_state(states[0])
        for p, s in zip(self.pans, states[1:]):
            p.set_state(s)

    def _free(self, states):
        self.cat.free_state(states[0])
        for p, s in zip(self.pans, states[1:]):
            p.free_state(s)

    #: what the coupler holds but does not own (left alone by :meth:`warm_up`)
    _SHARED = ("cat", "pans", "law", "s", "scheme", "rollback")

    def warm_up(self, t: float, h: float) -> None:
        """Take one step of h and put everything back (the participants' states and the
        coupler's own): what a first step pays once (numba loading its kernels inside the
        FMUs, the catenary's factorization for h) is paid at set-up, not inside the paced
        loop. A failing step is left for the run to report."""
        own = copy.deepcopy({k: v for k, v in vars(self).items() if k not in self._SHARED})
        self.rollback.release()
        states = self._save()
        failed = None
        try:
            self.step(t, h)
        except PantocosimError as exc:
            failed = exc
        try:
            self.restore(states)
        except PantocosimError:
            if failed is None:
                raise
            raise failed from None
        finally:
            self._free(states)
            self.rollback.release()
        vars(self).update(own)

    def step(self, t: float, h: float) -> int:
        """One communication step t -> t + h; returns the number of coupling iterations.

        When a participant discards the step (fmi2Discard, or a model's Newton failure), every
        participant is rolled back to t (:mod:`.rollback`) and the step is retried as two
        halves, recursively, down to ``settings.min_step``; below it the run stops with the
        participant's message.
        """
        rollback = self.rollback
        rollback.begin_step()
        try:
            iters = self._step_once(t, h, rollback.states_at_t)
        except (ConvergenceError, _Discard) as exc:
            rollback.back_to_step_start()
            if h / 2.0 < self.s.min_step:
                raise ConvergenceError(
                    f"step at t = {t:.6g} s discarded down to h = {h:.3g} s (floor "
                    f"{self.s.min_step:g} s): {exc}", time=t) from None
            self.halvings += 1
            return self.step(t, h / 2.0) + self.step(t + h / 2.0, h / 2.0)
        rollback.end_step()
        if self._law_now is not None:
            self._law_prev, self._law_now = self._law_now, None
        return iters

    def _step_once(self, t: float, h: float, states) -> int:
        try:
            return self._step_scheme(t, h, states)
        except Exception as exc:
            if getattr(exc, "status", None) == 2:  # fmi2Discard: retry with a smaller step
                raise _Discard(str(exc)) from None
            raise

    def _step_scheme(self, t: float, h: float, states) -> int:
        F, iters = self.scheme.step(self, t, h, states)
        self.forces_prev, self.forces = self.forces, F
        self.iterations.append(iters)
        self.catenary_newton_iterations.append(self._newton)
        self._newton = 0.0
        return iters


class _Discard(Exception):
    """A participant discarded the step (fmi2Discard)."""
