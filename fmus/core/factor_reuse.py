"""When the HHT integrator factorizes its Newton matrix c_a M + c_f (c_v C + K): the
policies of :class:`FactorReuse`, the kept :class:`Factorization` and :class:`FactorPolicy`
(docs/performance.md, "Factorizations").

A kept factorization makes the Newton iteration a chord (modified Newton) method: the same
converged solution to the residual tolerance, in as many or more iterations. Under
``ACROSS_STEPS`` a factorization made at the first iteration of a step is kept for the
following steps while the model's ``structure_key`` and the step size are unchanged; a step
that needed more than ``refresh_after`` iterations marks it stale (the next step factorizes
at its first iteration), and an iteration past ``refresh_after + 4`` factorizes at once.
A step redone from the same state with other inputs (an implicit coupling's next pass)
starts from the same predictor, so the factorization its first pass made at its first
iteration is the one it would make again: it is taken, bit for bit the same step.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Any


class FactorReuse(Enum):
    """When the Newton matrix is factorized (``HHTSettings.reuse_factorization``)."""

    #: full Newton: at every iteration
    NEVER = "never"
    #: at the first iteration of each step, reused within the step (chord method)
    PER_STEP = "per-step"
    #: also reused across steps while the model's structure_key and the step size are
    #: unchanged (modified Newton). With either reuse, a step redone from the same state
    #: (co-simulation rollback) takes the factorization its first pass made at its first
    #: iteration
    ACROSS_STEPS = "across-steps"


@dataclass(frozen=True)
class Factorization:
    """A factorized Newton matrix c_a M + c_f (c_v C + K) kept for reuse."""

    #: the model's ``structure_key`` at the evaluation it was made from
    structure_key: Any
    #: the step size it was made for [s]
    h: float
    #: the Newton matrix (a deserialized state factorizes it again, bit for bit)
    matrix: Any
    #: ``model.factorize(matrix)``; None in a picklable state
    solve: Any


class FactorPolicy:
    """The factorization a step starts from, when an iteration needs a new one, and what a
    finished step keeps, for one integrator under ``settings`` (its ``reuse_factorization``
    and ``refresh_after``, read at each use)."""

    def __init__(self, settings):
        self.settings = settings
        #: kept across steps (``ACROSS_STEPS``)
        self.factor: Factorization | None = None
        #: refactorize at the next step
        self.stale = False
        #: ((start state, h), the factorization made at the first iteration from it)
        self._redo = None
        self._start = None

    def reset(self) -> None:
        self.factor, self.stale = None, False

    def start(self, h: float, state) -> Factorization | None:
        """The factorization the first iteration of a step of size h from the state labelled
        ``state`` may use. A step redone from the same state (a co-simulation's passes over
        one step) meets the same predictor, hence the same first Newton matrix: the one its
        first pass factorized at its first iteration is taken again."""
        reuse = self.settings.reuse_factorization
        self._start = (state, h)
        if reuse is FactorReuse.NEVER:
            return None
        if self._redo is not None and self._redo[0] == self._start:
            return self._redo[1]
        if reuse is FactorReuse.ACROSS_STEPS and not self.stale:
            factor = self.factor
            return factor if factor is not None and factor.h == h else None
        return None

    def needs_tangent(self, k: int, factor: Factorization | None) -> bool:
        """Whether iteration k factorizes (before the structure key is compared)."""
        s = self.settings
        return (factor is None or k > s.refresh_after + 4
                or (s.reuse_factorization is FactorReuse.NEVER and k > 0))

    def made(self, k: int, factor: Factorization) -> None:
        """A factorization was made at iteration k."""
        if k == 0 and self.settings.reuse_factorization is not FactorReuse.NEVER:
            self._redo = (self._start, factor)

    def finish(self, iterations: int, factor: Factorization | None) -> None:
        """After a converged step: keep its factorization, stale if it took long."""
        if self.settings.reuse_factorization is FactorReuse.ACROSS_STEPS:
            self.factor = factor
            self.stale = iterations > self.settings.refresh_after
