"""Building a native FMU: its modelDescription.xml (FMI 2.0 or 3.0), the C sources of
``fmus/native/`` in ``sources/`` (with ``buildDescription.xml`` for FMI 3.0), the data file
in ``resources/`` (:mod:`.data_file`) and the binaries compiled from those sources (linux64
with the system's C compiler, win64 with mingw-w64)."""

from __future__ import annotations

import hashlib
import shutil
import subprocess
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape

from pantocosim.core.errors import ParameterError
from pantocosim.master.fmu.embedding import compiler
from pantocosim.master.native.data_file import DATA_FILE, write_data
# value_references stays importable from here (the models' exporters read it)
from pantocosim.master.native.headers import SOURCE_DIR, header_numbers, value_references

__all__ = ["SOURCE_DIR", "CFLAGS", "NativeModel", "Variable", "build_fmu", "model_table",
           "value_references"]

#: warnings are errors: the sources compile clean with any C99 compiler
CFLAGS = ["-std=c99", "-O3", "-ffp-contract=off", "-Wall", "-Wextra", "-pedantic", "-Werror"]
MINGW = "x86_64-w64-mingw32-gcc"


def fmi3_bases() -> dict[str, int]:
    """FMI 3.0 value references are unique across types: the offsets of the model's Integer,
    Boolean and String references (pcs_model.h)."""
    n = header_numbers("pcs_model.h")
    return {"Integer": int(n["PCS_FMI3_INT32_BASE"]), "Boolean": int(n["PCS_FMI3_BOOLEAN_BASE"]),
            "String": int(n["PCS_FMI3_STRING_BASE"]), "Real": 0}


@dataclass
class Variable:
    name: str
    type: str              # Real, Integer, Boolean, String
    vr: int
    causality: str
    variability: str
    start: object = None
    unit: str | None = None
    description: str = ""


def _start_text(v: Variable) -> str:
    if v.type == "Real":
        return repr(float(v.start))
    if v.type == "Boolean":
        return "true" if v.start else "false"
    if v.type == "Integer":
        return str(int(v.start))
    return escape(str(v.start), {'"': "&quot;"})


def model_description_fmi2(name: str, identifier: str, guid: str, description: str,
                           variables: list[Variable], sources: list[str], step: float) -> str:
    """The FMI 2.0 modelDescription.xml of a native co-simulation FMU."""
    rows = []
    for v in variables:
        attrs = (f'name="{v.name}" valueReference="{v.vr}" causality="{v.causality}" '
                 f'variability="{v.variability}"')
        if v.description:
            attrs += f' description="{escape(v.description, {chr(34): "&quot;"})}"'
        if v.causality in ("parameter", "input") or v.variability == "constant":
            inner = f' start="{_start_text(v)}"'
            if v.causality == "parameter":
                attrs += ' initial="exact"'
        else:
            inner = ""
        if v.unit and v.type == "Real":
            inner += f' unit="{v.unit}"'
        rows.append(f"    <ScalarVariable {attrs}>\n      <{v.type}{inner}/>\n"
                    "    </ScalarVariable>")
    units = sorted({v.unit for v in variables if v.unit and v.type == "Real"})
    outputs = [i + 1 for i, v in enumerate(variables) if v.causality == "output"]
    files = "\n".join(f'        <File name="{s}"/>' for s in sources)
    unit_defs = "\n".join(f'    <Unit name="{u}"/>' for u in units)
    unknowns = "\n".join(f'      <Unknown index="{i}"/>' for i in outputs)
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="{name}" guid="{guid}"
  description="{escape(description, {chr(34): '&quot;'})}" generationTool="pantocosim export-native"
  variableNamingConvention="flat" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="{identifier}" canHandleVariableCommunicationStepSize="true"
    canGetAndSetFMUstate="true" canSerializeFMUstate="true" canBeInstantiatedOnlyOncePerProcess="false"
    canNotUseMemoryManagementFunctions="false">
    <SourceFiles>
{files}
    </SourceFiles>
  </CoSimulation>
  <UnitDefinitions>
{unit_defs}
  </UnitDefinitions>
  <DefaultExperiment startTime="0" stepSize="{step!r}"/>
  <ModelVariables>
{chr(10).join(rows)}
  </ModelVariables>
  <ModelStructure>
    <Outputs>
{unknowns}
    </Outputs>
    <InitialUnknowns>
{unknowns}
    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""


FMI3_TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String"}


