"""A scenario as files any FMI master runs unaided: the scenario's FMUs (start values baked
in), an SSP 1.0 file and a CoFmuPy configuration (``pantocosim build-fmus`` writes them for
the default scenario into ``dist/fmus/<scenario>/`` and ``dist/fmus/<scenario>.ssp``).

The SSP holds one pantograph FMU and the catenary FMU in ``contact_mode`` 1 (built-in penalty
contact). Nothing in it belongs to one pantograph model: the two FMUs settle the static start
between themselves (docs/third-party.md, "The static start handshake"): the catenary offers
its start laws as outputs in initialisation mode (operating height and static contact height
against the force, :mod:`pantocosim.catenary.operating_height`), the pantograph (start_mode 2)
sets its actuation and start on them (:mod:`pantocosim.interaction.pantograph_start`), and the
catenary settles its static state against the pantograph's height at t0. So replacing the
pantograph FMU in the SSP by any other pantograph FMU is a file swap.

Any pantograph FMU with the three required ports (:data:`REQUIRED_PORTS`) couples with the
catenary FMU: :func:`write_pantograph_ssp` (``pantocosim ssp --pantograph FMU``) writes the
SSP of a user's FMU with the catenary FMU baked for a scenario, connecting the optional ports
the FMU has (:data:`OPTIONAL_INPUTS`: the start laws and the train speed).

The SSD is written with ElementTree and validated against the SSP 1.0 schemas fmpy ships;
names are identifiers (letters, digits, underscores); String parameters stay in the FMUs'
start values (fmpy's SSP support and OMSimulator do not take them from an SSD).
"""

from __future__ import annotations

import json
import math
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np

from pantocosim.catenary.definition import load_catenary, with_spans
from pantocosim.catenary.model import CatenaryModel
from pantocosim.catenary.models import model_code
from pantocosim.catenary.operating_height import contact_height_laws
from pantocosim.core.errors import OutputError, ParameterError
from pantocosim.fmi.catenary_ports import MAX_SUPPORTS, SPEED_OUTPUT
from pantocosim.fmi.catenary_ports import VARIABLES as CATENARY_VARIABLES
from pantocosim.fmi.catenary_ports import PortNames
from pantocosim.fmi.pantograph_ports import LAW_INPUTS, REQUIRED_PORTS, SPEED_INPUT
from pantocosim.fmi.pantograph_ports import VARIABLES as PANTOGRAPH_VARIABLES
from pantocosim.fmi.slave_base import bundled_stamp
from pantocosim.interaction.pantograph_start import static_start_on_laws
from pantocosim.master.fmu.build import CATENARY_FMU, FMU_NAMES, build_fmus
from pantocosim.master.fmu.binary_check import check_binary_fmu
from pantocosim.master.fmu.runtime import fmi_version
from pantocosim.master.run.checks import analysis_window
from pantocosim.master.scenario import load_scenario, require_port_contact
from pantocosim.pantograph.presets import load_pantograph

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
OMS = "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd"
for _prefix, _uri in (("ssd", SSD), ("ssc", SSC), ("ssv", SSV), ("oms", OMS)):
    ET.register_namespace(_prefix, _uri)

#: name of the SSP parameter set (ecos applies the set named at init, merged over components)
PARAMETER_SET = "default"
#: the scenarios written by ``build-fmus``
DEFAULT_SCENARIOS = ("dsa380-ave-300",)
#: the catenary's ports of its pantograph 1, the one of an SSP file
CATENARY_PORTS = PortNames.of(1)
#: the optional pantograph inputs (Real) -> the catenary output each is connected to
OPTIONAL_INPUTS = {**dict(zip(LAW_INPUTS, CATENARY_PORTS.laws[0])), SPEED_INPUT: SPEED_OUTPUT}


