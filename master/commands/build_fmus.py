"""``pantocosim build-fmus``: build the FMI 2.0 co-simulation FMUs into dist/fmus/."""

from __future__ import annotations

from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("build-fmus", help="build the FMUs (pythonfmu) into dist/fmus/",
                       description="Build one FMU per pantograph preset, the catenary FMU and "
                       "the SSP file of the default scenario.")
    p.add_argument("--out", default=None, help="output folder (default dist/fmus)")
    p.add_argument("--only", nargs="*", help="build only these FMUs")
    return p


def run(args) -> int:
    from pantocosim.master.fmu_build import DEFAULT_OUT, build_fmus

    build_fmus(Path(args.out) if args.out else DEFAULT_OUT, only=args.only)
    return 0
