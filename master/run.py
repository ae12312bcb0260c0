"""Running a scenario: set-up shared by every coupling, the monolithic reference run, outputs.

``prepare(scenario)`` validates the scenario against the catenary (speed below 0.7 of the wave
speed, analysis window inside the model, start positions on the line), builds the catenary
and pantograph models and the static start. ``run_monolithic`` integrates the assembled
system with the one HHT-alpha integrator. ``finish`` computes the EN 50317 statistics and
writes the CSV time series, the JSON summary and the plots; the co-simulation couplings reuse
``prepare`` and ``finish``.
"""

from __future__ import annotations

import math
import sys
import time as _time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pantocosim.core.errors import Interrupted, ParameterError, PantocosimError
from pantocosim.core.hht import HHTSettings
from pantocosim.core.contact_laws import ContactLaw, make_contact
from pantocosim.core.penalty_contact import DEFAULT_CONTACT_STIFFNESS
from pantocosim.master.interrupt import interrupted_at, stop_on_interrupt
from pantocosim.master.output_folder import writing
from pantocosim.master.recorder import Recorder
from pantocosim.master.results import write_json
from pantocosim.master.scenario import Scenario, load_scenario
from pantocosim.master.size_guard import check_steps
from pantocosim.master.statistics import contact_statistics, window_mask

#: EN 50119: operating speed at most 0.7 of the contact-wire wave speed
MAX_WAVE_SPEED_RATIO = 0.7


@dataclass
class Prepared:
    scenario: Scenario
    definition: object
    catenary: object            # a model of pantocosim.catenary.models (CatenaryModel...)
    pantographs: list           # PantographModel per pantograph
    contact: ContactLaw         # the scenario's contact law (pantocosim.core.contact_laws)
    window_m: tuple[float, float]
    duration: float
    n_steps: int
    q_cat0: np.ndarray
    q_pan0: list
    static_forces: np.ndarray
    wave_speed: float
    support_x: np.ndarray
    dropper_x: np.ndarray
    extra: dict = field(default_factory=dict)

    @property
    def speed(self) -> float:
        return self.scenario.speed


def analysis_window(sc: Scenario, definition) -> tuple[tuple[float, float], str, float]:
    """(window [m], the scenario field that sets it, duration [s]): the analysis window
    inside the model and the run's duration (by default
    :func:`~pantocosim.catenary.operating_height.passage_duration`)."""
    from pantocosim.catenary.operating_height import passage_duration

    support_x = definition.support_x
    length = float(support_x[-1])
    src = sc.source
    if sc.window_supports is not None:
        i, j = sc.window_supports
        if j > definition.n_spans:
            raise ParameterError("analysis.window_supports", list(sc.window_supports),
                                 f"the model has supports 0..{definition.n_spans}", src)
        window = (float(support_x[i]), float(support_x[j]))
        wfield = "analysis.window_supports"
    else:
        window = sc.window_m
        wfield = "analysis.window_m"
        if window[0] < 0 or window[1] > length:
            raise ParameterError(wfield, list(window),
                                 f"outside the model (0 .. {length:g} m)", src)
    if sc.duration_s is None:
        duration = passage_duration(window[1], [p.position_m for p in sc.pantographs],
                                    sc.speed)
    else:
        duration = sc.duration_s
    return window, wfield, float(duration)


def check_passages(sc: Scenario, definition, window, wfield: str, duration: float) -> None:
    """Every pantograph starts on the line before the analysis window, is raised (ramp
    start) before it and stays on the line until the run ends."""
    src = sc.source
    length = float(definition.support_x[-1])
    dfield = "simulation.duration_s" if sc.duration_s is not None else wfield
    dvalue = sc.duration_s if sc.duration_s is not None else list(window)
    for k, p in enumerate(sc.pantographs):
        if not (0.0 < p.position_m < length):
            raise ParameterError(f"pantographs[{k}].position_m", p.position_m,
                                 f"must lie on the line (0 .. {length:g} m)", src)
        if p.position_m > window[0]:
            raise ParameterError(f"pantographs[{k}].position_m", p.position_m,
                                 f"past the start of the analysis window ({wfield} starts "
                                 f"at {window[0]:g} m); a pantograph starts before it", src)
        if p.ramp is not None and p.ramp.start_m + p.ramp.length_m > window[0]:
            raise ParameterError(f"pantographs[{k}].ramp.length_m", p.ramp.length_m,
                                 f"the raising ends at x = "
                                 f"{p.ramp.start_m + p.ramp.length_m:g} m, inside the analysis "
                                 f"window ({window[0]:g} .. {window[1]:g} m); it must end "
                                 "before the window", src)
        if p.ramp is not None:
            z = float(definition.design_contact_height(p.position_m)[0])
            if p.ramp.lowered_height >= z:
                raise lowered_above_wire(sc, k, z)
        end = p.position_m + sc.speed * duration
        if end >= length:
            raise ParameterError(dfield, dvalue,
                                 f"pantograph {k + 1} would run past the end of the model "
                                 f"(x = {end:.0f} m > {length:g} m) before the run ends", src)
        if end < window[1]:
            raise ParameterError("simulation.duration_s", duration,
                                 f"too short: pantograph {k + 1} does not reach the end of "
                                 f"the analysis window", src)


