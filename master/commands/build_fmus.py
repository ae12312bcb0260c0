"""``pantocosim build-fmus``: build the co-simulation FMUs into dist/fmus/ (FMI 2.0) and
dist/fmus/fmi3/ (FMI 3.0)."""

from __future__ import annotations

from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("build-fmus", help="build the FMUs (FMI 2.0 and 3.0) into dist/fmus/",
                       description="Build one FMU per pantograph preset and the catenary FMU, "
                       "then the default scenario's FMUs, SSP file and (FMI 2.0) CoFmuPy "
                       "configuration; FMI 2.0 (pythonfmu) into the folder, FMI 3.0 "
                       "(pythonfmu3) into its fmi3/ subfolder.")
    p.add_argument("--out", default=None, help="output folder (default dist/fmus)")
    p.add_argument("--only", nargs="*", help="build only these FMUs (no scenario files)")
    p.add_argument("--no-ssp", action="store_true", help="skip the scenario FMUs and SSP file")
    p.add_argument("--fmi", type=int, nargs="+", choices=(2, 3), default=None,
                   help="FMI versions to build (default both: 2 into --out, 3 into --out/fmi3)")
    p.add_argument("--wait", action="store_true",
                   help="if another build writes --out, wait for it to end (default: stop)")
    return p


def run(args) -> int:
    from pantocosim.core.errors import OutputError
    from pantocosim.master.fmu.build import FMI_VERSIONS, check_names, default_out
    from pantocosim.master.fmu.dist import build_all
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
        build_all(out, only=args.only, ssp=not args.no_ssp, fmi=args.fmi or FMI_VERSIONS)
    return 0
