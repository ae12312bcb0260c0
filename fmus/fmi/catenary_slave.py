"""FMI 2.0 co-simulation adapter for the catenary finite-element model.

Port contract (README.md, "The FMUs and their ports"; docs/third-party.md):

parameters
  ``catenary`` (String, preset name or TOML path; relative paths are also looked up in the
  FMU resources), ``spans`` (0 = as defined), ``element_size`` [m] (0 = as defined),
  ``speed_kmh``, ``n_pantographs`` (1..4), ``position_k`` [m] (x of pantograph k at the
  experiment's start time t0; the model runs on the time since t0, x_k = position_k + V (t - t0)),
  ``static_force_k`` [N] (upward static contact force at t0 for the static start, 0 = none),
  ``hht_alpha``, ``contact_mode`` (0 = contact forces are inputs, 1 = built-in penalty
  contact), ``contact_stiffness`` [N/m], ``contact_damping`` [N s/m], ``n_substeps``,
  ``factorization`` (HHT Newton matrix policy: 0 full Newton, 1 once per step, 2 reuse
  across steps, the default), ``newton_rtol`` (Newton residual tolerance),
  ``catenary_model`` (Integer: 0 nonlinear, the default; 1 linear; 2 modal) and
  ``modal_cutoff_hz`` [Hz] (modal model: modes below it; 0 = the default cutoff).
inputs
  ``contact_force_k`` [N] (mode 0), ``pantograph_height_k`` [m] and
  ``pantograph_velocity_k`` [m/s] (mode 1).
outputs
  ``wire_height_k`` [m], ``wire_velocity_k`` [m/s] (including the convective term V dz/dx
  seen by the moving pantograph), ``contact_force_out_k`` [N], ``support_uplift_j`` [m]
  (j = 0..63; uplift of the contact wire at support j relative to the unloaded static
  configuration; 0 beyond the last support; a line of more supports logs a warning at
  initialisation) and ``n_supports``; ``train_speed_kmh`` (the speed, for pantograph FMUs) and
  the start laws ``operating_height_k``, ... are available in initialisation mode.

Timing (both modes): the input values set before ``doStep(t, h)`` are the values at
``t + h``; the values at ``t`` are the previous accepted step's, kept in the FMU state. In
mode 0 the forces enter the HHT-alpha step weighted (1 + alpha) F(t+h) - alpha F(t) exactly
as in the monolithic solver; at t0 the force is ``static_force_k``. In mode 1 the FMU solves
the penalty contact F = max(0, k_H (z_p - z_w) + c_H (v_p - v_w)) implicitly with the wire,
with the pantograph's height/velocity at t + h from the inputs (at t0 the pantograph is taken
at z_w + static_force_k / k_H, so the contact force at t0 is ``static_force_k``; with a zero
static force the inputs set during initialisation are used, else their start values; a
height first delivered after t0 that is off the settled one is refused). With
``n_substeps`` > 1 the inputs are interpolated linearly inside the communication step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pantocosim.core.penalty_contact import DEFAULT_CONTACT_STIFFNESS
from pantocosim.core.hht import DEFAULT_ALPHA, FactorReuse
from pantocosim.core.stepping import make_stepper

from .front import Status
from .given import track_sets
from .slave_base import IntegratorSlave

MAX_PANTOGRAPHS = 4
#: the parameter ``factorization``: full Newton, once per step, reuse across steps
FACTORIZATION_POLICIES = (FactorReuse.NEVER, FactorReuse.PER_STEP, FactorReuse.ACROSS_STEPS)
#: a pantograph height at t0 that differs from the settled one by more settles it again [m]
HEIGHT_TOL_M = 1e-9
#: a pantograph height first delivered after t0 may differ from the height the start was
#: settled against by at most the height of this static contact force [N] (a pantograph that
#: started on this catenary moves micrometres in a step; one that did not is centimetres off)
START_FORCE_TOL_N = 1.0
#: support_uplift_j outputs: the FMU's port limit (a longer line reports the first ones)
MAX_SUPPORTS = 64
#: model field -> this FMU's parameter, for errors raised by the model side
FIELD_NAMES = {"alpha": "hht_alpha", "rtol": "newton_rtol",
               "contact.stiffness": "contact_stiffness", "contact.damping": "contact_damping"}

#: the start laws offered to pantograph FMUs in start_mode 2 (operating_height.py)
LAW_OUTPUTS = (
    ("operating_height", "m", "contact height where a pantograph of mean uplift F operates: "
     "operating_height + operating_height_slope F (mean dynamic wire height over the "
     "analysis window + F / k_H)"),
    ("operating_height_slope", "m/N", "slope of the operating-height law"),
    ("static_height", "m", "contact height at t0 under a static contact force F: "
     "static_height + static_height_slope F"),
    ("static_height_slope", "m/N", "slope of the static-height law"))

TIMING = ("the value set before doStep(t, h) is the value at t + h; the value at t is the "
          "previous accepted step's (kept in the FMU state)")


@dataclass(frozen=True)
class PortNames:
    """The names of the ports of pantographs 1..n and of the support uplifts (a step sets
    and reads its variables by these names, built once)."""

    forces: tuple            # contact_force_k (input, contact_mode 0)
    heights: tuple           # pantograph_height_k (input, contact_mode 1)
    velocities: tuple        # pantograph_velocity_k (input, contact_mode 1)
    wire_heights: tuple      # wire_height_k
    wire_velocities: tuple   # wire_velocity_k
    forces_out: tuple        # contact_force_out_k
    uplifts: tuple           # support_uplift_j, j = 0 .. MAX_SUPPORTS - 1

    @classmethod
    def of(cls, n: int) -> "PortNames":
        k = range(1, n + 1)
        return cls(*(tuple(f"{base}_{i}" for i in k) for base in (
            "contact_force", "pantograph_height", "pantograph_velocity", "wire_height",
            "wire_velocity", "contact_force_out")),
            tuple(f"support_uplift_{j}" for j in range(MAX_SUPPORTS)))


class CatenarySlave(IntegratorSlave):
    description = "pantocosim catenary"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.description = ("pantocosim catenary (finite elements, HHT-alpha). Inputs: " + TIMING
                            + ". contact_mode 0: contact forces are inputs (at t0: "
                            "static_force_k); contact_mode 1: built-in penalty contact from "
                            "pantograph_height_k/pantograph_velocity_k.")
        self.string("catenary_definition", "en50318", "catenary definition: preset name "
                    "(en50318, ave64, benchmark55) or TOML file (relative paths are also looked "
                    "up in the FMU resources)")
        self.integer("spans", 0, "number of spans (span data cycled); 0 = as defined")
        self.integer("catenary_model", 0, "catenary model: 0 = nonlinear (finite elements, "
                     "the reference), 1 = linear (about the static equilibrium, droppers "
                     "slacken), 2 = modal (the linear model on its modes below "
                     "modal_cutoff_hz, static corrections at the droppers and contact points)")
        self.real("modal_cutoff_hz", 0.0, "parameter", "Hz", "catenary_model 2: modes below "
                  "this frequency; 0 = the default cutoff")
        self.real("element_size", 0.0, "parameter", "m",
                  "target finite-element length; 0 = as defined")
        self.real("speed_kmh", 0.0, "parameter", "km/h", "train speed")
        self.integer("n_pantographs", 1, "number of pantographs (1..4)")
        for k in range(1, MAX_PANTOGRAPHS + 1):
            self.real(f"position_{k}", 30.0, "parameter", "m",
                      f"track position x of pantograph {k} at t0")
        for k in range(1, MAX_PANTOGRAPHS + 1):
            self.real(f"static_force_{k}", 0.0, "parameter", "N",
                      f"upward static contact force of pantograph {k} at t0 (static start); "
                      "0 = none")
        self.real("hht_alpha", DEFAULT_ALPHA, "parameter", "1", "HHT-alpha parameter in [-1/3, 0]")
        self.integer("contact_mode", 0, "0 = contact forces are inputs (contact_force_k); "
                     "1 = built-in penalty contact from pantograph_height_k and "
                     "pantograph_velocity_k")
        self.real("contact_stiffness", DEFAULT_CONTACT_STIFFNESS, "parameter", "N/m",
                  "penalty stiffness k_H (contact_mode 1)")
        self.real("contact_damping", 0.0, "parameter", "N.s/m",
                  "penalty contact damping c_H (contact_mode 1)")
        self.boolean("extrapolate_heights", True,
                     "contact_mode 1: take pantograph_height_k as the height at the start of "
                     "the communication step (what a zero-order-hold master sets) and "
                     "extrapolate it with pantograph_velocity_k over the step; false: take it "
                     "as the height at t + h (an iterating master)")
        self.real("window_start", 0.0, "parameter", "m", "analysis window start x: the "
                  "operating-height law averages the wire height there (window_end <= "
                  "window_start: the middle span of the line)")
        self.real("window_end", 0.0, "parameter", "m", "analysis window end x")
        self.real("averaging_step", 1e-3, "parameter", "s", "time step of the moving-load "
                  "run behind the operating-height law")
        self.integer("n_substeps", 1, "integration steps per communication step (inputs "
                     "interpolated linearly)")
        self.integer("max_dofs", 0, "largest catenary model the FMU builds (degrees of "
                     "freedom); 0 = the default limit (the size guard refuses larger models "
                     "before building them)")
        self.integer("factorization", 2, "Newton matrix policy of the HHT solver: 0 = full "
                     "Newton (refactorize every iteration), 1 = factorize once per step "
                     "(chord), 2 = reuse across steps (refreshed when droppers change state "
                     "or a step needs more than 2 iterations; linear predictor)")
        from pantocosim.core.hht import RUN_RTOL

        self.real("newton_rtol", RUN_RTOL, "parameter", "1", "Newton residual tolerance, "
                  "relative to the largest force in the residual")
        ports = PortNames.of(MAX_PANTOGRAPHS)
        for k, name in enumerate(ports.forces, start=1):
            self.real(name, 0.0, "input", "N",
                      f"contact_mode 0: upward contact force of pantograph {k} on the wire, "
                      f">= 0; {TIMING}; at t0 it is static_force_{k}")
        for k, (height, velocity) in enumerate(zip(ports.heights, ports.velocities), start=1):
            self.real(height, 0.0, "input", "m",
                      f"contact_mode 1: contact height of pantograph {k} above the rail; "
                      f"{TIMING}")
            self.real(velocity, 0.0, "input", "m/s",
                      f"contact_mode 1: vertical velocity of pantograph {k}'s contact point; "
                      f"{TIMING}")
        for k, names in enumerate(zip(ports.wire_heights, ports.wire_velocities,
                                      ports.forces_out), start=1):
            height, velocity, force = names
            self.real(height, 0.0, "output", "m",
                      f"contact-wire height above the rail under pantograph {k}")
            self.real(velocity, 0.0, "output", "m/s",
                      f"vertical velocity of the contact wire seen by pantograph {k} "
                      "(including the convective term V dz/dx)")
            self.real(force, 0.0, "output", "N",
                      f"contact force of pantograph {k}: mode 1 the penalty force at the end "
                      "of the step, mode 0 the input force")
        #: the start-law outputs: computed when a master first reads one (:meth:`_output_value`)
        self._law_names = set()
        for k in range(1, MAX_PANTOGRAPHS + 1):
            for name, unit, text in LAW_OUTPUTS:
                self.real(f"{name}_{k}", 0.0, "output", unit, f"start law of pantograph {k} "
                          f"(constant; available in initialisation mode): {text}")
                self._law_names.add(f"{name}_{k}")
        self._attribute_reals -= {vr for vr, v in self.vars.items() if v.name in self._law_names}
        for j, name in enumerate(ports.uplifts):
            self.real(name, 0.0, "output", "m",
                      f"uplift of the contact wire at support {j} relative to the unloaded "
                      "static configuration (0 beyond the last support)")
        self.real("n_supports", 0.0, "output", "1", "number of supports of the line (spans + 1)")
        self.real("train_speed_kmh", 0.0, "output", "km/h", "the train speed (speed_kmh; "
                  "available in initialisation mode): pantograph FMUs take it as their input "
                  "of the same name")
        self.real("newton_iterations", 0.0, "local", None,
                  "Newton iterations of the last communication step")
        self._model = None       # CatenaryModel
        self._standins = []      # PrescribedPantograph per pantograph (mode 1)
        self._integ = None
        self._n = 1
        self._mode = 0
        self._prev_inputs = None  # mode 0: forces at t; mode 1: (z_p, v_p) at t
        self._port_names = PortNames.of(1)   # of the active pantographs (initialise)
        self._prepared = False    # the structure's prepare ran (the first step)
        self._state_attributes = ["_integ_state", "_prev_inputs", "_given", "_delivered"]
        #: the inputs a master set; per pantograph, whether a master delivered its height
        #: (at t0, or later: :meth:`_check_late_heights`)
        self._given: set = set()
        self._delivered = np.zeros(0, bool)
        track_sets(self, ports.heights)
        self._cache: dict = {}    # model and start laws by the parameters they depend on
        self.apply_start_values()

    # ------------------------------------------------------------------ lifecycle

    def _catenary_source(self):
        from pantocosim.catenary.definition import load_catenary
        from pantocosim.core.errors import ParameterError

        name = str(self.catenary_definition).strip()
        if not name:
            raise ParameterError("catenary_definition", self.catenary_definition,
                                 "empty catenary name")
        p = Path(name)
        if not p.is_absolute() and not p.exists() and self.resources:
            cand = Path(self.resources) / p
            if cand.exists():
                return load_catenary(cand)
        return load_catenary(name)

    def _check_line(self, definition, spans: int, esize: float, speed: float) -> None:
        """What the FMU can represent, checked before anything is built: the model's size
        (DOFs), the support outputs, the train speed below the contact wire's wave speed."""
        import dataclasses

        from pantocosim.core.size_guard import check_catenary_size, culprit
        from pantocosim.core.errors import ParameterError

        finer = 0 < esize < definition.element_size
        if esize > 0:
            definition = dataclasses.replace(definition, element_size=esize)
        field, value = (("element_size", esize) if finer else ("spans", spans) if spans
                        else culprit(definition))
        limit = int(self.max_dofs)
        check_catenary_size(definition, field, value, None, limit if limit > 0 else None,
                            lift="max_dofs =")
        supports = len(definition.support_x)
        if supports > MAX_SUPPORTS:
            raise ParameterError("spans", definition.n_spans, f"the line has {supports} "
                                 f"supports; the FMU outputs the uplift of {MAX_SUPPORTS} "
                                 f"(support_uplift_0..{MAX_SUPPORTS - 1}): at most "
                                 f"{MAX_SUPPORTS - 1} spans")
        wave = definition.contact.wave_speed
        if speed >= wave:
            raise ParameterError("speed_kmh", speed * 3.6, f"must be below the contact wire's "
                                 f"wave speed c = {wave * 3.6:.0f} km/h (catenary "
                                 f"'{definition.name}'): at or above it the wire cannot carry "
                                 "the moving load")

    def _build_model(self):
        """The catenary model of the current parameters (checked; cached)."""
        from pantocosim.catenary.definition import with_spans
        from pantocosim.catenary.models import make_catenary, model_name
        from pantocosim.core.errors import ParameterError

        n = int(self.n_pantographs)
        if not 1 <= n <= MAX_PANTOGRAPHS:
            raise ParameterError("n_pantographs", n, f"must be 1..{MAX_PANTOGRAPHS}")
        speed = self.finite("speed_kmh", self.speed_kmh) / 3.6
        esize = self.finite("element_size", self.element_size)
        if esize < 0:
            raise ParameterError("element_size", esize, "must be >= 0 (0 = as defined)")
        spans = int(self.spans)
        if spans < 0:
            raise ParameterError("spans", spans, "must be >= 0 (0 = as defined)")
        x0 = [self.finite(f"position_{k}", getattr(self, f"position_{k}"))
              for k in range(1, n + 1)]
        kind = model_name(int(self.catenary_model))
        cutoff = self.finite("modal_cutoff_hz", self.modal_cutoff_hz)
        if cutoff < 0:
            raise ParameterError("modal_cutoff_hz", cutoff, "must be >= 0 (0 = default)")
        key = ("model", str(self.catenary_definition), spans, esize, speed, tuple(x0), kind,
               cutoff)
        if key not in self._cache:
            definition = self._catenary_source()
            if spans:
                definition = with_spans(definition, spans)
            self._check_line(definition, spans, esize, speed)
            length = float(definition.support_x[-1])
            for k, x in enumerate(x0, start=1):
                if not 0.0 < x < length:
                    raise ParameterError(f"position_{k}", x, f"must lie on the line (0 .. "
                                         f"{length:g} m of catenary '{definition.name}')")
            self._cache = {key: make_catenary(
                kind, definition, x0=x0, speed=speed, element_size=esize if esize > 0 else None,
                modal_cutoff_hz=cutoff if cutoff > 0 else None)}
        return self._cache[key]

    def _run_settings(self):
        """The HHT settings of runs (:meth:`HHTSettings.for_runs`, which checks hht_alpha and
        newton_rtol)."""
        from pantocosim.core.errors import ParameterError
        from pantocosim.core.hht import HHTSettings

        try:
            return HHTSettings.for_runs(self.finite("hht_alpha", self.hht_alpha),
                                        self.finite("newton_rtol", self.newton_rtol))
        except ParameterError as exc:
            raise exc.renamed(FIELD_NAMES) from None

    def _contact(self):
        from pantocosim.core.penalty_contact import PenaltyContact
        from pantocosim.core.errors import ParameterError

        try:
            return PenaltyContact(self.finite("contact_stiffness", self.contact_stiffness),
                                  self.finite("contact_damping", self.contact_damping))
        except ParameterError as exc:
            raise exc.renamed(FIELD_NAMES) from None

    def _laws(self, model):
        """The start laws (operating_height.ContactHeightLaws) of the current parameters."""
        from pantocosim.catenary.analysis import central_window
        from pantocosim.catenary.operating_height import contact_height_laws, passage_duration
        from pantocosim.core.errors import ParameterError

        window = (self.finite("window_start", self.window_start),
                  self.finite("window_end", self.window_end))
        if window[1] <= window[0]:
            window = central_window(model.support_x)
        dt = self.finite("averaging_step", self.averaging_step)
        if not dt > 0:
            raise ParameterError("averaging_step", dt, "must be > 0")
        duration = passage_duration(window[1], model.x0, model.speed if model.speed > 0
                                    else 1.0)
        alpha = self._run_settings().alpha
        key = ("laws", window, dt, alpha, self._contact().stiffness)
        if key not in self._cache:
            from pantocosim.catenary.models import law_model

            self._cache[key] = contact_height_laws(law_model(model), self._contact().stiffness,
                                                   window, dt, duration, alpha)
        return self._cache[key]

    def update_initial_outputs(self):
        """In initialisation mode the train speed is an output as soon as it is set."""
        self.train_speed_kmh = self.finite("speed_kmh", self.speed_kmh)

    def _output_value(self, name: str):
        """A start-law output is computed when a master reads it (in initialisation mode, where
        pantograph FMUs in start_mode 2 read them, or later): the moving-load runs behind it
        cost nothing to a master that never reads them. Before initialisation mode (the model
        description's start values) it is its start value, 0."""
        if name in self._law_names and (self._in_initialization or self.initialised):
            try:          # (computed once for the parameters: :meth:`_laws` keeps them)
                self._set_law_outputs(self._laws(self._build_model()))
            except Exception as exc:  # noqa: BLE001 - an early read; initialise() decides
                if self.initialised:
                    raise             # the read is refused (fmi2Error), never a stale 0
                self.log(f"start laws not available yet: {exc}", Status.warning)
        return super()._output_value(name)

    def _set_law_outputs(self, laws):
        values = (laws.operating_offset, laws.operating_slope, laws.static_offset,
                  laws.static_slope)
        for (name, _, _), v in zip(LAW_OUTPUTS, values):
            for k in range(1, len(v) + 1):
                setattr(self, f"{name}_{k}", float(v[k - 1]))

    def _static_forces(self, n):
        from pantocosim.core.errors import ParameterError

        F0 = []
        for k in range(1, n + 1):
            F = self.finite(f"static_force_{k}", getattr(self, f"static_force_{k}"))
            if F < 0:
                raise ParameterError(f"static_force_{k}", F, "must be >= 0 (upward force)")
            F0.append(F)
        return np.array(F0)

    def _settle(self, model, heights, contact, forces):
        """q0 of the catenary in static equilibrium with pantographs held at ``heights``
        (penalty contact), from the static state under ``forces`` as the first guess."""
        from pantocosim.core.coupled import CoupledSystem
        from pantocosim.core.prescribed import PrescribedPantograph

        system = CoupledSystem(model, [PrescribedPantograph(z, 0.0) for z in heights],
                               contact)
        return system.static_solve(model.static_state(forces))

    def initialise(self):
        from pantocosim.core.errors import ParameterError

        self.check_build_stamp()
        if self._error:
            return
        mode = int(self.contact_mode)
        if mode not in (0, 1):
            raise ParameterError("contact_mode", mode, "must be 0 (force inputs) or 1 "
                                 "(built-in penalty)")
        self.substeps()
        self._settings = self._run_settings()
        model = self._model = self._build_model()
        n = len(model.x0)
        contact = self._contact()
        F0 = self._static_forces(n)
        policy = int(self.factorization)
        if policy not in (0, 1, 2):
            raise ParameterError("factorization", policy, "must be 0 (full Newton), 1 (once "
                                 "per step) or 2 (reuse across steps)")
        self._settings.reuse_factorization = FACTORIZATION_POLICIES[policy]
        self._mode, self._n = mode, n
        self._port_names = PortNames.of(n)
        if mode == 0:
            q0 = model.static_state(F0 if np.any(F0 != 0.0) else None)
            integ = make_stepper(model, self._settings, redo=True)
            integ.initialize(0.0, q0, np.zeros(model.n_dofs), F0.copy())
            self._prev_inputs = F0.copy()
            for k in range(1, n + 1):
                setattr(self, f"contact_force_{k}", float(F0[k - 1]))
            self._integ = integ
        else:
            self._delivered = np.array([F0[k - 1] > 0 or (
                f"pantograph_height_{k}" in self._given
                and getattr(self, f"pantograph_height_{k}") > 0.0) for k in range(1, n + 1)])
            self._start_penalty(model, contact, F0, self._input_heights(n, F0))
        self.train_speed_kmh = self.finite("speed_kmh", self.speed_kmh)
        self.n_supports = float(len(model.support_x))
        self.apply_pending_state()
        self._update_outputs(initial=True)

    def _input_heights(self, n, F0):
        """Pantograph heights and velocities at t0: at z_w(F) + F / k_H for a static force F,
        else the inputs."""
        model = self._build_model()
        k_h = self._contact().stiffness
        zw = model.wire_height(0.0, model.static_state(F0)) if np.any(F0 > 0) else None
        out = np.empty((n, 2))
        for k in range(1, n + 1):
            if F0[k - 1] > 0:
                out[k - 1] = (float(zw[k - 1] + F0[k - 1] / k_h), 0.0)
            else:
                name = f"pantograph_height_{k}"
                out[k - 1] = (self.finite(name, self.given_or_start(name, lambda z: z > 0.0)),
                              self.finite(f"pantograph_velocity_{k}",
                                          getattr(self, f"pantograph_velocity_{k}")))
        return out

    def _start_penalty(self, model, contact, F0, heights):
        """Mode 1: the catenary and its pantograph stand-ins at ``heights`` [(z, v)] in the
        static start (settled against the heights where no static force is given)."""
        from pantocosim.catenary.operating_height import static_height_law
        from pantocosim.core.prescribed import PrescribedPantograph

        if np.all(F0 > 0):
            q0 = model.static_state(F0)
        else:
            guess = F0.copy()
            self._late_height_tol = np.zeros(len(F0))
            for k in np.flatnonzero(F0 == 0):
                off, slope = static_height_law(model, k)
                guess[k] = max(0.0, (heights[k, 0] - off) / (slope + 1.0 / contact.stiffness))
                self._late_height_tol[k] = START_FORCE_TOL_N * (slope + 1.0 / contact.stiffness)
            q0 = self._settle(model, heights[:, 0], contact, guess)
        standins = [PrescribedPantograph(z, v) for z, v in heights]
        for k, (z, v) in enumerate(heights, start=1):
            setattr(self, f"pantograph_height_{k}", float(z))
            setattr(self, f"pantograph_velocity_{k}", float(v))
        integ = make_stepper(model, self._settings, standins, contact, redo=True)
        integ.initialize(0.0, q0)
        self._standins, self._integ = standins, integ
        self._settled_forces = F0
        self._prev_inputs = np.array(heights, float)

    # ------------------------------------------------------------------ stepping
    def _read_inputs(self):
        """Inputs at t + h for the active pantographs, or an error message."""
        d = self.__dict__
        if self._mode == 0:
            values = [float(d[name]) for name in self._port_names.forces]
            for name, x in zip(self._port_names.forces, values):
                if not (math.isfinite(x) and x >= 0.0):
                    return None, f"{name} = {x!r}: must be finite and >= 0"
            return np.array(values), None
        out = np.empty((self._n, 2))
        for k, names in enumerate(zip(self._port_names.heights, self._port_names.velocities)):
            for j, name in enumerate(names):
                x = float(d[name])
                if not math.isfinite(x):
                    return None, f"{name} = {x!r}: must be finite"
                out[k, j] = x
        return out, None

    def advance(self, current_time, step_size):
        if self._error or self._integ is None:
            self.log(self._error or "not initialised", Status.discard)
            return False
        try:
            new, err = self._read_inputs()
        except Exception as exc:  # noqa: BLE001
            new, err = None, f"inputs: {exc}"
        if err is not None:
            self.log(err, Status.discard)
            return False
        n = int(self.n_substeps)
        # a closed-form step leaves the state alone until it succeeds: no state to save
        saved = None if (n == 1 and self._integ.closed_form) else self._integ.get_state()
        try:
            if self._mode == 1 and self.extrapolate_heights and self._integ.t == 0.0:
                new = self._first_step_heights(new)
            elif self._mode == 1 and not self._delivered.all():
                problem = self._check_late_heights(new, current_time)
                if problem:
                    self._error = problem
                    self.log(problem, Status.discard)
                    return False
            h = step_size / n
            self._prepare_once(h)
            old = self._prev_inputs
            iters = 0
            for i in range(1, n + 1):
                u = new if i == n else old + (new - old) * (i / n)
                if self._mode == 0:
                    iters += self._integ.step(h, u.copy()).iterations
                else:
                    for s, (z, v), (z_new, v_new) in zip(self._standins, u, new):
                        if self.extrapolate_heights:  # first-order hold from t
                            z, v = z_new + v_new * i * h, v_new
                        s.set(z, v)
                    iters += self._integ.step(h).iterations
            self._prev_inputs = new   # made by _read_inputs (the steps took copies)
            self.newton_iterations = float(iters)
            self._update_outputs()
            return True
        except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
            if saved is not None:
                self._integ.set_state(saved)
            self.log(f"doStep(t = {current_time:.6g}, h = {step_size:.3g}) failed: "
                     f"{type(exc).__name__}: {exc}", Status.discard)
            return False

    def _prepare_once(self, h: float) -> None:
        """At the first step, the structure's set-up for steps of h (``prepare``, where it has
        one: the factorization, the dropper columns, numba loading the kernels of slack
        droppers), so the step where a dropper first goes slack pays none of it. A master's
        first step (ours: its warm-up) pays it; a later step size (a halved step) does not
        prepare again."""
        if self._prepared:
            return
        self._prepared = True
        self._integ.prepare(h)

    def _first_step_heights(self, new):
        """A zero-order-hold master passes the pantographs' heights at t0 before the first
        step: where the start was settled against the heights (no static force), a new
        positive height settles it again (the master delivered the t0 value only now); else
        the start's heights stand (fmpy's SSP support passes 0)."""
        F0 = self._settled_forces
        held = self._prev_inputs.copy()
        given = (F0 == 0.0) & (new[:, 0] > 0.0)
        self._delivered = self._delivered | given
        if np.any(given & (np.abs(new[:, 0] - held[:, 0]) > HEIGHT_TOL_M)):
            held[given] = new[given]
            self._start_penalty(self._build_model(), self._contact(), F0, held)
            self._update_outputs(initial=True)
        return held

    def _check_late_heights(self, new, t: float) -> str | None:
        """The pantograph heights a master delivers first after t0 (it passed none at t0:
        fmpy's simulate_ssp and CoFmuPy pass 0 at the first step): the start was settled
        against the height the FMU had (its start value), so a pantograph that is not there
        did not start on this catenary. Why the run cannot go on, or None."""
        for k in np.flatnonzero(~self._delivered & (new[:, 0] > 0.0)):
            self._delivered[k] = True
            z, held = float(new[k, 0]), float(self._prev_inputs[k, 0])
            if abs(z - held) > self._late_height_tol[k]:
                name = f"pantograph_height_{k + 1}"
                return (f"{name} = {z:.6g} m at t = {t:.6g} s: the pantograph is "
                        f"{(z - held) * 1e3:+.1f} mm from the height this catenary settled "
                        f"against at t0 ({held:.6g} m, the start value of {name}; more than "
                        f"{START_FORCE_TOL_N:g} N of static force). The master passed no "
                        f"pantograph height at t0 (it exchanges nothing in initialisation "
                        f"mode), so the pantograph did not start on this catenary: run the "
                        f"SSP in a master that exchanges values in initialisation mode "
                        f"(libcosim, ecos), or use the pantograph FMU this catenary FMU was "
                        f"built with")
        return None

    def _update_outputs(self, initial: bool = False):
        model, integ = self._model, self._integ
        t = integ.t
        qc = integ.q[:model.n_dofs]
        vc = integ.v[:model.n_dofs]
        zw, vw = model.wire_state(t, qc, vc)
        if self._mode == 0:
            F = self._prev_inputs
        else:
            F = integ.contacts()[0]
        names, d = self._port_names, self.__dict__
        d.update(zip(names.wire_heights, zw.tolist()))
        d.update(zip(names.wire_velocities, vw.tolist()))
        d.update(zip(names.forces_out, F.tolist()))
        d.update(zip(names.uplifts, model.support_uplift(qc).tolist()))