def lowered_above_wire(sc: Scenario, k: int, z_wire: float) -> ParameterError:
    p = sc.pantographs[k]
    return ParameterError(f"pantographs[{k}].ramp.lowered_height", p.ramp.lowered_height,
                          f"not below the contact wire at the start ({z_wire:.3f} m at "
                          f"x = {p.position_m:g} m); a lowered pantograph is out of "
                          "contact", sc.source)


def check_size(sc: Scenario, base, definition, element_size, max_dofs, n_steps) -> int:
    """Size guard of the scenario's catenary model (before it is built): names the input
    that makes it large (``--element-size``, the scenario's ``spans`` or the catenary
    file's field)."""
    import dataclasses

    from pantocosim.catenary.mesh import estimate_dofs
    from pantocosim.master.size_guard import MAX_DOFS, check_catenary_size, culprit

    limit = MAX_DOFS if max_dofs is None else max_dofs
    if element_size is not None:
        definition = dataclasses.replace(definition, element_size=element_size)
        field, value, source = "--element-size", element_size, None
    elif sc.spans and estimate_dofs(base) <= limit:
        field, value, source = "spans", sc.spans, sc.source
    else:
        (field, value), source = culprit(base), base.source
    return check_catenary_size(definition, field, value, source, limit, n_steps)


def scenario_pantograph(sc: Scenario, k: int):
    """The model of the scenario's pantograph ``k`` (its options, speed and ramp); errors
    name the scenario's field."""
    from pantocosim.pantograph.base import Ramp
    from pantocosim.pantograph.presets import load_pantograph

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


