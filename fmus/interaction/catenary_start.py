"""The catenary's side of the start handshake of a co-simulation (the catenary FMU calls it;
docs/third-party.md, "The static start handshake"):

- :func:`start_laws`: the start laws it offers the pantographs (operating and static contact
  height against the force, :mod:`.operating_height`) for an analysis window;
- :func:`static_contact_heights`: where a pantograph stands at t0 when it presses with a
  given static force (the static wire height under the force + the penalty compliance);
- :func:`settled_start`: the catenary's static state with the pantographs held at given
  contact heights (penalty contact), and how far a height delivered later may lie from the
  one it settled against.
"""

from __future__ import annotations

import numpy as np

from pantocosim.core.errors import ParameterError
from pantocosim.core.hht import DEFAULT_ALPHA
from pantocosim.interaction.coupled import CoupledSystem
from pantocosim.interaction.prescribed import PrescribedPantograph

from ..catenary.analysis import central_window
from ..catenary.models import law_model
from ..catenary.operating_height import (MAX_LAW_STEPS, ContactHeightLaws, contact_height_laws,
                                         law_run_steps, passage_duration, static_height_law)

#: a pantograph height first delivered after t0 may differ from the height the start was
#: settled against by at most the height of this static contact force [N] (a pantograph that
#: started on this catenary moves micrometres in a step; one that did not is centimetres off)
START_FORCE_TOL_N = 1.0


def start_laws(model, contact_stiffness: float, window: tuple[float, float], dt: float,
               alpha: float = DEFAULT_ALPHA) -> ContactHeightLaws:
    """The start laws of every pantograph of ``model`` over ``window`` (an empty window,
    end <= start: the middle span of the line), from moving-load runs of steps ``dt`` until
    the last pantograph leaves the window (:func:`~.operating_height.passage_duration`); a
    train at rest has no moving-load run (its operating laws are its static laws), and a
    speed whose runs would take more than :data:`~.operating_height.MAX_LAW_STEPS` steps is
    refused naming ``speed_kmh``."""
    if window[1] <= window[0]:
        window = central_window(model.support_x)
    duration = 0.0
    if model.speed > 0:
        duration = passage_duration(window[1], model.x0, model.speed)
        steps = law_run_steps(duration, dt)
        if steps > MAX_LAW_STEPS:
            raise ParameterError("speed_kmh", model.speed * 3.6, f"the start laws' moving-load "
                                 f"run over the analysis window would take {steps:,} steps "
                                 f"of averaging_step = {dt:g} s (at most {MAX_LAW_STEPS:,}): "
                                 f"use a speed of at least "
                                 f"{model.speed * 3.6 * steps / MAX_LAW_STEPS:.3g} km/h, 0 "
                                 "for a standing train, or a longer averaging_step")
    return contact_height_laws(law_model(model), contact_stiffness, window, dt, duration,
                               alpha)


def static_contact_heights(model, contact_stiffness: float, forces) -> np.ndarray:
    """The contact height of each pantograph at t0 pressing with its static force F_k > 0:
    z_w(F) + F / k_H (the static wire height under all the forces)."""
    forces = np.asarray(forces, float)
    zw = model.wire_height(0.0, model.static_state(forces))
    return zw + forces / contact_stiffness


def settled_start(model, contact, forces, heights) -> tuple[np.ndarray, np.ndarray]:
    """(q0, tolerance): the catenary's static start with pantograph k pressing with its static
    force F_k > 0, or, where F_k = 0, held at ``heights[k]`` through the penalty contact
    (settled from the static state under the force its static-height law gives there); the
    tolerance [m] on a height delivered after t0 for the pantographs held at a height (the
    height of :data:`START_FORCE_TOL_N` more force; 0 for the others)."""
    forces = np.asarray(forces, float)
    tolerance = np.zeros(len(forces))
    if np.all(forces > 0):
        return model.static_state(forces), tolerance
    guess = forces.copy()
    compliance = 1.0 / contact.stiffness
    for k in np.flatnonzero(forces == 0):
        offset, slope = static_height_law(model, k)
        guess[k] = max(0.0, (heights[k] - offset) / (slope + compliance))
        tolerance[k] = START_FORCE_TOL_N * (slope + compliance)
    system = CoupledSystem(model, [PrescribedPantograph(z, 0.0) for z in heights], contact)
    return system.static_solve(model.static_state(guess)), tolerance
