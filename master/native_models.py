"""The native FMUs of a scenario (``pantocosim export-native``): the catenary (linear or
modal model) and the constant-matrix pantographs, with the Python FMUs' variable names and
the export's values as fixed parameters; their constants come from
:mod:`.native_export`, the FMUs are built by :mod:`.native_fmu`."""

from __future__ import annotations

from pathlib import Path

from pantocosim.core.errors import ParameterError
from pantocosim.master.native_fmu import NativeModel, Variable, build_fmu, value_references


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
