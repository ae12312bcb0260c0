"""The ``pantocosim`` command line.

Each subcommand lives in ``pantocosim.master.commands.<name>`` and exposes
``add_parser(subparsers)`` and ``run(args) -> int``. Errors the user can fix (bad parameter,
unknown preset, non-convergence) are printed as one clear line and exit with status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from pantocosim import __version__
from pantocosim.core.errors import PantocosimError

#: subcommand modules, in the order ``pantocosim --help`` lists them
COMMANDS = ["run", "sweep", "report", "modal", "pantograph", "static", "modes", "pendulum",
            "build-fmus", "regress", "bench"]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pantocosim",
        description="Pantograph-catenary dynamic interaction with FMI 2.0 co-simulation.")
    parser.add_argument("--version", action="version", version=f"pantocosim {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"pantocosim.master.commands.{name.replace('-', '_')}")
        except ModuleNotFoundError as exc:
            if exc.name == f"pantocosim.master.commands.{name.replace('-', '_')}":
                continue  # command not built yet
            raise
        p = module.add_parser(sub)
        p.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 1
    try:
        return int(args._run(args) or 0)
    except PantocosimError as exc:
        print(f"pantocosim {args.command}: error: {exc}", file=sys.stderr)
        return 2


def console_main() -> None:
    """Console entry point. After runs that loaded pythonfmu FMUs into this process, exit with
    ``os._exit`` once everything is written: pythonfmu 0.7.0 can abort at interpreter shutdown
    (design/fmi-toolchain.md, defect B5) and would turn a finished run into a crash."""
    code = main()
    if "fmpy.fmi2" in sys.modules:
        import os

        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    console_main()
