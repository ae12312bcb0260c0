"""The check of an FMU file against what it claims: its variables and structure are of its
``fmiVersion``, it has a binary for this platform named after its ``modelIdentifier``, that
binary exports the FMI functions of that version, and (a PythonFMU export) its slave module
defines that class. ``build-fmus`` checks each FMU it builds with it; runs, SSP files and the
third-party masters check the FMUs they are given."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from pantocosim.core.errors import ParameterError


#: what a model description of each FMI version holds and the other's does not
_VERSION_MARKS = {
    "2.0": {"token": "guid", "variable": "ScalarVariable", "outputs": "Outputs",
            "entry": "fmi2DoStep"},
    "3.0": {"token": "instantiationToken", "variable": None, "outputs": "Output",
            "entry": "fmi3DoStep"},
}


def check_binary_fmu(path: Path, field: str, source: str | None = None) -> None:
    """Check that the FMU file ``path`` can run here and is what its model description
    says: its variables and structure are of its ``fmiVersion``, it has a binary for this
    platform named after its ``modelIdentifier``, that binary exports the FMI functions of
    that version, and (a PythonFMU export) its slave module defines that class. Raises
    ParameterError naming ``field``, the file and what is accepted."""
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        root = ET.fromstring(z.read("modelDescription.xml"))
        version = root.get("fmiVersion")
        _check_version_structure(root, version, path, field, source)
        cs = root.find("CoSimulation")
        ident = cs.get("modelIdentifier", "") if cs is not None else ""
        library = _platform_library(names, version, ident, path, field, source)
        _check_library(z.read(library), library, version, path, field, source)
        _check_slave_module(z, names, ident, path, field, source)


def _check_version_structure(root, version: str, path, field, source) -> None:
    mine = _VERSION_MARKS.get(version)
    if mine is None:
        return                                   # refused by the version check itself
    other_version, other = next((v, m) for v, m in _VERSION_MARKS.items() if v != version)
    variables = root.find("ModelVariables")
    tags = {v.tag for v in variables} if variables is not None else set()
    structure = root.find("ModelStructure")
    parts = {s.tag for s in structure} if structure is not None else set()
    wrong = []
    if root.get(mine["token"]) is None:
        wrong.append(f"no {mine['token']} attribute")
    if root.get(other["token"]) is not None:
        wrong.append(f"an FMI {other_version} {other['token']}")
    if mine["variable"] and tags - {mine["variable"]}:
        wrong.append(f"FMI {other_version} variables ({', '.join(sorted(tags - {mine['variable']}))})")
    if not mine["variable"] and "ScalarVariable" in tags:
        wrong.append(f"FMI {other_version} variables (ScalarVariable)")
    if other["outputs"] in parts:
        wrong.append(f"an FMI {other_version} ModelStructure ({other['outputs']})")
    if wrong:
        raise ParameterError(field, str(path), f"its model description says fmiVersion "
                             f"{version} but holds {', '.join(wrong)}; accepted: a model "
                             f"description consistent with its FMI version", source)


def _platform_library(names: set, version: str, ident: str, path, field, source) -> str:
    """The zip entry of the FMU's binary for this platform (refused when absent or another
    model's)."""
    import fmpy

    platform = fmpy.platform if version == "2.0" else fmpy.platform_tuple
    folder = f"binaries/{platform}/"
    library = f"{folder}{ident}{fmpy.sharedLibraryExtension}"
    if library in names:
        return library
    others = sorted(n[len(folder):] for n in names
                    if n.startswith(folder) and n.endswith(fmpy.sharedLibraryExtension))
    if others:
        raise ParameterError(field, str(path), f"its binary for {platform} is "
                             f"{', '.join(others)}, not {ident}{fmpy.sharedLibraryExtension} "
                             f"named by its model description (modelIdentifier '{ident}'): "
                             "the binary is another model's; accepted: an FMU whose binary "
                             "and model description were exported together", source)
    built = sorted({n.split("/")[1] for n in names
                    if n.startswith("binaries/") and n.count("/") >= 2 and n.split("/")[1]})
    sources = any(n.startswith("sources/") for n in names)
    raise ParameterError(field, str(path), f"has no binary for this platform ({library}; "
                         f"it has {', '.join(built) or 'no binaries'}"
                         f"{', and sources: compile them for ' + platform if sources else ''}"
                         f"); accepted: an FMU built for {platform}", source)


def _check_library(data: bytes, library: str, version: str, path, field, source) -> None:
    entry = _VERSION_MARKS[version]["entry"]
    if entry.encode() not in data:
        raise ParameterError(field, str(path), f"its binary {library} does not export "
                             f"{entry}: not an FMI {version} co-simulation library, as its "
                             f"model description says; accepted: an FMU whose binary and "
                             "model description were exported together", source)


def _check_slave_module(z, names: set, ident: str, path, field, source) -> None:
    """A PythonFMU export runs the class ``modelIdentifier`` of its slave module."""
    if "resources/slavemodule.txt" not in names:
        return
    module = z.read("resources/slavemodule.txt").decode("utf-8", "replace").strip()
    text = f"resources/{module}.py"
    if text in names and not re.search(rf"^class {re.escape(ident)}\b",
                                       z.read(text).decode("utf-8", "replace"), re.M):
        raise ParameterError(field, str(path), f"its slave module {text} defines no class "
                             f"{ident} (the modelIdentifier of its model description): its "
                             "resources are another model's; accepted: an FMU whose resources "
                             "and model description were exported together", source)