def _ports() -> list[tuple]:
    """Connections of the pantograph and the catenary FMU (pantograph k = 1)."""
    force, height, velocity = REQUIRED_PORTS
    return [("pantograph", height, "catenary", CATENARY_PORTS.heights[0]),
            ("pantograph", velocity, "catenary", CATENARY_PORTS.velocities[0]),
            ("catenary", CATENARY_PORTS.forces_out[0], "pantograph", force)] + [
        ("catenary", out, "pantograph", port) for port, out in OPTIONAL_INPUTS.items()]


PORTS = _ports()


def identifier(name: str) -> str:
    """``name`` as an identifier (letters, digits, underscores; not starting with a digit)."""
    out = "".join(c if c.isalnum() or c == "_" else "_" for c in name)
    return out if out and not out[0].isdigit() else "_" + out


# ------------------------------------------------------------------ the scenario's values
def scenario_start_values(scenario) -> dict:
    """{"catenary": {...}, "pantograph": {...}, "<model>": {...}, "stop_time", "window"}:
    the start values of the scenario's FMUs. The catenary gets the scenario's parameters and
    contact_mode 1; every pantograph FMU the scenario's speed and integrator, start_mode 2 and
    the catenary's start laws as the start values of its law inputs (what a master that
    exchanges nothing in initialisation mode gives it). The catenary's pantograph_height_1
    start value is the scenario pantograph's start height (a master that passes no height at
    t0, fmpy's SSP support, starts from it)."""
    sc = load_scenario(scenario)
    require_port_contact(sc, "an SSP export")
    if len(sc.pantographs) != 1 or sc.pantographs[0].start != "static":
        raise ParameterError("pantographs", len(sc.pantographs), "an SSP export takes one "
                             "pantograph with a static start", sc.source)
    (spec,) = sc.pantographs
    definition = load_catenary(sc.catenary)
    if sc.spans:
        definition = with_spans(definition, sc.spans)
    window, _, duration = analysis_window(sc, definition)
    catenary = CatenaryModel(definition, x0=[spec.position_m], speed=sc.speed)
    laws = contact_height_laws(catenary, sc.contact_stiffness, window, sc.dt, duration,
                               sc.alpha)
    law_values = {"operating_height": float(laws.operating_offset[0]),
                  "operating_height_slope": float(laws.operating_slope[0]),
                  "static_height": float(laws.static_offset[0]),
                  "static_height_slope": float(laws.static_slope[0])}
    pan = load_pantograph(spec.model, speed_kmh=sc.speed_kmh, **spec.options)
    q0, _ = static_start_on_laws(pan, *law_values.values())
    cat = {"catenary_definition": sc.catenary, "spans": int(sc.spans or 0),
           "speed_kmh": float(sc.speed_kmh), "n_pantographs": 1,
           "position_1": float(spec.position_m), "static_force_1": 0.0,
           "hht_alpha": float(sc.alpha), "contact_mode": 1,
           "contact_stiffness": float(sc.contact_stiffness),
           "contact_damping": float(sc.contact_damping), "extrapolate_heights": True,
           "newton_rtol": float(sc.newton_rtol), "window_start": float(window[0]),
           "window_end": float(window[1]), "averaging_step": float(sc.dt),
           "catenary_model": model_code(sc.catenary_model),
           "modal_cutoff_hz": float(sc.modal_cutoff_hz or 0.0),
           CATENARY_PORTS.heights[0]: float(pan.contact_height(q0))}
    pantograph = {"speed_kmh": float(sc.speed_kmh), "hht_alpha": float(sc.alpha),
                  "start_mode": 2, "force_extrapolation": True}
    stop = math.ceil(duration / sc.dt - 1e-9) * sc.dt
    return {"scenario": sc, "catenary": cat, "pantograph": pantograph, "laws": law_values,
            "options": dict(spec.options), "stop_time": stop, "window": window}


def fmu_start_values(values: dict, model: str) -> dict:
    """The start values baked into the scenario's FMU ``model``."""
    if model == CATENARY_FMU:
        return dict(values["catenary"])
    out = dict(values["pantograph"], **values["laws"])
    if model == values["scenario"].pantographs[0].model:
        out.update(values["options"])
    return out


