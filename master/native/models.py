"""The native FMUs of a scenario (``pantocosim export-native``): the catenary (linear or
modal model) and the pantographs with a native form (the constant-matrix chains, the rigid
and the flexible DSA-380: :data:`NATIVE_PANTOGRAPHS`), with the Python FMUs' variable names and
the export's values as fixed parameters; their constants come from
:mod:`.export`, the FMUs are built by :mod:`.build`."""

from __future__ import annotations

import tempfile
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

from pantocosim.core.errors import ParameterError
from pantocosim.core.hht import HHTSettings
from pantocosim.fmi.catenary_ports import VARIABLES as CATENARY_VARIABLES
from pantocosim.fmi.pantograph_ports import VARIABLES as PANTOGRAPH_VARIABLES
from pantocosim.master.native import export as native_export
from pantocosim.master.fmu.build import CATENARY_CLASS, PANTOGRAPH_FMUS
from pantocosim.master.native.build import NativeModel, Variable, build_fmu
from pantocosim.master.native.headers import fields, header_numbers, unpack, value_references
from pantocosim.master.run.setup import scenario_pantograph
from pantocosim.pantograph.dsa380 import Dsa380Model
from pantocosim.pantograph.dsa380_flexible import Dsa380FlexibleModel
from pantocosim.pantograph.lumped import LumpedPantograph

CATENARY = NativeModel(("catenary.c", "catenary_linear.c", "catenary_modal.c"),
                       ("catenary_vars.h", "catenary.h"),
                       ("pcs_linear_catenary", "pcs_modal_catenary"))
MAX_SUPPORTS = int(header_numbers("catenary_vars.h")["CAT_MAX_SUPPORTS"])


FIXED = "fixed at export (pantocosim export-native)"


def declared(table, name: str, vr: int, start=None, fixed: bool = False,
             note: str = "") -> Variable:
    """The native FMU's variable ``name`` as the Python FMU declares it (type, causality,
    unit, meaning: ``table``, fmus/fmi/*_ports.py), at value reference ``vr``; a parameter
    is fixed (the export's value ``start``), an input starts at ``start``."""
    row = table[name]
    variability = ("fixed" if row.causality == "parameter" else
                   "continuous" if row.type == "Real" else "discrete")
    meaning = row.meaning + (f"; {FIXED}" if fixed else "") + (f"; {note}" if note else "")
    return Variable(name, row.type, vr, row.causality, variability,
                    start if row.causality in ("parameter", "input") else None, row.unit,
                    meaning)


#: the catenary models with a native form: the export of their sections, their sizes' fields
CATENARY_EXPORTS = {"linear": native_export.linear_catenary,
                    "modal": native_export.modal_catenary}
SIZE_FIELDS = {"linear": "LIN_SIZE", "modal": "MOD_SIZE"}


def catenary_variables(sections: dict, model_name: str) -> list[Variable]:
    """The native catenary's variables: the Python catenary FMU's (fmus/fmi/catenary_ports.py),
    the export's values as fixed parameters."""
    table = CATENARY_VARIABLES
    vr = value_references(CATENARY.headers[0])
    sizes = unpack(sections["sizes"], SIZE_FIELDS[model_name])
    sc = dict(zip(fields("CAT_SCALAR"), sections["scalars"].tolist()))
    n_p = int(sizes["PANTOGRAPHS"])
    name = bytes(sections["definition"].tobytes()).split(b"\0")[0].decode()
    out = [declared(table, key, vr[key.upper()], value, fixed=True) for key, value in (
        ("catenary_definition", name), ("n_pantographs", n_p), ("spans", sizes["SPANS"]),
        ("catenary_model", sizes["MODEL_CODE"]), ("speed_kmh", sc["SPEED"] * 3.6),
        ("hht_alpha", sc["ALPHA"]), ("contact_stiffness", sc["CONTACT_STIFFNESS"]),
        ("contact_damping", sc["CONTACT_DAMPING"]), ("modal_cutoff_hz", sc["MODAL_CUTOFF"]))]
    out += [declared(table, "contact_mode", vr["CONTACT_MODE"], 0),
            declared(table, "extrapolate_heights", vr["EXTRAPOLATE_HEIGHTS"], True),
            declared(table, "newton_rtol", vr["NEWTON_RTOL"], sc["NEWTON_RTOL"],
                     note="accepted; the closed-form step has no Newton iteration")]
    for k in range(1, n_p + 1):
        out += [declared(table, f"position_{k}", vr["POSITION"] + k - 1, sections["x0"][k - 1],
                         fixed=True),
                declared(table, f"static_force_{k}", vr["STATIC_FORCE"] + k - 1,
                         sections["F0"][k - 1], fixed=True),
                declared(table, f"contact_force_{k}", vr["CONTACT_FORCE"] + k - 1,
                         sections["F0"][k - 1]),
                declared(table, f"pantograph_height_{k}", vr["PANTOGRAPH_HEIGHT"] + k - 1, 0.0),
                declared(table, f"pantograph_velocity_{k}", vr["PANTOGRAPH_VELOCITY"] + k - 1,
                         0.0)]
        out += [declared(table, f"{base}_{k}", vr[base.upper()] + k - 1)
                for base in ("wire_height", "wire_velocity", "contact_force_out")]
    out += [declared(table, f"support_uplift_{j}", vr["SUPPORT_UPLIFT"] + j)
            for j in range(MAX_SUPPORTS)]
    out += [declared(table, key, vr[key.upper()])
            for key in ("n_supports", "train_speed_kmh", "newton_iterations")]
    out.append(Variable("internal_step", "Real", vr["INTERNAL_STEP"], "local", "constant",
                        sc["STEP"], "s", "the fixed internal step: a communication step is "
                        "a whole number of it"))
    return out


