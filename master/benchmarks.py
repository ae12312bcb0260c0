"""``pantocosim bench``: speed and memory of the solvers, as ratios measured in one run.

Each case runs as ``pantocosim run`` in its own process (so its peak memory is its own) on a
scenario written for the bench (fixed simulated time). Reported per case: wall time, simulated
time, real-time factor (wall / simulated), time per step, Newton and coupling iterations per
step, peak memory, and the ratios

- ``floor_ratio``: wall time per step / one solve with an already factorised catenary Newton
  matrix (the unavoidable work of any implicit method on the mesh), timed in this process;
- ``cosim_over_monolithic``: explicit co-simulation wall time / monolithic wall time;
- ``implicit_over_explicit``: implicit / explicit co-simulation wall time;

the distribution of the time per step (``p50_step_ms``, ``p99_step_ms``, ``max_step_ms``: the
compute time of each step with its recorded row, as ``pantocosim run`` reports it in
``step_time``; a real-time loop has to fit the p99 and the max, not the mean),

and the growth of the cost per simulated second per doubling of the number of spans, raw and
per catenary DOF. Wall times are those of the time stepping; the co-simulation's set-up (FMU
instantiation, the catenary's initial configuration inside the FMU) is reported apart.
"""

from __future__ import annotations

import dataclasses
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

from pantocosim.catenary.definition import load_catenary, with_spans
from pantocosim.catenary.model import CatenaryModel
from pantocosim.core.errors import PantocosimError, ParameterError
from pantocosim.core.hht import DEFAULT_ALPHA, HHTSettings
from pantocosim.master.cosim import fmu_paths, fmu_subsystems
from pantocosim.master.fmu.build import default_out, ensure_fmus
from pantocosim.master.native.host import build_host
from pantocosim.master.native.models import export_scenario
from pantocosim.master.run import prepare
from pantocosim.master.scenario import load_scenario

CASES = {
    # name: (catenary, spans, pantograph, speed km/h, position m)
    "en50318-300": ("en50318", 10, "en50318-2mass", 300.0, 30.0),
    "en50318-300-linear": ("en50318", 10, "en50318-2mass", 300.0, 30.0),
    "en50318-300-modal": ("en50318", 10, "en50318-2mass", 300.0, 30.0),
    "dsa380-ave-300-40span": ("ave64", 40, "dsa380-rigid", 300.0, 32.0),
}
#: extra ``[simulation]`` keys of a case (e.g. a catenary model option): a new variant of a
#: case is a new CASES entry with its options here
CASE_OPTIONS: dict[str, dict] = {"en50318-300-linear": {"catenary_model": "linear"},
                                 "en50318-300-modal": {"catenary_model": "modal"}}
#: simulated seconds of each case (quick, full); a case not listed runs 0.5 / 2.0 s
DURATIONS = {"en50318-300": (0.5, 2.0), "dsa380-ave-300-40span": (0.3, 1.0)}
#: catenary models of the span scaling (cost per simulated second on 10, 20, 40 spans)
SCALING_MODELS = ("nonlinear", "linear", "modal")
SCALING_SPANS = (10, 20, 40)
#: a model whose largest line does not fit this machine scales over fewer spans (the modal
#: model at its default cutoff keeps its modes on every DOF while it builds its tables:
#: about 3.4 GB on 40 spans)
SCALING_SPANS_OF = {"modal": (10, 20)}
COUPLINGS = ("monolithic", "explicit", "implicit")


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    return repr(value)


def scenario_text(name, catenary, spans, pantograph, speed, x0, duration,
                  simulation: dict | None = None) -> str:
    extra = "".join(f"{k} = {_toml_value(v)}\n" for k, v in (simulation or {}).items())
    return (f'name = "{name}"\ncatenary = "{catenary}"\nspans = {spans}\n'
            f"speed_kmh = {speed}\n\n[[pantographs]]\nmodel = \"{pantograph}\"\n"
            f"position_m = {x0}\nstart = \"static\"\n\n[analysis]\n"
            f"window_m = [{x0 + 1.0}, {x0 + speed / 3.6 * duration - 1.0}]\n\n"
            f"[simulation]\ndt = 0.001\nalpha = {DEFAULT_ALPHA}\nduration_s = {duration}\n{extra}")


