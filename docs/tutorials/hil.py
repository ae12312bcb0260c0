"""Tutorial: native FMUs for a hardware-in-the-loop rig.

    python docs/tutorials/hil.py [--out DIR] [--steps N]

Exports en50318-300's linear catenary and its 2-mass pantograph as native C FMUs
(``pantocosim export-native``), unpacks them, compiles the package's C host
(``fmus/native/host``) with the system's C compiler and runs the coupled loop at 1 kHz, first as fast as it goes, then paced to the wall clock; writes ``summary.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import zipfile
from pathlib import Path

from tutorial_cli import pantocosim  # (beside this script)


def host_run(host: Path, out: Path, steps: int, paced: bool) -> dict:
    """The C loop over the two FMUs: its rows (t, F, z_pantograph, z_wire), the doStep
    percentiles, the deadline misses and the allocations it counted."""
    # --8<-- [start:loop]
    run = subprocess.run([str(host), "coupled-forces", "hil/catenary", "hil/en50318-2mass",
                          str(steps), "0.001", *(["paced"] if paced else [])],
                         cwd=out, capture_output=True, text=True, check=True)
    # --8<-- [end:loop]
    rows = [[float(x) for x in line.split()] for line in run.stdout.splitlines()
            if line[:1].isdigit()]
    result = {"steps": steps, "paced": paced}
    for line in run.stdout.splitlines():
        words = line.split()
        if "doStep us:" in line:
            result[words[0]] = {"p50_ms": float(words[4]) / 1e3,
                                "p99_ms": float(words[6]) / 1e3,
                                "max_ms": float(words[8]) / 1e3}
        elif line.startswith("deadline misses:"):
            result["deadline_misses"] = int(words[2])
        elif line.startswith("allocations in doStep:"):
            result["allocations_in_do_step"] = int(words[-1])
    if rows:
        forces = [r[1] for r in rows]
        result.update(mean_force_n=sum(forces) / len(forces), min_force_n=min(forces),
                      max_force_n=max(forces),
                      max_gap_m=max(abs(r[2] - r[3]) for r in rows))
    return result


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("tutorial-hil"))
    ap.add_argument("--steps", type=int, default=2000, help="steps of 1 ms (default 2000)")
    args = ap.parse_args(argv)
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)

    # --8<-- [start:export]
    print(pantocosim("export-native", "en50318-300", "--out", "hil", "--win64", "no",
                     cwd=out), end="")
    # --8<-- [end:export]
    for name in ("catenary", "en50318-2mass"):
        with zipfile.ZipFile(out / "hil" / f"{name}.fmu") as z:
            z.extractall(out / "hil" / name)
    # --8<-- [start:host]
    import pantocosim as package

    sources = sorted((Path(package.__file__).resolve().parent / "native" / "host").glob("*.c"))
    cc = os.environ.get("CC") or shutil.which("gcc") or shutil.which("cc")
    subprocess.run([cc, "-std=c99", "-O2", *map(str, sources), "-o", str(out / "pantocosim_host"),
                    "-ldl", "-lm"], check=True)
    # --8<-- [end:host]
    runs = {"unpaced": host_run(out / "pantocosim_host", out, args.steps, False),
            "paced": host_run(out / "pantocosim_host", out, args.steps, True)}
    (out / "summary.json").write_text(json.dumps(runs, indent=2))
    for label, r in runs.items():
        c = r["catenary"]
        print(f"{label:>8}: catenary doStep p50 {c['p50_ms']:.3f} ms, p99 {c['p99_ms']:.3f} "
              f"ms, max {c['max_ms']:.3f} ms; allocations in doStep "
              f"{r['allocations_in_do_step']}"
              + (f"; deadline misses {r['deadline_misses']} of {r['steps']}" if r["paced"]
                 else f"; mean contact force {r['mean_force_n']:.1f} N"))
    return runs


if __name__ == "__main__":
    main()
