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
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError
from ..core.params import Table, load_toml
from .supports import Support, parse_support

DATA_DIR = Path(__file__).resolve().parent / "data"


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
    allowed = ["mass_per_length", "EA", "EI", "tension"] + (["length"] if stitch else [])
    w.unknown_keys(allowed)
    return Wire(mass_per_length=w.number("mass_per_length", positive=True),
                EA=w.number("EA", positive=True), EI=w.number("EI", nonnegative=True),
                tension=w.number("tension", positive=True),
                length=w.number("length", positive=True) if stitch else 0.0)


def parse_definition(data: dict, source: str) -> CatenaryDefinition:
    """Validate a parsed TOML table; raise ParameterError naming the field and value."""
    t = Table(data, source)
    t.unknown_keys(["name", "description", "gravity", "spans", "geometry", "contact_wire",
                    "messenger_wire", "stitch_wire", "droppers", "contact_support",
                    "messenger_support", "damping"])
    name = t.string("name", Path(source).stem)
    sp = t.sub("spans")
    sp.unknown_keys(["count", "length", "lengths"])
    if sp.has("lengths"):
        lengths = sp.numbers("lengths", positive=True)
        if len(lengths) < 1:
            raise ParameterError("spans.lengths", lengths, "needs at least one span", source)
    else:
        count = sp.integer("count", minimum=1)
        lengths = [sp.number("length", positive=True)] * count

    geo = t.sub("geometry")
    geo.unknown_keys(["system_height", "contact_wire_height", "stagger", "presag",
                      "element_size"])
    system_height = geo.number("system_height", positive=True)
    cw_height = geo.number("contact_wire_height", positive=True)
    stagger = geo.numbers("stagger", [0.0])
    if not stagger:
        raise ParameterError("geometry.stagger", stagger, "needs at least one value", source)
    for i, s in enumerate(stagger):
        if abs(s) > 1.0:
            raise ParameterError(f"geometry.stagger[{i}]", s, "must be within +/- 1 m", source)
    presag = geo.number("presag", 0.0, nonnegative=True)
    element_size = geo.number("element_size", positive=True)
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
    dr.unknown_keys(["positions", "mass_per_length", "EA", "axial_stiffness",
                     "clamp_mass_contact", "clamp_mass_messenger"])
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
    d_mass = dr.number("mass_per_length", nonnegative=True)
    d_EA = dr.number("EA", positive=True) if dr.has("EA") else None
    d_k = dr.number("axial_stiffness", positive=True) if dr.has("axial_stiffness") else None
    if (d_EA is None) == (d_k is None):
        raise ParameterError("droppers.EA", None,
                             "give exactly one of EA or axial_stiffness", source)
    clamp_c = dr.number("clamp_mass_contact", 0.0, nonnegative=True)
    clamp_m = dr.number("clamp_mass_messenger", 0.0, nonnegative=True)

    contact_support = parse_support(t.sub("contact_support"), "contact")
    contact_support.check_line(stagger, len(lengths), source)
    messenger_support = parse_support(t.sub("messenger_support"), "messenger")

    dm = t.sub("damping")
    dm.unknown_keys(["ratios", "frequencies_hz"])
    ratios = dm.numbers("ratios", length=2, nonnegative=True)
    freqs = dm.numbers("frequencies_hz", length=2, positive=True)
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
        gravity=t.number("gravity", 9.81, nonnegative=True),
        description=t.string("description", ""), raw=data)


def _positions(dr: Table, value, name: str, source: str) -> list[float]:
    from ..core.params import check_number

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