def select_cases(names=None) -> list[str]:
    """The case names asked for (all by default); an unknown one is an error."""
    if not names:
        return list(CASES) + list(FIGURES)
    for name in names:
        if name not in CASES and name not in FIGURES:
            raise ParameterError("--case", name, f"unknown bench case; one of "
                                 f"{', '.join([*CASES, *FIGURES])}")
    return list(dict.fromkeys(names))


#: the short run of the time-to-result figures (the scenario, its options)
TIME_TO_RESULT = ("en50318-250", ["--catenary-model", "linear"])


def time_to_result(tmp: Path, printer=print) -> dict:
    """``pantocosim run en50318-250`` (linear catenary, monolithic) end to end (the process'
    wall time) against its time stepping, with an empty set-up cache (cold) and again with
    the entries the first run kept (warm)."""
    scenario, options = TIME_TO_RESULT
    env = {"PANTOCOSIM_CACHE_DIR": str(tmp / "setup-cache")}
    out = {}
    for label in ("cold", "warm"):
        s = run_case(Path(scenario), "monolithic", tmp / f"ttr-{label}", env, options)
        out[label] = {"process_wall_s": s["process_wall_s"], "stepping_s": s["wall_time_s"],
                      "end_to_end_over_stepping": s["process_wall_s"] / s["wall_time_s"]}
        printer(f"time to result, {scenario} linear monolithic, set-up cache {label}: "
                f"{s['process_wall_s']:.1f} s end to end, {s['wall_time_s']:.1f} s stepping: "
                f"ratio {out[label]['end_to_end_over_stepping']:.2f}")
    return out


#: what the FMU start measures: a fresh extraction (as fmpy's simulate_fmu makes), then
#: instantiate, set-up, initialisation and one step of the catenary FMU on the default
#: scenario's line, the forces given (as our master starts it); prints the seconds taken
FMU_START_PROBE = """
import sys, time
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
path = sys.argv[1]
md = read_model_description(path)
vr = {v.name: v.valueReference for v in md.modelVariables}
folder = extract(path)
t0 = time.perf_counter()
fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder, instanceName="catenary",
                modelIdentifier=md.coSimulation.modelIdentifier)
fmu.instantiate()
fmu.setupExperiment(startTime=0.0)
fmu.setString([vr["catenary_definition"]], ["ave64"])
fmu.setInteger([vr["spans"]], [10])
fmu.setReal([vr["speed_kmh"], vr["position_1"], vr["static_force_1"]], [300.0, 32.0, 120.0])
fmu.enterInitializationMode()
fmu.exitInitializationMode()
fmu.doStep(0.0, 1e-3)
print(time.perf_counter() - t0)
fmu.terminate()
fmu.freeInstance()
"""


def fmu_start(tmp: Path, printer=print) -> dict:
    """The catenary FMU's instantiate-to-first-step time in fmpy (its own process, a fresh
    extraction), with an empty set-up cache (cold) and again (warm); the FMU is built into
    ``dist/fmus`` first if missing or stale."""
    fmu = default_out() / "catenary.fmu"
    ensure_fmus([fmu], default_out())
    env = dict(os.environ, PANTOCOSIM_CACHE_DIR=str(tmp / "fmu-start-cache"))
    out = {}
    for label in ("cold", "warm"):
        run = subprocess.run([sys.executable, "-c", FMU_START_PROBE, str(fmu)], env=env,
                             capture_output=True, text=True)
        if run.returncode != 0:
            raise PantocosimError(f"fmu-start ({fmu}): {run.stderr.strip()[-500:]}")
        out[label] = {"instantiate_to_first_step_s": float(run.stdout.split()[-1])}
        printer(f"catenary FMU in fmpy, instantiate to first step, set-up cache {label}: "
                f"{out[label]['instantiate_to_first_step_s']:.2f} s")
    return out


