"""Run the default scenario in CoFmuPy from its shipped configuration
(``dist/fmus/<scenario>/cofmupy.json``, written by ``pantocosim build-fmus``).

Recipe (docs/third-party.md)::

    python -m venv cofmupy-venv && cofmupy-venv/bin/pip install cofmupy==1.0.0 numba
    pantocosim build-fmus
    python -m pantocosim.master.thirdparty.cofmupy_json --python cofmupy-venv/bin/python
        [--config dist/fmus/dsa380-ave-300/cofmupy.json] [--ssp dist/fmus/dsa380-ave-300.ssp]
        [--step 0.001] [--stop SECONDS] [--window START END] [--out CSV]

CoFmuPy 1.0 pins pythonfmu 0.6.3 (this project pins 0.7.0), so it lives in a venv of its own;
the FMUs run in any Python with numpy, scipy and numba. CoFmuPy sets every start value with
fmi2SetReal and exchanges nothing in initialisation mode; the shipped configuration sets none
(the scenario's FMUs carry the scenario) and couples by Jacobi. The FMU paths in the
configuration are relative to its folder, where the child runs. The SSP file gives the
catenary's layout and the window for the statistics.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

MODULE = "pantocosim.master.thirdparty.cofmupy_json"
OUTPUTS = [("catenary", "contact_force_out_1"), ("pantograph", "contact_height"),
           ("catenary", "wire_height_1")]


def child(config: str, step: float, stop: float, out: str, n_supports: int, x0: float,
          speed: float) -> None:
    """Runs in CoFmuPy's venv: imports neither pantocosim nor anything beyond CoFmuPy."""
    import csv

    import scipy.sparse.linalg  # noqa: F401  (before any FMU is loaded)
    from cofmupy import Coordinator

    os.chdir(Path(config).parent)
    t_wall, t_cpu = time.perf_counter(), time.process_time()
    coord = Coordinator()
    coord.start(Path(config).name)
    n = int(round(stop / step))
    for _ in range(n):
        coord.do_step(step)
    wall = time.perf_counter() - t_wall
    res = coord.get_results()
    keys = OUTPUTS + [("catenary", f"support_uplift_{j}") for j in range(n_supports)]
    cols = [np.asarray(res[k], float)[-n:] for k in keys]
    t = step * np.arange(1, n + 1)
    names = (["time", "x_1", "contact_force_1", "contact_height_1", "wire_height_1"]
             + [f"support_uplift_{j}" for j in range(n_supports)])
    with open(out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(names)
        for row in np.column_stack([t, x0 + speed * t] + cols):
            w.writerow([repr(float(x)) for x in row])
    print(f"CPU {time.process_time() - t_cpu!r}")
    print(f"WALL {wall!r}", flush=True)
    os._exit(0)


def main(argv=None) -> int:
    # not at module top: this file also runs as CoFmuPy's child, in that tool's own venv
    from pantocosim.master.thirdparty import common as run_common

    p = run_common.ssp_parser(__doc__, "cofmupy")
    p.add_argument("--config", type=Path, default=None,
                   help="CoFmuPy configuration (default: <ssp folder>/<ssp name>/cofmupy.json)")
    p.add_argument("--python", default=sys.executable,
                   help="the Python of CoFmuPy's venv (default: this one)")
    a = p.parse_args(argv)
    r = run_common.ssp_run(a, "cofmupy")
    config = (a.config or a.ssp.with_suffix("") / "cofmupy.json").resolve()
    cmd = [a.python, str(Path(__file__).resolve()), "--child", "--", config, a.step, r.stop,
           Path(r.out).resolve(), r.n_sup, r.cat["position_1"], r.cat["speed_kmh"] / 3.6]
    Path(r.out).parent.mkdir(parents=True, exist_ok=True)
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    wall = [l for l in proc.stdout.splitlines() if l.startswith("WALL ")]
    if proc.returncode != 0 or not wall:
        run_common.failed(MODULE, proc)
    cpu = [float(l.split()[1]) for l in proc.stdout.splitlines() if l.startswith("CPU ")]
    run_common.report("cofmupy", r.out, r.window, r.support_x,
                      (float(wall[-1].split()[1]), None, cpu[-1] if cpu else None),
                      {"ssp": str(a.ssp), "config": str(config), "step_s": a.step})
    return 0


if __name__ == "__main__":
    if "--child" in sys.argv:
        sys.path.pop(0)  # this file's folder: nothing there may shadow CoFmuPy's packages
        args = sys.argv[sys.argv.index("--") + 1:]
        child(args[0], float(args[1]), float(args[2]), args[3], int(args[4]),
              float(args[5]), float(args[6]))
    sys.exit(main())