def model_description_fmi3(name: str, identifier: str, guid: str, description: str,
                           variables: list[Variable], step: float) -> str:
    """The FMI 3.0 modelDescription.xml of a native co-simulation FMU (value references
    offset per type, :func:`fmi3_bases`)."""
    bases = fmi3_bases()
    rows = ['    <Float64 name="time" valueReference="0" causality="independent" '
            'variability="continuous" unit="s" description="simulation time"/>']
    outputs = []
    for v in variables:
        vr = v.vr + bases[v.type]
        attrs = (f'name="{v.name}" valueReference="{vr}" causality="{v.causality}" '
                 f'variability="{v.variability}"')
        if v.description:
            attrs += f' description="{escape(v.description, {chr(34): "&quot;"})}"'
        if v.causality == "parameter":
            attrs += ' initial="exact"'
        has_start = v.causality in ("parameter", "input") or v.variability == "constant"
        if v.unit and v.type == "Real":
            attrs += f' unit="{v.unit}"'
        tag = FMI3_TYPES[v.type]
        if v.type == "String":
            inner = f'<Start value="{_start_text(v)}"/>' if has_start else ""
            rows.append(f"    <{tag} {attrs}>{inner}</{tag}>")
        else:
            start = f' start="{_start_text(v)}"' if has_start else ""
            rows.append(f"    <{tag} {attrs}{start}/>")
        if v.causality == "output":
            outputs.append(vr)
    units = sorted({v.unit for v in variables if v.unit and v.type == "Real"} | {"s"})
    unit_defs = "\n".join(f'    <Unit name="{u}"/>' for u in units)
    structure = "\n".join([f'    <Output valueReference="{vr}"/>' for vr in outputs]
                          + [f'    <InitialUnknown valueReference="{vr}"/>' for vr in outputs])
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="{name}" instantiationToken="{guid}"
  description="{escape(description, {chr(34): '&quot;'})}" generationTool="pantocosim export-native"
  variableNamingConvention="flat">
  <CoSimulation modelIdentifier="{identifier}" canHandleVariableCommunicationStepSize="true"
    canGetAndSetFMUState="true" canSerializeFMUState="true" fixedInternalStepSize="{step!r}"
    hasEventMode="false"/>
  <UnitDefinitions>
{unit_defs}
  </UnitDefinitions>
  <DefaultExperiment startTime="0" stepSize="{step!r}"/>
  <ModelVariables>
{chr(10).join(rows)}
  </ModelVariables>
  <ModelStructure>
{structure}
  </ModelStructure>
</fmiModelDescription>
"""


def build_description_fmi3(identifier: str, c_files: list[str]) -> str:
    """sources/buildDescription.xml of an FMI 3.0 source FMU."""
    files = "\n".join(f'      <SourceFile name="{c}"/>' for c in c_files)
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiBuildDescription fmiVersion="3.0">
  <BuildConfiguration modelIdentifier="{identifier}" description="C99 and libm only">
    <SourceFileSet language="C99">
{files}
    </SourceFileSet>
  </BuildConfiguration>
</fmiBuildDescription>
"""


@dataclass(frozen=True)
class NativeModel:
    """What goes into a native FMU besides its variables: the model's C files and headers
    and the model tables (``PcsModelType``, pcs_model.h) its binary holds."""

    sources: tuple         # its C files, e.g. catenary.c
    headers: tuple         # its headers, the first one numbering the value references
    tables: tuple          # its model tables, e.g. pcs_linear_catenary


COMMON_SOURCES = ("pcs_instance.c", "pcs_memory.c", "pcs_data.c", "pcs_limits.c")
COMMON_HEADERS = ("pcs_instance.h", "pcs_memory.h", "pcs_data.h", "pcs_model.h",
                  "pcs_limits.h", "pcs_float.h", "pcs_layout.h")
#: the generated list of a binary's models (pcs_model_table)
TABLE_SOURCE = "model_table.c"


def model_table(model: NativeModel, token: str) -> str:
    """model_table.c: the models the FMU's binary holds, found by their data file's kind, and
    the instantiation token of its modelDescription.xml (pcs_model.h)."""
    names = ", ".join(f"&{t}" for t in model.tables)
    return ("/* The models of this FMU (written by pantocosim export-native). */\n"
            '#include "pcs_model.h"\n\n'
            + "".join(f"extern const PcsModelType {t};\n" for t in model.tables)
            + f"\nconst PcsModelType *const pcs_model_table[] = {{{names}, NULL}};\n"
            + f'const char pcs_instantiation_token[] = "{token}";\n')


def instantiation_token(data: bytes) -> str:
    """The guid (FMI 2.0) and instantiationToken (FMI 3.0) of a native FMU: its data file's
    SHA-256 as a GUID, written into modelDescription.xml and compiled into the binary."""
    h = hashlib.sha256(data).hexdigest()[:32]
    return "{" + f"{h[:8]}-{h[8:12]}-{h[12:16]}-{h[16:20]}-{h[20:]}" + "}"