def export_catenary(prep, out: Path, model_name: str = "linear", fmi: int = 2,
                    win64: bool | None = None) -> Path:
    """The native catenary FMU of a prepared scenario (:class:`~pantocosim.master.run.Prepared`
    whose catenary is the linear model)."""
    sc = prep.scenario
    if model_name not in CATENARY_EXPORTS:
        raise ParameterError("--catenary-model", model_name, "native FMUs are written for the "
                             "linear and the modal catenary (the nonlinear model stays a "
                             "Python FMU)")
    settings = HHTSettings.for_runs(sc.alpha, sc.newton_rtol)
    export = CATENARY_EXPORTS[model_name]
    sections = export(prep.catenary, settings, sc.dt, prep.static_forces, prep.contact,
                      sc.catenary, int(sc.spans or 0), settings.rtol, cutoff=sc.modal_cutoff_hz)

    return build_fmu(out, CATENARY, "pantocosim_catenary_native", CATENARY_CLASS,
                     f"pantocosim {model_name} catenary '{sc.catenary}' at {sc.speed_kmh:g} km/h "
                     f"(native C, internal step {sc.dt:g} s)", catenary_variables(sections, model_name),
                     model_name, sections, sc.dt, fmi=fmi, win64=win64)


# ---------------------------------------------------------------------- the pantograph FMU
LUMPED = NativeModel(("lumped.c",), ("lumped_vars.h",), ("pcs_lumped_pantograph",))


def pantograph_variables(sections: dict) -> list[Variable]:
    """The native pantograph's variables: the Python pantograph FMU's
    (fmus/fmi/pantograph_ports.py), the export's values as fixed parameters."""
    table = PANTOGRAPH_VARIABLES
    vr = value_references(LUMPED.headers[0])
    sc = unpack(sections["scalars"], "PAN_SCALAR")
    out = [declared(table, "contact_force", vr["CONTACT_FORCE"], sc["INITIAL_FORCE"])]
    out += [declared(table, key, vr[key.upper()]) for key in ("contact_height",
                                                              "contact_velocity")]
    out += [declared(table, key, vr[key.upper()], sc[field], fixed=True) for key, field in (
        ("static_force", "STATIC_FORCE"), ("aero_c1", "AERO_C1"), ("aero_c2", "AERO_C2"),
        ("speed_kmh", "SPEED_KMH"), ("friction_force", "FRICTION_FORCE"),
        ("friction_smoothing", "FRICTION_SMOOTHING"), ("hht_alpha", "ALPHA"),
        ("initial_height", "INITIAL_HEIGHT"), ("initial_contact_force", "INITIAL_FORCE"))]
    out += [declared(table, "start_mode", vr["START_MODE"], 0, fixed=True),
            declared(table, "one_way_damper", vr["ONE_WAY_DAMPER"], False, fixed=True),
            declared(table, "force_extrapolation", vr["FORCE_EXTRAPOLATION"], False),
            declared(table, "newton_iterations", vr["NEWTON_ITERATIONS"]),
            Variable("internal_step", "Real", vr["INTERNAL_STEP"], "local", "constant",
                     sc["STEP"], "s", "the fixed internal step: a communication step is a "
                     "whole number of it")]
    return out


