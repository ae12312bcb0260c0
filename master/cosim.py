"""Co-simulation runs of a scenario: the pantograph FMUs and the catenary FMU coupled by the
master through their ports only (explicit Jacobi / Gauss-Seidel, or implicit with rollback).

The same coupling runs on in-process subsystems (:class:`ModelSubsystem`: a model and the
stepper it declares, as inside its FMU, behind the same port semantics), which the tests use
to check the algorithms against the monolithic solution without FMUs.
"""

from __future__ import annotations

import time as _time
from pathlib import Path

import numpy as np

from pantocosim.catenary.models import model_code
from pantocosim.core.errors import Interrupted, PantocosimError
from pantocosim.core.hht import HHTSettings
from pantocosim.fmi.catenary_ports import VARIABLES as CATENARY_VARIABLES
from pantocosim.fmi.catenary_ports import PortNames
from pantocosim.fmi.pantograph_ports import REQUIRED_PORTS
from pantocosim.interaction.stepper_factory import make_stepper
from pantocosim.master import stability
from pantocosim.master.coupling import Coupler, CouplingSettings, scheme_named
from pantocosim.master.fmu.build import PARAMETER_FILE_FMU, default_out, ensure_fmus, fmi_out
from pantocosim.master.fmu.check import check_fmus
from pantocosim.master.fmu.runtime import FmuInstance
from pantocosim.master.folder_lock import FolderLock
from pantocosim.master.interrupt import interrupted_at, stop_on_interrupt
from pantocosim.master.pacing import StepClock
from pantocosim.master.results.recorder import Recorder
from pantocosim.master.run.outcome import COSIM_COUNTERS, RunResult, column_names
from pantocosim.master.run.setup import Prepared
from pantocosim.master.run.stepping import progress_bar
from pantocosim.master.scenario import require_port_contact, scenario_catenary
from pantocosim.master.stability import Monitor
from pantocosim.pantograph.presets import PRESETS

#: pantograph options a pantocosim pantograph FMU takes as parameters: the master sets them
#: from the scenario's model, so the FMU runs the same pantograph
PANTOGRAPH_OPTIONS = ("static_force", "aero_c1", "aero_c2", "friction_force",
                      "friction_smoothing", "one_way_damper")


# ---------------------------------------------------------------------- subsystems
class ModelSubsystem:
    """A model with the stepper it declares (:func:`~pantocosim.interaction.stepper_factory.make_stepper`,
    as its FMU takes it) behind the FMU port semantics (in-process)."""

    def __init__(self, model, q0, settings: HHTSettings, inputs0, outputs):
        self.model = model
        self.integ = make_stepper(model, settings, redo=True)
        self.integ.initialize(0.0, q0, np.zeros(model.n_dofs), np.asarray(inputs0, float))
        self._outputs = outputs
        self._forces = np.asarray(inputs0, float).copy()
        self._newton_iterations = 0

    def set_forces(self, forces):
        self._forces = np.asarray(forces, float).copy()

    def step(self, t, h):
        self._newton_iterations = self.integ.step(h, self._forces).iterations

    def newton_iterations(self) -> float:
        return float(self._newton_iterations)

    def outputs(self):
        return self._outputs(self.integ)

    def get_state(self):
        return self.integ.get_state()

    def set_state(self, state):
        self.integ.set_state(state)

    def free_state(self, state):
        pass

    def uplift(self):
        return self.model.support_uplift(self.integ.q)


class _FmuState:
    """FMU state save/restore/free of an adapter holding ``self.fmu``; the values read after
    a step (``self.reads``) and the outputs made of them are kept until the FMU's state or
    inputs change (one fmi2GetReal per step for everything the master reads)."""

    _read = None
    _outputs = None

    def _changed(self):
        self._read = self._outputs = None

    def get_state(self):
        return self.fmu.get_state()

    def set_state(self, s):
        self.fmu.set_state(s)
        self._changed()

    def free_state(self, s):
        self.fmu.free_state(s)

    def set_forces(self, forces):
        self.inputs.set(forces)
        self._changed()

    def step(self, t, h):
        self._changed()
        self.fmu.do_step(t, h)

    def _values(self) -> np.ndarray:
        """The values of ``self.reads``, read once per change."""
        if self._read is None:
            self._read = self.reads.get()
        return self._read

    def outputs(self):
        """(heights, velocities) at the interface, made once per change (the same arrays
        until then: a caller must not change them)."""
        if self._outputs is None:
            self._outputs = self._make_outputs(self._values())
        return self._outputs


