"""Checks of the FMU files of a co-simulation, before any is loaded or anything is written.

- each file is an FMI 2.0 or 3.0 co-simulation FMU: a readable zip archive with a model
  description (not a folder, an empty or truncated file);
- each pantograph FMU is a pantocosim pantograph FMU holding the scenario's model: the model
  of an FMU is its ``modelName``, the slave class of its preset
  (:data:`pantocosim.master.fmu.build.PANTOGRAPH_FMUS`); a pantograph given by a parameter
  file is handed to the FMU as its ``parameter_file``;
- the catenary FMU is pantocosim's and has inputs for every pantograph and uplift outputs for
  every support of the line (its capacities are read from its model description).

Errors name the scenario file, the field (``pantographs[k].fmu``, ``pantographs``,
``spans``) and the value.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

from pantocosim.core.errors import ParameterError
from pantocosim.master.fmu.build import CATENARY_CLASS, PANTOGRAPH_FMUS
from pantocosim.pantograph.presets import PRESETS


@dataclass
class FmuPlan:
    """The checked FMUs of a co-simulation."""

    catenary: Path
    pantographs: list[Path]
    #: per pantograph: the parameter file handed to its FMU (None: the FMU's preset)
    parameter_files: list[str | None]


def read_fmu(path: Path, field: str, source: str | None):
    """The model description of the FMU file ``path`` (checked)."""
    from fmpy import read_model_description

    p = Path(path)
    if not p.exists():
        raise ParameterError(field, str(p), "FMU file not found (build the FMUs with "
                             "`pantocosim build-fmus`)", source)
    if p.is_dir():
        raise ParameterError(field, str(p), "is a folder; an FMU is a .fmu file (a zip "
                             "archive)", source)
    if p.stat().st_size == 0:
        raise ParameterError(field, str(p), "is an empty file, not an FMU", source)
    if not zipfile.is_zipfile(p):
        raise ParameterError(field, str(p), "is not an FMU: not a zip archive (truncated or "
                             "another kind of file)", source)
    try:
        with zipfile.ZipFile(p) as z:
            bad = z.testzip()
            names = set(z.namelist())
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
        raise ParameterError(field, str(p), f"is a damaged zip archive: {exc}",
                             source) from None
    if bad is not None:
        raise ParameterError(field, str(p), f"is a damaged zip archive ({bad} fails its "
                             "checksum)", source)
    if "modelDescription.xml" not in names:
        raise ParameterError(field, str(p), "is not an FMU: no modelDescription.xml", source)
    try:
        md = read_model_description(str(p), validate=False)
    except Exception as exc:  # noqa: BLE001 - fmpy raises many kinds on a bad description
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise ParameterError(field, str(p), f"has an unreadable modelDescription.xml: "
                             f"{first}", source) from None
    if md.fmiVersion not in ("2.0", "3.0") or md.coSimulation is None:
        raise ParameterError(field, str(p), f"is not an FMI 2.0 or 3.0 co-simulation FMU (FMI "
                             f"{md.fmiVersion}, co-simulation: "
                             f"{'yes' if md.coSimulation else 'no'})", source)
    return md


def pantograph_preset(md) -> str | None:
    """The preset of a pantocosim pantograph FMU (None: another FMU)."""
    return {cls: name for name, cls in PANTOGRAPH_FMUS.items()}.get(md.modelName)


def numbered(md, stem: str, causality: str) -> int:
    """How many variables ``<stem>_0``, ``<stem>_1``, ... of ``causality`` the FMU has."""
    pattern = re.compile(rf"{re.escape(stem)}_(\d+)$")
    return sum(1 for v in md.modelVariables
               if v.causality == causality and pattern.match(v.name))


def check_fmus(sc, n_sup: int, cat_path: Path, pan_paths: list[Path]) -> FmuPlan:
    """Check the FMU files of scenario ``sc`` against its pantographs and its line of
    ``n_sup`` supports (see the module)."""
    src = sc.source
    files = []
    for k, (spec, path) in enumerate(zip(sc.pantographs, pan_paths)):
        field = f"pantographs[{k}].fmu"
        md = read_fmu(path, field, src)
        preset = pantograph_preset(md)
        if preset is None:
            what = ("the catenary FMU" if md.modelName == CATENARY_CLASS
                    else f"model '{md.modelName}'")
            raise ParameterError(field, str(path), f"is not a pantocosim pantograph FMU "
                                 f"({what}); `pantocosim run` drives the FMUs of `pantocosim "
                                 "build-fmus` (other FMUs: the third-party masters of "
                                 "docs/third-party.md)", src)
        if spec.model in PRESETS:
            if preset != spec.model:
                raise ParameterError(field, str(path), f"holds the pantograph model "
                                     f"'{preset}', not pantographs[{k}].model = "
                                     f"'{spec.model}'; give the FMU of '{spec.model}' or "
                                     f"model = '{preset}'", src)
            files.append(None)
        else:
            files.append(str(Path(spec.model).resolve()))
    md = read_fmu(cat_path, "catenary FMU", src)
    if md.modelName != CATENARY_CLASS:
        raise ParameterError("catenary FMU", str(cat_path), f"is not the pantocosim catenary "
                             f"FMU (model '{md.modelName}')", src)
    n_p = len(sc.pantographs)
    cap = numbered(md, "contact_force", "input")
    if n_p > cap:
        raise ParameterError("pantographs", n_p, f"the catenary FMU ({cat_path}) takes at "
                             f"most {cap} pantographs; use --coupling monolithic for more",
                             src)
    cap = numbered(md, "support_uplift", "output")
    if n_sup > cap:
        field, value = ("spans", sc.spans) if sc.spans else ("catenary", sc.catenary)
        raise ParameterError(field, value, f"the line has {n_sup} supports but the catenary "
                             f"FMU ({cat_path}) outputs the uplift of {cap} (support_uplift_0.."
                             f"{cap - 1}); co-simulate at most {cap - 1} spans, or use "
                             "--coupling monolithic", src)
    return FmuPlan(catenary=Path(cat_path), pantographs=[Path(p) for p in pan_paths],
                   parameter_files=files)


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
