"""The catenary FMU's variables (:mod:`.variables`): parameters, the ports of pantographs
1..:data:`MAX_PANTOGRAPHS` (``_k``), the support uplifts (``_j``) and the start laws. The
slave registers them, the master and the SSP writer take their port names from here, the
documentation's FMU reference lists them."""

from __future__ import annotations

from dataclasses import dataclass

from pantocosim.catenary.models import CATENARY_MODELS
from pantocosim.core.hht_defaults import DEFAULT_ALPHA, RUN_RTOL, RUN_RTOL_MAX
from pantocosim.interaction.penalty_contact import DEFAULT_CONTACT_STIFFNESS

from .variables import (MAX_SUBSTEPS, Choices, Described, Each, Interval, Positive,
                        VariableTable, parameter, real)

MAX_PANTOGRAPHS = 4
#: support_uplift_j outputs: the FMU's port limit (a longer line reports the first ones)
MAX_SUPPORTS = 64
PANTOGRAPHS = range(1, MAX_PANTOGRAPHS + 1)

TIMING = ("the value set before doStep(t, h) is the value at t + h; the value at t is the "
          "previous accepted step's (kept in the FMU state)")

#: the start laws offered to pantograph FMUs in start_mode 2 (operating_height.py): name,
#: unit, meaning; the catenary's outputs ``<name>_k``, a pantograph's inputs ``<name>``
LAW_OUTPUTS = (
    ("operating_height", "m", "contact height where a pantograph of mean uplift F operates: "
     "operating_height + operating_height_slope F (mean dynamic wire height over the "
     "analysis window + F / k_H)"),
    ("operating_height_slope", "m/N", "slope of the operating-height law"),
    ("static_height", "m", "contact height at t0 under a static contact force F: "
     "static_height + static_height_slope F"),
    ("static_height_slope", "m/N", "slope of the static-height law"))
LAW_NAMES = tuple(name for name, _, _ in LAW_OUTPUTS)
#: the output carrying the train speed (pantograph FMUs' input of the same name)
SPEED_OUTPUT = "train_speed_kmh"

CONTACT_MODES = {0: "contact forces are inputs", 1: "built-in penalty contact"}


