"""The set-up every coupling of a run shares: ``prepare(scenario)`` checks the scenario
against its catenary (:mod:`.checks`), builds the catenary and pantograph models, sets
each pantograph's actuation (:class:`Actuation`) and solves the static start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pantocosim.catenary.definition import with_spans
from pantocosim.catenary.models import law_model, make_catenary
from pantocosim.catenary.operating_height import mean_dynamic_wire_height
from pantocosim.core.errors import ConvergenceError, ParameterError
from pantocosim.interaction.contact_laws import CONTACT_LAWS, ContactLaw, make_contact
from pantocosim.interaction.coupled import CoupledSystem
from pantocosim.interaction.penalty_contact import DEFAULT_CONTACT_STIFFNESS
from pantocosim.master.run.checks import (analysis_window, check_passages, check_size, check_speed,
                                          lowered_above_wire)
from pantocosim.master.scenario import Scenario, load_scenario, scenario_catenary
from pantocosim.master.size_limits import check_steps
from pantocosim.pantograph.base import Ramp
from pantocosim.pantograph.presets import load_pantograph


@dataclass(frozen=True)
class Actuation:
    """Where each pantograph's actuation is set: it delivers its mean uplift ``force`` [N]
    at its operating ``height`` [m], the mean height of the contact wire under the moving
    mean force over the analysis window (``mean_wire_height``,
    :func:`~pantocosim.catenary.operating_height.mean_dynamic_wire_height`) plus the
    contact law's compliance (F / k_H for the penalty contact, 0 for the constraint)."""

    force: np.ndarray
    mean_wire_height: np.ndarray
    height: np.ndarray

    @classmethod
    def of(cls, sc: Scenario, catenary, pantographs, contact, window, duration) -> "Actuation":
        F = np.array([pan.options.mean_uplift for pan in pantographs])
        z = mean_dynamic_wire_height(law_model(catenary), F, window, sc.dt, duration, sc.alpha)
        return cls(force=F, mean_wire_height=z, height=z + F * contact.compliance)

    def apply(self, pantographs) -> None:
        """Set every pantograph's actuation (its ``static_equilibrium`` at the operating
        height)."""
        for pan, F, z in zip(pantographs, self.force, self.height):
            pan.static_equilibrium(F, z)


@dataclass
class Prepared:
    """A checked scenario with its models in the static start."""

    scenario: Scenario
    definition: object
    catenary: object            # a model of pantocosim.catenary.models (CatenaryModel...)
    pantographs: list           # PantographModel per pantograph
    contact: ContactLaw         # the scenario's contact law (pantocosim.interaction.contact_laws)
    window_m: tuple[float, float]
    duration: float
    n_steps: int
    q_cat0: np.ndarray
    q_pan0: list
    static_forces: np.ndarray
    wave_speed: float
    support_x: np.ndarray
    dropper_x: np.ndarray
    actuation: Actuation
    contact_law_state: object   # the contact law's state at the static start

    @property
    def speed(self) -> float:
        return self.scenario.speed


def scenario_pantograph(sc: Scenario, k: int):
    """The model of the scenario's pantograph ``k`` (its options, speed and ramp); errors
    name the scenario's field."""
    p = sc.pantographs[k]
    overrides = dict(p.options)
    overrides["speed_kmh"] = sc.speed_kmh
    if p.ramp is not None:
        overrides["ramp"] = Ramp(start=(p.ramp.start_m - p.position_m) / sc.speed,
                                 duration=p.ramp.length_m / sc.speed,
                                 lowered_height=p.ramp.lowered_height)
    try:
        return load_pantograph(p.model, **overrides)
    except ParameterError as exc:
        option = exc.field.removeprefix("options.")
        if option in p.options:
            raise ParameterError(f"pantographs[{k}].options.{option}", exc.value, exc.reason,
                                 sc.source) from None
        raise ParameterError(f"pantographs[{k}].model", p.model, str(exc), sc.source) from None


def scenario_catenary_model(sc: Scenario, definition, element_size: float | None = None):
    """The scenario's catenary model; a bad modal cutoff named as the scenario's field."""
    try:
        return make_catenary(sc.catenary_model, definition,
                             x0=[p.position_m for p in sc.pantographs], speed=sc.speed,
                             element_size=element_size, modal_cutoff_hz=sc.modal_cutoff_hz)
    except ParameterError as exc:
        if exc.field != "modal_cutoff_hz":
            raise
        raise ParameterError("simulation.modal_cutoff_hz", exc.value, exc.reason,
                             sc.source) from None


