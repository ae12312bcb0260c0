"""Co-simulation coupling: the :class:`Coupler` of the participants, its schemes
(:data:`SCHEMES`) and the accelerators of the implicit scheme (:data:`ACCELERATORS`), one per
module behind these registries. The master knows only ports: each pantograph k has an input
force F_k and outputs (z_p, v_p); the catenary has inputs F_1..F_n and outputs (z_w, v_w) per
pantograph."""

from .accelerators import ACCELERATORS, DEFAULT_ACCELERATOR
from .coupler import Coupler, CouplingSettings, Subsystem
from .schemes import SCHEME_NAMES, SCHEMES, scheme_named

__all__ = ["ACCELERATORS", "DEFAULT_ACCELERATOR", "Coupler", "CouplingSettings", "SCHEMES",
           "SCHEME_NAMES", "Subsystem", "scheme_named"]