def prepare(scenario: Scenario | str | None, force: bool = False,
            element_size: float | None = None, max_dofs: int | None = None,
            max_steps: int | None = None) -> Prepared:
    """Validate ``scenario`` and build the models and the static start; the size guard
    (:mod:`~pantocosim.master.size_guard`, limits ``max_dofs`` and ``max_steps``) runs before
    anything is built."""
    from pantocosim.catenary.models import law_model, make_catenary
    from pantocosim.master.scenario import scenario_catenary

    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    src = sc.source
    base = scenario_catenary(sc)
    definition = base
    if sc.spans:
        from pantocosim.catenary.definition import with_spans

        definition = with_spans(base, sc.spans)
    wave = definition.contact.wave_speed
    if sc.speed > MAX_WAVE_SPEED_RATIO * wave and not force:
        raise ParameterError("speed_kmh", sc.speed_kmh,
                             f"exceeds {MAX_WAVE_SPEED_RATIO} of the contact-wire wave speed "
                             f"c = {wave * 3.6:.0f} km/h (EN 50119 limit "
                             f"{MAX_WAVE_SPEED_RATIO * wave * 3.6:.0f} km/h); use --force to "
                             f"run anyway", src)
    support_x = definition.support_x
    window, wfield, duration = analysis_window(sc, definition)
    check_passages(sc, definition, window, wfield, duration)
    n_steps = int(math.ceil(duration / sc.dt - 1e-9))
    dofs = check_size(sc, base, definition, element_size, max_dofs, n_steps)
    check_steps(n_steps, "simulation.dt", sc.dt, src, max_steps, dofs)
    contact = make_contact(sc.contact_law, sc.contact_stiffness, sc.contact_damping)
    pantographs = [scenario_pantograph(sc, k) for k in range(len(sc.pantographs))]
    x0 = [p.position_m for p in sc.pantographs]
    catenary = make_catenary(sc.catenary_model, definition, x0=x0, speed=sc.speed,
                             element_size=element_size, modal_cutoff_hz=sc.modal_cutoff_hz)
    # The actuation of every pantograph is set so that it delivers its mean uplift at the mean
    # height of the contact wire under the moving mean force over the analysis window
    # (operating_height.py); the static start then solves catenary + pantographs + contacts
    # together,
    # so a pantograph that starts where the wire is higher or lower than the mean starts with
    # the matching force.
    F0 = np.array([pan.options.mean_uplift for pan in pantographs])
    from pantocosim.catenary.operating_height import mean_dynamic_wire_height

    z_mean = mean_dynamic_wire_height(law_model(catenary), F0, window, sc.dt, duration, sc.alpha)
    q_cat_guess = catenary.static_state(np.where(
        [spec.start == "static" for spec in sc.pantographs], F0, 0.0))
    q_pan_guess = []
    actuation_height = z_mean + F0 * contact.compliance
    for k, (pan, spec) in enumerate(zip(pantographs, sc.pantographs)):
        pan.static_equilibrium(F0[k], z_mean[k] + F0[k] * contact.compliance)
        if spec.start == "static":
            q = pan.static_equilibrium(F0[k], catenary.wire_height(0.0, q_cat_guess)[k]
                                       + F0[k] * contact.compliance)
            pan.static_equilibrium(F0[k], z_mean[k] + F0[k] * contact.compliance)
            q_pan_guess.append(q)
        else:
            q_pan_guess.append(pan.lowered_equilibrium(spec.ramp.lowered_height))
    from pantocosim.core.coupled import CoupledSystem

    system = CoupledSystem(catenary, pantographs, contact)
    q0 = static_start(sc, system, np.concatenate([q_cat_guess] + q_pan_guess))
    q_cat0, q_pan0 = system.split(q0)
    q_pan0 = [x.copy() for x in q_pan0]
    static = system.contact_forces(0.0, q0, np.zeros_like(q0))
    for k, spec in enumerate(sc.pantographs):
        if spec.start == "ramp" and static[k] > 0.0:
            raise lowered_above_wire(sc, k, float(catenary.wire_height(0.0, q_cat0)[k]))
    dropper_x = np.concatenate([support_x[s] + np.asarray(pos)
                                for s, pos in enumerate(definition.dropper_positions)])
    return Prepared(scenario=sc, definition=definition, catenary=catenary,
                    pantographs=pantographs, contact=contact, window_m=window,
                    duration=float(duration), n_steps=n_steps,
                    q_cat0=q_cat0, q_pan0=q_pan0, static_forces=static, wave_speed=wave,
                    support_x=np.asarray(support_x, float), dropper_x=dropper_x,
                    extra={"actuation_height": actuation_height, "mean_wire_height": z_mean,
                           "contact_law_state": system.law.get_state()})


def static_start(sc: Scenario, system, q_guess) -> np.ndarray:
    """The start state of the scenario (:meth:`CoupledSystem.static_solve`); a failure names
    the scenario, the start (static start in contact, or the ramp start's lowered
    pantographs) and the setting that makes it hard."""
    from pantocosim.core.contact_laws import CONTACT_LAWS
    from pantocosim.core.errors import ConvergenceError

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
    from pantocosim.core.coupled import CoupledSystem
    from pantocosim.core.errors import ConvergenceError

    undamped = make_contact(sc.contact_law, sc.contact_stiffness, 0.0)
    try:
        CoupledSystem(system.catenary, system.pantographs, undamped).static_solve(q_guess)
    except ConvergenceError:
        return False
    return True


def column_names(n_pantographs: int, n_supports: int) -> list[str]:
    names = ["time"]
    for k in range(1, n_pantographs + 1):
        names += [f"x_{k}", f"contact_force_{k}", f"contact_height_{k}", f"wire_height_{k}"]
    names += [f"support_uplift_{j}" for j in range(n_supports)]
    names += ["iterations"]
    return names


def progress_bar(total: int, label: str, enabled: bool | None = None):
    from tqdm import tqdm

    if enabled is None:
        enabled = sys.stderr.isatty()
    return tqdm(total=total, desc=label, unit="step", disable=not enabled, mininterval=0.5,
                smoothing=0.1)