@dataclass(frozen=True)
class Front:
    """An FMI version's interface files and binary folders."""

    sources: tuple           # C files of the front
    headers: tuple           # its headers in the package (folder/name)
    linux: str               # binaries/<linux>/
    windows: str             # binaries/<windows>/


FRONTS = {
    2: Front(("fmi2_front.c",), ("fmi2/fmi2Functions.h", "fmi2/fmi2FunctionTypes.h",
                                 "fmi2/fmi2TypesPlatform.h"), "linux64", "win64"),
    3: Front(("fmi3_front.c", "fmi3_unsupported.c"),
             ("fmi3_front.h", "fmi3/fmi3Functions.h", "fmi3/fmi3FunctionTypes.h",
              "fmi3/fmi3PlatformTypes.h"), "x86_64-linux", "x86_64-windows"),
}


def source_files(model: NativeModel, fmi: int) -> dict[str, Path]:
    """{name in the FMU's sources/: file in the package} of a native FMU."""
    front = FRONTS[fmi]
    out = {name: SOURCE_DIR / name for name in (*front.sources, *model.sources,
                                                 *COMMON_SOURCES, *COMMON_HEADERS,
                                                 *model.headers)}
    out.update({Path(h).name: SOURCE_DIR / h for h in front.headers})
    return out


def compile_library(sources: Path, c_files: list[str], target: Path, cc: str) -> None:
    """Compile the FMU's own sources into a shared library; a failure names the compiler
    and its first lines of output."""
    target.parent.mkdir(parents=True, exist_ok=True)
    windows = target.suffix == ".dll"
    cmd = [cc, *CFLAGS, "-shared", f"-I{sources}", *[str(sources / c) for c in c_files],
           "-o", str(target)]
    if windows:
        cmd += ["-static-libgcc"]
    else:
        cmd[1:1] = ["-fPIC", "-fvisibility=hidden"]
        cmd += ["-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise ParameterError("compiler", cc, "compiling the native FMU failed:\n"
                             + (proc.stderr or proc.stdout)[:2000])


def c_compiler() -> str:
    """The C compiler of the native FMUs (``$CC``, else cc or gcc on PATH); none is an
    error."""
    cc = compiler()
    if cc is None:
        raise ParameterError("compiler", "gcc", "no C compiler on PATH (set CC)")
    return cc


def build_fmu(out: Path, model: NativeModel, identifier: str, name: str, description: str,
              variables: list[Variable], kind: str, sections: dict, step: float,
              fmi: int = 2, win64: bool | None = None) -> Path:
    """Write the native FMU ``out`` (a .fmu file); ``win64``: also build the Windows DLL
    (None: when mingw-w64 is installed)."""
    cc = c_compiler()
    mingw = shutil.which(MINGW)
    if win64 and mingw is None:
        raise ParameterError("--win64", True, f"{MINGW} is not installed (apt-get install "
                             "gcc-mingw-w64-x86-64)")
    win64 = mingw is not None if win64 is None else win64
    if fmi not in FRONTS:
        raise ParameterError("--fmi", fmi, f"native FMUs are written for FMI {', '.join(map(str, FRONTS))}")
    files = source_files(model, fmi)
    c_files = [n for n in files if n.endswith(".c")] + [TABLE_SOURCE]
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        src = root / "sources"
        src.mkdir()
        for n, p in files.items():
            shutil.copyfile(p, src / n)
        (root / "resources").mkdir()
        data = write_data(root / "resources" / DATA_FILE, kind, sections)
        guid = instantiation_token(data)
        (src / TABLE_SOURCE).write_text(model_table(model, guid))
        if fmi == 2:
            text = model_description_fmi2(name, identifier, guid, description, variables,
                                          c_files, step)
        else:
            text = model_description_fmi3(name, identifier, guid, description, variables, step)
            (src / "buildDescription.xml").write_text(build_description_fmi3(identifier,
                                                                            c_files))
        (root / "modelDescription.xml").write_text(text)
        front = FRONTS[fmi]
        compile_library(src, c_files, root / "binaries" / front.linux / f"{identifier}.so", cc)
        if win64:
            compile_library(src, c_files, root / "binaries" / front.windows /
                            f"{identifier}.dll", mingw)
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        partial = out.with_suffix(".fmu.partial")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
            for p in sorted(root.rglob("*")):
                if p.is_file():
                    z.write(p, p.relative_to(root).as_posix())
        partial.replace(out)
    return out