class FmuPantograph(_FmuState):
    """A pantograph FMU behind the common port contract (:data:`REQUIRED_PORTS`)."""

    def __init__(self, fmu):
        self.fmu = fmu
        force, height, velocity = REQUIRED_PORTS
        self.inputs = fmu.reals([force])
        self.reads = fmu.reals([height, velocity])

    @staticmethod
    def _make_outputs(values):
        return values[0:1], values[1:2]


class FmuCatenary(_FmuState):
    """The catenary FMU: contact_force_k in, wire_height_k / wire_velocity_k out."""

    def __init__(self, fmu, n_pantographs: int, n_supports: int):
        self.fmu = fmu
        ports = PortNames.of(n_pantographs, n_supports)
        self.inputs = fmu.reals(ports.forces)
        self.n, self.n_supports = n_pantographs, n_supports
        #: wire heights, wire velocities, support uplifts, Newton iterations
        self.reads = fmu.reals([*ports.wire_heights, *ports.wire_velocities, *ports.uplifts,
                                CATENARY_VARIABLES["newton_iterations"].name])

    def newton_iterations(self) -> float:
        return float(self._values()[-1])

    def _make_outputs(self, values):
        return values[:self.n], values[self.n:2 * self.n]

    def uplift(self):
        return self._values()[2 * self.n:2 * self.n + self.n_supports]


# ---------------------------------------------------------------------- set-up
def in_process_subsystems(prep: Prepared):
    """Catenary and pantograph models as in-process subsystems, in the static start."""
    cat = prep.catenary
    sc = prep.scenario
    csub = ModelSubsystem(cat, prep.q_cat0, HHTSettings.for_runs(sc.alpha, sc.newton_rtol),
                          prep.static_forces,
                          lambda integ: cat.wire_state(integ.t, integ.q, integ.v))
    psubs = []
    for k, pan in enumerate(prep.pantographs):
        psubs.append(ModelSubsystem(
            pan, prep.q_pan0[k], HHTSettings(alpha=sc.alpha), prep.static_forces[k:k + 1],
            lambda integ, pan=pan: (np.array([pan.contact_height(integ.q)]),
                                    np.array([pan.contact_velocity(integ.q, integ.v)]))))
    return csub, psubs


def line_supports(scenario) -> int:
    """Number of supports of the scenario's line (its catenary, its ``spans``)."""
    return (scenario.spans or scenario_catenary(scenario).n_spans) + 1


def fmu_paths(prep, build: bool = True):
    """The checked FMU files of the scenario (:class:`~pantocosim.master.fmu.check.FmuPlan`)
    of ``prep`` (a :class:`Prepared` or a scenario):
    a pantograph's ``fmu`` (relative to the working folder, else to the scenario file), by
    default ``dist/fmus/<model>.fmu`` of the working folder (a model given by a parameter
    file: ``dist/fmus/<PARAMETER_FILE_FMU>.fmu``, which gets the file; ``dist/fmus/fmi3/`` with
    ``[simulation] fmi = 3``); the default ones are built if missing or stale."""
    sc = prep.scenario if isinstance(prep, Prepared) else prep
    n_supports = len(prep.support_x) if isinstance(prep, Prepared) else line_supports(sc)
    base = Path(sc.source).resolve().parent
    dist = fmi_out(default_out(), sc.fmi)
    pans = []
    for spec in sc.pantographs:
        if spec.fmu:
            p = Path(spec.fmu)
            if not p.is_absolute() and not p.exists() and (base / p).exists():
                p = base / p
        else:
            p = dist / f"{spec.model if spec.model in PRESETS else PARAMETER_FILE_FMU}.fmu"
        pans.append(p)
    cat = dist / "catenary.fmu"
    if build:
        with FolderLock(default_out(), "dist/fmus", wait=True, required=False):   # one build at a time in that folder
            ensure_fmus(pans + [cat], dist, fmi=sc.fmi)
    return check_fmus(sc, n_supports, cat, pans)


