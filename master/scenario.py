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
    fmi = 2                        # co-simulation: FMI version of the default FMUs (2 or 3)

    [contact]
    law = "penalty"                # "penalty" or "constraint" (rigid, unilateral; monolithic)
    stiffness = 50000.0            # penalty law: k_H [N/m]
    damping = 0.0                  # penalty law: c_H [N s/m]

Loading validates every field and names the file, the field and the value in its errors.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from pantocosim.catenary.models import DEFAULT_MODAL_CUTOFF_HZ, MODEL_NAMES
from pantocosim.core.errors import ParameterError
from pantocosim.interaction.contact_laws import CONTACT_LAWS, DEFAULT_LAW
from pantocosim.interaction.penalty_contact import DEFAULT_CONTACT_STIFFNESS
from pantocosim.core.hht import ALPHA_MAX, ALPHA_MIN, DEFAULT_ALPHA, RUN_RTOL, RUN_RTOL_MAX
from pantocosim.core.params import Table, load_toml
from pantocosim.core.schema import OPTIONAL, Field, Format, Section
from pantocosim.catenary.definition import load_catenary

SCENARIO_DIR = Path(__file__).resolve().parent / "scenarios"
DEFAULT_SCENARIO = "dsa380-ave-300"
#: closest two pantographs may be along the track [m]: a pantograph head is about 2 m long
#: (two collector strips), so two heads closer than that would overlap
MIN_SPACING_M = 2.0


#: the declared fields of a scenario file (the loader reads each through its declaration;
#: the reference page of the format is generated from them)
ROOT = Section("", [
    Field("name", "string", default=OPTIONAL, doc="name of the scenario (default: the "
          "file's name)"),
    Field("description", "string", default="", doc="free text"),
    Field("catenary", "file", doc="catenary preset (en50318, benchmark55, ave64) or definition "
          "file, relative to this file's folder"),
    Field("spans", "integer", default=OPTIONAL, minimum=2,
          doc="repeat or cut the catenary to this many spans"),
    Field("speed_kmh", unit="km/h", positive=True, doc="train speed"),
], extra=("pantographs", "analysis", "simulation", "contact"))
PANTOGRAPH = Section("pantographs", [
    Field("model", "file", doc="pantograph preset (dsa380-rigid, dsa380-flexible, "
          "dsa380-lumped3, en50318-2mass) or parameter file, relative to this file's folder"),
    Field("fmu", "string", default=OPTIONAL, doc="the co-simulation couplings' FMU of this "
          "model (default dist/fmus/MODEL.fmu; a parameter file runs in "
          "dist/fmus/dsa380-rigid.fmu)", rule="not empty"),
    Field("position_m", unit="m", doc="x of the contact point at t = 0",
          rule=f"pantographs at least {MIN_SPACING_M:g} m apart"),
    Field("start", "string", default="static", choices=("static", "ramp"),
          doc='"static": in contact and in equilibrium; "ramp": raised from a lowered height'),
    Field("options", "table", default=OPTIONAL, doc="pantograph options overriding the "
          "parameter file's [options] (see the pantograph format)"),
], doc="One `[[pantographs]]` table per pantograph (at least one).", extra=("ramp",),
    array=True)
