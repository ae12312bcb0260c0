"""Size guard of the command line: before a model is built or a run starts, estimate its
DOFs, memory and time, and refuse beyond a limit with the estimate and the option that lifts
the limit (``--max-dofs``, ``--max-steps``). The catenary's estimate and DOF limit are
:mod:`pantocosim.catenary.size_guard`'s (the FMUs apply them too); the step limit is here.
"""

from __future__ import annotations

import dataclasses

from pantocosim.catenary.size_guard import (MAX_DOFS, check_catenary_size,  # noqa: F401
                                            culprit, describe)
from pantocosim.core.errors import ParameterError

#: most time steps of a run without --max-steps (the recorded series: about 0.4 GB)
MAX_STEPS = 1_000_000

def check_steps(n_steps: int, field: str, value, source: str | None = None,
                max_steps: int | None = None, dofs: int = 0) -> None:
    """Refuse a run of more than ``max_steps`` (default :data:`MAX_STEPS`) time steps, naming
    ``field`` = ``value`` (the duration or the time step), the estimate and --max-steps."""
    limit = MAX_STEPS if max_steps is None else int(max_steps)
    if n_steps > limit:
        cost = f": {describe(dofs, n_steps)}" if dofs else ""
        raise ParameterError(field, value, f"the run would take {n_steps:,} time steps"
                             f"{cost}, above the limit of {limit:,}; use a longer time step or "
                             f"a shorter run, or --max-steps {n_steps} to run it anyway",
                             source)


def check_limit_option(name: str, value) -> None:
    """``--max-dofs`` / ``--max-steps`` must be positive integers."""
    if value is not None and (isinstance(value, bool) or not isinstance(value, int)
                              or value < 1):
        raise ParameterError(name, value, "must be a positive integer")


def check_cli_catenary(catenary: str, element_size: float | None,
                       max_dofs: int | None) -> int:
    """Size guard of a command that builds ``catenary`` (``static``, ``modes``), with its
    ``--element-size`` and ``--max-dofs``."""
    # deferred: `pantocosim --help` imports this module for its limits; the definition
    # loader costs it 0.09 s (measured)
    from pantocosim.catenary.definition import load_catenary

    check_limit_option("--max-dofs", max_dofs)
    definition = load_catenary(catenary)
    if element_size is not None:
        definition = dataclasses.replace(definition, element_size=element_size)
        return check_catenary_size(definition, "--element-size", element_size, None,
                                   max_dofs)
    (field, value), source = culprit(definition), definition.source
    return check_catenary_size(definition, field, value, source, max_dofs)
