"""The start of a pantograph in a co-simulation (:func:`start_state`, what the pantograph
FMU's ``start_mode`` selects), and its static start against the start laws a catenary gives it
(:class:`pantocosim.catenary.operating_height.ContactHeightLaws`), so that a pantograph and a
catenary settle their static start between themselves through ports (the FMU handshake).

The actuation is set to deliver the mean uplift F0 at the operating height
h_op = a + b F0; the pantograph is then solved in equilibrium pressing on the static catenary
and the penalty contact, seen from its contact point as a linear spring whose contact height
under a force F is h = c + d F. This is the monolithic static start (``master.run.prepare``)
with the catenary replaced by its secant laws.
"""

from __future__ import annotations

import numpy as np

from pantocosim.core.errors import ParameterError
from pantocosim.interaction.coupled import CoupledSystem, RigidWire
from pantocosim.interaction.penalty_contact import PenaltyContact

#: residual tolerance of the static start [N]
STATIC_TOL_N = 1e-7
#: the starts of a pantograph: code -> what it is (the pantograph FMU's ``start_mode``)
START_MODES = {0: "static at a height", 1: "ramp raising", 2: "static on the start laws"}


def start_state(pantograph, mode: int, *, height: float | None = None, force: float = -1.0,
                lowered_height: float | None = None, laws: tuple | None = None
                ) -> tuple[np.ndarray, float]:
    """(q0, F0): the start shape and the contact force at t0 of :data:`START_MODES`
    ``mode``; sets the pantograph's actuation. 0: static in contact at ``height`` under
    ``force`` (< 0: the mean uplift); 1: lowered at ``lowered_height``, no contact, the
    actuation set as for 0 (ramp raising, thesis 3.3.1); 2: on the catenary's start ``laws``
    (:func:`static_start_on_laws`)."""
    if mode == 2:
        return static_start_on_laws(pantograph, *laws)
    if force < 0:
        force = pantograph.options.mean_uplift
    q_static = pantograph.static_equilibrium(force, height)
    if mode == 1:
        return pantograph.lowered_equilibrium(lowered_height), 0.0
    return q_static, force


def static_start_on_laws(pantograph, operating_offset: float, operating_slope: float,
                         static_offset: float, static_slope: float
                         ) -> tuple[np.ndarray, float]:
    """(q0, F*): the pantograph's start shape and static contact force; sets its actuation."""
    for name, value in (("operating_height_slope", operating_slope),
                        ("static_height_slope", static_slope)):
        if not np.isfinite(value) or value <= 0.0:
            raise ParameterError(name, value, "must be a positive compliance [m/N] (the "
                                 "catenary's start law)")
    F0 = float(pantograph.options.mean_uplift)
    h_op = operating_offset + operating_slope * F0
    # a first shape at the expected contact height, then the actuation at h_op
    q_guess = pantograph.static_equilibrium(F0, static_offset + static_slope * F0)
    pantograph.static_equilibrium(F0, h_op)
    spring = PenaltyContact(1.0 / static_slope)
    system = CoupledSystem(RigidWire(1, static_offset), [pantograph], spring)
    # the rigid wire carries no weight to scale the residual by: 1e-7 N absolute, far below
    # what moves a start, above the flexible bar model's round-off floor
    q = system.static_solve(np.asarray(q_guess, float), tol=STATIC_TOL_N)
    force = float(system.contact_forces(0.0, q, np.zeros_like(q))[0])
    return q, force
