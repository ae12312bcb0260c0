"""The FMUs' export library: its C source and the Python bridge it calls (both bundled)."""

from pathlib import Path

HERE = Path(__file__).resolve().parent
#: C source of the FMI 2.0 export library (binaries/linux64/<modelIdentifier>.so)
EXPORT_SOURCE = HERE / "fmi2_export.c"
#: the bridge module, copied into every FMU's resources under :data:`BRIDGE_MODULE`
BRIDGE_SOURCE = HERE / "bridge.py"
BRIDGE_MODULE = "pantocosim_fmi2_bridge"
#: resources file naming the Python that built the FMU (``executable=...``)
RUNTIME_FILE = "pantocosim_runtime.txt"
