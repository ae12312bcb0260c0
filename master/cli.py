"""The ``pantocosim`` command line.

Each subcommand lives in ``pantocosim.master.commands.<name>`` and exposes
``add_parser(subparsers)`` and ``run(args) -> int``. Errors the user can fix (bad parameter or
flag, unknown preset, non-convergence, an output place that cannot be written) are printed as
one clear line and exit with status 2; Ctrl-C prints one line and exits with status 130 (a
run keeps what it computed, :mod:`pantocosim.master.interrupt`).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from pantocosim import __version__
from pantocosim.core.disk_cache import check_settings
from pantocosim.core.errors import Interrupted, PantocosimError
from pantocosim.core.registry import Registry
from pantocosim.master.interrupt import remember_interrupts

#: exit status of an interrupted command (128 + SIGINT, as shells report it)
EXIT_INTERRUPTED = 130
EXIT_USER_ERROR = 2


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``pantocosim run: error: argument --coupling: invalid
    choice: 'x' (choose from ...)``, exit status 2 (the usage is in ``--help``)."""

    def error(self, message):
        self.exit(EXIT_USER_ERROR, f"{self.prog}: error: {message} (see {self.prog} "
                  "--help)\n")

#: subcommand -> its module, in the order ``pantocosim --help`` lists them
COMMANDS = Registry("command")
for _name in ("run", "sweep", "report", "modal", "pantograph", "static", "modes", "pendulum",
              "build-fmus", "ssp", "regress", "bench", "validate", "export-native"):
    COMMANDS.add(_name, f"pantocosim.master.commands.{_name.replace('-', '_')}")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="pantocosim",
        description="Pantograph-catenary dynamic interaction as FMI 2.0 and 3.0 co-simulation "
        "components.")
    parser.add_argument("--version", action="version", version=f"pantocosim {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module_name in COMMANDS.values():
        module = importlib.import_module(module_name)   # a missing one is a broken install
        p = module.add_parser(sub)
        p.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 1
    prefix = f"pantocosim {args.command}"
    if getattr(args, "no_cache", False):
        os.environ["PANTOCOSIM_NO_CACHE"] = "1"   # inherited by workers and FMUs

    try:
        with remember_interrupts():
            check_settings()                      # a bad cache setting before any work
            return int(args._run(args) or 0)
    except Interrupted as exc:
        print(f"{prefix}: {one_line(exc)}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except KeyboardInterrupt:
        print(f"{prefix}: interrupted (Ctrl-C)", file=sys.stderr)
        return EXIT_INTERRUPTED
    except PantocosimError as exc:
        print(f"{prefix}: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_USER_ERROR
    except MemoryError:
        print(f"{prefix}: error: out of memory (the size guard's estimate was too low: "
              "use a smaller model or a shorter run)", file=sys.stderr)
        return EXIT_USER_ERROR
    except BrokenPipeError:
        raise
    except OSError as exc:   # a file the user named cannot be read or written
        where = f" {exc.filename!r}" if exc.filename else ""
        print(f"{prefix}: error:{where} {exc.strerror or exc}", file=sys.stderr)
        return EXIT_USER_ERROR


def one_line(exc: Exception) -> str:
    """The message of ``exc`` on one line."""
    return " ".join(str(exc).split())


def console_main() -> None:
    """Console entry point. After runs that loaded pythonfmu FMUs into this process, exit with
    ``os._exit`` once everything is written: pythonfmu 0.7.0 can abort at interpreter shutdown
    (docs/pythonfmu-notes.md, B5) and would turn a finished run into a crash."""
    try:
        code = main()
    except BrokenPipeError:
        # the reader of our output went away (``pantocosim static x | head``): stop quietly

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = 141   # 128 + SIGPIPE, as shells report it
    except KeyboardInterrupt:   # before a command started (loading the modules)
        print("pantocosim: interrupted (Ctrl-C)", file=sys.stderr)
        code = EXIT_INTERRUPTED
    if "fmpy.fmi2" in sys.modules or "fmpy.fmi3" in sys.modules:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    console_main()
