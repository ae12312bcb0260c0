#!/usr/bin/env python3
"""The modal catenary's cutoff study (docs/modal-cutoff.md): each scenario run
monolithically with the linear catenary (the modal model's own reference: the modal model
is the linear model on fewer coordinates) and with the modal one at each cutoff, same time
step; per cutoff the number of modes, the EN 50317 statistics' errors against the linear
run, max |dF| over the analysis window, the set-up time (modes and residual tables) and the
wall time per step (p50 of the run's step times).

    python scripts/modal_cutoff_study.py [--scenarios en50318-300 dsa380-ave-300]
        [--cutoffs 20 40 60 80 100 120] [--cache out/modal-cutoff-study.json]
        [--docs docs/modal-cutoff.md] [--reuse]

Each run's figures go to the JSON cache as they finish (``--reuse`` keeps the runs already
there); the table is written between ``<!-- cutoff:start -->`` and ``<!-- cutoff:end -->``
of the docs page.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
from _tables import markdown_table, write_between  # noqa: E402
from fast_catenary_study import errors, max_force_difference, within_targets  # noqa: E402

START, END = "<!-- cutoff:start -->", "<!-- cutoff:end -->"
SCENARIOS = ("en50318-300", "dsa380-ave-300")
CUTOFFS = (20.0, 40.0, 60.0, 80.0, 100.0, 120.0)


def run(scenario: str, model: str, cutoff: float | None = None) -> dict:
    """One monolithic run: statistics, contact forces, set-up and step times."""
    from pantocosim.catenary import models
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    sc = dataclasses.replace(load_scenario(scenario), catenary_model=model)
    if cutoff is not None:
        sc = dataclasses.replace(sc, modal_cutoff_hz=cutoff)
    factory = models.CATENARY_MODELS[model]
    timing = {}

    def timed(*args, **kwargs):
        t0 = time.perf_counter()
        out = factory(*args, **kwargs)
        timing["setup_s"] = time.perf_counter() - t0
        return out

    with models.CATENARY_MODELS.swapped(model, timed):
        prep = prepare(sc)
    res = run_monolithic(prep, None, progress=False)
    if res.error is not None:
        return {"error": str(res.error)}
    c = res.columns
    st = res.summary.get("step_time", {})
    return {"statistics": res.statistics()[0].as_dict(),
            "force": np.asarray(c["contact_force_1"]).tolist(),
            "x": np.asarray(c["x_1"]).tolist(), "window_m": list(prep.window_m),
            "setup_s": timing.get("setup_s"), "p50_ms": st.get("p50_ms"),
            "p99_ms": st.get("p99_ms"), "mean_ms": st.get("mean_ms"),
            "modes": getattr(prep.catenary, "m", None), "dofs": int(prep.catenary.n_dofs)}


def compare(ref: dict, r: dict) -> dict:
    """Errors of run ``r`` against the linear reference (first pantograph)."""
    err = errors(ref["statistics"], r["statistics"])
    dF = max_force_difference(ref["x"], ref["window_m"], r["force"], ref["force"])
    return {**err, "max_dF": dF, "ok": within_targets(err, "modal")}


def table(cache: dict, scenarios, cutoffs) -> str:
    head = markdown_table(("scenario", "cutoff [Hz]", "modes", "Δσ", "Δmean", "Δmax", "Δmin",
                           "Δuplift", "max abs dF [N]", "set-up [s]", "ms/step p50 (p99)",
                           "targets"), [])
    lines = []
    for sc in scenarios:
        ref = cache.get(f"{sc}/linear")
        if not ref or "error" in ref:
            continue
        s = ref["statistics"]
        lines.append(f"| {sc} | linear ({ref['dofs']} DOFs) | - | σ {s['std_n']:.2f} N | mean "
                     f"{s['mean_n']:.2f} N | {s['max_n']:.1f} N | {s['min_n']:.1f} N | "
                     f"{1e3 * s['max_uplift_at_support_m']:.1f} mm | - | "
                     f"{ref['setup_s']:.1f} | {ref['p50_ms']:.2f} ({ref['p99_ms']:.2f}) | ref. |")
        for f in cutoffs:
            r = cache.get(f"{sc}/modal/{f:g}")
            if not r:
                continue
            if "error" in r:
                lines.append(f"| {sc} | {f:g} | - | failed: {r['error']} |||||||||")
                continue
            e = compare(ref, r)
            lines.append(
                f"| {sc} | {f:g} | {r['modes']} | {e['std_n']:+.2f} % | {e['mean_n']:+.3f} % | "
                f"{e['max_n']:+.2f} % | {e['min_n']:+.2f} % | "
                f"{e['max_uplift_at_support_m']:+.2f} % | {e['max_dF']:.1f} | "
                f"{r['setup_s']:.1f} | {r['p50_ms']:.2f} ({r['p99_ms']:.2f}) | "
                f"{'yes' if e['ok'] else '**no**'} |")
    return head + "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenarios", nargs="+", default=list(SCENARIOS))
    p.add_argument("--cutoffs", nargs="+", type=float, default=list(CUTOFFS))
    p.add_argument("--cache", type=Path, default=ROOT / "out" / "modal-cutoff-study.json")
    p.add_argument("--docs", type=Path, default=ROOT / "docs" / "modal-cutoff.md")
    p.add_argument("--reuse", action="store_true", help="keep the runs already in the cache")
    a = p.parse_args(argv)
    cache = json.loads(a.cache.read_text()) if a.cache.exists() else {}
    jobs = [(sc, "linear", None) for sc in a.scenarios]
    jobs += [(sc, "modal", f) for sc in a.scenarios for f in a.cutoffs]
    for sc, model, f in jobs:
        key = f"{sc}/{model}" + ("" if f is None else f"/{f:g}")
        if a.reuse and key in cache and "error" not in cache[key]:
            continue
        t0 = time.perf_counter()
        cache[key] = run(sc, model, f)
        print(f"{key}: {time.perf_counter() - t0:.0f} s", flush=True)
        a.cache.parent.mkdir(parents=True, exist_ok=True)
        a.cache.write_text(json.dumps(cache))
    text = table(cache, a.scenarios, a.cutoffs)
    print(text)
    if a.docs.exists():
        write_between(a.docs, (START, END), text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
