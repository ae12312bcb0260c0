"""Run an SSP file of pantocosim FMUs with OMSimulator's native command line.

Recipe (docs/third-party.md)::

    pantocosim build-fmus                   # dist/fmus/dsa380-ave-300.ssp and its FMUs
    python -m pantocosim.master.thirdparty.omsimulator [--omsimulator PATH]
        [--ssp dist/fmus/dsa380-ave-300.ssp] [--stop SECONDS] [--window START END] [--out CSV]

The executable is ``--omsimulator``, else ``$OMSIMULATOR``, else ``OMSimulator`` on PATH. It
runs as a user runs it: ``OMSimulator --stopTime=T --resultFile=R.csv FILE.ssp``, in the
environment of the shell (the FMUs need no LD_PRELOAD or PYTHONPATH). For an SSP file the
command line takes the stop time from ``--stopTime`` only (default 1 s): the recipe passes the
SSD's. The step is the SSD's fixed-step master's (``--stepSize`` does not apply to SSP
files). OMSimulator writes each time twice (before and after the exchange of the step): the
last row of each time is kept.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from pantocosim.master.thirdparty import common as run_common

MODULE = "pantocosim.master.thirdparty.omsimulator"


def executable(given: str | None) -> str:
    """The OMSimulator command line: ``given``, $OMSIMULATOR, or ``OMSimulator`` on PATH."""
    exe = given or os.environ.get("OMSIMULATOR") or shutil.which("OMSimulator")
    if not exe or not Path(exe).is_file():
        raise SystemExit("omsimulator: no OMSimulator executable: pass --omsimulator PATH or "
                         "set OMSIMULATOR (docs/third-party.md says how to build it)")
    return str(exe)


def result_columns(path: Path) -> dict:
    """{port (``component.variable``): values} of an OMSimulator CSV result, one row per time
    (the last one written)."""
    with open(path) as fh:
        names = [c.strip() for c in fh.readline().split(",")]
    data = np.genfromtxt(path, delimiter=",", skip_header=1, ndmin=2)
    last = np.r_[data[1:, 0] != data[:-1, 0], True]
    data = data[last]
    out = {"time": data[:, 0]}
    for i, name in enumerate(names[1:], start=1):
        out[".".join(name.split(".")[-2:])] = data[:, i]
    return out


def child(ssp: str, step: float, stop: float, out: str, n_supports: int, x0: float,
          speed: float, exe: str) -> None:
    with tempfile.TemporaryDirectory(prefix="pantocosim_oms_") as tmp:
        result = Path(tmp) / "result.csv"
        t_wall = time.perf_counter()
        proc = subprocess.run([exe, f"--stopTime={stop!r}", f"--resultFile={result}", ssp],
                              capture_output=True, text=True, cwd=tmp)
        wall = time.perf_counter() - t_wall
        sys.stdout.write(proc.stdout[-4000:])
        if proc.returncode != 0 or not result.exists():
            sys.stderr.write(proc.stderr[-4000:])
            raise SystemExit(f"OMSimulator exited with {proc.returncode}")
        c = result_columns(result)
    t = c["time"]
    cols = [c["catenary.contact_force_out_1"], c["pantograph.contact_height"],
            c["catenary.wire_height_1"]]
    cols += [c[f"catenary.support_uplift_{j}"] for j in range(n_supports)]
    run_common.write_csv(out, run_common.columns(n_supports), np.column_stack(
        [t, x0 + speed * t] + cols))
    print(f"WALL {wall!r}", flush=True)
    os._exit(0)


def main(argv=None) -> int:
    p = run_common.ssp_parser(__doc__, "omsimulator")
    p.add_argument("--omsimulator", help="the OMSimulator executable")
    a = p.parse_args(argv)
    if a.child:
        ssp, step, stop, out, n_sup, x0, speed, exe = a.child_args
        child(ssp, float(step), float(stop), out, int(n_sup), float(x0), float(speed), exe)
        return 0
    run_common.run_ssp_child(MODULE, a, run_common.ssp_run(a, "omsimulator"),
                             executable(a.omsimulator))
    return 0


if __name__ == "__main__":
    sys.exit(main())
