#!/usr/bin/env python3
"""Sensitivity of the EN 50318 quantities to the assumed values of the ``en50318`` preset.

Each variation changes one assumed value of the catenary definition (or the pantograph's
static force) and runs the scenario ``en50318-<speed>`` with the reference models
(nonlinear catenary, monolithic coupling), full length; the statistics, filter and window are
those of every run (EN 50317 / EN 50318: 0-20 Hz, whole spans). Also reported: the static
elasticity of the contact wire at a support and at mid-span (``CatenaryModel.elasticity``).
Runs one at a time; about 30 s each on one core at 1 m elements. Usage::

    nice -n 10 .venv/bin/python scripts/en50318_sensitivity.py [--speed 250]
        [--base FILE.toml] [--only NAME ...] [--out DIR] [--scenario FILE.toml]

``--scenario`` runs another scenario than ``en50318-<speed>`` (its catenary replaced by each
variation; the tests use a short one). The elasticity is taken at the central span's first
support and mid-span (support 5 of the 10-span preset).

Writes ``sensitivity-<speed>.json`` and ``.md`` to ``--out`` (default
``out/en50318-sensitivity``); docs/en50318-validation.md quotes the table.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import json
import sys
import time
from pathlib import Path

from _tables import markdown_table

ROOT = Path(__file__).resolve().parents[1]

#: name -> (what changes, edits of the definition: dotted key -> value, None deletes, a dict
#: replaces the table); the key "pantograph.static_force" sets the pantograph's option
VARIATIONS: dict[str, tuple[str, dict]] = {
    "base": ("the preset as it is", {}),
    "msup-fixed": ("messenger support: fixed", {"messenger_support": {"type": "fixed"}}),
    "msup-k5e5": ("messenger support: spring 5e5 N/m",
                  {"messenger_support": {"type": "spring", "stiffness": 5e5}}),
    "msup-k1e5": ("messenger support: spring 1e5 N/m",
                  {"messenger_support": {"type": "spring", "stiffness": 1e5}}),
    "msup-k3e4": ("messenger support: spring 3e4 N/m",
                  {"messenger_support": {"type": "spring", "stiffness": 3e4}}),
    "msup-k1e4": ("messenger support: spring 1e4 N/m",
                  {"messenger_support": {"type": "spring", "stiffness": 1e4}}),
    "msup-k5e3": ("messenger support: spring 5e3 N/m",
                  {"messenger_support": {"type": "spring", "stiffness": 5e3}}),
    "msup-k3e3": ("messenger support: spring 3e3 N/m",
                  {"messenger_support": {"type": "spring", "stiffness": 3e3}}),
    "msup-k2e3": ("messenger support: spring 2e3 N/m",
                  {"messenger_support": {"type": "spring", "stiffness": 2e3}}),
    "msup-k3e3-m10": ("messenger support: spring 3e3 N/m + 10 kg",
                      {"messenger_support": {"type": "spring", "stiffness": 3e3,
                                             "mass": 10.0}}),
    "arm-L0.5": ("steady arm length 0.5 m", {"contact_support.length": 0.5}),
    "arm-L2": ("steady arm length 2 m", {"contact_support.length": 2.0}),
    "arm-m0.5": ("steady arm mass 0.5 kg", {"contact_support.mass": 0.5}),
    "arm-m2": ("steady arm mass 2 kg", {"contact_support.mass": 2.0}),
    "arm-EA2e6": ("steady arm EA 2e6 N", {"contact_support.EA": 2e6}),
    "drop-k5e4": ("dropper stiffness 5e4 N/m", {"droppers.axial_stiffness": 5e4}),
    "drop-k2e5": ("dropper stiffness 2e5 N/m", {"droppers.axial_stiffness": 2e5}),
    "clamps-0": ("no clamp masses", {"droppers.clamp_mass_contact": 0.0,
                                     "droppers.clamp_mass_messenger": 0.0}),
    "clamps-x2": ("clamp masses doubled", {"droppers.clamp_mass_contact": 0.33,
                                           "droppers.clamp_mass_messenger": 0.39}),
    "damp-0.5%": ("Rayleigh 0.5 % at 1 and 20 Hz", {"damping.ratios": [0.005, 0.005]}),
    "damp-2%": ("Rayleigh 2 % at 1 and 20 Hz", {"damping.ratios": [0.02, 0.02]}),
    "damp-4%": ("Rayleigh 4 % at 1 and 20 Hz", {"damping.ratios": [0.04, 0.04]}),
    "EAc-x0.5": ("contact wire EA halved", {"contact_wire.EA": 0.7e7}),
    "EAc-x2": ("contact wire EA doubled", {"contact_wire.EA": 2.8e7}),
    "EAm-x0.5": ("messenger wire EA halved", {"messenger_wire.EA": 0.55e7}),
    "EAm-x2": ("messenger wire EA doubled", {"messenger_wire.EA": 2.2e7}),
    "elem-0.5": ("element size 0.5 m", {"geometry.element_size": 0.5}),
    "elem-2": ("element size 2 m", {"geometry.element_size": 2.0}),
    "F0-110": ("pantograph static force 110 N", {"pantograph.static_force": 110.0}),
    "F0-120": ("pantograph static force 120 N", {"pantograph.static_force": 120.0}),
}

#: the eight EN 50318 quantities: (column, ContactStatistics field, scale)
QUANTITIES = [("mean [N]", "mean_n", 1.0), ("sigma [N]", "std_n", 1.0),
              ("stat max [N]", "stat_max_n", 1.0), ("stat min [N]", "stat_min_n", 1.0),
              ("max [N]", "max_n", 1.0), ("min [N]", "min_n", 1.0),
              ("uplift [mm]", "max_uplift_at_support_m", 1000.0),
              ("loss [%]", "loss_of_contact_percent", 1.0)]


def toml_text(data: dict) -> str:
    """A catenary definition table as TOML (scalars, arrays, one level of sub-tables)."""
    def value(v):
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(v)

    lines = [f"{k} = {value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for k, v in data.items():
        if isinstance(v, dict):
            lines += ["", f"[{k}]"] + [f"{kk} = {value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def edited(base: dict, edits: dict) -> tuple[dict, dict]:
    """(definition with the edits applied, pantograph option overrides)."""
    data = copy.deepcopy(base)
    options = {}
    for key, v in edits.items():
        if key.startswith("pantograph."):
            options[key.split(".", 1)[1]] = v
            continue
        node = data
        *path, last = key.split(".")
        for part in path:
            node = node.setdefault(part, {})
        if v is None:
            node.pop(last, None)
        else:
            node[last] = copy.deepcopy(v)
    return data, options


def run_case(name: str, base: dict, scenario: str, work: Path) -> dict:
    from pantocosim.catenary.analysis import central_span
    from pantocosim.catenary.model import CatenaryModel
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    data, options = edited(base, VARIATIONS[name][1])
    path = work / f"{name}.toml"
    path.write_text(toml_text(data))
    sc = load_scenario(scenario)
    pans = [dataclasses.replace(p, options={**p.options, **options}) for p in sc.pantographs]
    sc = dataclasses.replace(sc, catenary=str(path), pantographs=pans)
    t0 = time.perf_counter()
    prep = prepare(sc)
    res = run_monolithic(prep, None, progress=False)
    if res.error is not None:
        return {"name": name, "error": str(res.error)}
    st = res.statistics()[0].as_dict()
    sx = prep.definition.support_x
    s = central_span(sx)
    cat = CatenaryModel(prep.definition)
    e_sup, e_mid = cat.elasticity([sx[s], 0.5 * (sx[s] + sx[s + 1])])
    return {"name": name, "change": VARIATIONS[name][0], "statistics": st,
            "elasticity_support_mm_per_n": 1e3 * e_sup, "elasticity_mid_mm_per_n": 1e3 * e_mid,
            "wall_s": time.perf_counter() - t0}


def markdown(rows: list[dict], speed: int, base_file: str) -> str:
    head = ["variation", "change", *(q[0] for q in QUANTITIES), "e support / mid [mm/N]"]
    cells = []
    for r in rows:
        if "error" in r:
            cells.append((r["name"], f"run stopped: {r['error']}"))
            continue
        st = r["statistics"]
        cells.append((r["name"], r["change"],
                      *(f"{scale * st[field]:.1f}" for _, field, scale in QUANTITIES),
                      f"{r['elasticity_support_mm_per_n']:.3f} / "
                      f"{r['elasticity_mid_mm_per_n']:.3f}"))
    return (f"## Sensitivity at {speed} km/h (base: {base_file})\n\n"
            "Generated by `scripts/en50318_sensitivity.py`; each row changes one value of the "
            "base.\n\n" + markdown_table(head, cells))


def main(argv=None) -> int:
    from pantocosim.catenary.definition import DATA_DIR
    from pantocosim.core.params import load_toml

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speed", type=int, default=250, choices=[250, 300])
    ap.add_argument("--base", type=Path, default=DATA_DIR / "en50318.toml",
                    help="catenary definition the variations start from")
    ap.add_argument("--only", nargs="*", choices=list(VARIATIONS), help="these variations")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "en50318-sensitivity")
    ap.add_argument("--scenario", help="scenario name or file (default en50318-<speed>)")
    args = ap.parse_args(argv)
    scenario = args.scenario or f"en50318-{args.speed}"
    base = load_toml(args.base)
    args.out.mkdir(parents=True, exist_ok=True)
    work = args.out / "definitions"
    work.mkdir(exist_ok=True)
    rows = []
    for name in args.only or VARIATIONS:
        r = run_case(name, base, scenario, work)
        rows.append(r)
        if "error" in r:
            print(f"{name}: {r['error']}", flush=True)
            continue
        st = r["statistics"]
        print(f"{name:15s} " + "  ".join(f"{q[0].split(' [')[0]} {q[2] * st[q[1]]:.1f}"
                                         for q in QUANTITIES)
              + f"  e_sup {r['elasticity_support_mm_per_n']:.3f}  ({r['wall_s']:.0f} s)",
              flush=True)
    stem = args.out / f"sensitivity-{args.speed}"
    stem.with_suffix(".json").write_text(json.dumps(rows, indent=1))
    stem.with_suffix(".md").write_text(markdown(rows, args.speed, args.base.name))
    print(f"wrote {stem}.json and .md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
