"""FMI call scripts for the C host's script mode (fmus/native/host/host_script.c) and their
fmpy twin.

:class:`Script` writes the script; ``python fmi_script.py < script`` runs it through fmpy's
``FMU2Slave`` or ``FMU3Slave`` (the FMU's version) and prints what the C host prints for the
``get`` calls (``= LINE get STATUS VALUES``), so the two hosts' outputs compare line by line.
"""

from __future__ import annotations

import os
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path


def model_info(fmu: Path) -> tuple[str, str, dict]:
    """(modelIdentifier, guid or instantiation token, {variable name: (value reference, type
    letter)}) of an FMI 2.0 or 3.0 FMU."""
    with zipfile.ZipFile(fmu) as z:
        md = ET.fromstring(z.read("modelDescription.xml"))
    ident = md.find("CoSimulation").get("modelIdentifier")
    kinds = {"Real": "r", "Integer": "i", "Boolean": "b", "String": "s"}
    variables = {}
    for v in md.iter("ScalarVariable"):
        kind = next(kinds[c.tag] for c in v if c.tag in kinds)
        variables[v.get("name")] = (int(v.get("valueReference")), kind)
    kinds3 = {"Float64": "r", "Int32": "i", "Boolean": "b", "String": "s"}
    for v in md.iterfind("ModelVariables/*"):
        if v.tag in kinds3:
            variables[v.get("name")] = (int(v.get("valueReference")), kinds3[v.tag])
    return ident, md.get("guid") or md.get("instantiationToken"), variables


class Script:
    """An FMI call script (one call a line) over FMUs extracted into ``folder``."""

    def __init__(self, folder: Path):
        self.folder = Path(folder)
        self.lines: list[str] = []
        self.vars: dict[str, dict] = {}

    def load(self, alias: str, fmu: Path) -> None:
        target = self.folder / alias
        with zipfile.ZipFile(fmu) as z:
            z.extractall(target)
        ident, guid, variables = model_info(fmu)
        self.vars[alias] = variables
        self.lines.append(f"load {alias} {target} {ident} {guid}")

    def vr(self, alias: str, name: str) -> int:
        return self.vars[alias][name][0]

    def call(self, *words) -> int:
        """Append a call; returns its line number (as the hosts print it)."""
        self.lines.append(" ".join(str(w) for w in words))
        return len(self.lines)

    def set(self, alias: str, name: str, value) -> int:
        vr, kind = self.vars[alias][name]
        if kind == "r":
            value = repr(float(value))
        return self.call("set", alias, kind, vr, value)

    def get(self, alias: str, *names: str) -> int:
        kind = self.vars[alias][names[0]][1]
        return self.call("get", alias, kind, *(self.vr(alias, n) for n in names))

    def start(self, alias: str, name: str, params: dict) -> None:
        """instantiate, setupExperiment(0), the parameters in initialisation mode, exit."""
        self.call("instantiate", alias, name)
        self.call("setup", alias, 0.0)
        self.call("enter", alias)
        for key, value in params.items():
            self.set(alias, key, value)
        self.call("exit", alias)

    def text(self) -> str:
        return "\n".join(self.lines) + "\n"


def results(output: str) -> dict[int, list]:
    """{line: [status, *values]} of a host's ``= LINE CALL STATUS ...`` lines."""
    out = {}
    for line in output.splitlines():
        if line.startswith("= "):
            words = line.split()
            if len(words) >= 4 and words[1].isdigit():
                out[int(words[1])] = [int(words[3])] + [_number(w) for w in words[4:]]
    return out


def _number(word: str):
    try:
        return float(word)
    except ValueError:
        return word


# ----------------------------------------------------------------------- the fmpy twin
#: per FMI version: the fmpy class, its getters and setters by type letter
TWIN_CALLS = {
    "2.0": ("fmpy.fmi2:FMU2Slave",
            {"r": "getReal", "i": "getInteger", "b": "getBoolean", "s": "getString"},
            {"r": ("setReal", float), "i": ("setInteger", int), "b": ("setBoolean", int),
             "s": ("setString", str)}),
    "3.0": ("fmpy.fmi3:FMU3Slave",
            {"r": "getFloat64", "i": "getInt32", "b": "getBoolean", "s": "getString"},
            {"r": ("setFloat64", float), "i": ("setInt32", int),
             "b": ("setBoolean", lambda x: bool(int(x))), "s": ("setString", str)}),
}


def _run_fmpy(lines) -> None:
    import importlib

    from fmpy.fmi1 import FMICallException

    fmus: dict = {}
    calls: dict = {}     # alias -> (getters, setters, start time, FMI 3.0)
    for number, line in enumerate(lines, start=1):
        a = line.split()
        if not a:
            continue
        cmd, s = a[0], fmus.get(a[1]) if len(a) > 1 else None
        try:
            values = []
            if cmd == "load":
                version = ET.parse(Path(a[2]) / "modelDescription.xml").getroot().get(
                    "fmiVersion")
                cls, getters, setters = TWIN_CALLS[version]
                module, name = cls.split(":")
                fmus[a[1]] = getattr(importlib.import_module(module), name)(
                    guid=a[4], unzipDirectory=a[2], modelIdentifier=a[3], instanceName=a[1])
                calls[a[1]] = [getters, setters, 0.0, version == "3.0"]
            elif cmd == "instantiate":
                s.instanceName = a[2]
                s.instantiate(loggingOn=False)
            elif cmd == "setup":
                if calls[a[1]][3]:
                    calls[a[1]][2] = float(a[2])      # FMI 3.0: given to enter
                else:
                    s.setupExperiment(startTime=float(a[2]))
            elif cmd == "enter" and calls[a[1]][3]:
                s.enterInitializationMode(startTime=calls[a[1]][2])
            elif cmd in ("enter", "exit", "terminate", "reset"):
                getattr(s, {"enter": "enterInitializationMode",
                            "exit": "exitInitializationMode"}.get(cmd, cmd))()
            elif cmd == "step":
                s.doStep(float(a[2]), float(a[3]))
            elif cmd == "set":
                name, conv = calls[a[1]][1][a[2]]
                getattr(s, name)([int(a[3])], [conv(a[4])])
            elif cmd == "get":
                values = getattr(s, calls[a[1]][0][a[2]])([int(x) for x in a[3:]])
                if a[2] == "b" and calls[a[1]][3]:    # FMI 3.0: C bool, printed 0/1
                    values = [int(bool(v)) for v in values]
            elif cmd == "copy":
                x = getattr(s, calls[a[1]][0]["r"])([int(a[2])])
                getattr(fmus[a[3]], calls[a[3]][1]["r"][0])([int(a[4])], x)
            elif cmd == "free":
                s.freeInstance()
            status = 0
        except FMICallException as exc:
            status = exc.status
        if cmd == "get":
            text = " ".join(repr(float(v)) if isinstance(v, float) else str(v) for v in values)
            print(f"= {number} get {status} {text}".rstrip(), flush=True)


if __name__ == "__main__":
    import numpy  # noqa: F401
    import scipy.sparse.linalg  # noqa: F401  (imported before any FMU is loaded)

    _run_fmpy(sys.stdin.read().splitlines())
    sys.stdout.flush()
    os._exit(0)
