"""Building the co-simulation FMUs, FMI 2.0 with pythonfmu and FMI 3.0 with pythonfmu3
(``pantocosim build-fmus``, ``build_fmus.py``), from the installed package: it works from any
folder and any install.

Every FMU bundles the same copy of the model package ``pantocosim`` (the installed package
without its ``master`` and ``multibody`` subpackages, which no FMU uses), a build stamp that
each slave checks at initialisation (:func:`pantocosim.core.stamp.package_stamp`), and a
small generated slave module with a unique name (pythonfmu 0.7.0 lets two FMUs whose slave modules share a name collide).

The FMI 2.0 FMUs go into the output folder (default ``dist/fmus`` of the working folder), the
FMI 3.0 ones into its subfolder ``fmi3/`` (:data:`FMI_BUILDS`); both are the same slave cores
with the front of their version (:mod:`pantocosim.fmi.front`). Two sets are built:

- the generic FMUs ``<out>/<model>.fmu`` and ``<out>/catenary.fmu``, neutral start values,
  which our master and anyone's set up by parameters;
- the scenario FMUs ``<out>/<scenario>/<model>.fmu`` whose start values are the scenario's
  (:func:`pantocosim.master.ssp.scenario_start_values`), so a master that sets no parameter runs the
  scenario, with its SSP file ``<out>/<scenario>.ssp`` and CoFmuPy configuration
  (:mod:`pantocosim.master.ssp`).
"""

from __future__ import annotations

import importlib
import shutil
import sys
import tempfile
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

import pantocosim
from pantocosim.core.errors import ParameterError
from pantocosim.core.registry import Registry
from pantocosim.core.stamp import UNBUNDLED, package_stamp
from pantocosim.fmi.front import FRONTS
from pantocosim.fmi.slave_base import STAMP_FILE, bundled_stamp
from pantocosim.master.fmu.binary_check import check_binary_fmu
from pantocosim.master.fmu.embedding import compile_export_library, install_export_library

#: pantograph FMU name (the preset) -> slave class name
PANTOGRAPH_FMUS = {
    "dsa380-rigid": "Dsa380Rigid",
    "dsa380-flexible": "Dsa380Flexible",
    "dsa380-lumped3": "Dsa380Lumped3",
    "en50318-2mass": "En50318TwoMass",
}
CATENARY_FMU = "catenary"
#: the catenary FMU's slave class name (its modelName)
CATENARY_CLASS = "Catenary"
FMU_NAMES = [*PANTOGRAPH_FMUS, CATENARY_FMU]
#: the FMU that runs a pantograph given by a parameter file (any pantograph FMU loads any
#: parameter file given as its ``parameter_file``)
PARAMETER_FILE_FMU = next(iter(PANTOGRAPH_FMUS))


@dataclass(frozen=True)
class FmiBuild:
    """How the FMUs of one FMI version are built."""

    builder: str                   # module of the builder's ``FmuBuilder``
    folder: str                    # subfolder of the output folder ("" = the folder itself)
    module_prefix: str             # of the generated slave modules (unique per version)
    options: dict = field(default_factory=dict)   # capability flags given to the builder
    #: a base the builder wants to read in the class statement (pythonfmu3 finds the slave
    #: class by its name there); the front is already one
    named_base: tuple[str, str] | None = None


#: FMI major version -> its build; ``build-fmus`` builds both by default
FMI_BUILDS = Registry("FMU build", "--fmi")
FMI_BUILDS.add(2, FmiBuild("pythonfmu.builder", "", "pantocosim_fmu_",
                           {"canGetAndSetFMUstate": True, "canSerializeFMUstate": True}))
FMI_BUILDS.add(3, FmiBuild("pythonfmu3.builder", "fmi3", "pantocosim_fmu3_",
                           {"canGetAndSetFMUState": True, "canSerializeFMUState": True,
                            "canHandleVariableCommunicationStepSize": True},
                           named_base=("pythonfmu3.fmi3slave", "Fmi3Slave")))
FMI_VERSIONS = tuple(FMI_BUILDS)


def fmi_out(out: Path, fmi: int) -> Path:
    """The folder of the FMI ``fmi`` FMUs of the output folder ``out``."""
    folder = FMI_BUILDS[fmi].folder
    return Path(out) / folder if folder else Path(out)


def default_out() -> Path:
    """``dist/fmus`` of the working folder."""
    return Path("dist") / "fmus"


def model_package_dir() -> Path:
    return Path(pantocosim.__file__).resolve().parent


def stage_package(dest: Path) -> tuple[Path, Path]:
    """Copy the installed model package (without the subpackages FMUs do not use,
    :data:`~pantocosim.core.stamp.UNBUNDLED`) and write the build stamp."""
    src = model_package_dir()
    pkg = dest / "pantocosim"

    def ignore(folder, names):
        skip = set(shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc")(folder,
                                                                                  names))
        if Path(folder).resolve() == src:
            skip |= set(UNBUNDLED) & set(names)
        return skip

    shutil.copytree(src, pkg, ignore=ignore)
    stamp = dest / STAMP_FILE
    stamp.write_text(package_stamp(pkg) + "\n")
    return pkg, stamp


