"""The embedding library of the Python FMUs (``pantocosim.fmi.embedding``): the C library that
embeds Python in them, one per FMI version.

``pantocosim build-fmus`` compiles the library of each FMI version it builds once per build
with the system's C compiler (``$CC``, else ``cc``): ``fmi2_export.c`` or ``fmi3_export.c``
with the shared ``export_common.c``. It goes into every FMU of that version as
``binaries/<platform>/<modelIdentifier>.so`` (``linux64`` in FMI 2.0, ``x86_64-linux`` in
FMI 3.0), in place of pythonfmu's or pythonfmu3's library, together with the bridge module it
calls and the name of the Python that built the FMU. The Windows DLLs are kept as they are.
Without a C compiler the build keeps pythonfmu's library and says what that costs (C and C++
hosts then need libpython preloaded).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

from pantocosim.core.errors import ParameterError
from pantocosim.fmi.embedding import BRIDGE_SOURCE, COMMON_SOURCES, EXPORTS, RUNTIME_FILE

CFLAGS = ["-std=c11", "-O2", "-fPIC", "-shared", "-fvisibility=hidden", "-Wall"]
LIBS = ["-ldl", "-lpthread"]


def compiler() -> str | None:
    """The C compiler: ``$CC`` (refused when it names no program), else ``cc`` or ``gcc`` on
    PATH (None: none)."""
    cc = os.environ.get("CC", "").strip()
    if not cc:
        return shutil.which("cc") or shutil.which("gcc")
    if shutil.which(cc) is None:
        raise ParameterError("CC", cc, "no such compiler: give a C compiler's name on PATH "
                             "or its path, or unset CC for cc or gcc on PATH",
                             source="environment variable")
    return cc


def compile_export_library(work: Path, fmi: int = 2) -> Path | None:
    """The embedding library of FMI version ``fmi`` compiled into ``work``; None (with a
    warning) without a compiler."""
    cc = compiler()
    source = EXPORTS[fmi].source
    out = Path(work) / f"{source.stem}.so"
    if cc is None:
        print("build-fmus: warning: no C compiler (set CC or install gcc): the FMUs keep "
              "pythonfmu's library, which C and C++ FMI hosts load only with libpython "
              "preloaded (docs/third-party.md)", file=sys.stderr)
        return None
    cmd = [cc, *CFLAGS, "-o", str(out), str(source), *map(str, COMMON_SOURCES), *LIBS]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"compiling {source} failed ({' '.join(cmd)}):\n"
                           f"{done.stderr.strip()}")
    return out


def runtime_record() -> str:
    """The resources file naming the Python that builds the FMU."""
    return f"executable={sys.executable}\n"


def install_export_library(fmu: Path, library: Path | None, fmi: int = 2) -> None:
    """Rewrite ``fmu`` (FMI version ``fmi``) with ``library`` as its Linux binary, the bridge
    module and the runtime record in its resources (in place, through a sibling file). The
    sources of the replaced library (pythonfmu3 ships them in ``sources/``) are dropped: they
    do not build the binary the FMU carries."""
    export = EXPORTS[fmi]
    tmp = fmu.with_name(fmu.name + ".tmp")
    added = {f"resources/{export.bridge_module}.py": BRIDGE_SOURCE.read_bytes(),
             f"resources/{RUNTIME_FILE}": runtime_record().encode()}
    binaries = f"binaries/{export.platform}/"
    with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            if info.filename in added:
                continue
            if library is not None and info.filename.startswith("sources/"):
                continue
            data = src.read(info)
            if library is not None and info.filename.startswith(binaries) \
                    and info.filename.endswith(".so"):
                data = library.read_bytes()
            dst.writestr(info, data)
        for name, data in added.items():
            dst.writestr(name, data)
    tmp.replace(fmu)
