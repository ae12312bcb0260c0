"""Regression runs scripted with fmpy: a fixed set of cases run through the FMUs and compared
with references stored in the repository (``master/regression/``).

Each reference file ``<case>.json`` holds the statistics and a decimated time series of one
case; ``history.toml`` records the date and reason of every change of the references (as
Exudyn's test suite does). ``pantocosim regress`` prints a table of the comparisons;
``pantocosim regress --update --reason "..."`` rewrites the references and appends a history
entry.
"""

from __future__ import annotations

import datetime as _dt
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pantocosim.core.errors import ParameterError
from pantocosim.master.cosim import run_cosim
from pantocosim.master.fmu.build import default_out, ensure_fmus
from pantocosim.master.fmu.runtime import FmuInstance
from pantocosim.master.run import prepare

REGRESSION_DIR = Path(__file__).resolve().parent / "regression"
#: relative tolerances: statistics, and time series (max abs difference / signal scale)
STAT_RTOL = 1e-6
SERIES_RTOL = 1e-5
DECIMATE = 10


@dataclass
class CaseResult:
    name: str
    statistics: dict
    series: dict


def _pantograph_case(preset: str, fmu: Path) -> CaseResult:
    """A pantograph FMU under F(t) = F0 + 30 sin(4 pi t) for 2 s (fmpy, 1 ms steps)."""
    inst = FmuInstance(fmu, f"regress_{preset}")
    try:
        F0 = 120.0
        inst.initialize({"initial_contact_force": F0})
        rf = inst.refs(["contact_force"])
        ro = inst.refs(["contact_height", "contact_velocity"])
        h, n = 1e-3, 2000
        t = np.arange(n + 1) * h
        z = np.empty(n + 1)
        z[0] = inst.get_real(ro)[0]
        for i in range(n):
            inst.set_real(rf, [F0 + 30.0 * np.sin(4 * np.pi * t[i + 1])])
            inst.do_step(t[i], h)
            z[i + 1] = inst.get_real(ro)[0]
    finally:
        inst.terminate()
    stats = {"height_mean_m": float(z.mean()), "height_std_m": float(z.std()),
             "height_min_m": float(z.min()), "height_max_m": float(z.max())}
    return CaseResult(f"pantograph-{preset}", stats,
                      {"time": t[::DECIMATE], "contact_height": z[::DECIMATE]})


def _coupled_case(scheme: str) -> CaseResult:
    """The short EN 50318-type scenario co-simulated through the FMUs."""
    prep = prepare(REGRESSION_DIR / "short-en50318.toml")
    res = run_cosim(prep, None, scheme=scheme, progress=False)
    if res.error is not None:
        raise res.error
    st = res.statistics()[0].as_dict()
    keep = ("mean_n", "std_n", "stat_max_n", "stat_min_n", "max_n", "min_n",
            "loss_of_contact_percent", "max_uplift_at_support_m")
    c = res.columns
    return CaseResult(f"short-en50318-{scheme}", {k: st[k] for k in keep},
                      {"time": c["time"][::DECIMATE],
                       "contact_force": c["contact_force_1"][::DECIMATE]})


def cases() -> dict:
    dist = default_out()
    out = {}
    for preset in ("dsa380-rigid", "dsa380-lumped3", "en50318-2mass"):
        out[f"pantograph-{preset}"] = (lambda p=preset: _pantograph_case(p, dist / f"{p}.fmu"))
    for scheme in ("jacobi", "implicit"):
        out[f"short-en50318-{scheme}"] = (lambda s=scheme: _coupled_case(s))
    return out


def compare(result: CaseResult, reference: dict) -> tuple[bool, float, float]:
    """(passed, worst relative statistic difference, relative series difference)."""
    worst_stat = 0.0
    for key, ref in reference["statistics"].items():
        val = result.statistics.get(key, np.nan)
        scale = max(abs(ref), 1e-12)
        worst_stat = max(worst_stat, abs(val - ref) / scale if np.isfinite(val) else np.inf)
    worst_series = 0.0
    for key, ref in reference["series"].items():
        if key == "time":
            continue
        ref = np.asarray(ref, float)
        val = np.asarray(result.series[key], float)
        if val.shape != ref.shape:
            return False, worst_stat, np.inf
        scale = max(float(np.max(np.abs(ref))), 1e-12)
        worst_series = max(worst_series, float(np.max(np.abs(val - ref))) / scale)
    return (worst_stat <= STAT_RTOL and worst_series <= SERIES_RTOL), worst_stat, worst_series


def run_regression(update: bool = False, reason: str | None = None,
                   only: list[str] | None = None, printer=print) -> bool:
    if update and not reason:
        raise ParameterError("--reason", reason, "an update of the references needs a reason")
    known = list(cases())
    for name in only or []:
        if name not in known:
            raise ParameterError("--only", name, f"unknown case; one of {', '.join(known)}")

    dist = default_out()
    names = ["dsa380-rigid", "dsa380-lumped3", "en50318-2mass", "catenary"]
    ensure_fmus([dist / f"{n}.fmu" for n in names], dist)
    all_ok = True
    rows = []
    for name, fn in cases().items():
        if only and name not in only:
            continue
        result = fn()
        ref_file = REGRESSION_DIR / f"{name}.json"
        if update:
            ref_file.write_text(json.dumps({
                "case": name, "statistics": result.statistics,
                "series": {k: np.asarray(v).tolist() for k, v in result.series.items()}},
                indent=1) + "\n")
            rows.append((name, "updated", 0.0, 0.0))
            continue
        if not ref_file.exists():
            rows.append((name, "NO REFERENCE", np.nan, np.nan))
            all_ok = False
            continue
        ok, ds, dser = compare(result, json.loads(ref_file.read_text()))
        all_ok &= ok
        rows.append((name, "ok" if ok else "FAILED", ds, dser))
    if update:
        history = REGRESSION_DIR / "history.toml"
        entry = (f'\n[[change]]\ndate = "{_dt.date.today().isoformat()}"\n'
                 f'reason = {json.dumps(reason)}\ncases = {json.dumps([r[0] for r in rows])}\n')
        with open(history, "a") as fh:
            fh.write(entry)
    printer(f"{'case':<34} {'result':<13} {'stat diff':>10} {'series diff':>12}   "
            f"(tolerances {STAT_RTOL:g}, {SERIES_RTOL:g})")
    for name, status, ds, dser in rows:
        printer(f"{name:<34} {status:<13} {ds:>10.2e} {dser:>12.2e}")
    return all_ok
