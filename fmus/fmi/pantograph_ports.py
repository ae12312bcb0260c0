"""The pantograph FMUs' variables (:mod:`.variables`): one port contract for every
pantograph model, parameters whose start values are the preset's (a start is a function of
the preset's :class:`~pantocosim.pantograph.presets.PresetDefaults`), and the optional inputs
of the start handshake (the catenary's start laws and train speed). The slave registers them;
the master, the SSP writer and the FMU reference read them from here."""

from __future__ import annotations

from pantocosim.core.hht_defaults import DEFAULT_ALPHA
from pantocosim.pantograph.base import Ramp
from pantocosim.interaction.pantograph_start import START_MODES

from .catenary_ports import LAW_NAMES, LAW_OUTPUTS, SPEED_OUTPUT
from .variables import (MAX_SUBSTEPS, Choices, Described, Interval, VariableTable, parameter,
                        real)

FORCE_TIMING = ("contact_force: the value set before doStep(t, h) is the force at t + h; the "
                "force at t is the previous accepted step's (kept in the FMU state).")
#: inputs carrying the catenary's start laws (catenary.operating_height.ContactHeightLaws)
LAW_INPUTS = LAW_NAMES
#: the input carrying the catenary's train speed (its output of the same name)
SPEED_INPUT = SPEED_OUTPUT
#: the optional inputs of the start handshake (a user's pantograph FMU may lack them)
HANDSHAKE_INPUTS = (*LAW_INPUTS, SPEED_INPUT)

#: meaning of the law inputs (the catenary's outputs say what the laws are)
_LAW_INPUT_TEXT = {
    "operating_height": "operating contact height h_op = operating_height + "
                        "operating_height_slope F under a mean uplift F: the actuation "
                        "delivers the mean uplift there"}


def _option(name):
    """The start value ``name`` of the preset's options."""
    return lambda defaults: getattr(defaults.options, name)


def _ramp(name):
    """The start value ``name`` of the preset's ramp (the default ramp where it has none)."""
    return lambda defaults: getattr(defaults.options.ramp or Ramp(), name)


VARIABLES = VariableTable((
    real("contact_force", "input", "N", 0.0,
         "contact force [N] >= 0 pushing the collector down. " + FORCE_TIMING,
         Described(">= 0")),
    real("contact_height", "output", "m", 0.0, "height of the contact point above the rail"),
    real("contact_velocity", "output", "m/s", 0.0, "vertical velocity of the contact point"),
    real("static_force", "parameter", "N", _option("static_force"), "static uplift force"),
    real("aero_c1", "parameter", "N.h/km", _option("aero_c1"),
         "aerodynamic uplift, linear coefficient: F = c1 v + c2 v^2, v in km/h"),
    real("aero_c2", "parameter", "N.h2/km2", _option("aero_c2"),
         "aerodynamic uplift, quadratic coefficient"),
    real("speed_kmh", "parameter", "km/h", _option("speed_kmh"), "train speed (aerodynamic "
         f"law); not set: the input {SPEED_INPUT} if given, else (start_mode 0, 1) this "
         "start value"),
    real("friction_force", "parameter", "N", _option("friction_force"),
         "collector friction amplitude f_r (thesis 2.16)"),
    real("friction_smoothing", "parameter", "m/s", _option("friction_smoothing"),
         "friction smoothing k_t (thesis 2.16)"),
    parameter("Boolean", "one_way_damper", _option("one_way_damper"),
              "the damper acts only while the mechanism moves down"),
    real("hht_alpha", "parameter", "1", DEFAULT_ALPHA, "HHT-alpha parameter in [-1/3, 0]",
         Described("-1/3 .. 0")),
    real("initial_height", "parameter", "m", lambda defaults: defaults.working_height,
         "contact height at t0 (static start: equilibrium at this height)"),
    real("initial_contact_force", "parameter", "N", -1.0, "contact force at t0 for a static "
         "start; < 0 means static + aerodynamic uplift"),
    parameter("Integer", "start_mode", 0, "0 = static start in contact at initial_height "
              "under initial_contact_force, 1 = ramp raising (thesis 3.3.1), 2 = static "
              "start on the catenary's start laws (inputs operating_height.., connected to "
              "the catenary FMU's outputs of the same names)", Choices(START_MODES)),
    real("ramp_start_time", "parameter", "s", _ramp("start"), "ramp raising: start time"),
    real("ramp_duration", "parameter", "s", _ramp("duration"), "ramp raising: duration"),
    real("lowered_height", "parameter", "m", _ramp("lowered_height"),
         "ramp raising: contact height of the lowered pantograph at t0"),
    parameter("Integer", "n_substeps", 1, "integration steps per communication step",
              Interval(1, MAX_SUBSTEPS)),
    parameter("Boolean", "force_extrapolation", False, "take contact_force as the force at "
              "the start of the communication step (what a zero-order-hold master sets) and "
              "extrapolate it linearly to t + h from the previous input: F(t+h) = max(0, "
              "2 F(t) - F(t-h)); the input of the first step is not read (the force at t0 "
              "is the start's)"),
    *(real(name, "input", unit, 0.0, "start_mode 2: the catenary's start law, read in "
           "initialisation mode: " + _LAW_INPUT_TEXT.get(name, text))
      for name, unit, text in LAW_OUTPUTS),
    real(SPEED_INPUT, "input", "km/h", 0.0, "the catenary's train speed, read in "
         "initialisation mode where speed_kmh was not set"),
    parameter("String", "parameter_file", "", "parameter file (TOML) replacing the preset; "
              "a path or a file name in the FMU resources"),
    real("newton_iterations", "local", None, 0.0,
         "Newton iterations of the last communication step"),
))

#: the ports every pantograph FMU has (ours and a user's): name -> causality (all Real), in
#: the order force in, contact height out, contact velocity out
REQUIRED_PORTS = {v.name: v.causality for v in VARIABLES
                  if v.causality in ("input", "output") and v.name not in HANDSHAKE_INPUTS}
