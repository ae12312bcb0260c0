"""Co-simulation adapter (FMI 2.0 and 3.0) for the catenary finite-element model.

Its variables (parameters, the ports of pantographs 1..4 ``_k``, the support uplifts
``_j``, the start laws) are declared in :mod:`pantocosim.fmi.catenary_ports`, which the FMU
reference page of the documentation lists. The start's physics is the model's
(:mod:`pantocosim.interaction.catenary_start`); this adapter reads the parameters and
inputs, checks them against their declared ranges and drives the integrator.

Timing (both modes): the input values set before ``doStep(t, h)`` are the values at
``t + h``; the values at ``t`` are the previous accepted step's, kept in the FMU state. In
mode 0 the forces enter the HHT-alpha step weighted (1 + alpha) F(t+h) - alpha F(t) exactly
as in the monolithic solver; at t0 the force is ``static_force_k``. In mode 1 the FMU solves
the penalty contact F = max(0, k_H (z_p - z_w) + c_H (v_p - v_w)) implicitly with the wire,
with the pantograph's height/velocity at t + h from the inputs (at t0 the pantograph is taken
at z_w + static_force_k / k_H, so the contact force at t0 is ``static_force_k``; with a zero
static force the inputs set during initialisation are used, else their start values; a
height first delivered after t0 that is off the settled one is refused). With
``n_substeps`` > 1 the inputs are interpolated linearly inside the communication step. A
mode-1 step whose contacts' active set gives up (:func:`unsettled`) is discarded and the
state kept as it was.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from pantocosim.core.hht import FactorReuse, HHTSettings
from pantocosim.interaction.catenary_start import (START_FORCE_TOL_N, settled_start, start_laws,
                                                   static_contact_heights)
from pantocosim.interaction.stepper_factory import make_stepper

from ..catenary.definition import load_catenary, with_spans
from ..catenary.models import make_catenary, model_name
from ..catenary.size_guard import check_catenary_size, culprit
from ..core.errors import ParameterError
from ..interaction.penalty_contact import PenaltyContact
from ..interaction.prescribed import PrescribedPantograph
from .catenary_ports import MAX_PANTOGRAPHS, MAX_SUPPORTS, TIMING, VARIABLES, PortNames
from .front import Status
from .given import track_sets
from .slave_base import IntegratorSlave

#: the parameter ``factorization``: full Newton, once per step, reuse across steps
FACTORIZATION_POLICIES = (FactorReuse.NEVER, FactorReuse.PER_STEP, FactorReuse.ACROSS_STEPS)
#: a pantograph height at t0 that differs from the settled one by more settles it again [m]
HEIGHT_TOL_M = 1e-9
#: model field -> this FMU's parameter, for errors raised by the model side
FIELD_NAMES = {"alpha": "hht_alpha", "rtol": "newton_rtol",
               "contact.stiffness": "contact_stiffness", "contact.damping": "contact_damping"}


def unsettled(t: float, h: float, t_sub: float) -> str:
    """The discard message of a step whose built-in contact's active set gave up."""
    return (f"doStep(t = {t:.6g}, h = {h:.3g}): the built-in penalty contact's active set "
            f"did not settle (the set of pantographs in contact still changed after its last "
            f"pass, at t = {t_sub:.6g} s); the step is not taken: a smaller step may settle it")


