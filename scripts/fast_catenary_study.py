#!/usr/bin/env python3
"""The accuracy study of the constant-matrix catenary models (docs/fast-catenary.md): every
preset scenario run monolithically with the nonlinear (reference), linear and modal catenary
at the same time step; per model the EN 50317 statistics of each pantograph against the
nonlinear run, max |dF| over the analysis window, the maximum uplift at the supports, and
the wall time per step.

    python scripts/fast_catenary_study.py [--scenarios en50318-250 ...] [--models linear modal]
        [--cache out/fast-catenary-study.json] [--docs docs/fast-catenary.md] [--reuse]

Each run's figures go to the JSON cache as they finish (``--reuse`` keeps the runs already
there), and the table is written between ``<!-- study:start -->`` and ``<!-- study:end -->``
of the docs page.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np
from _tables import markdown_table, put_between

ROOT = Path(__file__).resolve().parents[1]
START, END = "<!-- study:start -->", "<!-- study:end -->"
STATICS = "<!-- statics:start -->", "<!-- statics:end -->"
SCENARIOS = ("en50318-250", "en50318-300", "dsa380-ave-300", "benchmark-320",
             "dsa380-ave-300-double")
#: the accuracy targets [%]: mean, sigma, actual max/min, max uplift at supports
TARGETS = {"linear": (0.2, 1.0, 2.0, 3.0), "modal": (0.5, 2.0, 3.0, 5.0)}
QUANTITIES = ("mean_n", "std_n", "max_n", "min_n", "max_uplift_at_support_m")


def run(scenario: str, model: str) -> dict:
    """One monolithic run: statistics and contact-force history of every pantograph."""
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    sc = dataclasses.replace(load_scenario(scenario), catenary_model=model)
    t0 = time.perf_counter()
    prep = prepare(sc)
    setup = time.perf_counter() - t0
    res = run_monolithic(prep, None, progress=False)
    if res.error is not None:
        return {"error": str(res.error)}
    c = res.columns
    n_p = len(prep.pantographs)
    return {"statistics": [s.as_dict() for s in res.statistics()],
            "forces": [np.asarray(c[f"contact_force_{k}"]).tolist() for k in range(1, n_p + 1)],
            "positions": [np.asarray(c[f"x_{k}"]).tolist() for k in range(1, n_p + 1)],
            "window_m": list(prep.window_m), "setup_s": setup,
            "ms_per_step": 1e3 * res.wall_time_s / max(len(c["time"]) - 1, 1),
            "dofs": int(prep.catenary.n_dofs), "modes": getattr(prep.catenary, "m", None)}


def errors(s_ref: dict, s: dict) -> dict:
    """Relative errors [%] of the statistics ``s`` against ``s_ref``."""
    return {q: 100.0 * (s[q] - s_ref[q]) / abs(s_ref[q]) for q in QUANTITIES}


def within_targets(err: dict, model: str) -> bool | None:
    """Whether the errors meet the accuracy targets of ``model`` (None: it has none)."""
    limits = TARGETS.get(model)
    if not limits:
        return None
    worst = (abs(err["mean_n"]), abs(err["std_n"]), max(abs(err["max_n"]), abs(err["min_n"])),
             abs(err["max_uplift_at_support_m"]))
    return all(w <= t for w, t in zip(worst, limits))


def max_force_difference(x, window, force, force_ref) -> float:
    """max |F - F_ref| [N] while the pantograph at ``x`` is inside the analysis window."""
    x = np.asarray(x)
    inside = (x >= window[0]) & (x <= window[1])
    return float(np.max(np.abs(np.asarray(force) - np.asarray(force_ref))[inside]))


def compare(ref: dict, other: dict, model: str) -> list[dict]:
    """Rows (one per pantograph) of ``other`` against the reference run."""
    rows = []
    for k, (s_ref, s) in enumerate(zip(ref["statistics"], other["statistics"])):
        dF = max_force_difference(ref["positions"][k], ref["window_m"], other["forces"][k],
                                  ref["forces"][k])
        err = errors(s_ref, s)
        ok = within_targets(err, model)
        rows.append({"pantograph": k + 1, **{q: s[q] for q in QUANTITIES},
                     **{f"err_{q}": err[q] for q in QUANTITIES},
                     "max_dF": dF, "ms_per_step": other["ms_per_step"],
                     "modes": other.get("modes"), "within_targets": ok})
    return rows


def table(cache: dict, scenarios, models) -> str:
    head = markdown_table(("scenario", "model", "pant.", "mean [N] (Δ)", "σ [N] (Δ)",
                           "max [N] (Δ)", "min [N] (Δ)", "max uplift [mm] (Δ)",
                           "max abs dF [N]", "ms/step", "targets"), [])
    lines = []
    for sc in scenarios:
        ref = cache.get(f"{sc}/nonlinear")
        if not ref or "error" in ref:
            continue
        for model in ("nonlinear",) + tuple(models):
            r = cache.get(f"{sc}/{model}")
            if not r:
                continue
            if "error" in r:
                lines.append(f"| {sc} | {model} | - | failed: {r['error']} |||||||||")
                continue
            for row in compare(ref, r, model):
                def cell(q, scale=1.0, fmt=".1f"):
                    v = format(row[q] * scale, fmt)
                    return v if model == "nonlinear" else f"{v} ({row['err_' + q]:+.2f} %)"
                ok = {None: "ref.", True: "yes", False: "**no**"}[row["within_targets"]]
                name = model if row["modes"] is None else f"{model} ({row['modes']} modes)"
                lines.append(
                    f"| {sc} | {name} | {row['pantograph']} | {cell('mean_n', fmt='.2f')} | "
                    f"{cell('std_n', fmt='.2f')} | {cell('max_n')} | {cell('min_n')} | "
                    f"{cell('max_uplift_at_support_m', 1e3)} | "
                    f"{'-' if model == 'nonlinear' else format(row['max_dF'], '.2f')} | "
                    f"{row['ms_per_step']:.2f} | {ok} |")
    return head + "\n".join(lines) + "\n"


def static_uplift_table(catenary: str = "en50318", spans: int = 4,
                        forces=(20.0, 80.0, 150.0)) -> str:
    """Static uplift of the contact wire under an upward point force at midspan and at a
    support, nonlinear against linear: the linearisation's own error (second order)."""
    from pantocosim.catenary.definition import load_catenary, with_spans
    from pantocosim.catenary.linear import LinearCatenary
    from pantocosim.catenary.model import CatenaryModel

    line = with_spans(load_catenary(catenary), spans)
    models = (CatenaryModel(line), LinearCatenary(line))
    span = float(np.diff(line.support_x)[1])
    places = {"support 2": float(line.support_x[2]),
              "midspan 2-3": float(line.support_x[2]) + 0.5 * span}
    rows = ["| force [N] | place | nonlinear [mm] | linear [mm] | Δ |", "|---|---|---|---|---|"]
    for F in forces:
        for name, x in places.items():
            up = [m.contact_wire_height(m.static_solution([(x, F)]).q, [x])[0]
                  - m.contact_wire_height(m.q_static, [x])[0] for m in models]
            rows.append(f"| {F:.0f} | {name} | {1e3 * up[0]:.2f} | {1e3 * up[1]:.2f} | "
                        f"{100 * (up[1] - up[0]) / up[0]:+.2f} % |")
    return "\n".join(rows) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenarios", nargs="+", default=list(SCENARIOS))
    p.add_argument("--models", nargs="+", default=["linear", "modal"])
    p.add_argument("--cache", type=Path, default=ROOT / "out" / "fast-catenary-study.json")
    p.add_argument("--docs", type=Path, default=ROOT / "docs" / "fast-catenary.md")
    p.add_argument("--reuse", action="store_true", help="keep the runs already in the cache")
    a = p.parse_args(argv)
    cache = json.loads(a.cache.read_text()) if a.cache.exists() else {}
    for sc in a.scenarios:
        for model in ["nonlinear"] + a.models:
            key = f"{sc}/{model}"
            if a.reuse and key in cache and "error" not in cache[key]:
                continue
            print(f"running {key} ...", flush=True)
            cache[key] = run(sc, model)
            a.cache.parent.mkdir(parents=True, exist_ok=True)
            a.cache.write_text(json.dumps(cache))
    text = table(cache, a.scenarios, a.models)
    statics = static_uplift_table()
    print(text + "\n" + statics)
    doc = a.docs.read_text()
    a.docs.write_text(put_between(put_between(doc, (START, END), text), STATICS, statics))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
