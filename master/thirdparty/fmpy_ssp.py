"""Run an SSP file of pantocosim FMUs with fmpy's SSP support (``fmpy.ssp.simulate_ssp``).

Recipe (docs/third-party.md)::

    pantocosim build-fmus                   # dist/fmus/dsa380-ave-300.ssp and its FMUs
    python -m pantocosim.master.thirdparty.fmpy_ssp [--ssp dist/fmus/dsa380-ave-300.ssp]
        [--step 0.001] [--stop SECONDS] [--window START END] [--out CSV]

``simulate_ssp`` sets no parameter (it ignores the SSD's parameter bindings unless a
parameter set is passed, and cannot set String ones), exchanges nothing in initialisation mode
and passes 0 on every connection at the first step; it steps the FMUs in order with the
values of the previous step (Jacobi). The scenario's FMUs in the SSP carry the scenario in
their start values, so it runs the scenario unaided. It records the SSD's connectors after
each step, labelled with the step's start time: the recipe labels them with its end.
"""

from __future__ import annotations

import os
import sys
import time

from pantocosim.master.thirdparty import common as run_common

MODULE = "pantocosim.master.thirdparty.fmpy_ssp"


def child(ssp: str, step: float, stop: float, out: str, n_supports: int, x0: float,
          speed: float) -> None:
    import numpy as np
    import scipy.sparse.linalg  # noqa: F401  (before any FMU is loaded)
    from fmpy.ssp.simulation import simulate_ssp

    t_wall, t_cpu = time.perf_counter(), time.process_time()
    res = simulate_ssp(ssp, stop_time=stop - 0.5 * step, step_size=step)
    wall = time.perf_counter() - t_wall
    t = step * (np.arange(len(res)) + 1)
    cols = [res["catenary.contact_force_out_1"], res["pantograph.contact_height"],
            res["catenary.wire_height_1"]]
    cols += [res[f"catenary.support_uplift_{j}"] for j in range(n_supports)]
    rows = np.column_stack([t, x0 + speed * t] + cols)
    run_common.write_csv(out, run_common.columns(n_supports), rows)
    print(f"CPU {time.process_time() - t_cpu!r}")
    print(f"WALL {wall!r}", flush=True)
    os._exit(0)


def main(argv=None) -> int:
    p = run_common.ssp_parser(__doc__, "fmpy")
    a = p.parse_args(argv)
    if a.child:
        ssp, step, stop, out, n_sup, x0, speed = a.child_args
        child(ssp, float(step), float(stop), out, int(n_sup), float(x0), float(speed))
        return 0
    run_common.run_ssp_child(MODULE, a, run_common.ssp_run(a, "fmpy"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