# ------------------------------------------------------------------ the SSD
def _sub(parent, ns: str, tag: str, **attrib) -> ET.Element:
    return ET.SubElement(parent, f"{{{ns}}}{tag}", {k: str(v) for k, v in attrib.items()})


def _ssd_type(value) -> tuple[str, str]:
    if isinstance(value, bool):
        return "Boolean", "true" if value else "false"
    if isinstance(value, int):
        return "Integer", str(value)
    return "Real", repr(float(value))


def system_structure(name: str, components: list[dict], connections: list[tuple],
                     stop_time: float, step_size: float) -> ET.ElementTree:
    """SystemStructure.ssd (SSP 1.0). ``components``: dicts with ``name``, ``source``,
    ``connectors`` [(name, kind, type)] and ``parameters`` {name: value}."""
    root = ET.Element(f"{{{SSD}}}SystemStructureDescription", version="1.0", name=name)
    system = _sub(root, SSD, "System", name=name)
    elements = _sub(system, SSD, "Elements")
    for c in components:
        comp = _sub(elements, SSD, "Component", name=c["name"], source=c["source"],
                    type="application/x-fmu-sharedlibrary")
        conns = _sub(comp, SSD, "Connectors")
        for cname, kind, typ in c["connectors"]:
            _sub(_sub(conns, SSD, "Connector", name=cname, kind=kind), SSC, typ)
        if c.get("parameters"):
            values = _sub(_sub(_sub(comp, SSD, "ParameterBindings"), SSD, "ParameterBinding"),
                          SSD, "ParameterValues")
            params = _sub(_sub(values, SSV, "ParameterSet", version="1.0",
                               name=PARAMETER_SET), SSV, "Parameters")
            for pname, value in c["parameters"].items():
                typ, text = _ssd_type(value)
                _sub(_sub(params, SSV, "Parameter", name=pname), SSV, typ, value=text)
    links = _sub(system, SSD, "Connections")
    for a, ac, b, bc in connections:
        _sub(links, SSD, "Connection", startElement=a, startConnector=ac, endElement=b,
             endConnector=bc)
    _oms_annotation(system, stop_time, step_size)
    # OMSimulator 3.0 takes no other root children than System, Units, Enumerations and
    # DefaultExperiment, and reads its step from the system annotation
    _sub(root, SSD, "DefaultExperiment", startTime="0.0", stopTime=repr(stop_time))
    ET.indent(root)
    return ET.ElementTree(root)


def _oms_annotation(system: ET.Element, stop_time: float, step_size: float) -> None:
    """OMSimulator's system annotation (without it OMSimulator 3.0 cannot make the system:
    ``[NewSystem] internal error``): a co-simulation system with its fixed-step master
    ``oms-ma``, as OMSimulator's own SSD export writes it."""
    note = _sub(_sub(system, SSD, "Annotations"), SSC, "Annotation", type="org.openmodelica")
    info = _sub(_sub(note, OMS, "Annotations"), OMS, "SimulationInformation")
    _sub(info, OMS, "FixedStepMaster", description="oms-ma", stepSize=repr(float(step_size)),
         absoluteTolerance="0.0001", relativeTolerance="0.0001")


