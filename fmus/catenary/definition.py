"""Catenary definition files (TOML): format, validation and presets.

A definition names every quantity in SI units (heights from the rail, x along the track,
y lateral, z up). Layout (see ``data/en50318.toml`` for a commented example)::

    name, description, gravity (optional, 9.81)
    [spans]            count + length, or lengths = [...]
    [geometry]         system_height, contact_wire_height, stagger = [...] (pattern repeated
                       over the supports), presag (contact-wire pre-sag at mid-span, parabola
                       between the first and last dropper of each span), element_size
    [contact_wire] [messenger_wire] [stitch_wire] (optional)
                       mass_per_length, EA, EI, tension (horizontal, at design); the stitch
                       wire also has ``length`` (centred on every intermediate support)
    [droppers]         positions (from the start of each span; one list for every span or one
                       list per span), mass_per_length, EA or axial_stiffness, clamp_mass_contact,
                       clamp_mass_messenger
    [contact_support]  type = "steady_arm" (length, mass, EA; pinned at the mast, in tension
                       from the stagger) | "spring" (stiffness, mass) | "fixed"
    [messenger_support] type = "fixed" | "spring" (stiffness)
                       (one class per type in :mod:`.supports`, which validates its table)
    [damping]          ratios = [z1, z2] at frequencies_hz = [f1, f2] (Rayleigh, (3.1))

The two end supports anchor both wires (x, y, z fixed). Errors are :class:`ParameterError`
naming the file, the dotted field and the value.
"""

from __future__ import annotations

import dataclasses
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError
from ..core.params import Table, check_number, load_toml
from ..core.schema import OPTIONAL, Field, Format, Section
from .supports import SUPPORTS, Support, parse_support

DATA_DIR = Path(__file__).resolve().parent / "data"

#: the declared fields of a catenary definition (the loader reads each through its
#: declaration; the reference page of the format is generated from them)
ROOT = Section("", [
    Field("name", "string", default=OPTIONAL, doc="name (default: the file's name)"),
    Field("description", "string", default="", doc="free text"),
    Field("gravity", unit="m/s^2", default=9.81, nonnegative=True, doc="gravity"),
], extra=("spans", "geometry", "contact_wire", "messenger_wire", "stitch_wire", "droppers",
          "contact_support", "messenger_support", "damping"))
SPANS = Section("spans", [
    Field("count", "integer", default=OPTIONAL, minimum=1, doc="number of equal spans"),
    Field("length", unit="m", default=OPTIONAL, positive=True, doc="their length"),
    Field("lengths", "numbers", unit="m", default=OPTIONAL, positive=True,
          doc="or the length of each span", rule="at least one span"),
], doc="`count` and `length`, or `lengths`.")
GEOMETRY = Section("geometry", [
    Field("system_height", unit="m", positive=True, rule="> 0.1 m",
          doc="messenger above contact wire at the supports"),
    Field("contact_wire_height", unit="m", positive=True, doc="contact wire above the rail "
          "at the supports"),
    Field("stagger", "numbers", unit="m", default=[0.0], rule="at least one value, each "
          "within +/- 1 m", doc="lateral offset of the contact wire at the supports; the "
          "pattern repeats over the supports"),
    Field("presag", unit="m", default=0.0, nonnegative=True, doc="contact-wire pre-sag at "
          "mid-span (parabola between the first and last dropper of each span)"),
    Field("element_size", unit="m", positive=True, rule="below half the shortest span",
          doc="target length of the wire elements"),
])
WIRE = Section("contact_wire", [
    Field("mass_per_length", unit="kg/m", positive=True, doc="mass per length"),
    Field("EA", unit="N", positive=True, doc="axial stiffness"),
    Field("EI", unit="N m^2", nonnegative=True, doc="bending stiffness"),
    Field("tension", unit="N", positive=True, doc="horizontal tension at design"),
], title="`[contact_wire]`, `[messenger_wire]`")
STITCH = Section("stitch_wire", WIRE.fields + (
    Field("length", unit="m", positive=True, rule="shorter than the shortest span",
          doc="length, centred on every intermediate support"),), doc="Optional table.")
