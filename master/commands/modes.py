"""``pantocosim modes``: natural frequencies of a catenary about its static configuration."""

from __future__ import annotations

import json

from pantocosim.master.commands.run import add_size_options


def add_parser(sub):
    p = sub.add_parser("modes", help="natural frequencies of a catenary",
                       description="Lowest natural frequencies of CATENARY linearised about "
                       "its static configuration (sparse shift-invert eigensolver).")
    p.add_argument("catenary", metavar="CATENARY",
                   help="preset name (en50318, benchmark55, ave64) or definition file")
    p.add_argument("--count", type=int, default=10, help="number of modes (default 10)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--element-size", type=float, default=None,
                   help="override the definition's target element size [m]")
    add_size_options(p, steps=False)
    return p


def run(args) -> int:
    from pantocosim.catenary.model import CatenaryModel
    from pantocosim.core.errors import ParameterError
    from pantocosim.core.params import check_number

    if args.count < 1:
        raise ParameterError("--count", args.count, "must be >= 1")
    from pantocosim.master.size_limits import check_cli_catenary

    if args.element_size is not None:
        check_number("--element-size", args.element_size, positive=True)
    dofs = check_cli_catenary(args.catenary, args.element_size, args.max_dofs)
    if args.count > dofs // 12:
        raise ParameterError("--count", args.count, f"more modes than the model can resolve "
                             f"(about {dofs // 12} for its {dofs:,} DOFs)")
    model = CatenaryModel(args.catenary, element_size=args.element_size)
    f, _ = model.modes(args.count)
    if args.json:
        print(json.dumps({"frequencies_hz": [float(x) for x in f]}, indent=2))
        return 0
    print(f"{model.definition.name}: {model.n_dofs} DOFs, lowest {args.count} modes")
    for i, x in enumerate(f):
        print(f"{i + 1:>4}  {x:10.4f} Hz")
    return 0
