"""Tutorial: the FMUs in your FMI tool: our master's couplings, the pantograph swap in a
third-party master (libcosim), and a pantograph FMU in a native C host.

    python docs/tutorials/fmi_tool.py [--out DIR] [--fmus DIR]

Works in DIR (default ``tutorial-fmi``): builds the FMUs into DIR/dist/fmus (or links the
folder --fmus, FMUs built before by ``pantocosim build-fmus``), runs a short scenario with each
coupling, writes the SSP file of a swapped pantograph and runs it in libcosim, and runs a
pantograph FMU in the C host of the package (``fmus/native/host``, its script mode); writes
``summary.json``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from tutorial_cli import FILES, pantocosim  # (beside this script)

from pantocosim.master.native.host import build_host

SHORT = (FILES / "short.toml").read_text()


def statistics(summary_json: str) -> dict:
    """The first pantograph's statistics of ``pantocosim run --json``."""
    summary = json.loads(summary_json)
    st = summary["pantographs"][0]["statistics"]
    return {k: st[k] for k in ("mean_n", "std_n", "max_n", "min_n")}


def recipe(master: str, *args: str, cwd: Path) -> dict:
    """Run the recipe of a third-party master; the statistics it prints."""
    proc = subprocess.run([sys.executable, "-m", f"pantocosim.master.thirdparty.{master}",
                           *args], cwd=cwd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"{master} failed:\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
    line = [s for s in proc.stdout.splitlines() if s.startswith("STATISTICS ")][-1]
    st = json.loads(line[len("STATISTICS "):])
    st = st[0] if isinstance(st, list) else st
    return {k: st[k] for k in ("mean_n", "std_n", "max_n", "min_n")}


def native_host(fmu: Path, work: Path) -> list[float]:
    """Run ``fmu`` in the package's C host (dlopen of its linux64 binary, in an environment
    without Python variables): static start under 120 N, then 100 steps of 1 ms under 130 N;
    the contact heights it reads after each step."""
    exe = build_host(work)
    unpacked = work / fmu.stem
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    md = ET.parse(unpacked / "modelDescription.xml").getroot()
    ident = md.find("CoSimulation").get("modelIdentifier")
    vr = {v.get("name"): v.get("valueReference") for v in md.iter("ScalarVariable")}
    # --8<-- [start:native]
    calls = [f"load P {unpacked} {ident} {md.get('guid')}", "instantiate P pantograph",
             f"set P r {vr['initial_contact_force']} 120.0", "setup P 0.0", "enter P",
             "exit P"]
    for k in range(100):
        calls += [f"set P r {vr['contact_force']} 130.0", f"step P {k * 1e-3!r} 0.001",
                  f"get P r {vr['contact_height']}"]
    calls += ["terminate P", "free P"]
    proc = subprocess.run([str(exe), "script"], input="\n".join(calls) + "\n",
                          capture_output=True, text=True, cwd=work, env={"PATH": "/usr/bin:/bin", "HOME": str(work)})
    # --8<-- [end:native]
    if proc.returncode != 0:
        sys.exit(f"native host failed:\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
    heights = []
    for line in proc.stdout.splitlines():    # "= LINE CALL STATUS [values]"
        parts = line.split()
        if parts[:1] == ["="] and parts[2] == "get":
            assert parts[3] == "0", line      # fmi2OK
            heights.append(float(parts[4]))
    return heights


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("tutorial-fmi"))
    ap.add_argument("--fmus", type=Path, default=None,
                    help="FMUs built before (pantocosim build-fmus); default: build them")
    args = ap.parse_args(argv)
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    (out / "short.toml").write_text(SHORT)
    (out / "short-2mass.toml").write_text(SHORT.replace('"dsa380-lumped3"', '"en50318-2mass"'))
    fmus = out / "dist" / "fmus"
    if args.fmus is not None and not fmus.exists():
        fmus.parent.mkdir(parents=True, exist_ok=True)
        fmus.symlink_to(args.fmus.resolve(), target_is_directory=True)
    elif not fmus.exists():
        # --8<-- [start:build]
        pantocosim("build-fmus", "--fmi", "2", "--no-ssp", cwd=out)   # dist/fmus/*.fmu
        # --8<-- [end:build]

    # --8<-- [start:couplings]
    runs = {}
    for coupling in ("monolithic", "explicit", "gauss-seidel", "implicit"):
        runs[coupling] = statistics(pantocosim(
            "run", "short.toml", "--coupling", coupling, "--json",
            "--out", f"runs/{coupling}", cwd=out))
    # --8<-- [end:couplings]

    # --8<-- [start:swap]
    runs["implicit, en50318-2mass"] = statistics(pantocosim(
        "run", "short-2mass.toml", "--coupling", "implicit", "--json",
        "--out", "runs/implicit-2mass", cwd=out))
    pantocosim("ssp", "--pantograph", "dist/fmus/en50318-2mass.fmu", "--scenario",
               "short.toml", "--out", "swap.ssp", cwd=out)
    runs["libcosim, en50318-2mass"] = recipe("libcosim", "--ssp", "swap.ssp",
                                             "--out", "libcosim.csv", cwd=out)
    # --8<-- [end:swap]

    heights = native_host(fmus / "dsa380-rigid.fmu", out)
    summary = {"runs": runs, "native_heights_m": heights}
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print("run                          F_m [N]  sigma [N]  max [N]  min [N]")
    for name, st in runs.items():
        print(f"{name:<28} {st['mean_n']:8.2f} {st['std_n']:9.3f} {st['max_n']:8.2f} "
              f"{st['min_n']:8.2f}")
    print(f"native host: contact height {heights[0]:.6f} m after 1 ms, "
          f"{heights[-1]:.6f} m after 100 ms under 130 N")
    return summary


if __name__ == "__main__":
    main()