RAMP = Section("pantographs.ramp", [
    Field("start_m", unit="m", doc="x where the raising starts",
          rule="not behind position_m"),
    Field("length_m", unit="m", positive=True, doc="distance over which the pantograph rises"),
    Field("lowered_height", unit="m", positive=True,
          doc="height of the lowered collector, below the contact wire"),
], doc='Only with `start = "ramp"`; the raising ends before the analysis window.')
ANALYSIS = Section("analysis", [
    Field("window_supports", "integers", default=OPTIONAL, length=2, doc="analyse between "
          "these supports (0 = first), applied to each pantograph's track",
          rule="two increasing integer support indices >= 0"),
    Field("window_m", "numbers", default=OPTIONAL, length=2, increasing=True, unit="m",
          doc="or an explicit x range", rule="not with window_supports"),
], doc="Give exactly one of `window_supports` and `window_m`.")
SIMULATION = Section("simulation", [
    Field("dt", unit="s", default=1e-3, positive=True, maximum=0.01, doc="time step"),
    Field("alpha", default=DEFAULT_ALPHA, minimum=ALPHA_MIN, maximum=ALPHA_MAX,
          doc="HHT-alpha parameter (numerical damping)"),
    Field("newton_rtol", default=RUN_RTOL, positive=True, maximum=RUN_RTOL_MAX,
          doc="Newton residual tolerance (relative)"),
    Field("coupling_rtol", default=RUN_RTOL, positive=True, maximum=RUN_RTOL_MAX,
          doc="implicit co-simulation: interface residual tolerance, relative to the "
          "pantographs' mean contact force"),
    Field("duration_s", unit="s", default=OPTIONAL, positive=True,
          doc="run length (default: until the last pantograph leaves the analysis window)"),
    Field("catenary_model", "string", default="nonlinear", choices=MODEL_NAMES,
          doc="nonlinear (reference), linear or modal catenary model"),
    Field("modal_cutoff_hz", unit="Hz", default=DEFAULT_MODAL_CUTOFF_HZ, positive=True,
          doc="modal model: the modes below this frequency are kept"),
    Field("fmi", "integer", default=2, choices=(2, 3),
          doc="co-simulation: the FMI version of the FMUs built by `pantocosim build-fmus` "
          "that the run uses (2: dist/fmus/, 3: dist/fmus/fmi3/); an FMU a pantograph names "
          "runs in the version its model description says"),
], doc="Optional table: every field has a default.")
CONTACT = Section("contact", [
    Field("law", "string", default=DEFAULT_LAW, choices=tuple(CONTACT_LAWS),
          doc='"penalty": F = k_H max(0, z_pantograph - z_wire) (every coupling); '
          '"constraint": rigid, unilateral contact, its force a Lagrange multiplier (the '
          'monolithic coupling only: no contact stiffness, no contact mode)'),
    Field("stiffness", unit="N/m", default=DEFAULT_CONTACT_STIFFNESS, positive=True,
          doc="penalty law: stiffness k_H", rule='not with law = "constraint"'),
    Field("damping", unit="N s/m", default=0.0, nonnegative=True,
          doc="penalty law: contact damping c_H", rule='not with law = "constraint"'),
], doc="Optional table: the contact law between each pantograph and the contact wire.")
FORMAT = Format("scenario", "Scenario files", """A scenario says which pantographs run on which catenary, how fast, and what is analysed. It is
read by `pantocosim run SCENARIO` and is the base of a sweep. Presets live in
`master/scenarios/` (`pantocosim run` lists them in its help); any of them is a good start for a
file of your own. Files named in a scenario are taken from the scenario's folder when relative.
""", (ROOT, PANTOGRAPH, RAMP, ANALYSIS, SIMULATION, CONTACT))


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
    #: contact law (pantocosim.interaction.contact_laws.CONTACT_LAWS)
    contact_law: str = DEFAULT_LAW
    spans: int | None = None
    description: str = ""
    #: catenary model (pantocosim.catenary.models.CATENARY_MODELS)
    catenary_model: str = "nonlinear"
    modal_cutoff_hz: float = DEFAULT_MODAL_CUTOFF_HZ
    #: co-simulation: FMI version of the default FMUs (2: dist/fmus/, 3: dist/fmus/fmi3/)
    fmi: int = 2

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
    ROOT.check_keys(root)
    pans = root._get("pantographs", None, required=True)
    if not isinstance(pans, list) or not pans:
        raise ParameterError("pantographs", pans, "must be a non-empty array of tables", source)
    specs = []
    for i, raw in enumerate(pans):
        t = Table(raw, source, f"pantographs[{i}]")
        PANTOGRAPH.check_keys(t)
        start = PANTOGRAPH.read(t, "start")
        ramp = None
        position = PANTOGRAPH.read(t, "position_m")
        if start == "ramp":
            r = t.sub("ramp")
            RAMP.check_keys(r)
            ramp = RampSpec(*(RAMP.read(r, f.name) for f in RAMP.fields))
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
        fmu = PANTOGRAPH.read(t, "fmu")
        if fmu is not None and not fmu.strip():
            raise ParameterError(f"pantographs[{i}].fmu", fmu, "empty; give an .fmu file or "
                                 "leave the field out (default: the model's FMU)", source)
        model = scenario_file(PANTOGRAPH.read(t, "model"), base, f"pantographs[{i}].model", source)
        specs.append(PantographSpec(model=model, position_m=position,
                                    start=start, ramp=ramp, fmu=fmu, options=dict(opts)))
    check_spacing(specs, source)
    analysis = root.sub("analysis")
    ANALYSIS.check_keys(analysis)
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
        wm = ANALYSIS.read(analysis, "window_m")
        window_m = (wm[0], wm[1])
    else:
        raise ParameterError("analysis.window_supports", None,
                             "missing field (or give analysis.window_m)", source)
    sim = root.sub("simulation", required=False)
    SIMULATION.check_keys(sim)
    contact = root.sub("contact", required=False)
    CONTACT.check_keys(contact)
    name = ROOT.read(root, "name")
    sc = Scenario(
        name=default_name if name is None else name, source=source,
        description=ROOT.read(root, "description"),
        catenary=scenario_file(ROOT.read(root, "catenary"), base, "catenary", source),
        spans=ROOT.read(root, "spans"), speed_kmh=ROOT.read(root, "speed_kmh"),
        pantographs=specs, window_supports=window_supports, window_m=window_m,
        **{f.name: f.read(sim) for f in SIMULATION.fields},
        contact_law=contact_law(contact, source),
        contact_stiffness=CONTACT.read(contact, "stiffness"),
        contact_damping=CONTACT.read(contact, "damping"))
    return sc


def contact_law(contact: Table, source: str) -> str:
    """The ``[contact]`` law; a value the law does not take is refused (its ``fields``)."""
    law = CONTACT.read(contact, "law")
    for name in ("stiffness", "damping"):
        if contact.has(name) and name not in CONTACT_LAWS[law].fields:
            raise ParameterError(f"contact.{name}", contact.data[name], f'not used by law = '
                                 f'"{law}"; remove it or use a law that takes it (laws: '
                                 + ", ".join(f'"{n}"' for n, c in CONTACT_LAWS.items()
                                             if name in c.fields) + ")", source)
    return law


def require_port_contact(sc: Scenario, what: str) -> None:
    """A coupling through FMU ports exchanges a force of the heights: refuse a law that is
    not one (``what``: the coupling or export that asked)."""
    if not CONTACT_LAWS[sc.contact_law].across_ports:
        raise ParameterError("contact.law", sc.contact_law,
                             f"{what} exchanges the contact force through FMU ports, which "
                             f'holds the "penalty" law only; the "{sc.contact_law}" law runs '
                             "with --coupling monolithic", sc.source)


def scenario_catenary(sc: Scenario):
    """The catenary definition of ``sc`` (without its ``spans``); an unknown name is an error
    of the scenario's field ``catenary``."""
    try:
        return load_catenary(sc.catenary)
    except ParameterError as exc:
        if exc.field != "catenary" or exc.source:
            raise
        raise ParameterError("catenary", exc.value, exc.reason, sc.source) from None
