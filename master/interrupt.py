"""Ctrl-C (SIGINT) during a run: stop cleanly between two steps.

Inside :func:`stop_on_interrupt` the first SIGINT only sets a flag; the time loops look at it
after every step and end the run there, so the step in flight (possibly inside an FMU, whose
Python code runs in this interpreter and would turn a KeyboardInterrupt into fmi2Fatal)
completes, the results so far are written and the summary says where the run stopped. A
second SIGINT raises KeyboardInterrupt at once (for a set-up that takes long). Outside it,
Ctrl-C raises KeyboardInterrupt as usual; the command line turns both into exit status 130.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

from pantocosim.core.errors import Interrupted


class StopRequest:
    """Set by the first SIGINT inside :func:`stop_on_interrupt`."""

    def __init__(self):
        self.requested = False

    def check(self, t: float, step: int, n_steps: int) -> None:
        """Raise :class:`Interrupted` naming the time and step if a stop was requested."""
        if self.requested:
            raise interrupted_at(t, step, n_steps)


def interrupted_at(t: float, step: int, n_steps: int) -> Interrupted:
    exc = Interrupted(f"interrupted (Ctrl-C) at t = {t:.6g} s, after step {step} of "
                      f"{n_steps}")
    exc.time, exc.step, exc.n_steps = float(t), int(step), int(n_steps)
    return exc


@contextmanager
def stop_on_interrupt():
    """Yield a :class:`StopRequest` that the first SIGINT sets (main thread only; elsewhere
    nothing changes and the request is never set)."""
    stop = StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def handler(signum, frame):
        if stop.requested:
            raise KeyboardInterrupt
        stop.requested = True

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield stop
    finally:
        signal.signal(signal.SIGINT, previous)
