"""The FMUs' own FMI 2.0 export library (``pantocosim.fmi.native``).

``pantocosim build-fmus`` compiles ``fmi2_export.c`` once per build with the system's C
compiler (``$CC``, else ``cc``) and puts it into every FMU as
``binaries/linux64/<modelIdentifier>.so``, in place of pythonfmu's library, together with the
bridge module it calls and the name of the Python that built the FMU. pythonfmu's win64 DLL
is kept as it is. Without a C compiler the build keeps pythonfmu's linux64 library and says
what that costs (native hosts then need libpython preloaded).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

from pantocosim.fmi.native import BRIDGE_MODULE, BRIDGE_SOURCE, EXPORT_SOURCE, RUNTIME_FILE

CFLAGS = ["-std=c11", "-O2", "-fPIC", "-shared", "-fvisibility=hidden", "-Wall"]
LIBS = ["-ldl", "-lpthread"]


def compiler() -> str | None:
    """The C compiler: ``$CC``, else ``cc`` or ``gcc`` on PATH."""
    cc = os.environ.get("CC")
    return cc if cc else shutil.which("cc") or shutil.which("gcc")


def compile_export_library(work: Path) -> Path | None:
    """``fmi2_export.c`` compiled into ``work``; None (with a warning) without a compiler."""
    cc = compiler()
    out = Path(work) / "fmi2_export.so"
    if cc is None:
        print("build-fmus: warning: no C compiler (set CC or install gcc): the FMUs keep "
              "pythonfmu's linux64 library, which native FMI hosts load only with libpython "
              "preloaded (docs/third-party.md)", file=sys.stderr)
        return None
    cmd = [cc, *CFLAGS, "-o", str(out), str(EXPORT_SOURCE), *LIBS]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"compiling {EXPORT_SOURCE} failed ({' '.join(cmd)}):\n"
                           f"{done.stderr.strip()}")
    return out


def runtime_record() -> str:
    """The resources file naming the Python that builds the FMU."""
    return f"executable={sys.executable}\n"


def install_export_library(fmu: Path, library: Path | None) -> None:
    """Rewrite ``fmu`` with ``library`` as its linux64 binary, the bridge module and the
    runtime record in its resources (in place, through a sibling file)."""
    tmp = fmu.with_name(fmu.name + ".tmp")
    added = {f"resources/{BRIDGE_MODULE}.py": BRIDGE_SOURCE.read_bytes(),
             f"resources/{RUNTIME_FILE}": runtime_record().encode()}
    with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            if info.filename in added:
                continue
            data = src.read(info)
            if library is not None and info.filename.startswith("binaries/linux64/") \
                    and info.filename.endswith(".so"):
                data = library.read_bytes()
            dst.writestr(info, data)
        for name, data in added.items():
            dst.writestr(name, data)
    tmp.replace(fmu)
