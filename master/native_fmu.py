"""Writing the native FMUs: the data file of ``resources/`` (:func:`write_data`), the
modelDescription.xml, the C sources of ``fmus/realtime/`` inside the FMU and its binaries
(linux64 with the system's C compiler, win64 with mingw-w64).

Data file (``resources/model.pcsdata``, read by ``fmus/realtime/pcs_data.c``), all integers
little-endian on the hosts we build for (the byte-order mark tells):

====================  ==========================================================
header, 40 bytes      ``PCSDATA\\0``, uint32 version (1), uint32 byte-order mark
                      0x01020304, uint32 model kind (1 linear catenary, 2 modal
                      catenary, 3 lumped pantograph), uint32 sections, uint64
                      payload bytes, uint64 FNV-1a 64 checksum of the payload
section, 40 + data    char name[24] (NUL padded), uint32 type (1 float64, 2 int32),
                      uint32 0, uint64 count, the values padded to 8 bytes
====================  ==========================================================
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np
from numba import njit

import pantocosim

from pantocosim.core.errors import ParameterError

MAGIC = b"PCSDATA\0"
VERSION = 1
BYTE_ORDER_MARK = 0x01020304
KINDS = {"linear": 1, "modal": 2, "lumped": 3}
TYPES = {np.dtype(np.float64): 1, np.dtype(np.int32): 2}
DATA_FILE = "model.pcsdata"
#: the C sources of the native models (installed with the package as pantocosim/realtime)
SOURCE_DIR = Path(pantocosim.__file__).resolve().parent / "realtime"
#: warnings are errors: the sources compile clean with any C99 compiler
CFLAGS = ["-std=c99", "-O3", "-ffp-contract=off", "-Wall", "-Wextra", "-pedantic", "-Werror"]
MINGW = "x86_64-w64-mingw32-gcc"


@njit(cache=True)
def _fnv1a(arr):
    h = np.uint64(14695981039346656037)
    prime = np.uint64(1099511628211)
    for b in arr:
        h = (h ^ np.uint64(b)) * prime
    return h


def fnv1a(data: bytes) -> int:
    """FNV-1a 64 (the data file's checksum)."""
    return int(_fnv1a(np.frombuffer(data, dtype=np.uint8)))


def pack_data(kind: str, sections: dict) -> bytes:
    """The data file of ``sections`` {name: float64 or int32 array}."""
    parts = []
    for name, values in sections.items():
        arr = np.ascontiguousarray(values)
        if arr.dtype not in TYPES:
            raise TypeError(f"section {name}: {arr.dtype} (float64 or int32 only)")
        if len(name.encode()) > 23:
            raise ValueError(f"section name {name!r} longer than 23 bytes")
        body = arr.astype(arr.dtype.newbyteorder("<")).tobytes()
        body += b"\0" * (-len(body) % 8)
        parts.append(name.encode().ljust(24, b"\0")
                     + np.array([TYPES[arr.dtype], 0], "<u4").tobytes()
                     + np.array([arr.size], "<u8").tobytes() + body)
    payload = b"".join(parts)
    head = (MAGIC + np.array([VERSION, BYTE_ORDER_MARK, KINDS[kind], len(sections)],
                             "<u4").tobytes()
            + np.array([len(payload), fnv1a(payload)], "<u8").tobytes())
    return head + payload


def write_data(path: Path, kind: str, sections: dict) -> bytes:
    data = pack_data(kind, sections)
    Path(path).write_bytes(data)
    return data


def read_data(path: Path) -> tuple[str, dict]:
    """(kind, sections) of a data file (for tests and inspection), checked as the C reader
    checks it."""
    raw = Path(path).read_bytes()
    if raw[:8] != MAGIC:
        raise ParameterError(str(path), raw[:8], "not a pantocosim data file")
    version, bom, kind, count = np.frombuffer(raw[8:24], "<u4")
    size, checksum = np.frombuffer(raw[24:40], "<u8")
    payload = raw[40:]
    if version != VERSION or bom != BYTE_ORDER_MARK or size != len(payload) \
            or checksum != fnv1a(payload):
        raise ParameterError(str(path), "header", "wrong version, byte order, size or checksum")
    out, pos = {}, 40
    for _ in range(int(count)):
        name = raw[pos:pos + 24].rstrip(b"\0").decode()
        typ = int(np.frombuffer(raw[pos + 24:pos + 28], "<u4")[0])
        n = int(np.frombuffer(raw[pos + 32:pos + 40], "<u8")[0])
        dtype = np.dtype("<f8") if typ == 1 else np.dtype("<i4")
        nbytes = n * dtype.itemsize
        out[name] = np.frombuffer(raw[pos + 40:pos + 40 + nbytes], dtype).copy()
        pos += 40 + nbytes + (-nbytes % 8)
    kinds = {v: k for k, v in KINDS.items()}
    return kinds[int(kind)], out


#: FMI 3.0 value references are unique across types: the offsets of the model's Integer,
#: Boolean and String references (pcs_model.h)
def fmi3_bases() -> dict[str, int]:
    text = (SOURCE_DIR / "pcs_model.h").read_text()
    bases = {m.group(1): int(m.group(2))
             for m in re.finditer(r"#define PCS_FMI3_(\w+)_BASE (\d+)u", text)}
    return {"Integer": bases["INT32"], "Boolean": bases["BOOLEAN"], "String": bases["STRING"],
            "Real": 0}


def value_references(header: str) -> dict[str, int]:
    """The ``#define PREFIX_VR_NAME number`` lines of a model's header in
    :data:`SOURCE_DIR`: {NAME: number} (the one place the value references are numbered)."""
    text = (SOURCE_DIR / header).read_text()
    return {m.group(1): int(m.group(2))
            for m in re.finditer(r"#define \w+?_VR_(\w+) (\d+)", text)}


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
    """What goes into a native FMU besides its variables: the model's C files and headers."""

    sources: tuple         # its C files, e.g. catenary.c
    headers: tuple         # its headers, the first one numbering the value references


COMMON_SOURCES = ("pcs_data.c",)
COMMON_HEADERS = ("pcs_data.h", "pcs_model.h")
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


def build_fmu(out: Path, model: NativeModel, identifier: str, name: str, description: str,
              variables: list[Variable], kind: str, sections: dict, step: float,
              fmi: int = 2, win64: bool | None = None) -> Path:
    """Write the native FMU ``out`` (a .fmu file); ``win64``: also build the Windows DLL
    (None: when mingw-w64 is installed)."""
    cc = os.environ.get("CC") or shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        raise ParameterError("compiler", "gcc", "no C compiler on PATH (set CC)")
    mingw = shutil.which(MINGW)
    if win64 and mingw is None:
        raise ParameterError("--win64", True, f"{MINGW} is not installed (apt-get install "
                             "gcc-mingw-w64-x86-64)")
    win64 = mingw is not None if win64 is None else win64
    if fmi not in FRONTS:
        raise ParameterError("--fmi", fmi, f"native FMUs are written for FMI {', '.join(map(str, FRONTS))}")
    files = source_files(model, fmi)
    c_files = [n for n in files if n.endswith(".c")]
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        src = root / "sources"
        src.mkdir()
        for n, p in files.items():
            shutil.copyfile(p, src / n)
        (root / "resources").mkdir()
        data = write_data(root / "resources" / DATA_FILE, kind, sections)
        guid = "{" + str(hashlib.sha256(data).hexdigest()[:32]) + "}"
        guid = guid[:9] + "-" + guid[9:13] + "-" + guid[13:17] + "-" + guid[17:21] + "-" \
            + guid[21:]
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


# ---------------------------------------------------------------------- the catenary FMU
CATENARY = NativeModel(("catenary.c", "catenary_modal.c"), ("catenary_vars.h", "catenary.h"))
MAX_SUPPORTS = 64


def catenary_variables(sections: dict) -> list[Variable]:
    """The native catenary's variables: the Python catenary FMU's names
    (fmus/fmi/catenary_slave.py), the export's values as fixed parameters."""
    vr = value_references(CATENARY.headers[0])
    sizes, sc = sections["sizes"], sections["scalars"]
    n_p = int(sizes[5])
    spans = int(sizes[-2])
    name = bytes(sections["definition"].tobytes()).split(b"\0")[0].decode()
    fixed = "fixed at export (pantocosim export-native)"
    out = [
        Variable("catenary_definition", "String", vr["CATENARY_DEFINITION"], "parameter",
                 "fixed", name, description=f"catenary definition; {fixed}"),
        Variable("n_pantographs", "Integer", vr["N_PANTOGRAPHS"], "parameter", "fixed", n_p,
                 description=f"number of pantographs; {fixed}"),
        Variable("spans", "Integer", vr["SPANS"], "parameter", "fixed", spans,
                 description=f"number of spans (0 = as defined); {fixed}"),
        Variable("catenary_model", "Integer", vr["CATENARY_MODEL"], "parameter", "fixed",
                 int(sizes[-1]), description=f"1 = linear, 2 = modal; {fixed}"),
        Variable("contact_mode", "Integer", vr["CONTACT_MODE"], "parameter", "fixed", 0,
                 description="0 = contact forces are inputs (contact_force_k); 1 = built-in "
                 "penalty contact from pantograph_height_k and pantograph_velocity_k"),
        Variable("extrapolate_heights", "Boolean", vr["EXTRAPOLATE_HEIGHTS"], "parameter",
                 "fixed", True, description="contact_mode 1: pantograph_height_k is the height "
                 "at the start of the communication step, extrapolated with "
                 "pantograph_velocity_k; false: the height at t + h"),
        Variable("speed_kmh", "Real", vr["SPEED_KMH"], "parameter", "fixed", sc[6] * 3.6,
                 "km/h", f"train speed; {fixed}"),
        Variable("hht_alpha", "Real", vr["HHT_ALPHA"], "parameter", "fixed", sc[1], "1",
                 f"HHT-alpha parameter; {fixed}"),
        Variable("contact_stiffness", "Real", vr["CONTACT_STIFFNESS"], "parameter", "fixed",
                 sc[8], "N/m", f"penalty stiffness k_H (contact_mode 1); {fixed}"),
        Variable("contact_damping", "Real", vr["CONTACT_DAMPING"], "parameter", "fixed",
                 sc[9], "N.s/m", f"penalty damping c_H (contact_mode 1); {fixed}"),
        Variable("newton_rtol", "Real", vr["NEWTON_RTOL"], "parameter", "fixed", sc[13], "1",
                 "accepted for the Python FMU's parameter set; the closed-form step has no "
                 "Newton iteration"),
        Variable("modal_cutoff_hz", "Real", vr["MODAL_CUTOFF_HZ"], "parameter", "fixed",
                 sc[12], "Hz", f"modal model: modes below it; {fixed}"),
    ]
    for base, unit, text in (("position", "m", "track position x of pantograph {k} at t0"),
                             ("static_force", "N", "static contact force of pantograph {k} "
                              "at t0 (static start)")):
        key = "x0" if base == "position" else "F0"
        for k in range(1, n_p + 1):
            out.append(Variable(f"{base}_{k}", "Real", vr[base.upper()] + k - 1, "parameter",
                                "fixed", sections[key][k - 1], unit,
                                text.format(k=k) + f"; {fixed}"))
    timing = ("the value set before doStep(t, h) is the value at t + h; the value at t is the "
              "previous accepted step's (kept in the FMU state)")
    for k in range(1, n_p + 1):
        out += [
            Variable(f"contact_force_{k}", "Real", vr["CONTACT_FORCE"] + k - 1, "input",
                     "continuous", sections["F0"][k - 1], "N", f"contact_mode 0: upward contact "
                     f"force of pantograph {k} on the wire, >= 0; {timing}"),
            Variable(f"pantograph_height_{k}", "Real", vr["PANTOGRAPH_HEIGHT"] + k - 1, "input",
                     "continuous", 0.0, "m", f"contact_mode 1: contact height of pantograph {k}"),
            Variable(f"pantograph_velocity_{k}", "Real", vr["PANTOGRAPH_VELOCITY"] + k - 1,
                     "input", "continuous", 0.0, "m/s",
                     f"contact_mode 1: vertical velocity of pantograph {k}'s contact point"),
            Variable(f"wire_height_{k}", "Real", vr["WIRE_HEIGHT"] + k - 1, "output",
                     "continuous", None, "m", f"contact-wire height under pantograph {k}"),
            Variable(f"wire_velocity_{k}", "Real", vr["WIRE_VELOCITY"] + k - 1, "output",
                     "continuous", None, "m/s", f"vertical velocity of the contact wire seen by "
                     f"pantograph {k} (including the convective term V dz/dx)"),
            Variable(f"contact_force_out_{k}", "Real", vr["CONTACT_FORCE_OUT"] + k - 1,
                     "output", "continuous", None, "N", f"contact force of pantograph {k}"),
        ]
    for j in range(MAX_SUPPORTS):
        out.append(Variable(f"support_uplift_{j}", "Real", vr["SUPPORT_UPLIFT"] + j, "output",
                            "continuous", None, "m", f"uplift of the contact wire at support "
                            f"{j} relative to the unloaded static configuration (0 beyond the "
                            "last support)"))
    out += [
        Variable("n_supports", "Real", vr["N_SUPPORTS"], "output", "continuous", None, "1",
                 "number of supports of the line"),
        Variable("train_speed_kmh", "Real", vr["TRAIN_SPEED_KMH"], "output", "continuous",
                 None, "km/h", "the train speed"),
        Variable("newton_iterations", "Real", vr["NEWTON_ITERATIONS"], "local", "continuous",
                 None, None, "solves of the last communication step (slack-set passes)"),
        Variable("internal_step", "Real", vr["INTERNAL_STEP"], "local", "constant",
                 float(sc[0]), "s", "the fixed internal step: a communication step is a whole "
                 "number of it"),
    ]
    return out


def export_catenary(prep, out: Path, model_name: str = "linear", fmi: int = 2,
                    win64: bool | None = None) -> Path:
    """The native catenary FMU of a prepared scenario (:class:`~pantocosim.master.run.Prepared`
    whose catenary is the linear model)."""
    from pantocosim.core.hht import HHTSettings
    from pantocosim.master import native_export

    sc = prep.scenario
    if model_name not in ("linear", "modal"):
        raise ParameterError("--catenary-model", model_name, "native FMUs are written for the "
                             "linear and the modal catenary (the nonlinear model stays a "
                             "Python FMU)")
    settings = HHTSettings.for_runs(sc.alpha, sc.newton_rtol)
    export = (native_export.linear_catenary if model_name == "linear"
              else native_export.modal_catenary)
    sections = export(prep.catenary, settings, sc.dt, prep.static_forces, prep.contact,
                      sc.catenary, int(sc.spans or 0), settings.rtol, cutoff=sc.modal_cutoff_hz)
    from pantocosim.master.fmu_build import CATENARY_CLASS

    return build_fmu(out, CATENARY, "pantocosim_catenary_native", CATENARY_CLASS,
                     f"pantocosim {model_name} catenary '{sc.catenary}' at {sc.speed_kmh:g} km/h "
                     f"(native C, internal step {sc.dt:g} s)", catenary_variables(sections),
                     model_name, sections, sc.dt, fmi=fmi, win64=win64)


# ---------------------------------------------------------------------- the pantograph FMU
LUMPED = NativeModel(("lumped.c",), ("lumped_vars.h",))


def pantograph_variables(sections: dict) -> list[Variable]:
    """The native pantograph's variables: the Python pantograph FMU's names
    (fmus/fmi/pantograph_slave.py), the export's values as fixed parameters."""
    vr = value_references(LUMPED.headers[0])
    sc = sections["scalars"]
    fixed = "fixed at export (pantocosim export-native)"
    timing = ("the value set before doStep(t, h) is the force at t + h; the force at t is the "
              "previous accepted step's (kept in the FMU state)")
    out = [Variable("contact_force", "Real", vr["CONTACT_FORCE"], "input", "continuous",
                    sc[11], "N", f"contact force [N] >= 0 pushing the collector down; {timing}"),
           Variable("contact_height", "Real", vr["CONTACT_HEIGHT"], "output", "continuous",
                    None, "m", "height of the contact point above the rail"),
           Variable("contact_velocity", "Real", vr["CONTACT_VELOCITY"], "output",
                    "continuous", None, "m/s", "vertical velocity of the contact point")]
    for key, i, unit, text in (
            ("static_force", 6, "N", "static uplift force"),
            ("aero_c1", 7, "N.h/km", "aerodynamic uplift, linear coefficient"),
            ("aero_c2", 8, "N.h2/km2", "aerodynamic uplift, quadratic coefficient"),
            ("speed_kmh", 9, "km/h", "train speed (aerodynamic law)"),
            ("friction_force", 12, "N", "collector friction amplitude (0: constant matrices)"),
            ("friction_smoothing", 13, "m/s", "friction smoothing"),
            ("hht_alpha", 1, "1", "HHT-alpha parameter"),
            ("initial_height", 10, "m", "contact height at t0 (static start)"),
            ("initial_contact_force", 11, "N", "contact force at t0 (static start); < 0 means "
             "the mean uplift")):
        out.append(Variable(key, "Real", vr[key.upper()], "parameter", "fixed", sc[i], unit,
                            f"{text}; {fixed}"))
    out += [Variable("start_mode", "Integer", vr["START_MODE"], "parameter", "fixed", 0,
                     description="0 = static start in contact (the only start of the native "
                     "FMU)"),
            Variable("one_way_damper", "Boolean", vr["ONE_WAY_DAMPER"], "parameter", "fixed",
                     False, description="false: the native FMU has constant matrices"),
            Variable("force_extrapolation", "Boolean", vr["FORCE_EXTRAPOLATION"], "parameter",
                     "fixed", False, description="take contact_force as the force at the start "
                     "of the communication step and extrapolate it: F(t+h) = max(0, 2 F(t) - "
                     "F(t-h))"),
            Variable("newton_iterations", "Real", vr["NEWTON_ITERATIONS"], "local",
                     "continuous", None, None, "closed-form steps of the last communication "
                     "step"),
            Variable("internal_step", "Real", vr["INTERNAL_STEP"], "local", "constant",
                     float(sc[0]), "s", "the fixed internal step: a communication step is a "
                     "whole number of it")]
    return out


def export_pantograph(prep, k: int, out: Path, fmi: int = 2,
                      win64: bool | None = None) -> Path:
    """The native FMU of the scenario's pantograph ``k`` (a constant-matrix model in the
    static start of the scenario, as the Python FMU starts in our master)."""
    from pantocosim.core.hht import HHTSettings
    from pantocosim.master import native_export
    from pantocosim.master.run import scenario_pantograph

    sc = prep.scenario
    spec = sc.pantographs[k]
    if spec.start != "static":
        raise ParameterError(f"pantographs[{k}].start", spec.start, "the native pantograph "
                             "FMU starts static in contact (start = \"static\")", sc.source)
    model = scenario_pantograph(sc, k)
    if model.linear_form() is None:
        raise ParameterError("pantograph", spec.model, "has no constant-matrix form (collector "
                             "friction, a one-way damper or a nonlinear mechanism)")
    height = float(prep.pantographs[k].contact_height(prep.q_pan0[k]))
    sections = native_export.lumped_pantograph(
        model, HHTSettings(alpha=sc.alpha), sc.dt, height, float(prep.static_forces[k]),
        spec.model)
    from pantocosim.master.fmu_build import PANTOGRAPH_FMUS

    return build_fmu(out, LUMPED, "pantocosim_pantograph_native",
                     PANTOGRAPH_FMUS.get(spec.model, "Pantograph"),
                     f"pantocosim pantograph '{spec.model}' (native C, constant matrices, "
                     f"internal step {sc.dt:g} s)", pantograph_variables(sections), "lumped",
                     sections, sc.dt, fmi=fmi, win64=win64)


def export_scenario(prep, out: Path, fmi: int = 2, win64: bool | None = None):
    """The native FMUs of a prepared scenario into the folder ``out``: ``catenary.fmu`` and
    ``<pantograph model>.fmu`` of each constant-matrix pantograph. Returns (written files,
    [(pantograph index, why it has no native FMU)])."""
    out = Path(out)
    written = [export_catenary(prep, out / "catenary.fmu", prep.scenario.catenary_model,
                               fmi=fmi, win64=win64)]
    kept = []
    for k, spec in enumerate(prep.scenario.pantographs):
        try:
            written.append(export_pantograph(prep, k, out / f"{spec.model}.fmu", fmi=fmi,
                                             win64=win64))
        except ParameterError as exc:
            if exc.field not in ("pantograph",) and not str(exc.field).startswith("pantographs["):
                raise
            kept.append((k, str(exc)))
    return written, kept
