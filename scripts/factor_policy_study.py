#!/usr/bin/env python3
"""What the factorization policy costs (docs/performance.md, "Factorizations"): a scenario
run monolithically in one process with the kept factorization refreshed after steps of more
than 1, 2 (the runs' setting), 3 and 4 Newton iterations (``HHTSettings.refresh_after``);
per threshold the Newton iterations and factorizations per step, the processor time per
step, and the largest change of the contact force against the runs' setting.

    python scripts/factor_policy_study.py [--scenario en50318-300] [--steps 1000]
        [--docs docs/performance.md]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from _tables import markdown_table, write_between

from pantocosim.core.hht import HHTSettings
from pantocosim.master.run import prepare
from pantocosim.master.run.stepping import monolithic_stepper

ROOT = Path(__file__).resolve().parents[1]
MARKERS = ("<!-- factorizations:start -->", "<!-- factorizations:end -->")
THRESHOLDS = (1, 2, 3, 4)
HEAD = ("refresh after", "Newton it./step", "factorizations/step", "CPU ms/step",
        "max abs(dF) / mean F")


def run(prep, refresh_after: int, steps: int) -> dict:
    """``steps`` monolithic steps with the threshold ``refresh_after``."""
    settings = HHTSettings.for_runs(prep.scenario.alpha)
    settings.refresh_after = refresh_after
    stepper = monolithic_stepper(prep, settings)
    forces, iterations, factorizations = [], 0, 0
    t0 = time.thread_time()
    for _ in range(steps):
        report = stepper.step(prep.scenario.dt)
        iterations += report.iterations
        factorizations += report.refactorizations
        forces.append(stepper.contacts()[0][0])
    cpu = time.thread_time() - t0
    return {"iterations": iterations / steps, "factorizations": factorizations / steps,
            "cpu_ms": 1e3 * cpu / steps, "force": np.array(forces)}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenario", default="en50318-300")
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--docs", type=Path, default=None,
                   help="write the table into this page (docs/performance.md)")
    args = p.parse_args(argv)
    prep = prepare(args.scenario)
    runs = {k: run(prep, k, args.steps) for k in THRESHOLDS}
    ref = runs[2]["force"]
    rows = []
    for k, r in runs.items():
        change = np.max(np.abs(r["force"] - ref)) / np.mean(ref)
        label = f"{k} (runs)" if k == 2 else str(k)
        rows.append((label, f"{r['iterations']:.2f}", f"{r['factorizations']:.3f}",
                     f"{r['cpu_ms']:.2f}", "0" if k == 2 else f"{change:.1e}"))
    table = markdown_table(HEAD, rows)
    print(table)
    if args.docs is not None:
        write_between(args.docs, MARKERS, table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
