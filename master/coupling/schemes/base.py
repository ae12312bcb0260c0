"""A coupling scheme: how one communication step sets, steps and iterates the participants
of a :class:`~pantocosim.master.coupling.coupler.Coupler` (one scheme per module, behind
:data:`pantocosim.master.coupling.schemes.SCHEMES`)."""

from __future__ import annotations


class Scheme:
    #: registry name and other names it answers to (``--coupling``)
    name = ""
    aliases: tuple[str, ...] = ()
    #: iterative schemes converge the interface forces: the recorded force is the converged
    #: one, and the run reports coupling iterations and the interface tolerance
    iterative = False
    #: the step restores the participants' states at t between its passes: the coupler
    #: saves them at every step (else it keeps a checkpoint and a journal, :mod:`..rollback`)
    restores_states = False

    def step(self, coupler, t: float, h: float, states) -> tuple:
        """Advance every participant from t to t + h: (interface forces, iterations);
        ``states`` are the participants' states at t (for rollback) if the scheme
        :attr:`restores_states`, else None."""
        raise NotImplementedError
