"""Size guard of the catenary model: its DOFs, memory and time estimated before it is built,
and a refusal beyond a limit with the estimate and what lifts the limit. Every front end
applies it (the command line's ``--max-dofs``, the catenary FMU's ``max_dofs``).

The estimates are rough figures of this project's nonlinear catenary model measured with
``pantocosim run`` and ``static`` on en50318 lines of 4 to 24 spans (2 shared cores):
peak memory about 0.2 GB + 10 kB per DOF (the banded matrices, the static report) + 0.4 kB
per recorded step; a time step about 1.5 us per DOF; the set-up (static start, operating
height) about 0.7 ms per DOF. The DOFs come from
:func:`pantocosim.catenary.mesh.estimate_dofs` (within 1 % of the built model).
"""

from __future__ import annotations

from pantocosim.core.errors import ParameterError

#: largest catenary model built without --max-dofs (about 2 GB, 0.3 s per step)
MAX_DOFS = 200_000

BASE_MEMORY_B = 0.2e9
MEMORY_PER_DOF_B = 10e3
MEMORY_PER_STEP_B = 400.0
STEP_TIME_PER_DOF_S = 1.5e-6
SETUP_TIME_PER_DOF_S = 0.7e-3


def _bytes(b: float) -> str:
    return f"{b / 1e9:.1f} GB" if b >= 1e9 else f"{b / 1e6:.0f} MB"


def _duration(s: float) -> str:
    if s >= 86400:
        return f"{s / 86400:.1f} days"
    if s >= 3600:
        return f"{s / 3600:.1f} h"
    if s >= 60:
        return f"{s / 60:.0f} min"
    return f"{s:.0f} s"


def describe(dofs: int, n_steps: int | None = None) -> str:
    """``about 1.2 GB of memory, set-up about 2 min, 1000 steps about 4 min``."""
    mem = BASE_MEMORY_B + MEMORY_PER_DOF_B * dofs + MEMORY_PER_STEP_B * (n_steps or 0)
    text = (f"about {_bytes(mem)} of memory, set-up about "
            f"{_duration(SETUP_TIME_PER_DOF_S * dofs)}")
    if n_steps:
        text += f", {n_steps:,} steps about {_duration(STEP_TIME_PER_DOF_S * dofs * n_steps)}"
    return text


def culprit(definition) -> tuple[str, object]:
    """The field of a catenary definition that makes its model large: the number of spans or
    the element size, whichever is further from a preset's (10 spans, 1 m)."""
    spans = definition.n_spans
    key = "spans.count" if "count" in definition.raw.get("spans", {}) else "spans.lengths"
    if spans / 10.0 >= 1.0 / definition.element_size:
        return key, spans
    return "geometry.element_size", definition.element_size


def check_catenary_size(definition, field: str, value, source: str | None,
                        max_dofs: int | None = None, n_steps: int | None = None,
                        lift: str = "--max-dofs") -> int:
    """The estimated DOFs of ``definition``'s model; above ``max_dofs`` (default
    :data:`MAX_DOFS`) a :class:`ParameterError` names ``field`` = ``value`` (the input that
    made it large), the estimate and the setting ``lift`` that lifts the limit."""
    # deferred: `pantocosim --help` shows MAX_DOFS without loading the mesh (measured: 0.16 s)
    from pantocosim.catenary.mesh import estimate_dofs

    limit = MAX_DOFS if max_dofs is None else int(max_dofs)
    dofs = estimate_dofs(definition)
    if dofs > limit:
        raise ParameterError(field, value, f"the catenary model would have about {dofs:,} "
                             f"DOFs ({definition.n_spans} spans, element size "
                             f"{definition.element_size:g} m: {describe(dofs, n_steps)}), "
                             f"above the limit of {limit:,}; use fewer spans or longer "
                             f"elements, or {lift} {dofs} to build it anyway", source)
    return dofs
