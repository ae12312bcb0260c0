"""Run an SSP file of pantocosim FMUs in ecos (the PythonFMU author's co-simulation engine)
via ecospy.

Recipe (docs/third-party.md)::

    apt-get install -y libtbb12            # ecospy's native library needs libtbb.so.12
    pip install -e ".[thirdparty]"          # ecospy
    pantocosim build-fmus                    # dist/fmus/*.fmu + dist/fmus/dsa380-ave-300.ssp
    python -m pantocosim.master.thirdparty.ecos [--ssp dist/fmus/dsa380-ave-300.ssp] [--step 0.001]
                               [--stop SECONDS] [--window START END] [--out CSV]

ecos loads the SSP (SystemStructure.ssd + resources/*.fmu), applies its parameter values and
connections and runs fixed-step coupling. The co-simulation runs in a child process (see
common.py); the time series goes to a CSV file and the statistics are printed.
"""

from __future__ import annotations

import os
import sys
import time

from pantocosim.master.thirdparty import common as run_common

MODULE = "pantocosim.master.thirdparty.ecos"


def child(ssp: str, step: float, stop: float, out: str, n_supports: int, x0: float,
          speed: float, parameter_set: str) -> None:
    import numpy as np
    import scipy.sparse.linalg  # noqa: F401  (B5: before any FMU is loaded)
    from ecospy import EcosSimulation
    from ecospy.lib import EcosLib

    EcosLib.set_log_level("warn")
    n = int(round(stop / step))
    names = (["catenary::contact_force_out_1", "pantograph::contact_height",
              "catenary::wire_height_1"]
             + [f"catenary::support_uplift_{j}" for j in range(n_supports)])
    rows = []
    ok = True
    t_wall, t_cpu = time.perf_counter(), time.process_time()
    sim = EcosSimulation(step_size=step, ssp_path=str(ssp))
    # ecos applies the SSP's parameter values only from the parameter set named here
    sim.init(parameter_set=parameter_set or None)
    t_init = time.perf_counter()

    def record(i):
        t = i * step
        rows.append([t, x0 + speed * t] + [sim.get_real(v) for v in names])

    record(0)
    try:
        for i in range(1, n + 1):
            sim.step(1)
            record(i)
    except Exception as exc:  # noqa: BLE001 - keep what was computed
        ok = False
        print(f"NOTE ecos stopped at t = {(len(rows) - 1) * step:g} s: {exc}")
    wall = time.perf_counter() - t_wall
    run_common.write_csv(out, run_common.columns(n_supports), np.array(rows))
    print(f"INIT {t_init - t_wall!r}")
    print(f"CPU {time.process_time() - t_cpu!r}")
    print(f"WALL {wall!r}", flush=True)
    os._exit(0 if ok else 3)


def main(argv=None) -> int:
    p = run_common.ssp_parser(__doc__, "ecos")
    a = p.parse_args(argv)
    if a.child:
        ssp, step, stop, out, n_sup, x0, speed, pset = a.child_args
        child(ssp, float(step), float(stop), out, int(n_sup), float(x0), float(speed), pset)
        return 0
    try:
        import ecospy  # noqa: F401 - loads its native library (libtbb.so.12)
    except (ImportError, OSError) as exc:
        print(f"ecos: error: ecospy cannot be loaded ({exc}); see the recipe: pip install "
              "ecospy, apt-get install -y libtbb12", file=sys.stderr)
        return 2
    r = run_common.ssp_run(a, "ecos")
    sets = r.ssd["parameter_sets"]
    if len(sets) > 1:
        raise SystemExit(f"{a.ssp}: several parameter set names {sets}; ecos applies one set "
                         "(by name) to every component")
    run_common.run_ssp_child(MODULE, a, r, sets[0] if sets else "")
    return 0


if __name__ == "__main__":
    sys.exit(main())
