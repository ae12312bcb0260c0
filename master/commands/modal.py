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
    p.add_argument("--count", type=int, default=None,
                   help="list the lowest N modes (default: all in JSON, those below 40 Hz "
                   "in the table)")
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
    n = len(res.frequencies_hz)
    if args.count is not None:
        if args.count < 1:
            from pantocosim.core.errors import ParameterError

            raise ParameterError("--count", args.count, "must be >= 1")
        n = min(n, args.count)
    elif not args.json:
        n = max(1, int(np.sum(res.frequencies_hz <= 40.0)))
    labels = [model.mode_label(res.shapes[:, r], M) for r in range(n)]
    equilibrium = {"contact_force_n": args.force,
                   "contact_height_m": model.contact_height(q0),
                   "q": {name: float(x) for name, x in zip(model.dof_names, q0)}}
    equilibrium.update(getattr(model, "equilibrium_info", lambda: {})())
    note = uplift_note(args.pantograph, model.options)
    if args.json:
        print(json.dumps({"pantograph": model.name,
                          "frequencies_hz": [float(x) for x in res.frequencies_hz[:n]],
                          "damping_ratios": [float(x) for x in res.damping_ratios[:n]],
                          "mode_labels": labels, "equilibrium": equilibrium,
                          "warnings": [note] if note else []}, indent=2))
        return 0
    print(f"{model.name}: linearised about F = {args.force:g} N at contact height "
          f"{model.contact_height(q0):.4f} m")
    print(f"{'mode':>4}  {'f [Hz]':>10}  {'zeta':>9}  label")
    for r in range(n):
        print(f"{r + 1:>4}  {res.frequencies_hz[r]:>10.4f}  {res.damping_ratios[r]:>9.4f}  "
              f"{labels[r]}")
    if n < len(res.frequencies_hz):
        print(f"({len(res.frequencies_hz) - n} more modes above; --count N lists them)")
    if note:
        print(f"WARNING: {note}")
    return 0


def uplift_note(name: str, options) -> str | None:
    """The speed above which the file's aerodynamic law leaves no uplift (``run`` refuses
    such a scenario), or None."""
    from pantocosim.pantograph.presets import preset_path

    top = options.highest_speed_kmh()
    if top is None:
        return None
    field = "aero_c2" if options.aero_c2 < 0.0 else "aero_c1"
    return (f"{preset_path(name).name}: options.{field} = {getattr(options, field)!r}: the "
            f"mean uplift static_force + aero_c1 v + aero_c2 v^2 is zero at {top:.0f} km/h "
            "and negative above: the pantograph does not press on the wire there, and "
            "pantocosim run refuses it at those speeds")
