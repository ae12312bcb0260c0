"""Ctrl-C (SIGINT) during a run: stop cleanly between two steps.

Inside :func:`stop_on_interrupt` the first SIGINT only sets a flag; the time loops look at it
after every step and end the run there, so the step in flight (possibly inside an FMU, whose
Python code runs in this interpreter and would turn a KeyboardInterrupt into fmi2Fatal)
completes, the results so far are written and the summary says where the run stopped. A
second SIGINT raises KeyboardInterrupt at once (for a set-up that takes long). Outside it,
Ctrl-C raises KeyboardInterrupt as usual; the command line turns both into exit status 130.

Python drops an exception raised inside a finaliser (``__del__``), and numba's compiler runs
finalisers often (llvmlite objects), so a Ctrl-C during a set-up can be lost. The command line
therefore installs :func:`remember_interrupts`: a Ctrl-C still raises at once, and is also
remembered, so that the next :func:`stop_on_interrupt` starts with its stop requested.
"""

from __future__ import annotations

import signal
import subprocess
import sys
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


_unseen = False


def _raise_and_remember(signum, frame):
    global _unseen
    _unseen = True
    raise KeyboardInterrupt


@contextmanager
def remember_interrupts():
    """Within it, Ctrl-C raises KeyboardInterrupt and is remembered for the next
    :func:`stop_on_interrupt` (main thread only)."""
    global _unseen
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _unseen = False
    previous = signal.signal(signal.SIGINT, _raise_and_remember)
    previous_hook = sys.unraisablehook

    def quiet_swallowed(unraisable):
        """A Ctrl-C raised where Python cannot propagate it (a garbage-collector callback) is
        remembered (:func:`raise_if_swallowed`), not printed."""
        if not isinstance(unraisable.exc_value, KeyboardInterrupt):
            previous_hook(unraisable)

    sys.unraisablehook = quiet_swallowed
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        sys.unraisablehook = previous_hook
        _unseen = False


def raise_if_swallowed() -> None:
    """Raise KeyboardInterrupt for a Ctrl-C that :func:`remember_interrupts` raised and that
    was swallowed on the way (e.g. raised inside a garbage-collector callback of Dask's): a
    loop that waits for work calls it between two results."""
    if _take_unseen():
        raise KeyboardInterrupt


def _take_unseen() -> bool:
    """True once if a Ctrl-C raised by :func:`remember_interrupts` may have been lost."""
    global _unseen
    seen, _unseen = _unseen, False
    return seen


@contextmanager
def stop_on_interrupt():
    """Yield a :class:`StopRequest` that the first SIGINT sets (main thread only; elsewhere
    nothing changes and the request is never set). It starts set if a Ctrl-C that
    :func:`remember_interrupts` raised was swallowed on the way."""
    stop = StopRequest()
    stop.requested = _take_unseen()
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


@contextmanager
def children_deaf_to_ctrl_c():
    """Within it, SIGINT is ignored, so the processes started meanwhile (e.g. Dask's worker
    processes, started by its threads) inherit an ignored SIGINT, which Python keeps: they
    never see the Ctrl-C a terminal sends to its whole process group, print no
    KeyboardInterrupt traceback of their own, and their parent stops them. A Ctrl-C pressed
    meanwhile is not lost: a watcher process started before (same process group, SIGINT at
    its default action) dies of it, and KeyboardInterrupt is raised on leaving (main thread
    only, on POSIX; elsewhere nothing changes)."""
    if (threading.current_thread() is not threading.main_thread()
            or not hasattr(signal, "pause")):
        yield
        return

    watcher = subprocess.Popen(
        [sys.executable, "-c", "import signal; signal.signal(signal.SIGINT, signal.SIG_DFL); "
         "signal.pause()"], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        pressed = watcher.poll() is not None
        if not pressed:
            watcher.kill()
        watcher.wait()
    if pressed:
        raise KeyboardInterrupt
