"""Co-simulation runs of a scenario: the pantograph FMUs and the catenary FMU coupled by the
master through their ports only (explicit Jacobi / Gauss-Seidel, or implicit with rollback).

The same coupling runs on in-process subsystems (:class:`ModelSubsystem`: a model and its own
HHT integrator behind the same port semantics), which the tests use to check the algorithms
against the monolithic solution without FMUs.
"""

from __future__ import annotations

import time as _time
from pathlib import Path

import numpy as np

from pantocosim.core.errors import ParameterError, PantocosimError
from pantocosim.core.hht import HHTIntegrator, HHTSettings
from pantocosim.master.coupling import Coupler, CouplingSettings
from pantocosim.master.recorder import Recorder
from pantocosim.master.run import Prepared, RunResult, column_names, progress_bar

MAX_SUPPORTS = 64


# ---------------------------------------------------------------------- subsystems
class ModelSubsystem:
    """A model with its own HHT integrator behind the FMU port semantics (in-process)."""

    def __init__(self, model, q0, settings: HHTSettings, inputs0, outputs):
        self.model = model
        self.integ = HHTIntegrator(model, settings)
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
    """FMU state save/restore/free of an adapter holding ``self.fmu``."""

    def get_state(self):
        return self.fmu.get_state()

    def set_state(self, s):
        self.fmu.set_state(s)

    def free_state(self, s):
        self.fmu.free_state(s)


class FmuPantograph(_FmuState):
    """A pantograph FMU behind the common port contract."""

    def __init__(self, fmu):
        self.fmu = fmu
        self.r_in = fmu.refs(["contact_force"])
        self.r_out = fmu.refs(["contact_height", "contact_velocity"])

    def set_forces(self, forces):
        self.fmu.set_real(self.r_in, forces)

    def step(self, t, h):
        self.fmu.do_step(t, h)

    def outputs(self):
        z, v = self.fmu.get_real(self.r_out)
        return np.array([z]), np.array([v])


class FmuCatenary(_FmuState):
    """The catenary FMU: contact_force_k in, wire_height_k / wire_velocity_k out."""

    def __init__(self, fmu, n_pantographs: int, n_supports: int):
        self.fmu = fmu
        k = range(1, n_pantographs + 1)
        self.r_in = fmu.refs([f"contact_force_{i}" for i in k])
        self.r_out = fmu.refs([f"wire_height_{i}" for i in k] + [f"wire_velocity_{i}" for i in k])
        self.n = n_pantographs
        self.r_uplift = fmu.refs([f"support_uplift_{j}" for j in range(n_supports)])
        self.r_newton = fmu.refs(["newton_iterations"])

    def set_forces(self, forces):
        self.fmu.set_real(self.r_in, forces)

    def step(self, t, h):
        self.fmu.do_step(t, h)

    def newton_iterations(self) -> float:
        return float(self.fmu.get_real(self.r_newton)[0])

    def outputs(self):
        y = self.fmu.get_real(self.r_out)
        return y[:self.n], y[self.n:]

    def uplift(self):
        return self.fmu.get_real(self.r_uplift)


# ---------------------------------------------------------------------- set-up
def in_process_subsystems(prep: Prepared):
    """Catenary and pantograph models as in-process subsystems, in the static start."""
    cat = prep.catenary
    sc = prep.scenario
    csub = ModelSubsystem(cat, prep.q_cat0, HHTSettings.for_runs(sc.alpha, sc.newton_rtol),
                          prep.static_forces,
                          lambda integ: (cat.wire_height(integ.t, integ.q),
                                         cat.wire_velocity(integ.t, integ.q, integ.v)))
    psubs = []
    for k, pan in enumerate(prep.pantographs):
        psubs.append(ModelSubsystem(
            pan, prep.q_pan0[k], HHTSettings(alpha=sc.alpha), prep.static_forces[k:k + 1],
            lambda integ, pan=pan: (np.array([pan.contact_height(integ.q)]),
                                    np.array([pan.contact_velocity(integ.q, integ.v)]))))
    return csub, psubs


def fmu_paths(prep: Prepared, build: bool = True) -> tuple[Path, list[Path]]:
    """FMU files of the scenario: a pantograph's ``fmu`` (relative to the working folder, else
    to the scenario file), by default ``dist/fmus/<model>.fmu`` of the working folder; the
    default ones are built if missing or stale."""
    from pantocosim.master.fmu_build import default_out, ensure_fmus

    sc = prep.scenario
    base = Path(sc.source).resolve().parent
    dist = default_out()
    pans = []
    for spec in sc.pantographs:
        if spec.fmu:
            p = Path(spec.fmu)
            if not p.is_absolute() and not p.exists() and (base / p).exists():
                p = base / p
        else:
            p = dist / f"{spec.model}.fmu"
        pans.append(p)
    cat = dist / "catenary.fmu"
    if build:
        ensure_fmus(pans + [cat], dist)
    missing = [p for p in pans + [cat] if not p.exists()]
    if missing:
        raise ParameterError("fmu", str(missing[0]), "FMU file not found (run "
                             "`pantocosim build-fmus`)", sc.source)
    return cat, pans