def fmu_subsystems(prep: Prepared, instances: list, plan=None):
    """Instantiate and initialise the FMUs of the scenario (``plan``: checked FMU files,
    default :func:`fmu_paths`) in the static start."""
    sc = prep.scenario
    plan = plan or fmu_paths(prep)
    n_p = len(prep.pantographs)
    cat_fmu = FmuInstance(plan.catenary, "catenary")
    instances.append(cat_fmu)
    params = {"catenary_definition": sc.catenary, "speed_kmh": sc.speed_kmh, "n_pantographs": n_p,
              "hht_alpha": sc.alpha, "contact_mode": 0, "newton_rtol": sc.newton_rtol}
    if sc.spans:
        params["spans"] = sc.spans
    if sc.catenary_model != "nonlinear":
        params["catenary_model"] = model_code(sc.catenary_model)
        params["modal_cutoff_hz"] = sc.modal_cutoff_hz
    k = range(1, n_p + 1)
    for spec, force, position_k, force_k in zip(
            sc.pantographs, prep.static_forces, CATENARY_VARIABLES.names("position_{k}", k),
            CATENARY_VARIABLES.names("static_force_{k}", k)):
        params[position_k] = spec.position_m
        params[force_k] = float(force)
    cat_fmu.initialize(params)
    csub = FmuCatenary(cat_fmu, n_p, len(prep.support_x))
    psubs = []
    for k, (spec, pan, path) in enumerate(zip(sc.pantographs, prep.pantographs,
                                              plan.pantographs)):
        fmu = FmuInstance(path, f"pantograph_{k + 1}")
        instances.append(fmu)
        F0 = pan.options.mean_uplift
        p = {"speed_kmh": sc.speed_kmh, "hht_alpha": sc.alpha}
        if plan.parameter_files[k]:
            p["parameter_file"] = plan.parameter_files[k]
        # the options of the scenario's model (its file, the scenario's overrides)
        p.update({key: getattr(pan.options, key) for key in PANTOGRAPH_OPTIONS})
        if spec.start == "static":
            Fs = float(prep.static_forces[k])
            p.update(initial_contact_force=Fs, start_mode=0,
                     initial_height=float(pan.contact_height(prep.q_pan0[k])))
        else:
            ramp = pan.options.ramp
            p.update(initial_contact_force=F0, start_mode=1,
                     initial_height=float(prep.actuation.height[k]),
                     ramp_start_time=ramp.start, ramp_duration=ramp.duration,
                     lowered_height=ramp.lowered_height)
        fmu.initialize(p)
        psubs.append(FmuPantograph(fmu))
    return csub, psubs


# ---------------------------------------------------------------------- the run
def _interrupted(rec: Recorder, prep: Prepared) -> Interrupted:
    t = rec.columns()["time"]
    return interrupted_at(t[-1] if len(t) else 0.0, max(len(t) - 1, 0), prep.n_steps)


def coupling_tolerance(prep: Prepared) -> float:
    """Interface residual tolerance [N] of the implicit coupling: the scenario's
    ``coupling_rtol`` times the largest mean contact force of its pantographs."""
    scale = max([float(p.options.mean_uplift) for p in prep.pantographs] + [1.0])
    return prep.scenario.coupling_rtol * scale


def run_cosim(prep: Prepared, out_dir: Path | None, scheme: str = "jacobi",
              accelerator: str = "iqn-imvj", progress: bool | None = None,
              in_process: bool = False, tolerance: float | None = None,
              realtime: bool = False, plan=None) -> RunResult:
    """Co-simulate the scenario through the FMUs (or in-process subsystems); ``tolerance``
    [N] of the implicit coupling defaults to :func:`coupling_tolerance`; with ``realtime``
    each communication step is paced to the wall clock (:mod:`pantocosim.master.pacing`);
    ``plan``: the checked FMU files (default :func:`fmu_paths`)."""
    sc = prep.scenario
    require_port_contact(sc, f"the {scheme} coupling")
    warnings = stability.check(prep, scheme)
    clock = StepClock(sc.dt, realtime=realtime)
    if tolerance is None:
        tolerance = coupling_tolerance(prep)
    settings = CouplingSettings(scheme=scheme, accelerator=accelerator, tolerance=tolerance)
    instances: list = []
    # the FMU files are checked before anything is written
    plan = None if in_process else (plan or fmu_paths(prep))
    names = column_names(len(prep.pantographs), len(prep.support_x), COSIM_COUNTERS)
    rec = Recorder(None if out_dir is None else Path(out_dir) / "timeseries.csv", names,
                   rows=prep.n_steps + 1)
    with stop_on_interrupt() as stop:
        return _run_cosim(prep, rec, scheme, settings, clock, plan, instances, progress,
                          stop, warnings)


