"""Effect of the tolerances of simulation runs on the EN 50317 statistics.

Runs a scenario monolithically with ``newton_rtol`` = 1e-10 (converged to round-off) and
with looser tolerances, and prints a Markdown table of the contact-force statistics, the
largest difference of the force history and the Newton iterations per step. With
``--coupling`` it runs the implicit co-simulation (in-process subsystems, the run's
``newton_rtol``) at each ``coupling_rtol`` instead, against the same round-off reference.

    python scripts/tolerance_study.py [--coupling] [scenario] [rtol ...]
"""

from __future__ import annotations

import dataclasses
import sys

import numpy as np
from _tables import markdown_table

from pantocosim.master.cosim import run_cosim
from pantocosim.master.run import prepare, run_monolithic
from pantocosim.master.scenario import load_scenario


def main(argv: list[str]) -> None:
    coupling = "--coupling" in argv
    argv = [a for a in argv if a != "--coupling"]
    name = argv[0] if argv else "en50318-300"
    tolerances = [float(x) for x in argv[1:]] or (
        [1e-6, 1e-4, 1e-3] if coupling else [1e-10, 1e-6, 1e-4, 1e-3])
    sc = load_scenario(name)
    prep = prepare(sc)
    prep.scenario = dataclasses.replace(sc, newton_rtol=1e-10)
    ref_run = run_monolithic(prep, None, progress=False)
    ref = ref_run.columns["contact_force_1"]
    rows = []
    for rtol in tolerances:
        if coupling:
            prep.scenario = dataclasses.replace(sc, coupling_rtol=rtol)
            run = run_cosim(prep, None, scheme="implicit", progress=False, in_process=True)
            its = float(np.mean(run.coupling_iterations))
        else:
            prep.scenario = dataclasses.replace(sc, newton_rtol=rtol)
            run = ref_run if rtol == 1e-10 else run_monolithic(prep, None, progress=False)
            its = float(np.mean(run.columns["newton_iterations"][1:]))
        if run.error is not None:
            raise SystemExit(f"rtol {rtol:g}: {run.error}")
        F = run.columns["contact_force_1"]
        st = run.statistics()[0]
        rows.append((rtol, st.mean_n, st.std_n, st.max_n, st.min_n,
                     float(np.max(np.abs(F - ref))), its, run.wall_time_s))
    if coupling:
        print(f"## Coupling tolerance ({sc.name}, implicit co-simulation, newton_rtol "
              f"{sc.newton_rtol:g}, dt = {sc.dt * 1e3:g} ms; reference: monolithic, newton_rtol "
              f"1e-10)\n")
        head = "coupling_rtol", "coupling iterations per step"
    else:
        print(f"## Newton tolerance ({sc.name}, monolithic, dt = {sc.dt * 1e3:g} ms)\n")
        head = "newton_rtol", "Newton iterations per step"
    print(markdown_table(
        (head[0], "mean [N]", "sigma [N]", "max [N]", "min [N]", "max abs(F - F_ref) [N]",
         head[1], "wall [s]"),
        [(f"{r[0]:g}", f"{r[1]:.4f}", f"{r[2]:.4f}", f"{r[3]:.3f}", f"{r[4]:.3f}",
          f"{r[5]:.2e}", f"{r[6]:.2f}", f"{r[7]:.1f}") for r in rows]), end="")


if __name__ == "__main__":
    main(sys.argv[1:])