def fmu_variables(fmu: Path) -> dict:
    """{name: (causality, type)} of an FMI 2.0 or 3.0 co-simulation FMU's model description
    (read with ElementTree; an FMI 3.0 array's type is e.g. "Real array"); a file that is not
    one raises ParameterError naming it."""
    fmu = Path(fmu)
    try:
        with zipfile.ZipFile(fmu) as z:
            text = z.read("modelDescription.xml")
    except (OSError, zipfile.BadZipFile, KeyError) as exc:
        why = ("no modelDescription.xml in it" if isinstance(exc, KeyError)
               else getattr(exc, "strerror", None) or str(exc))
        raise ParameterError("fmu", str(fmu), f"not an FMU ({why}); accepted: an FMI 2.0 "
                             "co-simulation FMU (a zip file with modelDescription.xml)"
                             ) from None
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ParameterError("modelDescription.xml", str(exc), "not well-formed XML; "
                             "accepted: an FMI 2.0 model description", str(fmu)) from None
    version = root.get("fmiVersion")
    if root.tag != "fmiModelDescription" or version not in ("2.0", "3.0"):
        raise ParameterError("fmiVersion", version, "accepted: 2.0 or 3.0 (an FMI 2.0 or 3.0 "
                             "co-simulation FMU)", str(fmu))
    if root.find("CoSimulation") is None:
        raise ParameterError("CoSimulation", None, "the FMU has no co-simulation interface; "
                             "accepted: an FMI 2.0 or 3.0 co-simulation FMU", str(fmu))
    out = {}
    for v in root.iterfind("ModelVariables/ScalarVariable"):
        kind = next((c.tag for c in v if c.tag in ("Real", "Integer", "Boolean", "String",
                                                    "Enumeration")), None)
        out[v.get("name")] = (v.get("causality", "local"), kind)
    for v in root.iterfind("ModelVariables/*"):     # FMI 3.0: one element per variable
        if v.tag in FMI3_KINDS:
            array = " array" if v.find("Dimension") is not None else ""
            out[v.get("name")] = (v.get("causality", "local"), FMI3_KINDS[v.tag] + array)
    return out


#: FMI 3.0 variable types as the SSP 1.0 connector types they map to (scalars)
FMI3_KINDS = {"Float64": "Real", "Float32": "Real", "Int32": "Integer", "Int64": "Integer",
              "Int16": "Integer", "Int8": "Integer", "UInt32": "Integer", "UInt16": "Integer",
              "UInt8": "Integer", "Boolean": "Boolean", "String": "String",
              "Enumeration": "Enumeration"}


def pantograph_connections(fmu: Path) -> list[tuple]:
    """The connections (:data:`PORTS`) of a pantograph FMU: the required ports, checked
    (a missing one raises ParameterError naming the file and the port), and the optional
    inputs it has."""
    variables = fmu_variables(fmu)
    for name, causality in REQUIRED_PORTS.items():
        found = variables.get(name)
        if found != (causality, "Real"):
            what = ("missing from the model description" if found is None
                    else f"a {found[1]} {found[0]} instead of a Real {causality}")
            raise ParameterError("port", name, f"a required port, {what}; accepted: a "
                                 f"pantograph FMU with {_required_ports_text()}", str(fmu))
    check_binary_fmu(fmu, "fmu")
    return [c for c in PORTS if c[2] != "pantograph" or c[3] in REQUIRED_PORTS
            or variables.get(c[3]) == ("input", "Real")]


def _required_ports_text() -> str:
    """The required ports in words: "the Real input contact_force [N] and the Real outputs
    contact_height [m], contact_velocity [m/s]"."""
    def names(causality):
        return ", ".join(f"{n} [{PANTOGRAPH_VARIABLES[n].unit}]"
                         for n, c in REQUIRED_PORTS.items() if c == causality)
    return f"the Real input {names('input')} and the Real outputs {names('output')}"


def _connectors(fmu: Path, parameters: dict, ports: list[str]) -> list[tuple]:
    variables = fmu_variables(fmu)
    missing = [n for n in list(parameters) + ports if n not in variables]
    if missing:
        raise ParameterError("fmu", str(fmu), f"has no variable {missing[0]!r}: not a "
                             "pantocosim FMU of this version (rebuild the FMUs)")
    return ([(n, "parameter", variables[n][1]) for n in parameters]
            + [(n, variables[n][0], variables[n][1]) for n in ports])


def _ssp_parameters(values: dict, variables) -> dict:
    """The values an SSD binds: non-String parameters of ``variables`` (the FMU's declared
    variables; inputs stay connections)."""
    return {k: v for k, v in values.items()
            if not isinstance(v, str) and variables[k].causality == "parameter"}


