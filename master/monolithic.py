"""The monolithic reference solver: the coupled model lives in :mod:`pantocosim.core.coupled`
(bundled in the FMUs too), the time loop in :func:`pantocosim.master.run.run_monolithic`."""

from pantocosim.core.coupled import CoupledSystem, RigidWire

__all__ = ["CoupledSystem", "RigidWire"]