def slave_source(module: str, base_module: str, base_class: str, class_name: str,
                 attributes: dict, fmi: int = 2) -> str:
    """The generated slave module: the core ``base_class`` with the front of FMI ``fmi``,
    setting class attributes (preset, start values)."""
    body = "".join(f"    {k} = {v!r}\n" for k, v in attributes.items())
    front_module, front_class = FRONTS[fmi].split(":")
    imports = [f"from pantocosim.fmi.{base_module} import {base_class}",
               f"from {front_module} import {front_class}"]
    bases = [base_class, front_class]
    named = FMI_BUILDS[fmi].named_base
    if named:
        imports.append(f"from {named[0]} import {named[1]}")
        bases.append(named[1])
    # the module must define a function of its own: pythonfmu 0.7.0 re-executes it at every
    # instantiation and frees its dict when it holds none (the second instance then fails)
    return textwrap.dedent(f'''\
        """Generated by pantocosim build-fmus ({module})."""
        {imports[0]}
        {imports[1]}
        {imports[2] if len(imports) > 2 else ""}

        class {class_name}({", ".join(bases)}):
        ''') + body + textwrap.dedent('''
            def __init__(self, **kwargs):
                super().__init__(**kwargs)
        ''').replace("\n", "\n    ").rstrip(" ")


def _build_one(module: str, source: str, project_files: list[Path], dest: Path,
               work: Path, library: Path | None, fmi: int = 2) -> Path:
    build = FMI_BUILDS[fmi]
    builder = importlib.import_module(build.builder).FmuBuilder
    script_dir = work / module
    script_dir.mkdir()
    script = script_dir / f"{module}.py"
    script.write_text(source)
    dest.parent.mkdir(parents=True, exist_ok=True)
    made = builder.build_FMU(script, dest=script_dir / "out", project_files=project_files,
                             **build.options)
    install_export_library(Path(made), library, fmi)
    check_binary_fmu(Path(made), "build-fmus", str(dest))      # as built: runs here or fails
    tmp = dest.with_name(dest.stem + ".part.fmu")  # moved whole beside dest, then into place
    shutil.move(str(made), tmp)
    tmp.replace(dest)
    return dest


def _module_name(name: str, scenario: str | None, fmi: int = 2) -> str:
    stem = name if scenario is None else f"{scenario}_{name}"
    return FMI_BUILDS[fmi].module_prefix + "".join(c if c.isalnum() else "_" for c in stem)


def check_names(only) -> list[str]:
    """The FMU names asked for (all by default); an unknown one is an error."""
    if not only:
        return list(FMU_NAMES)
    for name in only:
        if name not in FMU_NAMES:
            raise ParameterError("--only", name, f"unknown FMU; one of {', '.join(FMU_NAMES)}")
    return list(only)


def build_fmus(out: Path | None = None, only=None, quiet: bool = False,
               start_values: dict | None = None, scenario: str | None = None,
               fmi: int = 2) -> list[Path]:
    """Build the FMI ``fmi`` FMUs ``only`` (default all) into ``out`` (the folder itself:
    :func:`fmi_out` names a version's folder); ``start_values`` {fmu name: {variable: value}}
    bakes values into them (the scenario FMUs of ``scenario``)."""
    names = check_names(only)
    check_fmi(fmi)
    out = Path(out) if out is not None else default_out()
    built = []
    with tempfile.TemporaryDirectory(prefix="pantocosim_fmus_") as tmp:
        work = Path(tmp)
        pkg, stamp = stage_package(work / "stage")
        library = compile_export_library(work, fmi)
        for name in names:
            attrs = {} if name == CATENARY_FMU else {"preset": name}
            attrs.update({"start_values": start_values[name]} if start_values else {})
            module = _module_name(name, scenario, fmi)
            if name == CATENARY_FMU:
                src = slave_source(module, "catenary_slave", "CatenarySlave", CATENARY_CLASS,
                                   attrs, fmi)
            else:
                src = slave_source(module, "pantograph_slave", "PantographSlave",
                                   PANTOGRAPH_FMUS[name], attrs, fmi)
            path = _build_one(module, src, [pkg, stamp], out / f"{name}.fmu", work, library,
                              fmi)
            built.append(path)
            if not quiet:
                print(f"built {path}")
    return built


def check_fmi(fmi) -> tuple:
    """The FMI versions asked for (an int or several); an unknown one is an error."""
    versions = (fmi,) if isinstance(fmi, int) else tuple(fmi)
    for v in versions:
        if v not in FMI_BUILDS:
            raise ParameterError("--fmi", v, "unknown FMI version; one of "
                                 + ", ".join(map(str, FMI_VERSIONS)))
    return versions


def is_stale(fmu: Path) -> bool:
    """True when the FMU bundles another version of the model package than the one installed
    (its build stamp differs): such an FMU refuses to initialise, so it is rebuilt."""
    return bundled_stamp(fmu) != package_stamp()


def ensure_fmus(paths, out: Path | None = None, fmi: int = 2) -> None:
    """Build the FMI ``fmi`` FMUs among ``paths`` (files in ``out``) that are missing or stale
    (built from another version of the model package than the installed one)."""
    out = Path(out) if out is not None else default_out()
    todo = sorted({Path(p).stem for p in paths
                   if Path(p).parent == Path(out) and (not Path(p).exists() or is_stale(p))})
    if todo:
        print(f"building FMUs {', '.join(todo)} into {out}", file=sys.stderr, flush=True)
        build_fmus(out, only=todo, quiet=True, fmi=fmi)