VARIABLES = VariableTable((
    parameter("String", "catenary_definition", "en50318", "catenary definition: preset name "
              "(en50318, ave64, benchmark55) or TOML file (relative paths are also looked up "
              "in the FMU resources)"),
    parameter("Integer", "spans", 0, "number of spans (span data cycled); 0 = as defined",
              Interval(0, note="0 = as defined")),
    parameter("Integer", "catenary_model", 0, "catenary model: 0 = nonlinear (finite "
              "elements, the reference), 1 = linear (about the static equilibrium, droppers "
              "slacken), 2 = modal (the linear model on its modes below modal_cutoff_hz, "
              "static corrections at the droppers and contact points)",
              Choices({c: n for n, c in CATENARY_MODELS.codes().items()})),
    real("modal_cutoff_hz", "parameter", "Hz", 0.0, "catenary_model 2: modes below this "
         "frequency; 0 = the default cutoff", Interval(0, note="0 = the default")),
    real("element_size", "parameter", "m", 0.0, "target finite-element length; 0 = as "
         "defined", Interval(0, note="0 = as defined")),
    real("speed_kmh", "parameter", "km/h", 0.0, "train speed",
         Described("0 .. the contact wire's wave speed")),
    parameter("Integer", "n_pantographs", 1, "number of pantographs (1..4)",
              Interval(1, MAX_PANTOGRAPHS)),
    Each("k", PANTOGRAPHS, (
        real("position_{k}", "parameter", "m", 30.0,
             "track position x of pantograph {k} at t0", Described("on the line")),)),
    Each("k", PANTOGRAPHS, (
        real("static_force_{k}", "parameter", "N", 0.0, "upward static contact force of "
             "pantograph {k} at t0 (static start); 0 = none", Interval(0, note="0 = none")),)),
    real("hht_alpha", "parameter", "1", DEFAULT_ALPHA, "HHT-alpha parameter in [-1/3, 0]",
         Described("-1/3 .. 0")),
    parameter("Integer", "contact_mode", 0, "0 = contact forces are inputs "
              "(contact_force_k); 1 = built-in penalty contact from pantograph_height_k and "
              "pantograph_velocity_k", Choices(CONTACT_MODES)),
    real("contact_stiffness", "parameter", "N/m", DEFAULT_CONTACT_STIFFNESS,
         "penalty stiffness k_H (contact_mode 1)", Described("> 0")),
    real("contact_damping", "parameter", "N.s/m", 0.0,
         "penalty contact damping c_H (contact_mode 1)", Described(">= 0")),
    parameter("Boolean", "extrapolate_heights", True, "contact_mode 1: take "
              "pantograph_height_k as the height at the start of the communication step "
              "(what a zero-order-hold master sets) and extrapolate it with "
              "pantograph_velocity_k over the step; false: take it as the height at t + h "
              "(an iterating master)"),
    real("window_start", "parameter", "m", 0.0, "analysis window start x: the "
         "operating-height law averages the wire height there (window_end <= "
         "window_start: the middle span of the line)"),
    real("window_end", "parameter", "m", 0.0, "analysis window end x"),
    real("averaging_step", "parameter", "s", 1e-3, "time step of the moving-load run "
         "behind the operating-height law", Positive()),
    parameter("Integer", "n_substeps", 1, "integration steps per communication step (inputs "
              "interpolated linearly)", Interval(1, MAX_SUBSTEPS)),
    parameter("Integer", "max_dofs", 0, "largest catenary model the FMU builds (degrees of "
              "freedom); 0 = the default limit (the size guard refuses larger models before "
              "building them)", Interval(0, note="0 = the default limit")),
    parameter("Integer", "factorization", 2, "Newton matrix policy of the HHT solver: 0 = "
              "full Newton (refactorize every iteration), 1 = factorize once per step "
              "(chord), 2 = reuse across steps (refreshed when droppers change state or a "
              "step needs more than 2 iterations; linear predictor)",
              Choices({0: "full Newton", 1: "once per step", 2: "reuse across steps"})),
    real("newton_rtol", "parameter", "1", RUN_RTOL, "Newton residual tolerance, relative to "
         "the largest force in the residual", Described(f"> 0, <= {RUN_RTOL_MAX:g}")),
    Each("k", PANTOGRAPHS, (
        real("contact_force_{k}", "input", "N", 0.0, "contact_mode 0: upward contact force "
             "of pantograph {k} on the wire, >= 0; " + TIMING + "; at t0 it is "
             "static_force_{k}", Described(">= 0")),)),
    Each("k", PANTOGRAPHS, (
        real("pantograph_height_{k}", "input", "m", 0.0, "contact_mode 1: contact height of "
             "pantograph {k} above the rail; " + TIMING),
        real("pantograph_velocity_{k}", "input", "m/s", 0.0, "contact_mode 1: vertical "
             "velocity of pantograph {k}'s contact point; " + TIMING))),
    Each("k", PANTOGRAPHS, (
        real("wire_height_{k}", "output", "m", 0.0,
             "contact-wire height above the rail under pantograph {k}"),
        real("wire_velocity_{k}", "output", "m/s", 0.0, "vertical velocity of the contact "
             "wire seen by pantograph {k} (including the convective term V dz/dx)"),
        real("contact_force_out_{k}", "output", "N", 0.0, "contact force of pantograph {k}: "
             "mode 1 the penalty force at the end of the step, mode 0 the input force"))),
    Each("k", PANTOGRAPHS, tuple(
        real(name + "_{k}", "output", unit, 0.0, "start law of pantograph {k} (constant; "
             "available in initialisation mode): " + text)
        for name, unit, text in LAW_OUTPUTS)),
    Each("j", range(MAX_SUPPORTS), (
        real("support_uplift_{j}", "output", "m", 0.0, "uplift of the contact wire at "
             "support {j} relative to the unloaded static configuration (0 beyond the last "
             "support)"),)),
    real("n_supports", "output", "1", 0.0, "number of supports of the line (spans + 1)"),
    real(SPEED_OUTPUT, "output", "km/h", 0.0, "the train speed (speed_kmh; available in "
         "initialisation mode): pantograph FMUs take it as their input of the same name"),
    real("newton_iterations", "local", None, 0.0,
         "Newton iterations of the last communication step"),
))


@dataclass(frozen=True)
class PortNames:
    """The names of the ports of pantographs 1..n and of the support uplifts (a step sets
    and reads its variables by these names, built once)."""

    forces: tuple            # contact_force_k (input, contact_mode 0)
    heights: tuple           # pantograph_height_k (input, contact_mode 1)
    velocities: tuple        # pantograph_velocity_k (input, contact_mode 1)
    wire_heights: tuple      # wire_height_k
    wire_velocities: tuple   # wire_velocity_k
    forces_out: tuple        # contact_force_out_k
    uplifts: tuple           # support_uplift_j, j = 0 .. n_supports - 1
    laws: tuple              # the start laws of pantograph k: (operating_height_k, ...) per k

    @classmethod
    def of(cls, n: int, n_supports: int = MAX_SUPPORTS) -> "PortNames":
        k = range(1, n + 1)
        per_pantograph = (VARIABLES.names(f"{base}_{{k}}", k) for base in (
            "contact_force", "pantograph_height", "pantograph_velocity", "wire_height",
            "wire_velocity", "contact_force_out"))
        laws = tuple(zip(*(VARIABLES.names(f"{law}_{{k}}", k) for law in LAW_NAMES)))
        return cls(*per_pantograph, VARIABLES.names("support_uplift_{j}", range(n_supports)),
                   laws)
