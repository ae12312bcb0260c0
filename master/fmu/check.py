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
