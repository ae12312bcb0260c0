#!/usr/bin/env python3
"""The readings of the double pendulum's illegible data against the paper's out-of-plane
maxima of node 12 (the pendulum paper: 9e-7 / 0.025 / 0.08 m for rigid / steel / soft bars).

Fig. 2(a) of the paper shows a torque pulse whose peak reads 200 or 2000 N m over the 0.02 s
of its time axis, "tipo funcion delta"; its data line gives "m1 = m2 = 1 kg" beside a density
and section that make 7.02 kg per bar. Eight readings, 2 peaks x 2 shapes (triangular,
rectangular) x 2 bar masses (7.02 kg from density and section, 1 kg), each run on the three
cases, then ranked by the largest |ln(ours / paper)| over the three cases (ties: the RMS of
the three logs), the readings whose node 23 strikes the ground in every case first (the
paper's Fig. 7 and text have the impact in every case).

    python scripts/pendulum_readings.py [--cases steel,soft] [--jobs 2] [--reuse]
        [--duration 1.5] [--step 2.5e-4] [--cache out/pendulum-readings.json]
        [--docs docs/pendulum.md] [--extra] [--extra-cases steel,soft]

``--extra`` adds the runs that test other explanations on the best reading (by default on
the flexible cases): a stiffer and a softer ground contact, no contact damping, bar 2's
start leaning further out of the plane, and a longer run; the table also gives the maxima of
|z| of node 7 (middle of bar 1) and node 23 (tip of bar 2) of the same runs.
Each run goes to the JSON cache as it finishes (``--reuse`` keeps the runs already there);
the table is written between ``<!-- readings:start -->`` and ``<!-- readings:end -->`` of
the docs page (``<!-- readings-extra:start/end -->`` for ``--extra``).
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import itertools  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import multiprocessing  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from _tables import markdown_table, put_between  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MARKERS = ("<!-- readings:start -->", "<!-- readings:end -->")
EXTRA_MARKERS = ("<!-- readings-extra:start -->", "<!-- readings-extra:end -->")
PEAKS = (200.0, 2000.0)
SHAPES = ("triangular", "rectangular")
MASSES = (None, 1.0)          # None: from density and section (7.02 kg)
#: other explanations, each a name and the PendulumSpec fields it changes on the reading
EXTRA = {
    "contact k = 1e7 N/m": {"contact_stiffness": 1e7},
    "contact k = 1e5 N/m": {"contact_stiffness": 1e5},
    "contact c = 0": {"contact_damping": 0.0},
    "bar 2 leaning 60 deg": {"lean_deg": 60.0},
    "run of 3 s": {"duration": 3.0},
}


def key(case: str, reading: dict, extra: str = "") -> str:
    mass = "density" if reading["bar_mass"] is None else f"{reading['bar_mass']:g} kg"
    return (f"{case}|{reading['pulse_shape']}|{reading['pulse_peak']:g}|{mass}"
            + (f"|{extra}" if extra else ""))


def run_one(task) -> tuple[str, dict]:
    """One case of one reading: the maxima of |z| (the distance to the XY plane) of nodes
    12, 7 (middle of bar 1) and 23, when they occur, and the first impact. A run that fails
    (a beam element turning by 90 degrees within a step, or Newton) is run again with the
    step divided by 2, 4, then 16."""
    import numpy as np

    from pantocosim.core.errors import ConvergenceError
    from pantocosim.multibody.double_pendulum import CASES, load_spec, simulate_case

    case, reading, extra, duration, step, alpha = task
    fields = dict(EXTRA.get(extra, {}))
    duration = fields.pop("duration", duration)
    E, paper = CASES[case]
    spec = load_spec(E=E, **reading, **fields)
    t0 = time.perf_counter()
    try:
        _, r, h = simulate_case(spec, duration, step, alpha=alpha, nodes=(7, 12, 23),
                                divisors=(1, 2, 4, 16))
    except ConvergenceError as exc:
        return key(case, reading, extra), {"error": str(exc), "step": step / 16,
                                           "wall_s": round(time.perf_counter() - t0, 1)}
    z12 = np.abs(r.positions[12][:, 2])
    contact = np.nonzero(r.positions[23][:, 1] < spec.ground)[0]
    out = {
        "case": case, "reading": spec.reading(), "extra": extra, "E": E, "paper_m": paper,
        "bar_mass_kg": spec.mass, "step": h, "duration": duration,
        "max_z12_m": float(z12.max()), "t_max_z12_s": float(r.t[z12.argmax()]),
        "max_z7_m": float(np.abs(r.positions[7][:, 2]).max()),
        "max_z23_m": float(np.abs(r.positions[23][:, 2]).max()),
        "first_impact_s": float(r.t[contact[0]]) if contact.size else None,
        "pulse_work_J": float(r.energy["pulse_work"][-1]),
        "max_drift": float(r.drift.max()),
        "wall_s": round(time.perf_counter() - t0, 1),
    }
    return key(case, reading, extra), out


def readings():
    return [{"pulse_shape": s, "pulse_peak": p, "bar_mass": m}
            for p, s, m in itertools.product(PEAKS, SHAPES, MASSES)]


def score(res: dict, reading: dict, cases, extra: str = ""):
    """(largest |ln ratio|, RMS ln ratio, ratios) over ``cases``; None if a run is missing."""
    ratios = {}
    for c in cases:
        r = res.get(key(c, reading, extra))
        if r is None or "error" in r:
            return None
        ratios[c] = r["max_z12_m"] / r["paper_m"]
    logs = [math.log(x) for x in ratios.values()]
    return max(abs(x) for x in logs), math.sqrt(sum(x * x for x in logs) / len(logs)), ratios


def strikes(res: dict, reading: dict, cases, extra: str = "") -> bool:
    """Node 23 strikes the ground in every case, as in the paper (its Fig. 7 and text)."""
    return all((res.get(key(c, reading, extra)) or {}).get("first_impact_s") is not None
               for c in cases)


def label(reading: dict) -> str:
    mass = "7.02 kg (density)" if reading["bar_mass"] is None else f"{reading['bar_mass']:g} kg"
    return f"{reading['pulse_shape']}, {reading['pulse_peak']:g} N m, {mass}"


def table(res: dict, cases, extra_rows=None) -> tuple[str, list]:
    """The Markdown table of the readings, ranked; and the ranking [(reading, score)]."""
    from pantocosim.multibody.double_pendulum import CASES

    ranked = [(r, score(res, r, cases)) for r in readings()]
    ranked.sort(key=lambda x: (x[1] is None, not strikes(res, x[0], cases),
                               x[1][:2] if x[1] else ()))
    head = (["reading (pulse, peak, bar mass): node 12 max abs z in m (ratio to paper)"]
            + [f"{c} (paper {CASES[c][1]:g} m)" for c in cases]
            + ["max factor", "RMS ln ratio", "first impact (s)", "step (ms)"])
    rows = [["**paper**"] + [f"{CASES[c][1]:g}" for c in cases] + ["", "", "", ""]]
    for r, sc in ranked:
        cells = []
        for c in cases:
            x = res.get(key(c, r))
            cells.append("not run" if x is None else "failed" if "error" in x
                         else f"{x['max_z12_m']:.3g} ({x['max_z12_m'] / x['paper_m']:.2f})")
        xs = [res.get(key(c, r)) or {} for c in cases]
        impacts = " / ".join("-" if x.get("first_impact_s") is None else
                             f"{x['first_impact_s']:.3f}" for x in xs)
        steps = " / ".join(f"{x['step'] * 1e3:g}" if "step" in x else "-" for x in xs)
        rows.append([label(r)] + cells + ([f"{math.exp(sc[0]):.2f}", f"{sc[1]:.2f}"]
                                          if sc else ["", ""]) + [impacts, steps])
    return markdown_table(head, rows), ranked


def extra_table(res: dict, best: dict, cases) -> str:
    from pantocosim.multibody.double_pendulum import CASES

    head = (["run (on the chosen reading)"]
            + [f"{c}: node 12 (paper {CASES[c][1]:g} m)" for c in cases]
            + [f"{c}: node 7 / node 23" for c in cases]
            + [f"max factor node 12 ({', '.join(cases)})"])
    rows = []
    for name in [""] + list(EXTRA):
        if not all(key(c, best, name) in res for c in cases):
            continue
        xs = [res[key(c, best, name)] for c in cases]
        if any("error" in x for x in xs):
            rows.append([name or "as chosen"] + ["failed"] * (2 * len(cases) + 1))
            continue
        sc = score(res, best, cases, name)
        rows.append([name or "as chosen"]
                    + [f"{x['max_z12_m']:.3g} ({x['max_z12_m'] / x['paper_m']:.2f})" for x in xs]
                    + [f"{x['max_z7_m']:.3g} / {x['max_z23_m']:.3g}" for x in xs]
                    + [f"{math.exp(sc[0]):.2f}"])
    return markdown_table(head, rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default="rigid,steel,soft")
    ap.add_argument("--duration", type=float, default=1.5)
    ap.add_argument("--step", type=float, default=2.5e-4)
    ap.add_argument("--alpha", type=float, default=-0.05)
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (at most 2)")
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / "pendulum-readings.json")
    ap.add_argument("--docs", type=Path, default=ROOT / "docs" / "pendulum.md")
    ap.add_argument("--reuse", action="store_true", help="keep the runs already in the cache")
    ap.add_argument("--extra", action="store_true",
                    help="also the other explanations, on the best reading")
    ap.add_argument("--extra-cases", default="steel,soft",
                    help="the cases of the --extra runs (default: the flexible ones)")
    ap.add_argument("--extra-only", action="store_true",
                    help="only the --extra runs: the readings come from the cache")
    ap.add_argument("--no-docs", action="store_true", help="print only")
    a = ap.parse_args(argv)
    cases = [c.strip() for c in a.cases.split(",") if c.strip()]
    jobs = max(1, min(a.jobs, 2))
    a.extra = a.extra or a.extra_only
    reuse = a.reuse or a.extra_only
    res = json.loads(a.cache.read_text()) if reuse and a.cache.exists() else {}

    def launch(tasks):
        tasks = [t for t in tasks if key(t[0], t[1], t[2]) not in res]
        if not tasks:
            return
        with multiprocessing.Pool(jobs) as pool:
            for k, out in pool.imap_unordered(run_one, tasks):
                res[k] = out
                a.cache.parent.mkdir(parents=True, exist_ok=True)
                a.cache.write_text(json.dumps(res, indent=1) + "\n")
                print(f"{k}: " + (out["error"] if "error" in out else
                                  f"max |z| node 12 = {out['max_z12_m']:.3e} m at "
                                  f"{out['t_max_z12_s']:.3f} s, {out['wall_s']} s"),
                      flush=True)

    # flexible cases first, the readings that need small steps (rectangular 2000 N m) last
    order = sorted(cases, key=lambda c: c == "rigid")
    t0 = time.perf_counter()
    tasks = [(c, r, "", a.duration, a.step, a.alpha) for c in order for r in readings()]
    tasks.sort(key=lambda t: t[1]["pulse_shape"] == "rectangular" and t[1]["pulse_peak"] > 1e3)
    if not a.extra_only:
        launch(tasks)
    text, ranked = table(res, cases)
    print("\n" + text)
    best, sc = ranked[0]
    print(f"closest to the paper with node 23 striking the ground in every case: "
          f"{label(best)}: every case within a factor {math.exp(sc[0]):.2f} (RMS ln ratio "
          f"{sc[1]:.2f})")
    free = min((x for x in ranked if x[1] is not None), key=lambda x: x[1][:2])
    if free[0] is not best:
        print(f"closest of all: {label(free[0])}: within a factor {math.exp(free[1][0]):.2f} "
              f"(RMS ln ratio {free[1][1]:.2f}), but node 23 does not strike the ground "
              "in every case")
    doc = a.docs.read_text()
    doc = put_between(doc, MARKERS, text)
    ecases = []
    if a.extra:
        ecases = [c.strip() for c in a.extra_cases.split(",") if c.strip()]
    if a.extra and ecases:
        launch([(c, best, e, a.duration, a.step, a.alpha) for e in EXTRA for c in ecases])
        etext = extra_table(res, best, ecases)
        print("\n" + etext)
        doc = put_between(doc, EXTRA_MARKERS, etext)
    if not a.no_docs:
        a.docs.write_text(doc)
    print(f"{time.perf_counter() - t0:.0f} s wall")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
