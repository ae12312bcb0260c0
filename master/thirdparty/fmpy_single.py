"""Run one pantograph FMU under a prescribed contact force with fmpy's ``simulate_fmu``.

Recipe (docs/third-party.md)::

    pantocosim build-fmus --only en50318-2mass
    python -m pantocosim.master.thirdparty.fmpy_single [--fmu dist/fmus/en50318-2mass.fmu]
        [--force "120 + 30*sin(2*pi*5*t)"] [--stop 2.0] [--step 0.001] [--speed-kmh 300]
        [--out CSV]

The pantograph FMU takes the value of ``contact_force`` set before ``doStep(t, h)`` as the force
at t + h, while ``simulate_fmu`` sets the input from the signal at the start of each step, t.
The input signal therefore carries F(t + h) at time t, which reproduces the stand-alone
pantograph run (``pantocosim.master.standalone.simulate_pantograph``). The pantograph starts in
static equilibrium under F(0) at its working height. Statistics: the contact force over the
whole run, with the pantograph position x = V t.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from pantocosim.master.thirdparty import common as run_common
from pantocosim.master.standalone import force_expression

MODULE = "pantocosim.master.thirdparty.fmpy_single"

DEFAULT_FMU = Path("dist") / "fmus" / "en50318-2mass.fmu"


def child(fmu: str, signal_file: str, step: float, stop: float, out: str, speed: float,
          speed_kmh: float) -> None:
    import scipy.sparse.linalg  # noqa: F401  (B5: before any FMU is loaded)
    from fmpy import simulate_fmu

    sig = np.load(signal_file)            # columns: time t_i, F(t_i), F(t_i + h)
    signal = np.array([(t, f1) for t, _, f1 in sig],
                      dtype=[("time", np.float64), ("contact_force", np.float64)])
    start_values = {"initial_contact_force": float(sig[0, 1])}
    if speed_kmh:
        start_values["speed_kmh"] = speed_kmh
    t_wall = time.perf_counter()
    res = simulate_fmu(str(fmu), start_time=0.0, stop_time=stop, step_size=step,
                       output_interval=step, input=signal, start_values=start_values,
                       output=["contact_height", "contact_velocity"])
    wall = time.perf_counter() - t_wall
    n = min(len(res), len(sig))
    t = res["time"][:n]
    rows = np.column_stack([t, speed * t, sig[:n, 1], res["contact_height"][:n],
                            np.full(n, np.nan)])
    run_common.write_csv(out, run_common.columns(0), rows)
    if n < len(sig):
        print(f"NOTE simulate_fmu stopped at t = {t[-1]:g} s of {stop:g} s")
    print(f"WALL {wall!r}", flush=True)
    os._exit(0 if n == len(sig) else 3)


def main(argv=None) -> int:
    p = run_common.parser(__doc__, "results/<fmu>-fmpy.csv")
    p.add_argument("--fmu", type=Path, default=DEFAULT_FMU)
    p.add_argument("--force", default="120 + 30*sin(2*pi*5*t)",
                   help="contact force law in t [N] (numpy functions, pi)")
    p.add_argument("--stop", type=float, default=2.0, help="stop time [s]")
    p.add_argument("--step", type=float, default=1e-3, help="communication step [s]")
    p.add_argument("--speed-kmh", type=float, default=0.0,
                   help="train speed (FMU parameter speed_kmh: aerodynamic uplift); also "
                   "gives the position x = V t of the statistics (default 0: x = t)")
    a = p.parse_args(argv)
    if a.child:
        fmu, sig, step, stop, out, speed, speed_kmh = a.child_args
        child(fmu, sig, float(step), float(stop), out, float(speed), float(speed_kmh))
        return 0

    run_common.check_fmu(MODULE, a.fmu, "--fmu")
    force = force_expression(a.force)
    n = int(round(a.stop / a.step))
    t = np.arange(n + 1) * a.step
    sig = np.column_stack([t, [force(x) for x in t], [force(x) for x in np.append(t[1:],
                                                                                t[-1] + a.step)]])
    speed = a.speed_kmh / 3.6 if a.speed_kmh else 1.0
    out = a.out or Path("results") / f"{a.fmu.stem}-fmpy.csv"
    with tempfile.TemporaryDirectory() as tmp:
        sig_file = Path(tmp) / "signal.npy"
        np.save(sig_file, sig)
        wall = run_common.run_child(MODULE, ["--", a.fmu.resolve(), sig_file, a.step,
                                               a.stop, out, speed, a.speed_kmh])
    run_common.report("fmpy simulate_fmu", out, (0.0, speed * a.stop), np.zeros(0), wall,
                      {"fmu": str(a.fmu), "force": a.force, "step_s": a.step})
    return 0


if __name__ == "__main__":
    sys.exit(main())
