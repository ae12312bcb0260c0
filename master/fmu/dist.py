"""Everything ``pantocosim build-fmus`` (and ``build_fmus.py``) writes, for each FMI
version: the generic FMUs (:mod:`pantocosim.master.fmu.build`), then the default scenario's
FMUs, SSP file and (FMI 2.0) CoFmuPy configuration (:mod:`pantocosim.master.ssp`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pantocosim.core.errors import PantocosimError
from pantocosim.master.fmu.build import FMI_VERSIONS, build_fmus, check_fmi, default_out, fmi_out
from pantocosim.master.ssp import write_scenario_package


def build_all(out: Path | None = None, only=None, ssp: bool = True,
              quiet: bool = False, fmi=FMI_VERSIONS) -> list[Path]:
    """``pantocosim build-fmus``: for each FMI version of ``fmi`` (default both) the generic
    FMUs, then (unless ``ssp`` is false or ``only`` names a subset) the default scenario's
    FMUs, SSP file (and, FMI 2.0, CoFmuPy configuration), into :func:`fmi_out`."""
    out = Path(out) if out is not None else default_out()
    paths = []
    for version in check_fmi(fmi):
        folder = fmi_out(out, version)
        paths += build_fmus(folder, only, quiet, fmi=version)
        if ssp and not only:
            paths += write_scenario_package(folder, quiet=quiet, fmi=version)
    return paths


def main(argv: list[str] | None = None) -> int:
    """``build_fmus.py`` / ``python -m pantocosim.master.fmu.dist``."""
    parser = argparse.ArgumentParser(description="Build the pantocosim FMUs and the SSP file "
                                     "of the default scenario.")
    parser.add_argument("--out", type=Path, default=None, help="output folder (default "
                        "dist/fmus of the working folder)")
    parser.add_argument("--only", nargs="*", help="build only these FMUs (no SSP)")
    parser.add_argument("--no-ssp", action="store_true", help="do not write the scenario FMUs "
                        "and SSP file")
    parser.add_argument("--fmi", type=int, nargs="*", default=list(FMI_VERSIONS),
                        help="FMI versions to build (2, 3; default both: FMI 2.0 into --out, FMI "
                        "3.0 into its fmi3/)")
    args = parser.parse_args(argv)
    try:
        build_all(args.out, args.only, ssp=not args.no_ssp, fmi=args.fmi)
    except PantocosimError as exc:
        print(f"build-fmus: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