def export_lumped(prep, k: int, model, out: Path, fmi: int, win64: bool | None) -> Path:
    """The native FMU of the scenario's constant-matrix pantograph ``k`` (``model``) in the
    static start of the scenario, as the Python FMU starts in our master."""
    sc = prep.scenario
    spec = sc.pantographs[k]
    if spec.start != "static":
        raise ParameterError(f"pantographs[{k}].start", spec.start, "the native constant-"
                             "matrix pantograph FMU starts static in contact (start = "
                             "\"static\")", sc.source)
    if model.linear_form() is None:
        raise ParameterError("pantograph", spec.model, "has no constant-matrix form (collector "
                             "friction or a one-way damper)")
    height = float(prep.pantographs[k].contact_height(prep.q_pan0[k]))
    sections = native_export.lumped_pantograph(
        model, HHTSettings(alpha=sc.alpha), sc.dt, height, float(prep.static_forces[k]),
        spec.model)

    return build_fmu(out, LUMPED, "pantocosim_pantograph_native",
                     PANTOGRAPH_FMUS.get(spec.model, "Pantograph"),
                     f"pantocosim pantograph '{spec.model}' (native C, constant matrices, "
                     f"internal step {sc.dt:g} s)", pantograph_variables(sections), "lumped",
                     sections, sc.dt, fmi=fmi, win64=win64)


def pantograph_files(specs) -> list[str]:
    """The FMU file of each pantograph: ``<model>.fmu``, or ``<model>-<k + 1>.fmu`` where
    pantographs share a model (each FMU fixes its own start height and force)."""
    models = [spec.model for spec in specs]
    return [f"{m}.fmu" if models.count(m) == 1 else f"{m}-{k + 1}.fmu"
            for k, m in enumerate(models)]


# ---------------------------------------------------------------------- nonlinear pantographs
NONLINEAR = NativeModel(
    ("nonlinear_pantograph.c", "dsa380_rigid.c", "dsa380_flexible.c", "hht_dense.c",
     "actuation.c", "pcs_math.c"),
    ("nonlinear_pantograph_vars.h", "dsa380_rigid.h", "dsa380_flexible.h", "hht_dense.h",
     "actuation.h", "pcs_math.h"),
    ("pcs_dsa380_rigid", "pcs_dsa380_flexible"))
#: the body of each nonlinear pantograph model: (data-file kind, its sections)
NONLINEAR_BODIES = {Dsa380Model: ("dsa380-rigid", native_export.rigid_body),
                    Dsa380FlexibleModel: ("dsa380-flexible", native_export.dsa380_flexible_data)}


def nonlinear_variables(sections: dict) -> list[Variable]:
    """The native nonlinear pantograph's variables: the Python pantograph FMU's
    (fmus/fmi/pantograph_ports.py), the export's values as fixed parameters."""
    table = PANTOGRAPH_VARIABLES
    vr = value_references(NONLINEAR.headers[0])
    scalars = unpack(sections["scalars"], "NLP_SCALAR")

    def value(name):
        return float(scalars[name.upper()])

    out = [declared(table, "contact_force", vr["CONTACT_FORCE"], value("start_force"))]
    out += [declared(table, key, vr[key.upper()]) for key in ("contact_height",
                                                              "contact_velocity")]
    out += [declared(table, key, vr[key.upper()], value(key), fixed=True) for key in (
        "static_force", "aero_c1", "aero_c2", "speed_kmh", "friction_force",
        "friction_smoothing", "initial_height", "initial_contact_force", "ramp_start_time",
        "ramp_duration", "lowered_height")]
    out += [declared(table, "hht_alpha", vr["HHT_ALPHA"], value("alpha"), fixed=True),
            declared(table, "start_mode", vr["START_MODE"], int(value("start_mode")),
                     fixed=True),
            declared(table, "one_way_damper", vr["ONE_WAY_DAMPER"],
                     bool(value("one_way_damper")), fixed=True),
            declared(table, "force_extrapolation", vr["FORCE_EXTRAPOLATION"], False),
            declared(table, "newton_iterations", vr["NEWTON_ITERATIONS"]),
            Variable("internal_step", "Real", vr["INTERNAL_STEP"], "local", "constant",
                     value("step"), "s", "the fixed internal step: a communication step is a "
                     "whole number of it")]
    return out


