"""Which variables a master set: a start may rely only on what it was given."""

from __future__ import annotations


def track_sets(slave, names, attribute: str = "_given") -> None:
    """Add the name of each variable among ``names`` to the set ``slave.<attribute>`` when a
    master sets it (fmi2SetReal and the like; restoring an FMU state also sets it, then puts
    back the set of its time)."""
    for var in slave.vars.values():
        if var.name in names and var.setter is not None:
            var.setter = (lambda v, name=var.name, setter=var.setter:
                          (getattr(slave, attribute).add(name), setter(v)))
