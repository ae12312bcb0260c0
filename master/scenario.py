"""Scenario files: which pantographs run on which catenary, how fast, what is analysed.

A scenario is a TOML file (presets in ``master/scenarios/``)::

    name = "dsa380-ave-300"
    catenary = "ave64"             # catenary preset or definition file (a relative path is
                                   # taken from this file's folder, as every file named here)
    spans = 10                     # optional: override the catenary's number of spans
    speed_kmh = 300.0

    [[pantographs]]
    model = "dsa380-rigid"         # pantograph preset or parameter file
    fmu = "dist/fmus/dsa380-rigid.fmu"   # optional, used by the co-simulation couplings: a
                                   # pantocosim FMU of this model (checked; relative to the
                                   # working folder, else to this file's); a model given by
                                   # a parameter file runs in any pantograph FMU (default
                                   # dist/fmus/dsa380-rigid.fmu), which gets the file
    position_m = 32.0              # x of the contact point at t = 0 (pantographs at least
                                   # MIN_SPACING_M apart, before the analysis window)
    start = "static"               # "static" (in contact, in equilibrium) or "ramp"
    ramp = { start_m = 32.0, length_m = 20.0, lowered_height = 5.0 }   # start = "ramp":
                                   # from position_m on, ending before the analysis window,
                                   # lowered below the contact wire

    [analysis]
    window_supports = [5, 6]       # analyse between these supports (0 = first), or (not
    # window_m = [320.0, 384.0]    # both) an explicit x range, applied to each pantograph's
                                   # track

    [simulation]
    dt = 0.001                     # time step [s]
    alpha = -0.05                  # HHT alpha
    newton_rtol = 1e-4             # Newton residual tolerance (relative)
    coupling_rtol = 1e-4           # implicit co-simulation: interface residual tolerance,
                                   # relative to the pantographs' mean contact force
    duration_s = 5.0               # optional; default: until the last pantograph leaves the
                                   # analysis window
    catenary_model = "nonlinear"   # "nonlinear" (reference), "linear" or "modal"
    modal_cutoff_hz = 100.0        # modal model: modes below it (docs/modal-cutoff.md)

    [contact]
    stiffness = 50000.0            # k_H [N/m]
    damping = 0.0                  # c_H [N s/m]

Loading validates every field and names the file, the field and the value in its errors.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from pantocosim.catenary.models import DEFAULT_MODAL_CUTOFF_HZ, MODEL_NAMES
from pantocosim.core.errors import ParameterError
from pantocosim.core.penalty_contact import DEFAULT_CONTACT_STIFFNESS
from pantocosim.core.hht import ALPHA_MAX, ALPHA_MIN, DEFAULT_ALPHA, RUN_RTOL, RUN_RTOL_MAX
from pantocosim.core.params import Table, load_toml

SCENARIO_DIR = Path(__file__).resolve().parent / "scenarios"
DEFAULT_SCENARIO = "dsa380-ave-300"
#: closest two pantographs may be along the track [m]: a pantograph head is about 2 m long
#: (two collector strips), so two heads closer than that would overlap
MIN_SPACING_M = 2.0


@dataclass
class RampSpec:
    start_m: float
    length_m: float
    lowered_height: float


@dataclass
class PantographSpec:
    model: str
    position_m: float
    start: str = "static"
    ramp: RampSpec | None = None
    fmu: str | None = None
    options: dict = field(default_factory=dict)


@dataclass
class Scenario:
    name: str
    source: str
    catenary: str
    speed_kmh: float
    pantographs: list[PantographSpec]
    window_supports: tuple[int, int] | None
    window_m: tuple[float, float] | None
    dt: float = 1e-3
    alpha: float = DEFAULT_ALPHA
    newton_rtol: float = RUN_RTOL
    #: implicit co-simulation: interface residual tolerance relative to the pantographs'
    #: mean contact force (the Newton tolerance's counterpart at the ports)
    coupling_rtol: float = RUN_RTOL
    duration_s: float | None = None
    contact_stiffness: float = DEFAULT_CONTACT_STIFFNESS
    contact_damping: float = 0.0
    spans: int | None = None
    description: str = ""
    #: catenary model (pantocosim.catenary.models.CATENARY_MODELS)
    catenary_model: str = "nonlinear"
    modal_cutoff_hz: float = DEFAULT_MODAL_CUTOFF_HZ

    @property
    def speed(self) -> float:
        """Train speed [m/s]."""
        return self.speed_kmh / 3.6


def scenario_names() -> list[str]:
    return sorted(p.stem for p in SCENARIO_DIR.glob("*.toml"))


def scenario_path(name_or_path: str | Path | None) -> Path:
    key = DEFAULT_SCENARIO if name_or_path is None else str(name_or_path)
    candidate = SCENARIO_DIR / f"{key}.toml"
    if candidate.exists():
        return candidate
    p = Path(key)
    if p.exists():
        return p
    raise ParameterError("scenario", key, f"unknown scenario (presets: "
                         f"{', '.join(scenario_names())}) and not a file")


def check_spacing(specs: list[PantographSpec], source: str) -> None:
    """Pantographs must be at least :data:`MIN_SPACING_M` apart (two on one spot would press
    the same point of the wire)."""
    order = sorted(range(len(specs)), key=lambda i: specs[i].position_m)
    for a, b in zip(order, order[1:]):
        gap = specs[b].position_m - specs[a].position_m
        if gap < MIN_SPACING_M:
            raise ParameterError(f"pantographs[{b}].position_m", specs[b].position_m,
                                 f"{gap:g} m from pantographs[{a}] (position_m = "
                                 f"{specs[a].position_m:g}); pantographs must be at least "
                                 f"{MIN_SPACING_M:g} m apart", source)


def load_scenario(name_or_path: str | Path | None = None) -> Scenario:
    path = scenario_path(name_or_path)
    return parse_scenario(load_toml(path), str(path), path.stem, base=path.parent)


def looks_like_file(name: str) -> bool:
    """A catenary or pantograph named by a file (a path or a ``.toml`` name), not a preset."""
    return "/" in name or "\\" in name or name.endswith(".toml")


def scenario_file(value: str, base: Path | None, field: str, source: str) -> str:
    """A file named in a scenario, as an absolute path: relative paths are taken from the
    scenario's folder ``base`` (the working folder when the scenario is not a file); preset
    names stay as they are."""
    if not looks_like_file(value):
        return value
    path = Path(value).expanduser()
    if not path.is_absolute():
        path = (base if base is not None else Path.cwd()) / path
    if not path.is_file():
        where = "" if base is None else " (relative paths are taken from the scenario's folder)"
        raise ParameterError(field, value, f"no such file: {path.absolute()}{where}", source)
    return str(path.resolve())


def parse_scenario(data: dict, source: str, default_name: str = "scenario",
                   base: Path | None = None) -> Scenario:
    """Validate the parsed TOML table of a scenario (``source`` names it in errors); files it
    names are taken from the folder ``base`` (:func:`scenario_file`)."""
    root = Table(data, source)
    root.unknown_keys({"name", "description", "catenary", "spans", "speed_kmh", "pantographs",
                       "analysis", "simulation", "contact"})
    pans = root._get("pantographs", None, required=True)
    if not isinstance(pans, list) or not pans:
        raise ParameterError("pantographs", pans, "must be a non-empty array of tables", source)
    specs = []
    for i, raw in enumerate(pans):
        t = Table(raw, source, f"pantographs[{i}]")
        t.unknown_keys({"model", "fmu", "position_m", "start", "ramp", "options"})
        start = t.string("start", "static", choices=("static", "ramp"))
        ramp = None
        position = t.number("position_m")
        if start == "ramp":
            r = t.sub("ramp")
            r.unknown_keys({"start_m", "length_m", "lowered_height"})
            ramp = RampSpec(r.number("start_m"), r.number("length_m", positive=True),
                            r.number("lowered_height", positive=True))
            if ramp.start_m < position:
                raise ParameterError(f"pantographs[{i}].ramp.start_m", ramp.start_m,
                                     f"behind the pantograph's start (position_m = "
                                     f"{position:g}); the raising starts where the "
                                     "pantograph is or further on", source)
        elif t.has("ramp"):
            raise ParameterError(f"pantographs[{i}].ramp", raw["ramp"],
                                 'only allowed with start = "ramp"', source)
        opts = raw.get("options", {})
        if not isinstance(opts, dict):
            raise ParameterError(f"pantographs[{i}].options", opts, "must be a table", source)
        fmu = t.string("fmu") if t.has("fmu") else None
        if fmu is not None and not fmu.strip():
            raise ParameterError(f"pantographs[{i}].fmu", fmu, "empty; give an .fmu file or "
                                 "leave the field out (default: the model's FMU)", source)
        model = scenario_file(t.string("model"), base, f"pantographs[{i}].model", source)
        specs.append(PantographSpec(model=model, position_m=position,
                                    start=start, ramp=ramp, fmu=fmu, options=dict(opts)))
    check_spacing(specs, source)
    analysis = root.sub("analysis")
    analysis.unknown_keys({"window_supports", "window_m"})
    if analysis.has("window_supports") and analysis.has("window_m"):
        raise ParameterError("analysis.window_m", analysis.data["window_m"], "give either "
                             "analysis.window_supports or analysis.window_m, not both", source)
    window_supports = window_m = None
    if analysis.has("window_supports"):
        ws = analysis._get("window_supports", None, True)
        if (not isinstance(ws, list) or len(ws) != 2
                or not all(isinstance(x, int) and not isinstance(x, bool) for x in ws)
                or ws[1] <= ws[0] or ws[0] < 0):
            raise ParameterError("analysis.window_supports", ws,
                                 "must be two increasing support indices", source)
        window_supports = (ws[0], ws[1])
    elif analysis.has("window_m"):
        wm = analysis.numbers("window_m", length=2, increasing=True)
        window_m = (wm[0], wm[1])
    else:
        raise ParameterError("analysis.window_supports", None,
                             "missing field (or give analysis.window_m)", source)
    sim = root.sub("simulation", required=False)
    sim.unknown_keys({"dt", "alpha", "duration_s", "newton_rtol", "coupling_rtol",
                      "catenary_model", "modal_cutoff_hz"})
    contact = root.sub("contact", required=False)
    contact.unknown_keys({"stiffness", "damping"})
    sc = Scenario(
        name=root.string("name", default_name), source=source,
        description=root.string("description", ""),
        catenary=scenario_file(root.string("catenary"), base, "catenary", source),
        spans=root.integer("spans", minimum=2) if root.has("spans") else None,
        speed_kmh=root.number("speed_kmh", positive=True),
        pantographs=specs, window_supports=window_supports, window_m=window_m,
        dt=sim.number("dt", 1e-3, positive=True, maximum=0.01),
        alpha=sim.number("alpha", DEFAULT_ALPHA, minimum=ALPHA_MIN, maximum=ALPHA_MAX),
        newton_rtol=sim.number("newton_rtol", RUN_RTOL, positive=True,
                               maximum=RUN_RTOL_MAX),
        coupling_rtol=sim.number("coupling_rtol", RUN_RTOL, positive=True,
                                 maximum=RUN_RTOL_MAX),
        duration_s=sim.number("duration_s", positive=True) if sim.has("duration_s") else None,
        catenary_model=sim.string("catenary_model", "nonlinear", choices=MODEL_NAMES),
        modal_cutoff_hz=sim.number("modal_cutoff_hz", DEFAULT_MODAL_CUTOFF_HZ, positive=True),
        contact_stiffness=contact.number("stiffness", DEFAULT_CONTACT_STIFFNESS, positive=True),
        contact_damping=contact.number("damping", 0.0, nonnegative=True))
    return sc


def scenario_catenary(sc: Scenario):
    """The catenary definition of ``sc`` (without its ``spans``); an unknown name is an error
    of the scenario's field ``catenary``."""
    from pantocosim.catenary.definition import load_catenary

    try:
        return load_catenary(sc.catenary)
    except ParameterError as exc:
        if exc.field != "catenary" or exc.source:
            raise
        raise ParameterError("catenary", exc.value, exc.reason, sc.source) from None