class CatenarySlave(IntegratorSlave):
    description = "pantocosim catenary"

    variables = VARIABLES

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.description = ("pantocosim catenary (finite elements, HHT-alpha). Inputs: " + TIMING
                            + ". contact_mode 0: contact forces are inputs (at t0: "
                            "static_force_k); contact_mode 1: built-in penalty contact from "
                            "pantograph_height_k/pantograph_velocity_k.")
        self.declare()
        ports = PortNames.of(MAX_PANTOGRAPHS)
        #: the start-law outputs: computed when a master first reads one (:meth:`_output_value`)
        self._law_names = {name for names in ports.laws for name in names}
        self._attribute_reals -= {vr for vr, v in self.vars.items() if v.name in self._law_names}
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
        n = self.value("n_pantographs")
        speed = self.value("speed_kmh") / 3.6
        esize = self.value("element_size")
        spans = self.value("spans")
        x0 = [self.value(name) for name in VARIABLES.names("position_{k}", range(1, n + 1))]
        kind = model_name(self.value("catenary_model"))
        cutoff = self.value("modal_cutoff_hz")
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
        try:
            return HHTSettings.for_runs(self.finite("hht_alpha", self.hht_alpha),
                                        self.finite("newton_rtol", self.newton_rtol))
        except ParameterError as exc:
            raise exc.renamed(FIELD_NAMES) from None

    def _contact(self):
        try:
            return PenaltyContact(self.finite("contact_stiffness", self.contact_stiffness),
                                  self.finite("contact_damping", self.contact_damping))
        except ParameterError as exc:
            raise exc.renamed(FIELD_NAMES) from None

    def _laws(self, model):
        """The start laws (operating_height.ContactHeightLaws) of the current parameters
        (:func:`~pantocosim.interaction.catenary_start.start_laws`; kept for them)."""
        window = (self.value("window_start"), self.value("window_end"))
        dt = self.value("averaging_step")
        alpha = self._run_settings().alpha
        key = ("laws", window, dt, alpha, self._contact().stiffness)
        if key not in self._cache:
            self._cache[key] = start_laws(model, self._contact().stiffness, window, dt, alpha)
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
        values = np.column_stack((laws.operating_offset, laws.operating_slope,
                                  laws.static_offset, laws.static_slope))
        names = PortNames.of(len(values)).laws
        for k in range(len(values)):
            self.__dict__.update(zip(names[k], map(float, values[k])))

    def _static_forces(self, n):
        return np.array([self.value(name)
                         for name in VARIABLES.names("static_force_{k}", range(1, n + 1))])

    def initialise(self):
        self.check_build_stamp()
        if self._error:
            return
        mode = self.value("contact_mode")
        self.substeps()
        self._settings = self._run_settings()
        model = self._model = self._build_model()
        n = len(model.x0)
        contact = self._contact()
        F0 = self._static_forces(n)
        policy = self.value("factorization")
        self._settings.reuse_factorization = FACTORIZATION_POLICIES[policy]
        self._mode, self._n = mode, n
        self._port_names = PortNames.of(n)
        if mode == 0:
            q0 = model.static_state(F0 if np.any(F0 != 0.0) else None)
            integ = make_stepper(model, self._settings, redo=True)
            integ.initialize(0.0, q0, np.zeros(model.n_dofs), F0.copy())
            self._prev_inputs = F0.copy()
            self.__dict__.update(zip(self._port_names.forces, F0.tolist()))
            self._integ = integ
        else:
            self._delivered = np.array([force > 0 or (name in self._given
                                                      and getattr(self, name) > 0.0)
                                        for force, name in zip(F0, self._port_names.heights)])
            self._start_penalty(model, contact, F0, self._input_heights(n, F0))
        self.train_speed_kmh = self.finite("speed_kmh", self.speed_kmh)
        self.n_supports = float(len(model.support_x))
        self.apply_pending_state()
        self._update_outputs(initial=True)

    def _input_heights(self, n, F0):
        """Pantograph heights and velocities at t0: where pressing with a static force F
        (:func:`~pantocosim.interaction.catenary_start.static_contact_heights`), else the
        inputs."""
        model = self._build_model()
        if np.any(F0 > 0):
            pressing = static_contact_heights(model, self._contact().stiffness, F0)
        out = np.empty((n, 2))
        names = zip(self._port_names.heights, self._port_names.velocities)
        for k, (height, velocity) in enumerate(names):
            if F0[k] > 0:
                out[k] = (float(pressing[k]), 0.0)
            else:
                out[k] = (self.finite(height, self.given_or_start(height, lambda z: z > 0.0)),
                          self.value(velocity))
        return out

    def _start_penalty(self, model, contact, F0, heights):
        """Mode 1: the catenary and its pantograph stand-ins at ``heights`` [(z, v)] in the
        static start (:func:`~pantocosim.interaction.catenary_start.settled_start`: settled
        against the heights where no static force is given)."""
        q0, self._late_height_tol = settled_start(model, contact, F0, heights[:, 0])
        standins = [PrescribedPantograph(z, v) for z, v in heights]
        names = self._port_names
        self.__dict__.update(zip(names.heights, heights[:, 0].tolist()))
        self.__dict__.update(zip(names.velocities, heights[:, 1].tolist()))
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
                    report = self._integ.step(h)
                    if not report.settled:
                        self.log(unsettled(current_time, step_size, self._integ.t),
                                 Status.discard)
                        if saved is not None:
                            self._integ.set_state(saved)
                        return False
                    iters += report.iterations
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
                name = self._port_names.heights[k]
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