DROPPERS = Section("droppers", [
    Field("positions", "numbers", unit="m", rule="one list for every span or one list per "
          "span; at least 2 per span, increasing, inside the span",
          doc="dropper positions from the start of each span"),
    Field("mass_per_length", unit="kg/m", nonnegative=True, doc="mass per length"),
    Field("EA", unit="N", default=OPTIONAL, positive=True, rule="exactly one of EA and "
          "axial_stiffness", doc="axial stiffness of the dropper wire"),
    Field("axial_stiffness", unit="N/m", default=OPTIONAL, positive=True,
          doc="or the stiffness of each dropper"),
    Field("clamp_mass_contact", unit="kg", default=0.0, nonnegative=True,
          doc="clamp mass on the contact wire"),
    Field("clamp_mass_messenger", unit="kg", default=0.0, nonnegative=True,
          doc="clamp mass on the messenger wire"),
], doc="Droppers are tension-only: they go slack when compressed.")
SUPPORT_TYPE = Section("contact_support", [
    Field("type", "string", choices=tuple(SUPPORTS), rule='"steady_arm" holds the contact '
          'wire only', doc="support of the wire at the intermediate masts"),
], title="`[contact_support]`, `[messenger_support]`",
    doc="The two line ends anchor both wires. The other fields depend on `type` "
        "(sections below).")
DAMPING = Section("damping", [
    Field("ratios", "numbers", length=2, nonnegative=True, rule="each < 1",
          doc="damping ratios z1, z2"),
    Field("frequencies_hz", "numbers", unit="Hz", length=2, positive=True,
          rule="different unless the ratios are equal", doc="at frequencies f1, f2"),
], doc="Rayleigh damping C = a M + b K matching the two ratios, (3.1).")




def _support_sections() -> tuple:
    """One section per support type: its fields and its module's description."""
    return tuple(Section(SUPPORT_TYPE.path, cls.FIELDS.fields,
                         title=f'Support `type = "{name}"`',
                         doc=" ".join((sys.modules[cls.__module__].__doc__ or "").split()))
                 for name, cls in SUPPORTS.items())


FORMAT = Format("catenary", "Catenary definition files", """\
A catenary definition gives a line's data in SI units: heights from the rail, x along the
track, y lateral, z up. It is read by `pantocosim static`, `pantocosim modes` and by a
scenario's `catenary` field. The presets `en50318`, `benchmark55` and `ave64` live in
`fmus/catenary/data/`; `en50318.toml` is a commented example.
""", (ROOT, SPANS, GEOMETRY, WIRE, STITCH, DROPPERS, SUPPORT_TYPE, *_support_sections(),
      DAMPING))


@dataclass
class Wire:
    mass_per_length: float
    EA: float
    EI: float
    tension: float
    length: float = 0.0  # stitch wire only

    @property
    def wave_speed(self) -> float:
        """Transverse wave speed c = sqrt(T / m) [m/s] of the wire under its tension."""
        return float(np.sqrt(self.tension / self.mass_per_length))


@dataclass
class CatenaryDefinition:
    name: str
    source: str
    span_lengths: list[float]
    system_height: float
    contact_wire_height: float
    stagger: list[float]
    presag: float
    element_size: float
    contact: Wire
    messenger: Wire
    stitch: Wire | None
    dropper_positions: list[list[float]]     # per span, from the span start
    dropper_mass_per_length: float
    dropper_EA: float | None
    dropper_stiffness: float | None
    clamp_mass_contact: float
    clamp_mass_messenger: float
    contact_support: Support
    messenger_support: Support
    damping_ratios: tuple[float, float]
    damping_frequencies_hz: tuple[float, float]
    gravity: float = 9.81
    description: str = ""
    raw: dict = field(default_factory=dict, repr=False)

    # ------------------------------------------------------------------ derived
    @property
    def n_spans(self) -> int:
        return len(self.span_lengths)

    @property
    def support_x(self) -> np.ndarray:
        return np.concatenate([[0.0], np.cumsum(self.span_lengths)])

    def support_stagger(self) -> np.ndarray:
        n = self.n_spans + 1
        return np.array([self.stagger[i % len(self.stagger)] for i in range(n)])

    def rayleigh(self) -> tuple[float, float]:
        """(alpha, beta) of C = alpha M + beta K matching the damping ratios, (3.1)."""
        w1, w2 = 2 * np.pi * np.asarray(self.damping_frequencies_hz)
        z1, z2 = self.damping_ratios
        A = np.array([[1 / (2 * w1), w1 / 2], [1 / (2 * w2), w2 / 2]])
        a, b = np.linalg.solve(A, [z1, z2])
        return float(a), float(b)

    def design_contact_height(self, x: np.ndarray) -> np.ndarray:
        """Design contact-wire height: pre-sag parabola between first and last dropper."""
        x = np.atleast_1d(np.asarray(x, float))
        z = np.full(x.shape, self.contact_wire_height)
        xs = self.support_x
        for s, pos in enumerate(self.dropper_positions):
            if self.presag == 0.0 or len(pos) < 2:
                continue
            a, b = xs[s] + pos[0], xs[s] + pos[-1]
            m = (x > a) & (x < b)
            xi = (x[m] - a) / (b - a)
            z[m] -= 4.0 * self.presag * xi * (1.0 - xi)
        return z