def write_ssp(dest: Path, name: str, pantograph_fmu: Path, catenary_fmu: Path,
              values: dict, step_size: float) -> Path:
    """The SSP file of one pantograph FMU on the catenary FMU (see the module docstring);
    validated against the SSP 1.0 schema. A pantocosim pantograph FMU gets the scenario's
    pantograph parameters and every port; another one its required ports and the optional
    inputs it has, and no parameter."""
    stamps = {Path(f).name: bundled_stamp(f) for f in (pantograph_fmu, catenary_fmu)}
    ours = stamps[Path(pantograph_fmu).name] is not None
    if stamps[Path(catenary_fmu).name] is None or (ours and len(set(stamps.values())) != 1):
        raise ParameterError("fmu", str(pantograph_fmu), f"the FMUs come from different "
                             f"builds (stamps {stamps}): they bundle different pantocosim "
                             "copies and cannot run in one process; rebuild them together")
    connections = PORTS if ours else pantograph_connections(pantograph_fmu)
    pan_params = _ssp_parameters(values["pantograph"], PANTOGRAPH_VARIABLES) if ours else {}
    cat_params = _ssp_parameters(values["catenary"], CATENARY_VARIABLES)
    pan_ports = sorted({p for a, ap, b, bp in connections for el, p in ((a, ap), (b, bp))
                        if el == "pantograph"})
    cat_ports = sorted({p for a, ap, b, bp in connections for el, p in ((a, ap), (b, bp))
                        if el == "catenary"})
    # unconnected outputs a master records with the connectors (fmpy, OMSimulator)
    n_sup = min(len(scenario_support_x(values["catenary"])), MAX_SUPPORTS)
    cat_ports += [*CATENARY_PORTS.wire_heights, *PortNames.of(1, n_sup).uplifts]
    pan_entry = Path(pantograph_fmu).name
    if pan_entry == Path(catenary_fmu).name:
        pan_entry = f"pantograph_{pan_entry}"
    components = [
        {"name": "pantograph", "source": f"resources/{pan_entry}",
         "connectors": _connectors(pantograph_fmu, pan_params, pan_ports),
         "parameters": pan_params},
        {"name": "catenary", "source": f"resources/{Path(catenary_fmu).name}",
         "connectors": _connectors(catenary_fmu, cat_params, cat_ports),
         "parameters": cat_params}]
    tree = system_structure(identifier(name), components, connections, values["stop_time"],
                            step_size)
    dest = Path(dest)
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = dest.with_name(dest.name + ".part")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", ET.tostring(tree.getroot(), encoding="unicode",
                                                      xml_declaration=True) + "\n")
        z.write(pantograph_fmu, f"resources/{pan_entry}")
        z.write(catenary_fmu, f"resources/{Path(catenary_fmu).name}")
    try:
        validate_ssp(tmp)
        tmp.replace(dest)
    finally:
        tmp.unlink(missing_ok=True)
    return dest


def validate_ssp(ssp: Path) -> None:
    """Validate the SSD against fmpy's SSP 1.0 schemas (raises on a violation)."""
    from fmpy.ssp.ssd import read_ssd

    read_ssd(str(ssp), validate=True)


# ------------------------------------------------------------------ CoFmuPy
def cofmupy_config(fmus: dict, connections: list[tuple]) -> dict:
    """A CoFmuPy 1.0 configuration: the FMUs (paths relative to the configuration's folder)
    with no start values (CoFmuPy sets every value with fmi2SetReal; the scenario's FMUs
    carry the scenario), the connections, Jacobi coupling without iterations."""
    return {
        "fmus": [{"id": name, "path": str(path), "initialization": {}}
                 for name, path in fmus.items()],
        "connections": [{"source": {"type": "fmu", "id": a, "variable": ap},
                         "target": [{"type": "fmu", "id": b, "variable": bp}]}
                        for a, ap, b, bp in connections],
        "cosim_method": "jacobi",
        "iterative": False,
    }


