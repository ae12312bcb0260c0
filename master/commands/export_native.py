"""``pantocosim export-native``: the scenario's catenary and pantographs as native C FMUs
(no Python inside; docs/tutorials/hil.md)."""

from __future__ import annotations

import dataclasses
from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("export-native", help="write native C FMUs of a scenario (HIL rigs, "
                       "any FMI host)",
                       description="Write the scenario's catenary (linear or modal model) and "
                       "its pantographs (lumped chains with constant matrices, the rigid and "
                       "the flexible DSA-380) as co-simulation FMUs "
                       "whose binaries hold no Python: the Python models compute the constant "
                       "matrices, droppers, contact-wire geometry and start state once, into "
                       "resources/model.pcsdata; C steps them with the same HHT-alpha step "
                       "(closed form, or Newton for the DSA-380). Each FMU carries its C sources and binaries for linux64 "
                       "(gcc) and win64 (mingw-w64, when installed). The internal step is the "
                       "scenario's dt: a communication step is a whole number of it.")
    p.add_argument("scenario", metavar="SCENARIO", help="scenario name or TOML file")
    p.add_argument("--catenary-model", choices=("linear", "modal"), default="linear",
                   help="catenary model of the FMU (default linear)")
    p.add_argument("--modal-cutoff-hz", type=float, default=None,
                   help="modal model: modes below this frequency (default: the scenario's)")
    p.add_argument("--fmi", type=int, choices=(2, 3), default=2, help="FMI version (default 2)")
    p.add_argument("--out", default=None, help="output folder (default dist/native/SCENARIO)")
    p.add_argument("--force", action="store_true", help="export a speed above the EN 50119 "
                   "limit (0.7 of the contact wire's wave speed; never at or above it)")
    p.add_argument("--win64", choices=("auto", "yes", "no"), default="auto",
                   help="also build the win64 DLLs with x86_64-w64-mingw32-gcc (auto: when "
                   "installed)")
    return p


def run(args) -> int:
    from pantocosim.core.params import check_number
    from pantocosim.master.native.build import c_compiler
    from pantocosim.master.native.models import CATENARY_EXPORTS, export_scenario
    from pantocosim.master.output_folder import OutputFolder
    from pantocosim.master.commands.run import named_as_options
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario, require_port_contact

    sc = load_scenario(args.scenario)
    require_port_contact(sc, "a native FMU export")
    own_model = sc.catenary_model
    changes = {"catenary_model": args.catenary_model}
    if args.modal_cutoff_hz is not None:
        check_number("--modal-cutoff-hz", args.modal_cutoff_hz, positive=True)
        changes["modal_cutoff_hz"] = float(args.modal_cutoff_hz)
    sc = dataclasses.replace(sc, **changes)
    out = Path(args.out) if args.out else Path("dist") / "native" / sc.name
    win64 = {"auto": None, "yes": True, "no": False}[args.win64]
    c_compiler()                                  # before the set-up
    folder = OutputFolder(out)                    # --out checked before the set-up
    try:
        with named_as_options(args):
            prep = prepare(sc, force=args.force)
            written, kept = export_scenario(prep, folder.path, fmi=args.fmi, win64=win64)
        folder.commit()
    finally:
        folder.discard()
    for path in written:
        print(f"wrote {out / path.name}")
    if own_model not in CATENARY_EXPORTS:
        print(f"catenary: the scenario's {own_model} model has no native form (its matrices "
              f"change with the wire's shape); wrote the {args.catenary_model} model "
              "(--catenary-model); the nonlinear one stays a Python FMU")
    for k, why in kept:
        print(f"pantograph {k + 1} ({sc.pantographs[k].model}): {why}; it stays a Python FMU")
    return 0
