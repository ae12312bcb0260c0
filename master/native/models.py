"""The native FMUs of a scenario (``pantocosim export-native``): the catenary (linear or
modal model) and the constant-matrix pantographs, with the Python FMUs' variable names and
the export's values as fixed parameters; their constants come from
:mod:`.export`, the FMUs are built by :mod:`.build`."""

from __future__ import annotations

from pathlib import Path

from pantocosim.core.errors import ParameterError
from pantocosim.core.hht import HHTSettings
from pantocosim.fmi.catenary_ports import VARIABLES as CATENARY_VARIABLES
from pantocosim.fmi.pantograph_ports import VARIABLES as PANTOGRAPH_VARIABLES
from pantocosim.master.native import export as native_export
from pantocosim.master.fmu.build import CATENARY_CLASS, PANTOGRAPH_FMUS
from pantocosim.master.native.build import NativeModel, Variable, build_fmu, value_references
from pantocosim.master.run.setup import scenario_pantograph

CATENARY = NativeModel(("catenary.c", "catenary_modal.c"), ("catenary_vars.h", "catenary.h"))
MAX_SUPPORTS = 64


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


def catenary_variables(sections: dict) -> list[Variable]:
    """The native catenary's variables: the Python catenary FMU's (fmus/fmi/catenary_ports.py),
    the export's values as fixed parameters."""
    table = CATENARY_VARIABLES
    vr = value_references(CATENARY.headers[0])
    sizes, sc = sections["sizes"], sections["scalars"]
    n_p = int(sizes[5])
    name = bytes(sections["definition"].tobytes()).split(b"\0")[0].decode()
    out = [declared(table, key, vr[key.upper()], value, fixed=True) for key, value in (
        ("catenary_definition", name), ("n_pantographs", n_p), ("spans", int(sizes[-2])),
        ("catenary_model", int(sizes[-1])), ("speed_kmh", sc[6] * 3.6), ("hht_alpha", sc[1]),
        ("contact_stiffness", sc[8]), ("contact_damping", sc[9]),
        ("modal_cutoff_hz", sc[12]))]
    out += [declared(table, "contact_mode", vr["CONTACT_MODE"], 0),
            declared(table, "extrapolate_heights", vr["EXTRAPOLATE_HEIGHTS"], True),
            declared(table, "newton_rtol", vr["NEWTON_RTOL"], sc[13],
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
                        float(sc[0]), "s", "the fixed internal step: a communication step is "
                        "a whole number of it"))
    return out


def export_catenary(prep, out: Path, model_name: str = "linear", fmi: int = 2,
                    win64: bool | None = None) -> Path:
    """The native catenary FMU of a prepared scenario (:class:`~pantocosim.master.run.Prepared`
    whose catenary is the linear model)."""
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

    return build_fmu(out, CATENARY, "pantocosim_catenary_native", CATENARY_CLASS,
                     f"pantocosim {model_name} catenary '{sc.catenary}' at {sc.speed_kmh:g} km/h "
                     f"(native C, internal step {sc.dt:g} s)", catenary_variables(sections),
                     model_name, sections, sc.dt, fmi=fmi, win64=win64)


# ---------------------------------------------------------------------- the pantograph FMU
LUMPED = NativeModel(("lumped.c",), ("lumped_vars.h",))


def pantograph_variables(sections: dict) -> list[Variable]:
    """The native pantograph's variables: the Python pantograph FMU's
    (fmus/fmi/pantograph_ports.py), the export's values as fixed parameters."""
    table = PANTOGRAPH_VARIABLES
    vr = value_references(LUMPED.headers[0])
    sc = sections["scalars"]
    out = [declared(table, "contact_force", vr["CONTACT_FORCE"], sc[11])]
    out += [declared(table, key, vr[key.upper()]) for key in ("contact_height",
                                                              "contact_velocity")]
    out += [declared(table, key, vr[key.upper()], sc[i], fixed=True) for key, i in (
        ("static_force", 6), ("aero_c1", 7), ("aero_c2", 8), ("speed_kmh", 9),
        ("friction_force", 12), ("friction_smoothing", 13), ("hht_alpha", 1),
        ("initial_height", 10), ("initial_contact_force", 11))]
    out += [declared(table, "start_mode", vr["START_MODE"], 0, fixed=True),
            declared(table, "one_way_damper", vr["ONE_WAY_DAMPER"], False, fixed=True),
            declared(table, "force_extrapolation", vr["FORCE_EXTRAPOLATION"], False),
            declared(table, "newton_iterations", vr["NEWTON_ITERATIONS"]),
            Variable("internal_step", "Real", vr["INTERNAL_STEP"], "local", "constant",
                     float(sc[0]), "s", "the fixed internal step: a communication step is a "
                     "whole number of it")]
    return out


def export_pantograph(prep, k: int, out: Path, fmi: int = 2,
                      win64: bool | None = None) -> Path:
    """The native FMU of the scenario's pantograph ``k`` (a constant-matrix model in the
    static start of the scenario, as the Python FMU starts in our master)."""
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
            if exc.field not in ("pantograph",) and not str(exc.field).startswith("pantographs["):
                raise
            kept.append((k, str(exc)))
    return written, kept