def prepare(scenario: Scenario | str | None, force: bool = False,
            element_size: float | None = None, max_dofs: int | None = None,
            max_steps: int | None = None) -> Prepared:
    """Validate ``scenario`` and build the models and the static start; the size guard
    (:mod:`~pantocosim.master.size_limits`, limits ``max_dofs`` and ``max_steps``) runs before
    anything is built."""
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    base = scenario_catenary(sc)
    definition = with_spans(base, sc.spans) if sc.spans else base
    wave = definition.contact.wave_speed
    check_speed(sc, wave, force)
    window, wfield, duration = analysis_window(sc, definition)
    check_passages(sc, definition, window, wfield, duration)
    n_steps = int(math.ceil(duration / sc.dt - 1e-9))
    dofs = check_size(sc, base, definition, element_size, max_dofs, n_steps)
    check_steps(n_steps, "simulation.dt", sc.dt, sc.source, max_steps, dofs)
    contact = make_contact(sc.contact_law, sc.contact_stiffness, sc.contact_damping)
    pantographs = [scenario_pantograph(sc, k) for k in range(len(sc.pantographs))]
    catenary = scenario_catenary_model(sc, definition, element_size)
    actuation = Actuation.of(sc, catenary, pantographs, contact, window, duration)
    actuation.apply(pantographs)
    system = CoupledSystem(catenary, pantographs, contact)
    q0 = static_start(sc, system, start_guess(sc, catenary, pantographs, contact, actuation))
    q_cat0, q_pan0 = system.split(q0)
    static = system.contact_forces(0.0, q0, np.zeros_like(q0))
    for k, spec in enumerate(sc.pantographs):
        if spec.start == "ramp" and static[k] > 0.0:
            raise lowered_above_wire(sc, k, float(catenary.wire_height(0.0, q_cat0)[k]))
    support_x = np.asarray(definition.support_x, float)
    dropper_x = np.concatenate([support_x[s] + np.asarray(pos)
                                for s, pos in enumerate(definition.dropper_positions)])
    return Prepared(scenario=sc, definition=definition, catenary=catenary,
                    pantographs=pantographs, contact=contact, window_m=window,
                    duration=float(duration), n_steps=n_steps, q_cat0=q_cat0,
                    q_pan0=[x.copy() for x in q_pan0], static_forces=static, wave_speed=wave,
                    support_x=support_x, dropper_x=dropper_x, actuation=actuation,
                    contact_law_state=system.law.get_state())


def start_guess(sc: Scenario, catenary, pantographs, contact, actuation: Actuation):
    """The static start's first guess: the catenary under the mean uplifts of the pantographs
    that start in contact (``static``), each such pantograph in equilibrium under its mean
    uplift at that wire height, the others lowered (``ramp``). The actuations stay as
    :meth:`Actuation.apply` set them, so a pantograph that starts where the wire is higher
    or lower than its operating height starts with the matching force."""
    F0 = actuation.force
    q_cat = catenary.static_state(np.where(
        [spec.start == "static" for spec in sc.pantographs], F0, 0.0))
    z_wire = catenary.wire_height(0.0, q_cat)
    q_pans = [pan.equilibrium(F0[k], z_wire[k] + F0[k] * contact.compliance)[0]
              if spec.start == "static" else pan.lowered_equilibrium(spec.ramp.lowered_height)
              for k, (pan, spec) in enumerate(zip(pantographs, sc.pantographs))]
    return np.concatenate([q_cat] + q_pans)


def static_start(sc: Scenario, system, q_guess) -> np.ndarray:
    """The start state of the scenario (:meth:`CoupledSystem.static_solve`); a failure names
    the scenario, the start (static start in contact, or the ramp start's lowered
    pantographs) and the setting that makes it hard."""
    try:
        return system.static_solve(q_guess)
    except ConvergenceError as exc:
        starts = [f"pantograph {k + 1}: " + ("static start, in contact" if p.start == "static"
                                             else "ramp start, lowered")
                  for k, p in enumerate(sc.pantographs)]
        in_contact = any(p.start == "static" for p in sc.pantographs)
        what = (f"the start state ({'; '.join(starts)}) did not converge: residual "
                f"{exc.residual:.3g} N against the tolerance {exc.tolerance:.3g} N")
        takes_stiffness = "stiffness" in CONTACT_LAWS[sc.contact_law].fields
        if in_contact and takes_stiffness and sc.contact_damping > 0.0 and \
                _starts_undamped(sc, system, q_guess):
            raise ConvergenceError(
                f"{sc.source}: contact.damping = {sc.contact_damping:g}: {what}; the damping "
                "acts in the start state on the wire's slope at the train's speed "
                "(c_H V dz_w/dx), and without it the start converges: a smaller contact "
                "damping (default 0) starts", residual=exc.residual) from None
        if in_contact and takes_stiffness:
            raise ConvergenceError(
                f"{sc.source}: contact.stiffness = {sc.contact_stiffness:g}: {what}; a softer "
                f"contact (default {DEFAULT_CONTACT_STIFFNESS:g} N/m) starts",
                residual=exc.residual) from None
        if in_contact:
            raise ConvergenceError(f'{sc.source}: contact.law = "{sc.contact_law}": {what}',
                                   residual=exc.residual) from None
        raise ConvergenceError(f"{sc.source}: catenary = {sc.catenary!r}: {what} (the "
                               "catenary under its weight with the pantographs lowered)",
                               residual=exc.residual) from None


def _starts_undamped(sc: Scenario, system, q_guess) -> bool:
    """Whether the start state converges with the scenario's contact law without damping."""
    undamped = make_contact(sc.contact_law, sc.contact_stiffness, 0.0)
    try:
        CoupledSystem(system.catenary, system.pantographs, undamped).static_solve(q_guess)
    except ConvergenceError:
        return False
    return True