# ------------------------------------------------------------------ the package
def write_scenario_package(out: Path, scenarios=DEFAULT_SCENARIOS,
                           quiet: bool = False, fmi: int = 2) -> list[Path]:
    """For each scenario (preset name or file): its FMI ``fmi`` FMUs in ``out/<name>/``,
    ``out/<name>.ssp`` and (FMI 2.0: CoFmuPy takes FMI 2.0 only) ``out/<name>/cofmupy.json``
    (``name``: the scenario's)."""
    written = []
    for scenario in scenarios:
        values = scenario_start_values(scenario)
        sc = values["scenario"]
        name = sc.name
        folder = Path(out) / name
        baked = {m: fmu_start_values(values, m) for m in FMU_NAMES}
        written += build_fmus(folder, quiet=True, start_values=baked, scenario=name,
                              fmi=fmi)
        model = sc.pantographs[0].model
        ssp = write_ssp(Path(out) / f"{name}.ssp", name, folder / f"{model}.fmu",
                        folder / f"{CATENARY_FMU}.fmu", values, sc.dt)
        written.append(ssp)
        if fmi == 2:
            config = folder / "cofmupy.json"
            config.write_text(json.dumps(cofmupy_config(
                {"pantograph": f"{model}.fmu", "catenary": f"{CATENARY_FMU}.fmu"}, PORTS),
                indent=2) + "\n")
            written.append(config)
        if not quiet:
            cat = values["catenary"]
            print(f"wrote {ssp} and {folder}/ (FMI {fmi}.0 scenario FMUs"
                  f"{', cofmupy.json' if fmi == 2 else ''}): stop "
                  f"{values['stop_time']:g} s, window {values['window'][0]:g}.."
                  f"{values['window'][1]:g} m, start height {cat[CATENARY_PORTS.heights[0]]:.6f} m")
    return written


def write_pantograph_ssp(fmu: Path, scenario, dest: Path | None = None) -> tuple[Path, dict]:
    """The SSP file of a user's pantograph FMU on the catenary FMU baked for ``scenario``
    (preset name or file; its pantograph's model gives the catenary's start values only):
    (path, the scenario's start values). ``dest`` defaults to ``<fmu stem>-<scenario>.ssp``
    beside the FMU. The FMU's required ports are checked before anything is built; the
    catenary FMU is built in the FMU's FMI version (2.0 or 3.0)."""
    fmu = Path(fmu)
    pantograph_connections(fmu)
    values = scenario_start_values(scenario)
    sc = values["scenario"]
    dest = Path(dest) if dest else fmu.with_name(f"{fmu.stem}-{sc.name}.ssp")
    refuse_overwriting(dest, {"--pantograph": fmu, "--scenario": sc.source})
    with tempfile.TemporaryDirectory(prefix="pantocosim_ssp_") as tmp:
        (catenary,) = build_fmus(Path(tmp), only=[CATENARY_FMU], quiet=True,
                                 start_values={CATENARY_FMU: values["catenary"]},
                                 scenario=sc.name, fmi=fmi_version(fmu))
        write_ssp(dest, sc.name, fmu, catenary, values, sc.dt)
    return dest, values


def refuse_overwriting(dest: Path, inputs: dict) -> None:
    """Refuse an SSP destination that is one of the command's input files ({flag: path})."""
    for flag, given in inputs.items():
        if given and Path(given).exists() and dest.exists() and dest.samefile(given):
            raise OutputError("--out", dest, f"is the file given by {flag}: writing the SSP "
                              "there would replace it; accepted: another file name, e.g. "
                              f"{Path(given).stem}.ssp")


def scenario_support_x(values: dict) -> np.ndarray:
    """Support positions of the scenario's line."""
    d = load_catenary(values["catenary_definition"])
    if int(values.get("spans", 0)):
        d = with_spans(d, int(values["spans"]))
    return np.asarray(d.support_x, float)