def _wire(t: Table, key: str, stitch: bool = False) -> Wire:
    w = t.sub(key)
    section = STITCH if stitch else WIRE
    section.check_keys(w)
    return Wire(**{f.name: f.read(w) for f in section.fields})


def parse_definition(data: dict, source: str) -> CatenaryDefinition:
    """Validate a parsed TOML table; raise ParameterError naming the field and value."""
    t = Table(data, source)
    ROOT.check_keys(t)
    name = ROOT.read(t, "name")
    name = Path(source).stem if name is None else name
    sp = t.sub("spans")
    SPANS.check_keys(sp)
    if sp.has("lengths"):
        lengths = SPANS.read(sp, "lengths")
        if len(lengths) < 1:
            raise ParameterError("spans.lengths", lengths, "needs at least one span", source)
    else:
        count = SPANS.read(sp, "count", required=True)
        lengths = [SPANS.read(sp, "length", required=True)] * count

    geo = t.sub("geometry")
    GEOMETRY.check_keys(geo)
    system_height = GEOMETRY.read(geo, "system_height")
    cw_height = GEOMETRY.read(geo, "contact_wire_height")
    stagger = GEOMETRY.read(geo, "stagger")
    if not stagger:
        raise ParameterError("geometry.stagger", stagger, "needs at least one value", source)
    for i, s in enumerate(stagger):
        if abs(s) > 1.0:
            raise ParameterError(f"geometry.stagger[{i}]", s, "must be within +/- 1 m", source)
    presag = GEOMETRY.read(geo, "presag")
    element_size = GEOMETRY.read(geo, "element_size")
    if element_size > min(lengths) / 2:
        raise ParameterError("geometry.element_size", element_size,
                             "must be below half the shortest span", source)

    contact = _wire(t, "contact_wire")
    messenger = _wire(t, "messenger_wire")
    stitch = _wire(t, "stitch_wire", stitch=True) if t.has("stitch_wire") else None
    if stitch is not None and stitch.length >= min(lengths):
        raise ParameterError("stitch_wire.length", stitch.length,
                             "must be shorter than the shortest span", source)

    dr = t.sub("droppers")
    DROPPERS.check_keys(dr)
    raw_pos = dr._get("positions", None, True)
    if isinstance(raw_pos, list) and raw_pos and all(isinstance(p, list) for p in raw_pos):
        if len(raw_pos) != len(lengths):
            raise ParameterError("droppers.positions", raw_pos,
                                 f"needs one list per span ({len(lengths)})", source)
        per_span = [_positions(dr, raw_pos[i], f"droppers.positions[{i}]", source)
                    for i in range(len(lengths))]
    else:
        p = _positions(dr, raw_pos, "droppers.positions", source)
        per_span = [list(p) for _ in lengths]
    for s, (pos, L) in enumerate(zip(per_span, lengths)):
        for i, x in enumerate(pos):
            if not (0.0 < x < L):
                raise ParameterError(f"droppers.positions[{i}]", x,
                                     f"outside span {s + 1} (0, {L:g}) m", source)
        if len(pos) < 2:
            raise ParameterError("droppers.positions", pos, "needs >= 2 droppers per span",
                                 source)
    d_mass = DROPPERS.read(dr, "mass_per_length")
    d_EA = DROPPERS.read(dr, "EA")
    d_k = DROPPERS.read(dr, "axial_stiffness")
    if (d_EA is None) == (d_k is None):
        raise ParameterError("droppers.EA", None,
                             "give exactly one of EA or axial_stiffness", source)
    clamp_c = DROPPERS.read(dr, "clamp_mass_contact")
    clamp_m = DROPPERS.read(dr, "clamp_mass_messenger")

    contact_support = parse_support(t.sub("contact_support"), "contact")
    contact_support.check_line(stagger, len(lengths), source)
    messenger_support = parse_support(t.sub("messenger_support"), "messenger")

    dm = t.sub("damping")
    DAMPING.check_keys(dm)
    ratios = DAMPING.read(dm, "ratios")
    freqs = DAMPING.read(dm, "frequencies_hz")
    if freqs[0] == freqs[1] and ratios[0] != ratios[1]:
        raise ParameterError("damping.frequencies_hz", freqs, "must differ", source)
    for i, z in enumerate(ratios):
        if z >= 1.0:
            raise ParameterError(f"damping.ratios[{i}]", z, "must be < 1", source)
    if freqs[0] == freqs[1]:
        freqs = [freqs[0], 2 * freqs[0]]

    if system_height <= 0.1:
        raise ParameterError("geometry.system_height", system_height, "must exceed 0.1 m",
                             source)
    return CatenaryDefinition(
        name=name, source=source, span_lengths=[float(x) for x in lengths],
        system_height=system_height, contact_wire_height=cw_height, stagger=stagger,
        presag=presag, element_size=element_size, contact=contact, messenger=messenger,
        stitch=stitch, dropper_positions=per_span, dropper_mass_per_length=d_mass,
        dropper_EA=d_EA, dropper_stiffness=d_k, clamp_mass_contact=clamp_c,
        clamp_mass_messenger=clamp_m, contact_support=contact_support,
        messenger_support=messenger_support, damping_ratios=(ratios[0], ratios[1]),
        damping_frequencies_hz=(freqs[0], freqs[1]),
        gravity=ROOT.read(t, "gravity"), description=ROOT.read(t, "description"), raw=data)