def run_monolithic(prep: Prepared, out_dir: Path | None, progress: bool | None = None,
                   realtime: bool = False) -> "RunResult":
    """Integrate catenary + pantographs + penalty contacts monolithically (reference); with
    ``realtime`` each step is paced to the wall clock (:mod:`pantocosim.master.pacing`)."""
    from pantocosim.master import stability
    from pantocosim.master.pacing import StepClock
    from pantocosim.master.steppers import make_stepper

    sc = prep.scenario
    warnings = stability.check(prep, "monolithic")
    monitor = stability.Monitor(prep)
    stepper = make_stepper(prep, HHTSettings.for_runs(sc.alpha, sc.newton_rtol))
    stepper.warm_up(sc.dt)
    n_p = len(prep.pantographs)
    names = column_names(n_p, len(prep.support_x))
    rec = Recorder(None if out_dir is None else Path(out_dir) / "timeseries.csv", names,
                   rows=prep.n_steps + 1)
    t_wall = _time.perf_counter()

    row = np.zeros(len(names))

    def record(iterations):
        contacts, uplift = stepper.observe()
        t = stepper.t
        x = prep.catenary.positions(t)
        row[0] = t
        for k in range(n_p):
            row[1 + 4 * k:5 + 4 * k] = (x[k], *contacts[k])
        row[1 + 4 * n_p:-1] = uplift
        row[-1] = iterations
        rec.append(row)
        monitor.check(t, row[2:2 + 4 * n_p:4])

    error = None
    record(0)
    bar = progress_bar(prep.n_steps, f"{sc.name} monolithic", progress)
    clock = StepClock(sc.dt, realtime=realtime)
    with stop_on_interrupt() as stop:
        try:
            stop.check(stepper.t, 0, prep.n_steps)   # a Ctrl-C during the set-up
            for k in clock.steps(prep.n_steps):
                record(stepper.step(sc.dt))
                bar.update(1)
                stop.check(stepper.t, k + 1, prep.n_steps)
        except PantocosimError as exc:
            error = exc
        except KeyboardInterrupt:
            error = interrupted_at(rec.columns()["time"][-1], len(rec) - 1, prep.n_steps)
        finally:
            bar.close()
            rec.close()
    wall = _time.perf_counter() - t_wall
    result = RunResult(prep=prep, coupling="monolithic", columns=rec.columns(),
                       wall_time_s=wall, error=error, summary=clock.summary(),
                       warnings=warnings)
    return result


@dataclass
class RunResult:
    prep: Prepared
    coupling: str
    columns: dict
    wall_time_s: float
    error: Exception | None = None
    #: wall time spent before the time stepping (co-simulation: FMU set-up)
    setup_time_s: float = 0.0
    summary: dict = field(default_factory=dict)
    coupling_iterations: np.ndarray | None = None
    #: implicit co-simulation: the interface residual tolerance [N]
    coupling_tolerance: float | None = None
    #: co-simulation: the catenary's Newton iterations per step (all coupling iterations)
    newton_iterations: np.ndarray | None = None
    #: what makes the numbers doubtful (:mod:`pantocosim.master.stability`)
    warnings: list = field(default_factory=list)

    def statistics(self):
        prep = self.prep
        c = self.columns
        n_p = len(prep.pantographs)
        uplift = np.column_stack([c[f"support_uplift_{j}"] for j in range(len(prep.support_x))])
        return [contact_statistics(c["time"], c[f"contact_force_{k}"], c[f"x_{k}"],
                                   prep.window_m, uplift, prep.support_x)
                for k in range(1, n_p + 1)]


#: the files a run writes into its output folder (:func:`finish`)
RESULT_FILES = ("timeseries.csv", "summary.json", "contact_force.png", "spectrum.png",
                "support_uplift.png")