def fmu_subsystems(prep: Prepared, instances: list):
    """Instantiate and initialise the FMUs of the scenario in the static start."""
    from pantocosim.master.fmu_runtime import FmuInstance

    sc = prep.scenario
    cat_path, pan_paths = fmu_paths(prep)
    n_p = len(prep.pantographs)
    if n_p > 4:
        raise ParameterError("pantographs", n_p, "the catenary FMU takes at most 4", sc.source)
    cat_fmu = FmuInstance(cat_path, "catenary")
    instances.append(cat_fmu)
    params = {"catenary_definition": sc.catenary, "speed_kmh": sc.speed_kmh, "n_pantographs": n_p,
              "hht_alpha": sc.alpha, "contact_mode": 0, "newton_rtol": sc.newton_rtol}
    if sc.spans:
        params["spans"] = sc.spans
    if sc.catenary_model != "nonlinear":
        from pantocosim.catenary.models import MODEL_NAMES

        params["catenary_model"] = MODEL_NAMES.index(sc.catenary_model)
        params["modal_cutoff_hz"] = sc.modal_cutoff_hz
    for k, spec in enumerate(sc.pantographs, start=1):
        params[f"position_{k}"] = spec.position_m
        params[f"static_force_{k}"] = float(prep.static_forces[k - 1])
    cat_fmu.initialize(params)
    n_sup = min(len(prep.support_x), MAX_SUPPORTS)
    csub = FmuCatenary(cat_fmu, n_p, n_sup)
    psubs = []
    z_w0, _ = csub.outputs()
    for k, (spec, pan, path) in enumerate(zip(sc.pantographs, prep.pantographs, pan_paths)):
        fmu = FmuInstance(path, f"pantograph_{k + 1}")
        instances.append(fmu)
        F0 = pan.options.mean_uplift
        p = {"speed_kmh": sc.speed_kmh, "hht_alpha": sc.alpha}
        for key, value in spec.options.items():
            if fmu.has(key):
                p[key] = value
        if spec.start == "static":
            Fs = float(prep.static_forces[k])
            p.update(initial_contact_force=Fs, start_mode=0,
                     initial_height=float(pan.contact_height(prep.q_pan0[k])))
        else:
            ramp = pan.options.ramp
            p.update(initial_contact_force=F0, start_mode=1,
                     initial_height=float(prep.extra["actuation_height"][k]),
                     ramp_start_time=ramp.start, ramp_duration=ramp.duration,
                     lowered_height=ramp.lowered_height)
        fmu.initialize(p)
        psubs.append(FmuPantograph(fmu))
    return csub, psubs


# ---------------------------------------------------------------------- the run
def coupling_tolerance(prep: Prepared) -> float:
    """Interface residual tolerance [N] of the implicit coupling: the scenario's
    ``coupling_rtol`` times the largest mean contact force of its pantographs."""
    scale = max([float(p.options.mean_uplift) for p in prep.pantographs] + [1.0])
    return prep.scenario.coupling_rtol * scale


def run_cosim(prep: Prepared, out_dir: Path | None, scheme: str = "jacobi",
              accelerator: str = "iqn-imvj", progress: bool | None = None,
              in_process: bool = False, tolerance: float | None = None,
              realtime: bool = False) -> RunResult:
    """Co-simulate the scenario through the FMUs (or in-process subsystems); ``tolerance``
    [N] of the implicit coupling defaults to :func:`coupling_tolerance`; with ``realtime``
    each communication step is paced to the wall clock (:mod:`pantocosim.master.pacing`)."""
    from pantocosim.master.pacing import StepClock

    sc = prep.scenario
    clock = StepClock(sc.dt, realtime=realtime)
    if tolerance is None:
        tolerance = coupling_tolerance(prep)
    settings = CouplingSettings(scheme=scheme, accelerator=accelerator, tolerance=tolerance)
    instances: list = []
    names = column_names(len(prep.pantographs), len(prep.support_x))
    rec = Recorder(None if out_dir is None else Path(out_dir) / "timeseries.csv", names)
    error = None
    t_wall = _time.perf_counter()
    t_loop = None
    try:
        if in_process:
            csub, psubs = in_process_subsystems(prep)
        else:
            csub, psubs = fmu_subsystems(prep, instances)
        coupler = Coupler(csub, psubs, prep.contact, settings)
        coupler.initialise(prep.static_forces)
        n_p = len(psubs)
        n_sup = len(prep.support_x)

        def record(t, forces, iterations):
            zp, vp, zw, vw = coupler._interface()
            up = np.zeros(n_sup)
            u = csub.uplift()
            up[:min(n_sup, len(u))] = u[:n_sup]
            row = [t]
            for k in range(n_p):
                row += [spec_x(k, t), forces[k], zp[k], zw[k]]
            row += list(up)
            row.append(iterations)
            rec.append(row)

        def spec_x(k, t):
            return sc.pantographs[k].position_m + sc.speed * t

        record(0.0, prep.static_forces, 0)
        bar = progress_bar(prep.n_steps, f"{sc.name} {scheme}", progress)
        t = 0.0
        t_loop = _time.perf_counter()
        try:
            for i in clock.steps(prep.n_steps):
                iters = coupler.step(t, sc.dt)
                t = (i + 1) * sc.dt
                # explicit schemes record the force the law gives at the new state; implicit
                # records the converged interface force
                F = coupler.forces if scheme == "implicit" else coupler.contact_forces()
                record(t, F, iters)
                bar.update(1)
        finally:
            bar.close()
        iterations = np.array(coupler.iterations)
        newton = np.array(coupler.catenary_newton_iterations)
    except PantocosimError as exc:
        error = exc
        iterations = newton = np.zeros(0)
    finally:
        rec.close()
        for inst in instances:
            inst.terminate()
    end = _time.perf_counter()
    t_loop = end if t_loop is None else t_loop
    # wall time of the time stepping (what the real-time factor measures); setting up the
    # FMUs (instantiation, the catenary's initial configuration) is reported apart
    result = RunResult(prep=prep, coupling=scheme, columns=rec.columns(),
                       wall_time_s=end - t_loop, error=error, setup_time_s=t_loop - t_wall,
                       summary=clock.summary())
    result.coupling_iterations = iterations if scheme == "implicit" else None
    result.coupling_tolerance = tolerance if scheme == "implicit" else None
    result.newton_iterations = newton
    return result
