"""Co-simulation adapter for every pantograph model (one port contract; FMI 2.0 and 3.0
through the fronts of :mod:`pantocosim.fmi.front`).

Ports (identical for all variants; declared with the parameters in
:mod:`pantocosim.fmi.pantograph_ports`, which the FMU reference page lists):
  input  ``contact_force`` [N] >= 0: pushes the collector down;
  output ``contact_height`` [m] above the rail, ``contact_velocity`` [m/s];
  optional inputs (read in initialisation mode) the catenary's start laws
  (``operating_height``, ...; start_mode 2) and ``train_speed_kmh`` (where ``speed_kmh`` was
  not set). A start on the laws that lacks them or the speed is refused at
  fmi2ExitInitializationMode, naming what the master did not give. The start itself is the
  model's (:func:`pantocosim.interaction.pantograph_start.start_state`).

Timing of the force input: the value set before ``doStep(t, h)`` is the contact force at
``t + h``; the force at ``t`` is the one of the previous accepted step, kept in the FMU state
(at t0 it is the static force for a static start, 0 for a ramp start). Both enter the HHT-alpha
step with the integrator's weights (1 + alpha) F(t+h) - alpha F(t), exactly as in the
monolithic solver, so an iterating master reproduces the monolithic solution. With
``n_substeps`` > 1 the force is interpolated linearly inside the communication step.

The generated slave module of each FMU subclasses :class:`PantographSlave` and sets
``preset``; ``parameter_file`` (a path, or a file name inside the FMU resources) replaces the
preset's parameter set.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pantocosim.interaction.pantograph_start import start_state
from pantocosim.pantograph.base import Ramp
from pantocosim.pantograph.presets import load_pantograph, preset_defaults

from ..core.errors import ParameterError
from ..core.hht import HHTSettings
from ..interaction.stepper_factory import make_stepper
from .front import Status
from .given import track_sets
from .pantograph_ports import FORCE_TIMING, LAW_INPUTS, SPEED_INPUT, VARIABLES
from .slave_base import IntegratorSlave


class PantographSlave(IntegratorSlave):
    preset = "dsa380-rigid"
    description = "pantocosim pantograph"
    variables = VARIABLES

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.description = f"pantocosim pantograph '{self.preset}'. {FORCE_TIMING}"
        # start values of the parameters are the preset's (a broken bundled preset fails
        # the build with the file, field and value)
        self.declare(preset_defaults(self.preset))
        self._model = None
        self._u = np.zeros(1)   # the step's input (reused: a step allocates nothing)
        self._force_prev = 0.0
        self._input_prev = 0.0
        self._state_attributes = ["_integ_state", "_force_prev", "_input_prev", "_given"]
        #: the variables a master set (or the build baked): what the start may rely on
        self._given = set(self.start_values)
        track_sets(self, ("speed_kmh", SPEED_INPUT, *LAW_INPUTS))
        self.apply_start_values()

    # ------------------------------------------------------------------ lifecycle
    def _load_model(self):
        source = self.preset
        if self.parameter_file:
            p = Path(self.parameter_file)
            if not p.is_absolute() and self.resources and (Path(self.resources) / p).exists():
                p = Path(self.resources) / p
            if not p.exists():
                raise ParameterError("parameter_file", self.parameter_file, "no such file")
            source = str(p)
        overrides = {name: self.value(name) for name in (
            "static_force", "aero_c1", "aero_c2", "friction_force", "friction_smoothing")}
        overrides.update(speed_kmh=self._speed_kmh(), one_way_damper=bool(self.one_way_damper))
        start_mode = self.value("start_mode")
        self.substeps()
        if start_mode == 1:
            overrides["ramp"] = Ramp(start=self.value("ramp_start_time"),
                                     duration=self.value("ramp_duration"),
                                     lowered_height=self.value("lowered_height"))
        return load_pantograph(source, **overrides)

    def _speed_input(self) -> float | None:
        """The catenary's train speed where a master gave it (a positive value set)."""
        v = float(getattr(self, SPEED_INPUT))
        return v if SPEED_INPUT in self._given and math.isfinite(v) and v > 0.0 else None

    def _speed_kmh(self) -> float:
        """The train speed: speed_kmh where a master set it (or the build baked it), else the
        catenary's train_speed_kmh input where given, else speed_kmh's start value."""
        given = self._speed_input()
        if "speed_kmh" not in self._given and given is not None:
            return given
        return self.finite("speed_kmh", self.speed_kmh)

    def _check_given(self) -> None:
        """Refuse a start that lacks what it needs, naming all of it: a start on the
        catenary's laws (start_mode 2) needs the laws and the train speed (a master that
        exchanges nothing in initialisation mode gives neither to a pantograph whose start
        values do not carry them); a given train speed must be speed_kmh's."""
        problems = []
        given = self._speed_input()
        if self.start_mode == 2 and "speed_kmh" not in self._given and given is None:
            problems.append(f"speed_kmh was never set and the input {SPEED_INPUT} was not "
                            "given: set speed_kmh to the train speed, or connect "
                            f"{SPEED_INPUT} to the catenary FMU's output {SPEED_INPUT}")
        elif "speed_kmh" in self._given and given is not None \
                and abs(self.speed_kmh - given) > 1e-9 * max(1.0, given):
            problems.append(f"speed_kmh = {self.speed_kmh!r} but the catenary's "
                            f"{SPEED_INPUT} = {given!r}: the pantograph and the catenary "
                            "run at one train speed")
        if self.start_mode == 2 and min(self._law_values()[1::2]) <= 0.0:
            problems.append("the start-law inputs " + ", ".join(LAW_INPUTS) + " were not "
                            "given in initialisation mode (their slopes are 0): connect them "
                            "to the catenary FMU's outputs operating_height_1, ... in a "
                            "master that exchanges values in initialisation mode, or use "
                            "start_mode 0 with initial_height")
        if problems:
            raise ParameterError("start_mode", self.start_mode, "the pantograph's start lacks "
                                 "what this master did not give: " + "; ".join(problems))

    def _law_values(self) -> tuple[float, ...]:
        """The law inputs, or their baked start values where the master passed none."""
        if min(self.operating_height_slope, self.static_height_slope) > 0.0:
            return tuple(float(getattr(self, name)) for name in LAW_INPUTS)
        return tuple(float(self.given_or_start(name, lambda v: False)) for name in LAW_INPUTS)

    def _laws(self) -> tuple[float, float, float, float]:
        """The catenary's start laws (:meth:`_law_values`), checked finite."""
        return tuple(self.finite(name, value)
                     for name, value in zip(LAW_INPUTS, self._law_values()))

    def _start(self, model):
        """(q0, F0): the start shape and the contact force at t0 of ``start_mode``
        (:func:`~pantocosim.interaction.pantograph_start.start_state`)."""
        if self.start_mode == 2:
            return start_state(model, 2, laws=self._laws())
        return start_state(model, self.start_mode, height=self.value("initial_height"),
                           force=self.value("initial_contact_force"),
                           lowered_height=self.lowered_height)

    def update_initial_outputs(self):
        """In initialisation mode the contact height of the start is an output as soon as
        the parameters (and, for start_mode 2, the catenary's laws) are set."""
        key = (self._laws(), self.start_mode, self.initial_height, self._speed_kmh())
        if key == getattr(self, "_preview_key", None):
            return
        if self.start_mode == 2 and (min(key[0][1], key[0][3]) <= 0.0 or (
                "speed_kmh" not in self._given and self._speed_input() is None)):
            return  # the catenary's laws or speed are not there yet
        self._preview_key = key
        model = self._load_model()
        q0, _ = self._start(model)
        self.contact_height = float(model.contact_height(q0))
        self.contact_velocity = 0.0

    def initialise(self):
        self.check_build_stamp()
        if self._error:
            return
        self._check_given()
        model = self._load_model()
        settings = HHTSettings(alpha=self.finite("hht_alpha", self.hht_alpha))
        try:
            settings.validate()
        except ParameterError as exc:
            raise exc.renamed({"alpha": "hht_alpha"}) from None
        q0, F0 = self._start(model)
        integ = make_stepper(model, settings, redo=True)
        integ.initialize(0.0, q0, np.zeros(model.n_dofs), np.array([F0]))
        self._model, self._integ = model, integ
        self._height_range = model.height_range()
        self._force_prev = F0
        self._input_prev = F0
        self.contact_force = F0
        self.apply_pending_state()
        self._update_outputs()

    def advance(self, current_time, step_size):
        integ = self._integ
        if self._error or integ is None:
            self.log(self._error or "not initialised", Status.discard)
            return False
        F = float(self.contact_force)
        if not (math.isfinite(F) and F >= 0.0):
            self.log(f"contact_force = {F!r}: must be finite and >= 0", Status.discard)
            return False
        n = int(self.n_substeps)
        # a step outside the heights the model represents is discarded and undone (a
        # closed-form step too): the state before it is kept
        saved = integ.get_state()
        try:
            u = F
            if self.force_extrapolation:
                if integ.t == 0.0:
                    # the force at t0 is the start's: masters disagree on what they pass
                    # at the first step (fmpy's SSP support passes 0)
                    u = self._input_prev
                F = max(0.0, 2.0 * u - self._input_prev)
            h = step_size / n
            F0 = self._force_prev
            iters = 0
            buf = self._u
            for i in range(1, n + 1):
                buf[0] = F0 + (F - F0) * i / n
                iters += integ.step(h, buf).iterations
            problem = self._outside_range(current_time, step_size)
            if problem:
                integ.set_state(saved)
                self.log(problem, Status.discard)
                return False
            self._force_prev = F
            self._input_prev = u
            self.newton_iterations = float(iters)
            self._update_outputs()
            return True
        except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
            integ.set_state(saved)
            self.log(f"doStep(t = {current_time:.6g}, h = {step_size:.3g}) failed: {exc}",
                     Status.discard)
            return False

    def _outside_range(self, t: float, h: float) -> str | None:
        """Why the step just taken left the heights the model represents, or None."""
        z = float(self._model.contact_height(self._integ.q))
        lo, hi = self._height_range
        if lo <= z <= hi:
            return None
        return (f"doStep(t = {t:.6g}, h = {h:.3g}): the contact point would be at {z:.4g} m, "
                f"outside the heights pantograph '{self.preset}' represents ({lo:.3g} .. "
                f"{hi:.3g} m): contact_force = {float(self.contact_force):.6g} N and "
                f"speed_kmh = {float(self.speed_kmh):.6g} km/h are beyond what it can take")

    def _update_outputs(self):
        q, v = self._integ.q, self._integ.v
        self.contact_height = float(self._model.contact_height(q))
        self.contact_velocity = float(self._model.contact_velocity(q, v))