def export_nonlinear(prep, k: int, model, out: Path, fmi: int, win64: bool | None) -> Path:
    """The native FMU of the scenario's nonlinear pantograph ``k`` (``model``: the rigid or
    the flexible DSA-380) in the start our master gives the Python FMU (cosim.py): static at
    the static start's height and force, or ramp raising."""
    sc = prep.scenario
    spec = sc.pantographs[k]
    kind, body = NONLINEAR_BODIES[type(model)]
    if spec.start == "static":
        mode, force = 0, float(prep.static_forces[k])
        height = float(prep.pantographs[k].contact_height(prep.q_pan0[k]))
    else:
        mode, force = 1, float(model.options.mean_uplift)
        height = float(prep.actuation.height[k])
    ramp = model.options.ramp
    sections = native_export.nonlinear_pantograph(
        model, body, HHTSettings(alpha=sc.alpha), sc.dt, mode, height, force, spec.model,
        lowered_height=ramp.lowered_height if ramp else None)
    return build_fmu(out, NONLINEAR, "pantocosim_pantograph_native",
                     PANTOGRAPH_FMUS.get(spec.model, "Pantograph"),
                     f"pantocosim pantograph '{spec.model}' (native C, HHT-alpha Newton, "
                     f"internal step {sc.dt:g} s)", nonlinear_variables(sections), kind,
                     sections, sc.dt, fmi=fmi, win64=win64)


#: the native form of each pantograph model (by its class)
NATIVE_PANTOGRAPHS = {LumpedPantograph: export_lumped, Dsa380Model: export_nonlinear,
                      Dsa380FlexibleModel: export_nonlinear}


def export_pantograph(prep, k: int, out: Path, fmi: int = 2,
                      win64: bool | None = None) -> Path:
    """The native FMU of the scenario's pantograph ``k`` (see :data:`NATIVE_PANTOGRAPHS`)."""
    model = scenario_pantograph(prep.scenario, k)
    export = NATIVE_PANTOGRAPHS.get(type(model))
    if export is None:
        raise ParameterError("pantograph", prep.scenario.pantographs[k].model,
                             f"has no native form (model {type(model).__name__})")
    return export(prep, k, model, Path(out), fmi, win64)


def no_native_form(exc: ParameterError) -> bool:
    """Whether ``exc`` from :func:`export_pantograph` says the pantograph has no native form
    (it stays a Python FMU) rather than that the export failed."""
    return exc.field == "pantograph" or str(exc.field).startswith("pantographs[")


def export_scenario(prep, out: Path, fmi: int = 2, win64: bool | None = None):
    """The native FMUs of a prepared scenario into the folder ``out``: ``catenary.fmu`` and
    one per constant-matrix pantograph (:func:`pantograph_files`). Returns (written files,
    [(pantograph index, why it has no native FMU)])."""
    out = Path(out)
    written = [export_catenary(prep, out / "catenary.fmu", prep.scenario.catenary_model,
                               fmi=fmi, win64=win64)]
    kept = []
    for k, name in enumerate(pantograph_files(prep.scenario.pantographs)):
        try:
            written.append(export_pantograph(prep, k, out / name, fmi=fmi, win64=win64))
        except ParameterError as exc:
            if not no_native_form(exc):
                raise
            kept.append((k, str(exc)))
    return written, kept


@contextmanager
def native_pantographs(prep, plan, native: bool = True):
    """(plan, notes): the checked FMU ``plan`` of a co-simulation with each pantograph that
    has a native form replaced by its native FMU, exported for ``prep`` into a folder that
    lives as long as the context (``native`` false: the plan as it is); ``notes`` says, one
    line each, which pantographs run native and which stay Python FMUs and why."""
    if not native:
        yield plan, []
        return
    with tempfile.TemporaryDirectory(prefix="pantocosim-native-") as folder:
        paths, files, notes = list(plan.pantographs), list(plan.parameter_files), []
        for k, spec in enumerate(prep.scenario.pantographs):
            try:
                paths[k] = export_pantograph(prep, k, Path(folder) / f"{k}.fmu", win64=False)
                files[k] = None                  # its parameter set is in the native FMU
                notes.append(f"pantograph {k + 1} ({spec.model}): native FMU")
            except ParameterError as exc:
                if not no_native_form(exc):
                    raise
                notes.append(f"pantograph {k + 1} ({spec.model}): {exc}; it stays a Python FMU")
        yield replace(plan, pantographs=paths, parameter_files=files), notes
