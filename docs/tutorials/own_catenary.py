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
from pathlib import Path

from tutorial_cli import FILES, pantocosim  # (beside this script)


LINE = (FILES / "my-line.toml").read_text()

STITCH = (FILES / "stitch-wire.toml").read_text()


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
