"""pantocosim: pantograph-catenary dynamic interaction as FMI 2.0 and 3.0 co-simulation
components.

This package (source folder ``fmus/``) holds the physics: pantograph models, the catenary
finite-element model and the shared HHT-alpha integrator, and the FMU slaves. No module of
it imports fmpy; pythonfmu and pythonfmu3 are imported by the FMI fronts alone
(``pantocosim.fmi.fmi2_front``, ``pantocosim.fmi.fmi3_front``), which a slave class takes on
demand (:func:`pantocosim.fmi.front.front`), so every other module imports without them. It is
bundled unchanged into every FMU (all but the multibody core of the double
pendulum, which no FMU uses). The master, monolithic solver and CLI live in
``pantocosim.master`` (source folder ``master/``).
"""

__version__ = "0.1.0"

# numba keeps the package's kernels by module and source content, not by folder: every copy
# of the package (each FMU extraction) loads the kernels compiled once
from .core.kernel_cache import install as _install_kernel_cache  # noqa: E402

_install_kernel_cache()
