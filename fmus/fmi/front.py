"""The FMI version of a slave is its front: the project's slaves (:mod:`slave_base`,
:mod:`pantograph_slave`, :mod:`catenary_slave`) are version-neutral cores, and a front class
(``Fmi2Front`` over pythonfmu, ``Fmi3Front`` over pythonfmu3) gives them the FMI version's
variables, statuses, call names and model description. An FMU's slave class is a core with a
front mixed in (:func:`slave_class`); the fronts are registered here by FMI major version.

A front provides:

- ``fmi_version`` (2, 3) and ``TYPE_NAMES`` (the version's name of the neutral kinds Real,
  Integer, Boolean, String);
- ``make_variable(kind, name, causality, variability, initial, unit, description, getter)``:
  registers a variable and returns it, with ``var.kind`` the neutral kind; causality,
  variability and initial are given by name (``"parameter"``, ``"fixed"``, ``"exact"``, None);
- ``fmi_call(name)``: the version's name of an FMI call given by its FMI 2.0 name without
  prefix (``"DoStep"`` -> ``fmi2DoStep`` / ``fmi3DoStep``, ``"SetReal"`` -> ``fmi3SetFloat64``);
- ``log(message, status)`` taking a :class:`Status`.
"""

from __future__ import annotations

import importlib
from enum import IntEnum

from pantocosim.core.registry import Registry


class Status(IntEnum):
    """FMI status, the same numbers in FMI 2.0 and 3.0."""

    ok = 0
    warning = 1
    discard = 2
    error = 3
    fatal = 4


class VariableMaker:
    """``make_variable`` of a front, from its ``VARIABLE_CLASSES`` (neutral kind -> the
    version's variable class) and ``ENUMS`` (the version's causality, variability and initial
    enums, whose members have the neutral names)."""

    VARIABLE_CLASSES: dict = {}
    ENUMS: tuple = ()

    def make_variable(self, kind: str, name: str, causality: str, variability: str,
                      initial: str | None = None, unit: str | None = None,
                      description: str | None = None, getter=None):
        causalities, variabilities, initials = self.ENUMS
        kwargs = dict(causality=causalities[causality],
                      variability=variabilities[variability], description=description)
        if initial:
            kwargs["initial"] = initials[initial]
        if getter is not None:
            kwargs["getter"] = getter
        if kind == "Real":
            kwargs["unit"] = unit
        var = self.VARIABLE_CLASSES[kind](name, **kwargs)
        var.kind = kind
        self.register_variable(var)
        return var


#: FMI major version -> "module:class" of its front (imported when first asked for: a core
#: does not need pythonfmu3 to run as FMI 2.0)
FRONTS = Registry("FMI front", "FMI version")
FRONTS.add(2, "pantocosim.fmi.fmi2_front:Fmi2Front")
FRONTS.add(3, "pantocosim.fmi.fmi3_front:Fmi3Front")

_CLASSES: dict = {}


def front(version: int) -> type:
    """The front class of FMI ``version``."""
    module, name = FRONTS.entry(version).split(":")
    return getattr(importlib.import_module(module), name)


def slave_class(core: type, version: int) -> type:
    """``core`` (a slave class of this package) with the front of FMI ``version``."""
    key = (core, version)
    if key not in _CLASSES:
        _CLASSES[key] = type(core.__name__, (core, front(version)),
                             {"__module__": core.__module__})
    return _CLASSES[key]
