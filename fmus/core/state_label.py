"""Labels of integrator states: each step's end state gets a new one, and a saved state keeps
its own, so a step begun again from a restored state (a co-simulation rollback) is known as
the redo of the step last begun from it. The random token keeps a label restored from
another process's saved state unique."""

from __future__ import annotations

import itertools
import secrets

_TOKEN = secrets.randbits(64)
_COUNTER = itertools.count()


def new_label() -> tuple[int, int]:
    """A label no other state of any process has."""
    return _TOKEN, next(_COUNTER)