def _run_cosim(prep, rec, scheme, settings, clock, plan, instances, progress, stop,
               warnings):
    """The set-up and time loop of :func:`run_cosim` (a Ctrl-C sets ``stop``: the loop ends
    after the step in flight; a diverging run stops with
    :class:`~pantocosim.master.stability.Diverged`)."""
    sc = prep.scenario
    monitor = Monitor(prep)
    error = None
    coupler = None
    t_wall = _time.perf_counter()
    t_loop = None
    try:
        if plan is None:
            csub, psubs = in_process_subsystems(prep)
        else:
            csub, psubs = fmu_subsystems(prep, instances, plan)
        coupler = Coupler(csub, psubs, prep.contact, settings)
        coupler.initialise(prep.static_forces)
        coupler.warm_up(0.0, sc.dt)
        n_p = len(psubs)
        n_sup = len(prep.support_x)

        #: a row: time, (x, contact force, contact height, wire height) per pantograph,
        #: support uplifts, coupling and Newton iterations (:func:`column_names`)
        width = len(rec.names)
        first_uplift = 1 + 4 * n_p

        def record(t, forces, iterations, newton):
            zp, _, zw, _ = coupler.interface()
            row = np.zeros(width)
            row[0] = t
            for k in range(n_p):
                row[1 + 4 * k:5 + 4 * k] = (spec_x(k, t), forces[k], zp[k], zw[k])
            u = csub.uplift()[:n_sup]
            row[first_uplift:first_uplift + len(u)] = u
            row[-2:] = iterations, newton
            rec.append(row)
            monitor.check(t, forces)

        def spec_x(k, t):
            return sc.pantographs[k].position_m + sc.speed * t

        record(0.0, prep.static_forces, 0, 0.0)
        bar = progress_bar(prep.n_steps, f"{sc.name} {scheme}", progress)
        t = 0.0
        t_loop = _time.perf_counter()
        try:
            stop.check(t, 0, prep.n_steps)   # a Ctrl-C during the set-up
            newton = coupler.catenary_newton_iterations
            for i in clock.steps(prep.n_steps):
                done = len(newton)
                iters = coupler.step(t, sc.dt)
                t = (i + 1) * sc.dt
                # explicit schemes record the force the law gives at the new state; implicit
                # records the converged interface force
                F = coupler.forces if coupler.scheme.iterative else coupler.contact_forces()
                record(t, F, iters, sum(newton[done:]))
                bar.update(1)
                stop.check(t, i + 1, prep.n_steps)
        finally:
            bar.close()
    except PantocosimError as exc:
        # an FMU that fails because a second Ctrl-C reached its Python code was interrupted
        error = exc if not stop.requested or isinstance(exc, Interrupted) else \
            _interrupted(rec, prep)
    except KeyboardInterrupt:
        error = _interrupted(rec, prep)
    finally:
        rec.close()
        for inst in instances:
            inst.terminate()
    end = _time.perf_counter()
    t_loop = end if t_loop is None else t_loop
    # wall time of the time stepping (what the real-time factor measures); setting up the
    # FMUs (instantiation, the catenary's initial configuration) is reported apart
    return RunResult(prep=prep, coupling=scheme, columns=rec.columns(),
                     wall_time_s=end - t_loop, error=error, setup_time_s=t_loop - t_wall,
                     summary=clock.summary(), warnings=warnings,
                     coupling_tolerance=(settings.tolerance if scheme_named(scheme).iterative
                                         else None))