#: the native-loop figure: scenario, simulated seconds, catenary models
NATIVE_LOOP = ("en50318-300", 2.0, ("linear", "modal"))


def _percentiles(times_s) -> dict:
    t = np.sort(np.asarray(times_s)) * 1e3
    return {"p50_ms": float(t[len(t) // 2]), "p99_ms": float(t[int(0.99 * (len(t) - 1))]),
            "max_ms": float(t[-1])}


def _host_percentiles(text: str, what: str) -> dict:
    """The host's line "<what> doStep us: p50 A p99 B max C" in ms."""
    for line in text.splitlines():
        if line.startswith(f"{what} doStep us:"):
            w = line.split()
            return {"p50_ms": float(w[4]) / 1e3, "p99_ms": float(w[6]) / 1e3,
                    "max_ms": float(w[8]) / 1e3}
    raise ValueError(f"no {what} timing in the host's output")


def python_fmu_loop(prep, steps: int, h: float) -> dict:
    """The doStep times of the Python catenary FMU (catenary_model of the scenario) and the
    Python pantograph FMU in fmpy, in the native loop's scheme: the master applies the
    penalty law to the heights and gives the force to both (explicit, zero-order hold):
    {"catenary": percentiles, "pantograph": percentiles}."""
    instances: list = []
    csub, psubs = fmu_subsystems(prep, instances, fmu_paths(prep))
    k_h = prep.contact.stiffness
    times = {"catenary": [], "pantograph": []}
    try:
        for i in range(steps):
            t = i * h
            zp = psubs[0].outputs()[0][0]
            zw = csub.outputs()[0][0]
            F = np.array([max(0.0, k_h * (zp - zw))])
            csub.set_forces(F)
            t0 = time.perf_counter()
            csub.step(t, h)
            t1 = time.perf_counter()
            psubs[0].set_forces(F)
            psubs[0].step(t, h)
            times["catenary"].append(t1 - t0)
            times["pantograph"].append(time.perf_counter() - t1)
    finally:
        for fmu in instances:
            fmu.terminate()
    return {key: _percentiles(value) for key, value in times.items()}


def native_coupled(host: Path, prep, folder: Path, steps: int) -> str:
    """The scenario's native FMUs (export-native into ``folder``, unpacked) stepped by the
    host's explicit loop (coupled-forces); its output."""
    written, _ = export_scenario(prep, folder, win64=False)
    folders = []
    for fmu in written:
        folders.append(folder / fmu.stem)
        with zipfile.ZipFile(fmu) as z:
            z.extractall(folders[-1])
    return subprocess.run([str(host), "coupled-forces", str(folders[0]), str(folders[1]),
                           str(steps), repr(prep.scenario.dt)], capture_output=True, text=True,
                          check=True).stdout


def native_loop(tmp: Path, printer=print) -> dict:
    """The native FMUs (``pantocosim export-native``) of en50318-300 stepped 2 s at 1 ms from
    a C loop (the C host of fmus/native/host, the master applies the penalty law): p50 / p99 /
    max of the catenary's doStep for each catenary model with the native 2-mass pantograph,
    beside the Python catenary FMU in the same loop (fmpy) and the floor solve."""
    scenario, seconds, models = NATIVE_LOOP
    host = build_host(tmp)
    out = {"floor_solve_ms": 1e3 * floor_per_step("en50318", 10)}
    for model in models:
        sc = dataclasses.replace(load_scenario(scenario), catenary_model=model)
        prep = prepare(sc)
        steps = int(round(seconds / sc.dt))
        text = native_coupled(host, prep, tmp / f"native-{model}", steps)
        entry = {"native_catenary": _host_percentiles(text, "catenary"),
                 "native_pantograph": _host_percentiles(text, "pantograph"),
                 "python_catenary_fmu": python_fmu_loop(prep, steps, sc.dt)["catenary"]}
        entry["native_p99_over_floor"] = entry["native_catenary"]["p99_ms"] / out["floor_solve_ms"]
        entry["python_p99_over_native_p99"] = (entry["python_catenary_fmu"]["p99_ms"]
                                              / entry["native_catenary"]["p99_ms"])
        out[model] = entry
        for label in ("native_catenary", "python_catenary_fmu", "native_pantograph"):
            printer(do_step_line(f"native loop {scenario} {model}: {label}", entry[label]))
    printer(f"native loop: floor solve {out['floor_solve_ms']:.3f} ms")
    return out


def do_step_line(label: str, e: dict) -> str:
    return (f"{label} doStep p50 {e['p50_ms']:.3f} ms, p99 {e['p99_ms']:.3f} ms, max "
            f"{e['max_ms']:.3f} ms")


#: the native DSA-380 figure: scenario (its catenary as the linear model, native too),
#: simulated seconds, pantograph models
NATIVE_DSA380 = ("dsa380-ave-300", 2.0, ("dsa380-rigid", "dsa380-flexible"))


def native_dsa380(tmp: Path, printer=print) -> dict:
    """The native rigid and flexible DSA-380 FMUs' doStep (p50 / p99 / max) in the C loop of
    :func:`native_loop` on dsa380-ave-300 (the native linear catenary beside them), and the
    Python DSA-380 FMUs' in the same loop in fmpy (with the Python catenary FMU)."""
    scenario, seconds, models = NATIVE_DSA380
    host = build_host(tmp)
    out = {}
    for model in models:
        sc = load_scenario(scenario)
        pans = [dataclasses.replace(p, model=model) for p in sc.pantographs]
        sc = dataclasses.replace(sc, pantographs=pans, catenary_model="linear")
        prep = prepare(sc)
        steps = int(round(seconds / sc.dt))
        text = native_coupled(host, prep, tmp / f"native-{model}", steps)
        entry = {"native_pantograph": _host_percentiles(text, "pantograph"),
                 "python_pantograph_fmu": python_fmu_loop(prep, steps, sc.dt)["pantograph"]}
        entry["python_p99_over_native_p99"] = (entry["python_pantograph_fmu"]["p99_ms"]
                                               / entry["native_pantograph"]["p99_ms"])
        out[model] = entry
        for label in ("native_pantograph", "python_pantograph_fmu"):
            printer(do_step_line(f"{scenario} {model}: {label}", entry[label]))
    return out


#: figures other than the step-time cases, by name (``--case NAME``)
FIGURES = {"time-to-result": time_to_result, "fmu-start": fmu_start, "native-loop": native_loop,
           "native-dsa380": native_dsa380}


def step_time_entry(summary: dict) -> dict:
    """p50 / p99 / max of the time per step from a run summary's ``step_time``."""
    st = summary.get("step_time") or {}
    return {"p50_step_ms": st.get("p50_ms"), "p99_step_ms": st.get("p99_ms"),
            "max_step_ms": st.get("max_ms")}


def run_case(path: Path, coupling: str, out: Path, env: dict | None = None,
             options=()) -> dict:
    cmd = [sys.executable, "-m", "pantocosim.master.cli", "run", str(path), "--coupling",
           coupling, "--out", str(out), "--json", "--no-plots", "--quiet", *options]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True,
                          env=None if env is None else {**os.environ, **env})
    wall_process = time.perf_counter() - t0
    if proc.returncode != 0:
        raise PantocosimError(f"{path.name} {coupling}: {proc.stderr.strip()[-500:]}")
    summary = json.loads(proc.stdout)
    summary["process_wall_s"] = wall_process
    return summary


def factorised_newton_matrix(model, h: float = 1e-3, alpha: float = DEFAULT_ALPHA):
    """``solve`` of a catenary model's HHT Newton matrix at its static configuration."""
    n = model.n_dofs
    ev = model.evaluate(0.0, model.q_static, np.zeros(n), np.zeros(n), None)
    return model.factorize(model.effective_matrix(
        ev, *HHTSettings(alpha=alpha).newton_coefficients(h)))


def floor_per_step(catenary: str, spans: int, repeats: int = 200, rounds: int = 5) -> float:
    """Seconds for one solve with a factorised catenary Newton matrix (HHT, 1 ms): the
    fastest of ``rounds`` rounds (as timeit does; a round at the start of a process can run
    before the processor has raised its clock)."""
    model = CatenaryModel(with_spans(load_catenary(catenary), spans), x0=(10.0,), speed=80.0)
    solve = factorised_newton_matrix(model)
    r = np.random.default_rng(0).standard_normal(model.n_dofs)
    solve(r)
    best = np.inf
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(repeats):
            solve(r)
        best = min(best, (time.perf_counter() - t0) / repeats)
    return best


def bench(quick: bool = False, printer=print, cases=None) -> dict:
    """Run the bench; ``cases`` (names of :data:`CASES`) restricts it to those cases and then
    skips the cold first run and the span scaling (they belong to the full bench)."""
    chosen = select_cases(cases)
    selected = [name for name in chosen if name in CASES]
    full = not cases
    results: dict = {"cases": {}, "machine": _machine()}
    with tempfile.TemporaryDirectory(prefix="pantocosim_bench_") as tmp:
        tmp = Path(tmp)
        for name in chosen:
            if name in FIGURES:
                results[name] = FIGURES[name](tmp, printer)
        if not selected:
            return results
        cat, spans, pan, v, x0 = CASES[selected[0]]
        if full:
            # cold first run: empty numba cache and FMUs extracted afresh (every kernel
            # compiles), reported apart
            cat, spans, pan, v, x0 = CASES["en50318-300"]
            cold = tmp / "cold.toml"
            cold.write_text(scenario_text("cold", cat, spans, pan, v, x0,
                                          _duration("en50318-300", quick)))
            s = run_case(cold, "explicit", tmp / "cold", env={
                "NUMBA_CACHE_DIR": str(tmp / "numba-cold"),
                "PANTOCOSIM_FMU_CACHE": str(tmp / "fmus-cold")})
            results["cold_first_run"] = {
                "process_wall_s": s["process_wall_s"], "setup_s": s.get("setup_time_s", 0.0),
                "real_time_factor": s["wall_time_s"] / s["simulated_time_s"]}
            results["cold_first_run_s"] = s["process_wall_s"]
        # a short run warms the user's caches for the measured runs
        warm = tmp / "warm.toml"
        warm.write_text(scenario_text("warm", cat, spans, pan, v, x0, 0.05))
        run_case(warm, "explicit", tmp / "warm")
        for name in selected:
            cat, spans, pan, v, x0 = CASES[name]
            path = tmp / f"{name}.toml"
            path.write_text(scenario_text(name, cat, spans, pan, v, x0, _duration(name, quick),
                                          CASE_OPTIONS.get(name)))
            floor = floor_per_step(cat, spans)
            case = {"floor_solve_s": floor}
            for coupling in COUPLINGS:
                s = run_case(path, coupling, tmp / f"{name}-{coupling}")
                steps = max(s["steps"], 1)
                entry = {"wall_s": s["wall_time_s"], "simulated_s": s["simulated_time_s"],
                         "setup_s": s.get("setup_time_s", 0.0), "steps": steps,
                         "catenary_dofs": s.get("catenary_dofs"),
                         "real_time_factor": s["wall_time_s"] / s["simulated_time_s"],
                         "time_per_step_ms": 1e3 * s["wall_time_s"] / steps,
                         "newton_iterations_per_step": s["newton_iterations_mean"],
                         "peak_memory_mb": s.get("peak_memory_mb"),
                         "floor_ratio": s["wall_time_s"] / steps / floor}
                entry.update(step_time_entry(s))
                if "coupling_iterations_mean" in s:
                    entry["coupling_iterations_mean"] = s["coupling_iterations_mean"]
                case[coupling] = entry
                printer(format_entry(name, coupling, entry))
            case["cosim_over_monolithic"] = case["explicit"]["wall_s"] / case["monolithic"]["wall_s"]
            case["implicit_over_explicit"] = case["implicit"]["wall_s"] / case["explicit"]["wall_s"]
            results["cases"][name] = case
        if full:
            results["scaling"] = {m: span_scaling(m, quick, tmp) for m in SCALING_MODELS}
    for name, case in results["cases"].items():
        printer(f"{name}: floor {1e3 * case['floor_solve_s']:.3f} ms/solve, cosim_over_monolithic "
                f"{case['cosim_over_monolithic']:.2f}, implicit_over_explicit "
                f"{case['implicit_over_explicit']:.2f}")
    if full:
        for model, sc in results["scaling"].items():
            printer(scaling_line(model, sc))
        cold = results["cold_first_run"]
        printer(f"cold first run (en50318-300 explicit, empty numba and FMU caches): process "
                f"{cold['process_wall_s']:.1f} s, set-up {cold['setup_s']:.1f} s, RTF "
                f"{cold['real_time_factor']:.2f}")
    return results


def span_scaling(model: str, quick: bool, tmp: Path) -> dict:
    """Cost per simulated second on 10, 20, 40 spans (:data:`SCALING_SPANS_OF` for a model
    that does not fit on 40) of the AVE line (rigid DSA-380, monolithic) with the catenary
    ``model``, and its growth per doubling."""
    spans = SCALING_SPANS_OF.get(model, SCALING_SPANS)
    cost, dofs, modes = {}, {}, {}
    for n_spans in spans:
        path = tmp / f"scale-{model}-{n_spans}.toml"
        path.write_text(scenario_text(f"scale{n_spans}", "ave64", n_spans, "dsa380-rigid",
                                      300.0, 32.0, 0.3 if quick else 0.5,
                                      {"catenary_model": model}))
        s = run_case(path, "monolithic", tmp / f"scale-{model}-{n_spans}")
        cost[n_spans] = s["wall_time_s"] / s["simulated_time_s"]
        dofs[n_spans] = s["catenary_dofs"]
        modes[n_spans] = s.get("catenary_modes")
    return {"spans": list(spans), "cost_per_simulated_s": cost, "catenary_dofs": dofs,
            "modes": modes,
            "growth_per_doubling": [cost[b] / cost[a] for a, b in zip(spans, spans[1:])],
            "growth_first_to_last": cost[spans[-1]] / cost[spans[0]]}


def scaling_line(model: str, sc: dict) -> str:
    spans = sc["spans"]
    dofs = ", ".join(str(sc["catenary_dofs"][k]) for k in spans)
    cost = ", ".join(f"{sc['cost_per_simulated_s'][k]:.2f} s" for k in spans)
    modes = ""
    if any(sc["modes"].get(k) for k in spans):
        modes = " (" + ", ".join(str(sc["modes"][k]) for k in spans) + " modes)"
    g = ", ".join(f"{x:.2f}" for x in sc["growth_per_doubling"])
    return (f"{model}: cost per simulated second, {'/'.join(map(str, spans))} spans ({dofs} "
            f"DOFs{modes}): {cost}; growth per doubling {g}; "
            f"{spans[0]} -> {spans[-1]} spans {sc['growth_first_to_last']:.2f}x")


def _duration(name: str, quick: bool) -> float:
    q, f = DURATIONS.get(name, (0.5, 2.0))
    return q if quick else f


def format_entry(name: str, coupling: str, entry: dict) -> str:
    """One printed line of a case and coupling."""
    def ms(x):
        return "    -" if x is None else f"{x:5.2f}"

    return (f"{name:<24} {coupling:<11} RTF {entry['real_time_factor']:7.2f}  "
            f"{entry['time_per_step_ms']:7.2f} ms/step (p99 {ms(entry.get('p99_step_ms'))}, "
            f"max {ms(entry.get('max_step_ms'))})  Newton "
            f"{entry['newton_iterations_per_step']:5.2f}/step  floor_ratio "
            f"{entry['floor_ratio']:6.1f}  peak {entry['peak_memory_mb'] or 0:7.0f} MB"
            f"  set-up {entry['setup_s']:5.2f} s")


def _machine() -> dict:
    return {"python": platform.python_version(), "cpus": os.cpu_count(),
            "processor": platform.processor() or platform.machine()}