def finish(result: RunResult, out_dir: Path | None, plots: bool = True,
           report_dir: Path | None = None) -> dict:
    """Statistics, JSON summary and plots of a finished (or stopped) run, written into
    ``out_dir``; the summary names the files in ``report_dir`` (default ``out_dir``: where
    they end up, :class:`~pantocosim.master.output_folder.OutputFolder`). A stopped run's
    summary says where it stopped (``stopped``)."""
    prep = result.prep
    sc = prep.scenario
    c = result.columns
    stats = result.statistics() if result.error is None else []
    summary = {
        "scenario": sc.name,
        "coupling": result.coupling,
        "catenary": prep.definition.name,
        "speed_kmh": sc.speed_kmh,
        "dt_s": sc.dt,
        "wall_time_s": result.wall_time_s,
        "setup_time_s": result.setup_time_s,
        "simulated_time_s": float(c["time"][-1]) if len(c["time"]) else 0.0,
        "steps": int(len(c["time"]) - 1),
        "catenary_dofs": int(prep.catenary.n_dofs),
        "catenary_model": sc.catenary_model,
        "catenary_modes": getattr(prep.catenary, "n_modes", None),
        "analysis_window_m": list(prep.window_m),
        "target_mean_n": [float(p.options.mean_uplift) for p in prep.pantographs],
        "statistics": stats[0].as_dict() if stats else None,
        "pantographs": [{"index": k + 1, "model": spec.model, "position_m": spec.position_m,
                         "start": spec.start,
                         "statistics": stats[k].as_dict() if stats else None}
                        for k, spec in enumerate(sc.pantographs)],
        "newton_iterations_mean": float(np.mean(c["iterations"][1:])) if len(c["time"]) > 1
        else 0.0,
    }
    if result.newton_iterations is not None:
        # co-simulation: the iterations column holds coupling iterations
        summary["newton_iterations_mean"] = (float(np.mean(result.newton_iterations))
                                             if len(result.newton_iterations) else 0.0)
    if result.coupling_iterations is not None and len(result.coupling_iterations):
        summary["coupling_iterations_mean"] = float(np.mean(result.coupling_iterations))
        summary["coupling_iterations_max"] = int(np.max(result.coupling_iterations))
    if result.coupling_tolerance is not None:
        summary["coupling_tolerance_n"] = float(result.coupling_tolerance)
    try:
        import resource

        summary["peak_memory_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    except (ImportError, OSError):  # pragma: no cover - not on every platform
        pass
    summary["completed"] = result.error is None
    if result.error is not None:
        summary["error"] = str(result.error)
        summary["stopped"] = {"reason": str(result.error),
                              "interrupted": isinstance(result.error, Interrupted),
                              "time_s": summary["simulated_time_s"],
                              "steps": summary["steps"], "of_steps": int(prep.n_steps)}
    summary.update(result.summary)
    from pantocosim.master.stability import departures

    summary["warnings"] = list(result.warnings) + departures(prep, stats)
    #: the statistics are doubtful (see the warnings)
    summary["flagged"] = bool(summary["warnings"])
    if out_dir is not None:
        out = Path(out_dir)
        shown = Path(report_dir) if report_dir is not None else out
        summary["files"] = {"timeseries": str(shown / "timeseries.csv"),
                            "summary": str(shown / "summary.json")}
        if plots and stats:
            from pantocosim.master import plots as P

            n_p = len(prep.pantographs)
            labels = [f"pantograph {k}" for k in range(1, n_p + 1)]
            forces = [c[f"contact_force_{k}"] for k in range(1, n_p + 1)]
            positions = [c[f"x_{k}"] for k in range(1, n_p + 1)]
            title = f"{sc.name} ({result.coupling}, {sc.speed_kmh:g} km/h)"
            with writing("file", out / "contact_force.png"):
                P.plot_contact_force(out / "contact_force.png", c["time"], positions, forces,
                                     prep.window_m, prep.support_x, prep.dropper_x, labels,
                                     title)
            masks = [window_mask(x, *prep.window_m) for x in positions]
            with writing("file", out / "spectrum.png"):
                P.plot_spectrum(out / "spectrum.png", c["time"], forces, masks, labels, title)
            uplift = np.column_stack([c[f"support_uplift_{j}"]
                                      for j in range(len(prep.support_x))])
            with writing("file", out / "support_uplift.png"):
                P.plot_support_uplift(out / "support_uplift.png", c["time"], uplift,
                                      prep.support_x, title)
            summary["files"].update(contact_force=str(shown / "contact_force.png"),
                                    spectrum=str(shown / "spectrum.png"),
                                    support_uplift=str(shown / "support_uplift.png"))
        with writing("file", out / "summary.json"):
            write_json(out / "summary.json", summary)
    return summary