def _positions(dr: Table, value, name: str, source: str) -> list[float]:
    if not isinstance(value, list):
        raise ParameterError(name, value, "must be an array of numbers", source)
    out = [check_number(f"{name}[{i}]", x, source=source) for i, x in enumerate(value)]
    for i in range(1, len(out)):
        if out[i] <= out[i - 1]:
            raise ParameterError(f"{name}[{i}]", out[i], "positions must be increasing",
                                 source)
    return out


def preset_names() -> list[str]:
    return sorted(p.stem for p in DATA_DIR.glob("*.toml"))


def load_catenary(name_or_path: str | Path) -> CatenaryDefinition:
    """Load a preset by name (``en50318``, ``benchmark55``, ``ave64``) or a TOML file."""
    if not str(name_or_path).strip():
        raise ParameterError("catenary", str(name_or_path), f"empty name (presets: "
                             f"{preset_names()}, or a definition file)")
    p = Path(name_or_path)
    if p.suffix != ".toml" and not p.exists():
        cand = DATA_DIR / f"{name_or_path}.toml"
        if not cand.exists():
            raise ParameterError("catenary", str(name_or_path),
                                 f"unknown preset (available: {preset_names()}) and no such "
                                 "file")
        p = cand
    data = load_toml(p)
    return parse_definition(data, str(p.name if p.parent == DATA_DIR else p))


def with_spans(definition: CatenaryDefinition, n_spans: int) -> CatenaryDefinition:
    """The definition repeated/truncated to ``n_spans`` spans (span data cycled)."""
    n_spans = int(n_spans)
    if n_spans < 1:
        raise ParameterError("spans", n_spans, "must be >= 1", definition.source)
    lengths = [definition.span_lengths[i % definition.n_spans] for i in range(n_spans)]
    droppers = [definition.dropper_positions[i % len(definition.dropper_positions)]
                for i in range(n_spans)]
    return dataclasses.replace(definition, span_lengths=lengths, dropper_positions=droppers)
