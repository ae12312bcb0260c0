"""Run an SSP file of pantocosim FMUs in libcosim (Open Simulation Platform) via libcosimpy.

Recipe (docs/third-party.md)::

    pip install -e ".[thirdparty]"          # libcosimpy
    pantocosim build-fmus                    # dist/fmus/*.fmu + dist/fmus/dsa380-ave-300.ssp
    python -m pantocosim.master.thirdparty.libcosim [--ssp dist/fmus/dsa380-ave-300.ssp] [--step 0.001]
                                   [--stop SECONDS] [--window START END] [--out CSV]

libcosim loads the SSP (SystemStructure.ssd + resources/*.fmu), applies its parameter values
and connections and runs fixed-step Jacobi coupling. The pantograph x(t) = position_1 + V t of
the catenary FMU's parameters locates the analysis window (default: supports 5..6). The
co-simulation runs in a child process (see common.py); the time series goes to a CSV file
and the statistics are printed.
"""

from __future__ import annotations

import os
import sys
import time

from pantocosim.master.thirdparty import common as run_common

MODULE = "pantocosim.master.thirdparty.libcosim"


def child(ssp: str, step: float, stop: float, out: str, n_supports: int, x0: float,
          speed: float) -> None:
    import numpy as np
    import scipy.sparse.linalg  # noqa: F401  (B5: before any FMU is loaded)
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    step_ns = int(round(step * 1e9))
    n = int(round(stop / step))
    ex = CosimExecution.from_ssp_file(str(ssp), step_size=step_ns)
    ic = ex.slave_index_from_instance_name("catenary")
    ip = ex.slave_index_from_instance_name("pantograph")
    vc = {v.name.decode(): v.reference for v in ex.slave_variables(ic)}
    vp = {v.name.decode(): v.reference for v in ex.slave_variables(ip)}
    wanted = ([(ic, vc["contact_force_out_1"]), (ip, vp["contact_height"]),
               (ic, vc["wire_height_1"])]
              + [(ic, vc[f"support_uplift_{j}"]) for j in range(n_supports)])
    obs = CosimObserver.create_time_series()
    ex.add_observer(observer=obs)
    for idx, ref in wanted:
        obs.start_time_series(idx, ref, CosimVariableType.REAL)
    t_wall, t_cpu = time.perf_counter(), time.process_time()
    ok = ex.step(1)          # libcosim initialises the FMUs in the first step
    t_init = time.perf_counter()
    ok = ok and ex.step(n - 1)
    wall = time.perf_counter() - t_wall
    print(f"INIT {t_init - t_wall!r}")
    done = int(round(ex.status().current_time / step_ns))

    def samples(idx, ref):
        # libcosimpy 0.0.6 trims one sample per step number 0 it returns: read step 0..done-1
        # and step ``done`` separately
        _, steps_a, a = obs.time_series_real_samples(idx, ref, 0, done + 1)
        _, steps_b, b = obs.time_series_real_samples(idx, ref, done, 1)
        out = np.full(done + 1, np.nan)
        for s, v in zip(list(steps_a) + list(steps_b), list(a) + list(b)):
            if 0 <= s <= done:
                out[s] = v
        return out

    cols = [samples(i, r) for i, r in wanted]
    time_ = step * np.arange(done + 1)
    rows = np.column_stack([time_, x0 + speed * time_] + cols)
    run_common.write_csv(out, run_common.columns(n_supports), rows)
    if not ok or done < n:
        print(f"NOTE libcosim stopped at t = {done * step:g} s of {stop:g} s")
    print(f"CPU {time.process_time() - t_cpu!r}")
    print(f"WALL {wall!r}", flush=True)
    os._exit(0 if ok and done == n else 3)


def main(argv=None) -> int:
    p = run_common.ssp_parser(__doc__, "libcosim")
    a = p.parse_args(argv)
    if a.child:
        ssp, step, stop, out, n_sup, x0, speed = a.child_args
        child(ssp, float(step), float(stop), out, int(n_sup), float(x0), float(speed))
        return 0
    run_common.run_ssp_child(MODULE, a, run_common.ssp_run(a, "libcosim"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
