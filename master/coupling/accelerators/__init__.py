"""Accelerators of the implicit coupling, by name (``--accelerator``): a new one is a module
with an :class:`~.base.Accelerator` subclass and its line here."""

from pantocosim.core.registry import Registry

from .aitken import Aitken
from .base import Accelerator
from .iqn_ils import IQNILS
from .iqn_imvj import IQNIMVJ

#: name -> class; IQN-IMVJ converges in about 2 passes per step where IQN-ILS needs 3
ACCELERATORS = Registry("accelerator", "accelerator")
for _cls in (IQNIMVJ, IQNILS, Aitken):
    ACCELERATORS.add(_cls.name, _cls)
DEFAULT_ACCELERATOR = IQNIMVJ.name

__all__ = ["ACCELERATORS", "DEFAULT_ACCELERATOR", "Accelerator", "Aitken", "IQNILS", "IQNIMVJ"]
