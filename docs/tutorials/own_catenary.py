"""Tutorial: your own catenary, from a line's data to its static check, elasticity and modes.

    python docs/tutorials/own_catenary.py [--out DIR] [--figures DIR]

Writes the line's definition file ``my-line.toml`` into DIR (default ``tutorial-catenary``),
runs ``pantocosim static`` and ``pantocosim modes`` on it, then the same line with a stitch
wire, and writes ``summary.json`` and the figures ``my-line-static.png`` and
``my-line-stitched-static.png`` (also into --figures when given).
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
from pathlib import Path

# --8<-- [start:definition]
LINE = """\
# A simple catenary for 200 km/h: 6 spans of 55 m, CuAg 120 contact wire, Bz 70 messenger.
name = "my-line"
description = "simple catenary, 55 m spans, 15 kN / 15 kN"

[spans]
count = 6
length = 55.0

[geometry]
system_height = 1.4          # m, messenger above contact wire at the supports
contact_wire_height = 5.5    # m above the rail
stagger = [0.2, -0.2]        # m, alternating
presag = 0.03                # m at mid-span (about 1/2000 of the span)
element_size = 1.0           # m

[contact_wire]               # CuAg 120 mm2
mass_per_length = 1.07       # kg/m
EA = 1.2e7                   # N
EI = 150.0                   # N m2
tension = 15000.0            # N

[messenger_wire]             # Bz 70 mm2
mass_per_length = 0.6        # kg/m
EA = 7.0e6                   # N
EI = 60.0                    # N m2
tension = 15000.0            # N

[droppers]
positions = [4.5, 12.0, 20.0, 27.5, 35.0, 43.0, 50.5]   # m from each span start
mass_per_length = 0.11       # kg/m
axial_stiffness = 1.0e5      # N/m
clamp_mass_contact = 0.17    # kg
clamp_mass_messenger = 0.19  # kg

[contact_support]
type = "steady_arm"
length = 1.1                 # m
mass = 1.2                   # kg

[messenger_support]
type = "fixed"

[damping]                    # Rayleigh: 1 % at 1 Hz and at 20 Hz
ratios = [0.01, 0.01]
frequencies_hz = [1.0, 20.0]
"""
# --8<-- [end:definition]

# --8<-- [start:stitch]
STITCH = """
[stitch_wire]                # Bz 35 mm2, 18 m centred on every intermediate support
mass_per_length = 0.31       # kg/m
EA = 3.5e6                   # N
EI = 10.0                    # N m2
tension = 3500.0             # N
length = 18.0                # m
"""
# --8<-- [end:stitch]


def pantocosim(*args: str, cwd: Path) -> str:
    """Run ``pantocosim ARGS`` (the installed command line) and return what it prints."""
    proc = subprocess.run([sys.executable, "-m", "pantocosim.master.cli", *args], cwd=cwd,
                          capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"pantocosim {' '.join(args)} failed:\n{proc.stderr}")
    return proc.stdout


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("tutorial-catenary"))
    ap.add_argument("--figures", type=Path, default=None, help="also copy the figures here")
    args = ap.parse_args(argv)
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    (out / "my-line.toml").write_text(LINE)
    (out / "my-line-stitched.toml").write_text(LINE.replace('name = "my-line"',
                                                            'name = "my-line-stitched"')
                                               + STITCH)

    # --8<-- [start:run]
    static = json.loads(pantocosim("static", "my-line.toml", "--json",
                                   "--plot", "my-line-static.png", cwd=out))
    modes = json.loads(pantocosim("modes", "my-line.toml", "--count", "8", "--json", cwd=out))
    # --8<-- [end:run]
    stitched = json.loads(pantocosim("static", "my-line-stitched.toml", "--json",
                                     "--plot", "my-line-stitched-static.png", cwd=out))

    summary = {"my-line": summarise(static), "my-line-stitched": summarise(stitched),
               "frequencies_hz": modes["frequencies_hz"]}
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    for name in ("my-line", "my-line-stitched"):
        s = summary[name]
        print(f"{name}: {s['n_dofs']} DOFs")
        print(f"  contact wire tension  {s['contact_wire_tension_n']:.0f} N, messenger "
              f"{s['messenger_tension_n']:.0f} N")
        print(f"  height error at droppers  {1e3 * s['max_height_error_m']:.3f} mm")
        print(f"  dropper forces  {s['dropper_force_min_n']:.1f} .. "
              f"{s['dropper_force_max_n']:.1f} N")
        print(f"  elasticity  {s['elasticity_min_mm_per_n']:.3f} .. "
              f"{s['elasticity_max_mm_per_n']:.3f} mm/N (uniformity "
              f"{s['elasticity_uniformity_percent']:.1f} %)")
    print("my-line modes [Hz]  " + "  ".join(f"{f:.3f}" for f in summary["frequencies_hz"]))
    if args.figures:
        args.figures.mkdir(parents=True, exist_ok=True)
        for name in ("my-line-static.png", "my-line-stitched-static.png"):
            shutil.copy(out / name, args.figures / name)
    return summary


def summarise(static: dict) -> dict:
    """The figures of the static check of one definition."""
    el = static["elasticity_m_per_n"]["value"]
    return {
        "contact_wire_tension_n": static["contact_wire_tension_n"],
        "messenger_tension_n": static["messenger_tension_n"],
        "max_height_error_m": static["max_height_error_m"],
        "dropper_force_min_n": min(static["dropper_forces_n"]),
        "dropper_force_max_n": max(static["dropper_forces_n"]),
        "elasticity_min_mm_per_n": 1e3 * min(el),
        "elasticity_max_mm_per_n": 1e3 * max(el),
        "elasticity_uniformity_percent": 100 * (max(el) - min(el)) / (max(el) + min(el)),
        "n_dofs": static["n_dofs"],
    }


if __name__ == "__main__":
    main()
