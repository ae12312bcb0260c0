"""pantocosim: pantograph-catenary dynamic interaction as FMI 2.0 and 3.0 co-simulation
components.

This package (source folder ``fmus/``) holds the physics: pantograph models, the catenary
finite-element model and the shared HHT-alpha integrator. It imports neither pythonfmu nor
fmpy, and it is bundled unchanged into every FMU (all but the multibody core of the double
pendulum, which no FMU uses). The master, monolithic solver and CLI live in
``pantocosim.master`` (source folder ``master/``).
"""

__version__ = "0.1.0"

# numba keeps the package's kernels by module and source content, not by folder: every copy
# of the package (each FMU extraction) loads the kernels compiled once
from .core.kernel_cache import install as _install_kernel_cache  # noqa: E402

_install_kernel_cache()
