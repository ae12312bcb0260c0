"""The FMUs' embedding libraries: their C sources and the Python bridge they call (both bundled).

One library per FMI version (``fmi2_export.c``, ``fmi3_export.c``), each over the shared
part ``export_common.c`` (finding a Python runtime, the instance and FMU-state registries,
calling the bridge); one bridge module for both (its ``instantiate`` takes the version).
"""

from dataclasses import dataclass
from pathlib import Path

from pantocosim.core.registry import Registry

HERE = Path(__file__).resolve().parent
#: the bridge module's source, copied into every FMU's resources under its version's name
BRIDGE_SOURCE = HERE / "bridge.py"
#: resources file naming the Python that built the FMU (``executable=...``)
RUNTIME_FILE = "pantocosim_runtime.txt"
#: C sources every embedding library is compiled with
COMMON_SOURCES = (HERE / "export_common.c",)


@dataclass(frozen=True)
class ExportLibrary:
    """The embedding library of one FMI version."""

    source: Path            # its C source (compiled with COMMON_SOURCES)
    bridge_module: str      # the bridge's module name in the FMU's resources
    platform: str           # the FMU's binaries/<platform>/ folder of the library


#: FMI major version -> its embedding library
EXPORTS = Registry("embedding library", "FMI version")
EXPORTS.add(2, ExportLibrary(HERE / "fmi2_export.c", "pantocosim_fmi2_bridge", "linux64"))
EXPORTS.add(3, ExportLibrary(HERE / "fmi3_export.c", "pantocosim_fmi3_bridge", "x86_64-linux"))
