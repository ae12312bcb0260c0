"""``pantocosim ssp``: the SSP file of a user's pantograph FMU on our catenary FMU."""

from __future__ import annotations

from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("ssp", help="write the SSP file of your own pantograph FMU",
                       description="Read the pantograph FMU's model description, check its "
                       "required ports (contact_force in; contact_height, contact_velocity "
                       "out), connect the optional ones it has (start laws, train speed) and "
                       "write an SSP 1.0 file holding it and the catenary FMU baked for the "
                       "scenario (docs/third-party.md, 'Pantograph FMU contract').")
    p.add_argument("--pantograph", required=True, metavar="FMU",
                   help="your pantograph FMU (FMI 2.0 or 3.0 co-simulation; the catenary FMU "
                   "of the SSP file is of the same version)")
    p.add_argument("--scenario", default="dsa380-ave-300",
                   help="scenario preset or TOML file (default dsa380-ave-300): the catenary, "
                   "speed, position, window and step")
    p.add_argument("--out", default=None, help="SSP file to write (default "
                   "<fmu stem>-<scenario>.ssp beside the FMU)")
    return p


def run(args) -> int:
    from pantocosim.core.errors import OutputError
    from pantocosim.master.ssp import pantograph_connections, write_pantograph_ssp

    fmu = Path(args.pantograph)
    connections = pantograph_connections(fmu)      # before the catenary FMU is built
    out = Path(args.out) if args.out else None
    if out is not None and out.is_dir():
        raise OutputError("--out", out, "is a folder; accepted: an SSP file name")
    ssp, values = write_pantograph_ssp(fmu, args.scenario, out)
    optional = [b for a, ap, el, b in connections
                if el == "pantograph" and b not in ("contact_force",)]
    laws = values["laws"]
    print(f"wrote {ssp}: {fmu.name} on the catenary of scenario "
          f"'{values['scenario'].name}' (stop {values['stop_time']:g} s, step "
          f"{values['scenario'].dt:g} s)")
    print("optional inputs connected: " + (", ".join(optional) or "none"))
    if not {"operating_height", "static_height"} <= set(optional):
        print("start laws of this catenary (your FMU does not read them): operating height "
              f"{laws['operating_height']:.6f} m + {laws['operating_height_slope']:.6g} m/N F; "
              f"static contact height at t0 {laws['static_height']:.6f} m + "
              f"{laws['static_height_slope']:.6g} m/N F (F: the contact force; the catenary "
              "settles against your FMU's contact_height at t0)")
    return 0
