"""Coupling schemes, by name (``--coupling``): a new one is a module with a
:class:`~.base.Scheme` subclass and its line here."""

from pantocosim.core.errors import ParameterError
from pantocosim.core.registry import Registry

from .base import Scheme
from .gauss_seidel import GaussSeidel
from .implicit import Implicit
from .jacobi import Jacobi

#: name -> class
SCHEMES = Registry("coupling scheme", "coupling")
for _cls in (Jacobi, GaussSeidel, Implicit):
    SCHEMES.add(_cls.name, _cls)
#: every name a scheme answers to (its aliases too) -> its registry name
SCHEME_NAMES = {alias: cls.name for cls in SCHEMES.values() for alias in (cls.name, *cls.aliases)}


def scheme_named(name: str) -> Scheme:
    """The scheme called ``name`` (or one of its aliases)."""
    if name not in SCHEME_NAMES:
        raise ParameterError("coupling", name, "must be one of " + ", ".join(SCHEME_NAMES))
    return SCHEMES[SCHEME_NAMES[name]]()


__all__ = ["SCHEMES", "SCHEME_NAMES", "Scheme", "scheme_named"]
