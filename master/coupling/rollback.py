"""Rollback of a discarded communication step by checkpoint and replay.

A scheme that does not restore states itself (the explicit ones) needs the participants'
states at t only when a participant discards the step t -> t + h, which is rare. Saving every
participant's state every step (fmi2GetFMUstate + fmi2FreeFMUstate: about a tenth of an
explicit step of the linear catenary) is then replaced by a checkpoint every ``period`` steps
and a journal of what the participants were given since (their input forces and their
doStep calls, in order). To bring the participants back to t, the checkpoint is restored and
the journal replayed: each participant gets the same inputs and steps as before, so it
reaches the same state at t (bit for bit for a deterministic participant; within its own
solver tolerance for one whose solver keeps data outside its FMU state, e.g. a reused
Newton matrix).

A scheme that restores states between its passes (the implicit one) gets ``period`` 1: the
states at t are saved at every step and nothing is journaled.
"""

from __future__ import annotations

import numpy as np


class JournaledParticipant:
    """A participant (:class:`~.coupler.Subsystem`) whose ``set_forces`` and ``step`` calls
    are written to ``journal`` when it is on; everything else is the participant's."""

    def __init__(self, inner, journal: "Journal"):
        self.inner = inner
        self.journal = journal

    def set_forces(self, forces) -> None:
        if self.journal.on:
            self.journal.calls.append((self.inner.set_forces, (np.array(forces, float),)))
        self.inner.set_forces(forces)

    def step(self, t: float, h: float) -> None:
        if self.journal.on:
            self.journal.calls.append((self.inner.step, (t, h)))
        self.inner.step(t, h)

    def outputs(self):
        return self.inner.outputs()

    def newton_iterations(self) -> float:
        return self.inner.newton_iterations()

    def get_state(self):
        return self.inner.get_state()

    def set_state(self, state) -> None:
        self.inner.set_state(state)

    def free_state(self, state) -> None:
        self.inner.free_state(state)

    def __getattr__(self, name):
        return getattr(self.inner, name)


class Journal:
    """The calls made to the participants since the last checkpoint, in order."""

    def __init__(self, on: bool):
        self.on = on
        self.calls: list = []

    def replay(self, upto: int) -> None:
        """Make the first ``upto`` calls again."""
        for method, args in self.calls[:upto]:
            method(*args)


class Rollback:
    """The participants' states at the last checkpoint and the journal since; ``states_at_t``
    is the checkpoint when it was taken at the start of the current step (always with period
    1)."""

    def __init__(self, save, restore, free, period: int):
        self._save, self._restore, self._free = save, restore, free
        self.period = period
        self.journal = Journal(on=period > 1)
        self.states = None
        self._age = 0          # steps taken since the checkpoint
        self._mark = 0         # journal length at the start of the current step

    @property
    def states_at_t(self):
        return self.states if self._age == 0 else None

    def begin_step(self) -> None:
        """A checkpoint at the step's start if one is due; marks the journal."""
        if self.states is None or self._age >= self.period:
            self.checkpoint()
        self._mark = len(self.journal.calls)

    def end_step(self) -> None:
        self._age += 1

    def checkpoint(self) -> None:
        """Save the participants' states here and start a new journal."""
        states = self._save()
        self.release()
        self.states = states

    def back_to_step_start(self) -> None:
        """Put the participants back at the start of the current step (restore the
        checkpoint, replay the journal up to the step) and take a checkpoint there."""
        self._restore(self.states)
        self.journal.replay(self._mark)
        if self._mark:
            self.checkpoint()
        else:
            self.journal.calls.clear()
            self._age = 0

    def release(self) -> None:
        """Free the checkpoint's states and forget the journal."""
        if self.states is not None:
            self._free(self.states)
        self.states = None
        self.journal.calls.clear()
        self._age = self._mark = 0
