"""The C host of the FMUs (``fmus/native/host/``, shipped with the package): one program that
loads FMI 2.0 and 3.0 FMUs with no Python and runs the native FMUs' loops or a script of FMI
calls (``host_main.c`` lists its modes). Its sources and its build with the system's C
compiler."""

from __future__ import annotations

import subprocess
from pathlib import Path

from pantocosim.master.native.build import CFLAGS, c_compiler
from pantocosim.master.native.headers import SOURCE_DIR

__all__ = ["HOST_DIR", "HOST_NAME", "host_sources", "build_host"]

#: the host's sources
HOST_DIR = SOURCE_DIR / "host"
#: the program's name
HOST_NAME = "pantocosim_host"


def host_sources() -> list[Path]:
    """The host's C files: one compile line builds the program from them."""
    return sorted(HOST_DIR.glob("*.c"))


def build_host(folder: Path) -> Path:
    """The host compiled into ``folder`` with the system's C compiler (kept if there)."""
    exe = Path(folder) / HOST_NAME
    if not exe.exists():
        subprocess.run([c_compiler(), *CFLAGS, "-o", str(exe), *map(str, host_sources()),
                        "-ldl", "-lm"], check=True)
    return exe
