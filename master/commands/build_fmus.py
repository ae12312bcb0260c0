"""``pantocosim build-fmus``: build the FMI 2.0 co-simulation FMUs into dist/fmus/."""

from __future__ import annotations

from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("build-fmus", help="build the FMUs (pythonfmu) into dist/fmus/",
                       description="Build one FMU per pantograph preset and the catenary FMU, "
                       "then the default scenario's FMUs, SSP file and CoFmuPy configuration.")
    p.add_argument("--out", default=None, help="output folder (default dist/fmus)")
    p.add_argument("--only", nargs="*", help="build only these FMUs (no scenario files)")
    p.add_argument("--no-ssp", action="store_true", help="skip the scenario FMUs and SSP file")
    p.add_argument("--wait", action="store_true",
                   help="if another build writes --out, wait for it to end (default: stop)")
    return p


def run(args) -> int:
    from pantocosim.core.errors import OutputError
    from pantocosim.master.fmu_build import build_all, check_names, default_out
    from pantocosim.master.output_folder import reason

    check_names(args.only)
    out = Path(args.out) if args.out else default_out()
    if out.exists() and not out.is_dir():
        raise OutputError("--out", out, "is a file, not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError("--out", out, f"cannot create the folder: {reason(exc)}") from None
    from pantocosim.master.folder_lock import FolderLock

    with FolderLock(out, "--out", wait=args.wait):
        build_all(out, only=args.only, ssp=not args.no_ssp)
    return 0
