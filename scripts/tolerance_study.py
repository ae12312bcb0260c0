"""Effect of the Newton tolerance of simulation runs on the EN 50317 statistics.

Runs a scenario monolithically with ``newton_rtol`` = 1e-10 (converged to round-off) and
with looser tolerances, and prints a Markdown table of the contact-force statistics, the
largest difference of the force history and the Newton iterations per step.

    python scripts/tolerance_study.py [scenario] [rtol ...]
"""

from __future__ import annotations

import dataclasses
import sys

import numpy as np

from pantocosim.master.run import prepare, run_monolithic
from pantocosim.master.scenario import load_scenario


def main(argv: list[str]) -> None:
    name = argv[0] if argv else "en50318-300"
    tolerances = [float(x) for x in argv[1:]] or [1e-10, 1e-6, 1e-4, 1e-3]
    sc = load_scenario(name)
    prep = prepare(sc)
    rows = []
    ref = None
    for rtol in tolerances:
        prep.scenario = dataclasses.replace(sc, newton_rtol=rtol)
        run = run_monolithic(prep, None, progress=False)
        if run.error is not None:
            raise SystemExit(f"rtol {rtol:g}: {run.error}")
        F = run.columns["contact_force_1"]
        st = run.statistics()[0]
        its = float(np.mean(run.columns["iterations"][1:]))
        if ref is None:
            ref = F
        rows.append((rtol, st.mean_n, st.std_n, st.max_n, st.min_n,
                     float(np.max(np.abs(F - ref))), its, run.wall_time_s))
    print(f"## Newton tolerance ({sc.name}, monolithic, dt = {sc.dt * 1e3:g} ms)\n")
    print("| newton_rtol | mean [N] | sigma [N] | max [N] | min [N] | max abs(F - F_ref) [N] "
          "| Newton iterations per step | wall [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r[0]:g} | {r[1]:.4f} | {r[2]:.4f} | {r[3]:.3f} | {r[4]:.3f} | {r[5]:.2e} "
              f"| {r[6]:.2f} | {r[7]:.1f} |")


if __name__ == "__main__":
    main(sys.argv[1:])
