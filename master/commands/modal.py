"""``pantocosim modal``: linearise a pantograph about its static equilibrium and list modes."""

from __future__ import annotations

import json

import numpy as np


def add_parser(sub):
    p = sub.add_parser("modal", help="natural frequencies and damping of a pantograph",
                       description="Linearise PANTOGRAPH about the equilibrium under a static "
                       "contact force at a working height and print its modes (thesis 2.1.3).")
    p.add_argument("pantograph", help="preset name (dsa380-rigid, dsa380-lumped3, "
                   "en50318-2mass) or parameter file")
    p.add_argument("--height", type=float, default=None,
                   help="contact height above the rail [m] (default: the preset's)")
    p.add_argument("--force", type=float, default=120.0, help="static contact force [N]")
    p.add_argument("--json", action="store_true", help="print JSON")
    return p


def run(args) -> int:
    from pantocosim.core.params import check_number
    from pantocosim.pantograph.modal import modal_analysis
    from pantocosim.pantograph.presets import load_pantograph

    check_number("--force", args.force, nonnegative=True)
    if args.height is not None:
        check_number("--height", args.height, positive=True)
    model = load_pantograph(args.pantograph)
    q0 = model.static_equilibrium(args.force, args.height)
    M, C, K = model.linearize(q0, args.force)
    res = modal_analysis(M, C, K)
    labels = [model.mode_label(res.shapes[:, r], M) for r in range(len(res.frequencies_hz))]
    equilibrium = {"contact_force_n": args.force,
                   "contact_height_m": model.contact_height(q0),
                   "q": {name: float(x) for name, x in zip(model.dof_names, q0)}}
    equilibrium.update(getattr(model, "equilibrium_info", lambda: {})())
    if args.json:
        print(json.dumps({"pantograph": model.name,
                          "frequencies_hz": [float(x) for x in res.frequencies_hz],
                          "damping_ratios": [float(x) for x in res.damping_ratios],
                          "mode_labels": labels, "equilibrium": equilibrium}, indent=2))
        return 0
    print(f"{model.name}: linearised about F = {args.force:g} N at contact height "
          f"{model.contact_height(q0):.4f} m")
    print(f"{'mode':>4}  {'f [Hz]':>10}  {'zeta':>9}  label")
    for r, (f, z) in enumerate(zip(res.frequencies_hz, res.damping_ratios)):
        print(f"{r + 1:>4}  {f:>10.4f}  {z:>9.4f}  {labels[r]}")
    return 0
