"""Mesh of a catenary definition: nodes, DOF numbering, elements, supports and the design
data of the initial-configuration problem (thesis 3.1, 3.1.3).

Numbering: "stations" (x positions shared by all wires: supports, droppers, stitch-wire ends
and a subdivision reaching the target element size) are visited along the track and, at each
station, the contact-wire node, the messenger node and (near supports) the stitch-wire node get
their 6 DOFs (position, slope) in turn. Every element then couples DOFs of neighbouring
stations only, so the bandwidth stays about 3 stations x 6 DOFs whatever the line length.
A stitch wire ends on the messenger: its end node shares the messenger node's position DOFs
but has its own slope DOFs (a pinned joint, not a C1 one). The messenger is hinged the same
way over every intermediate support, where it has a real kink (a C1 node there would smear
the kink over the neighbouring elements and make the sag depend on the mesh).

The node positions built here are only the start of the initial-configuration Newton solve
(:mod:`pantocosim.catenary.statics`): contact wire at the design heights, messenger and stitch
wire as parabolas with an estimated sag.

:func:`build_mesh` runs in stages: geometry (stations, first-guess shapes), topology (nodes
and DOF numbering), elements (cables, droppers) and supports (line ends here, the masts'
supports from :mod:`pantocosim.catenary.supports`); the structure then collects the element
sets (:mod:`pantocosim.catenary.structure`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .ancf_cable import CableSet
from .definition import CatenaryDefinition
from .parts import Anchor, MeshParts
from .structure import Structure
from .supports import Site

__all__ = ["Anchor", "CatenaryMesh", "build_mesh", "straight_wire"]

X_DIGITS = 9                  # x positions are matched to 1e-9 m (stations, supports, ends)
X_TOL = 1e-9
DROPPER_LENGTH_GUESS = 0.8    # m per dropper: its mass in the messenger-sag estimate
STITCH_DIP_FACTOR = 0.25      # stitch-wire dip under the mast: 0.25 P (l/2) / T_stitch with
                              # P the weight of l/2 of contact wire (l: stitch-wire length)
SPRING_PRELOAD_LENGTH = 10.0  # m of contact wire whose weight a spring support is assumed to
                              # carry (first guess of its ground end)
TANGENT_STEP = 1e-4           # m, central difference for the node slopes
HINGE_STEP = 1e-6             # m, one-sided differences either side of a messenger hinge
STITCH_END_STEP = 1e-3        # m, one-sided difference at the stitch-wire ends


@dataclass
class CatenaryMesh:
    structure: Structure
    node_dofs: np.ndarray            # (n_nodes, 6) full DOFs (-1: none)
    contact_nodes: np.ndarray        # contact-wire nodes in x order
    contact_elems: np.ndarray        # contact-wire cable elements in x order
    support_x: np.ndarray
    support_contact_nodes: np.ndarray
    dropper_bars: np.ndarray
    dropper_x: np.ndarray
    dropper_contact_nodes: np.ndarray
    dropper_design_z: np.ndarray
    #: axial stiffness k [N/m] of each dropper when the definition gives one (EA then
    #: follows the unstretched length, EA = k l0, so that N = k (l - l0)); NaN: EA given
    dropper_k: np.ndarray = field(default_factory=lambda: np.zeros(0))
    group_elems: list = field(default_factory=list)
    group_tension: np.ndarray = field(default_factory=lambda: np.zeros(0))
    group_names: list = field(default_factory=list)
    anchors: list = field(default_factory=list)
    arms: list = field(default_factory=list)         # (bar, pin node, wire node, design y)
    definition: CatenaryDefinition | None = None
    messenger_nodes: np.ndarray = field(default_factory=lambda: np.zeros(0, int))


def _key_points(d: CatenaryDefinition) -> np.ndarray:
    """Sorted x of the supports, droppers and stitch-wire ends (to 1e-9 m)."""
    xs = d.support_x
    pts = [xs] + [xs[s] + np.asarray(pos, float) for s, pos in enumerate(d.dropper_positions)]
    if d.stitch is not None:
        pts += [xs[1:-1] - d.stitch.length / 2, xs[1:-1] + d.stitch.length / 2]
    return np.unique(np.round(np.concatenate(pts), X_DIGITS))


def _divisions(key: np.ndarray, element_size: float) -> np.ndarray:
    """Elements between consecutive key points: the fewest not longer than element_size."""
    return np.maximum(1, np.ceil(np.diff(key) / element_size - X_TOL)).astype(np.int64)


def _stations(d: CatenaryDefinition) -> np.ndarray:
    key = _key_points(d)
    out = [key[:1]]
    for a, b, n in zip(key[:-1], key[1:], _divisions(key, d.element_size)):
        out.append(a + (b - a) * np.arange(1, n + 1) / n)
    return np.concatenate(out)


def station_count(d: CatenaryDefinition) -> tuple[int, int]:
    """(stations, stations under the stitch wires) of the mesh of ``d``, counted without
    building it (cheap for any size: the size guard counts before anything is built)."""
    key = _key_points(d)
    n = _divisions(key, d.element_size)
    first = np.concatenate([[0], np.cumsum(n)])       # station index of each key point
    stitch = 0
    if d.stitch is not None:
        xs = d.support_x[1:-1]
        a = np.searchsorted(key, np.round(xs - d.stitch.length / 2, X_DIGITS))
        b = np.searchsorted(key, np.round(xs + d.stitch.length / 2, X_DIGITS))
        stitch = int(np.sum(first[b] - first[a] + 1))
    return int(first[-1] + 1), stitch


def estimate_dofs(d: CatenaryDefinition) -> int:
    """DOFs of the model of ``d`` without building it: 6 per node, a contact-wire and a
    messenger node at every station, a stitch-wire node where there is one (its two ends
    share the messenger's position: 3 each), less the anchored positions of both wires at
    the line ends (within 1 % of the built model's count; the masts' supports add a few)."""
    stations, stitch = station_count(d)
    ends = 2 * (d.n_spans - 1) if d.stitch is not None else 0
    return 12 * stations + 6 * stitch - 3 * ends - 12


# ==================================================================== geometry
class _Geometry:
    """Stations and the first-guess shapes of the wires: contact wire at its design heights,
    messenger and stitch wire as parabolas with an estimated sag."""

    def __init__(self, d: CatenaryDefinition):
        self.d = d
        self.xs = d.support_x
        self.stations = _stations(d)
        self.station_of = {round(x, X_DIGITS): i for i, x in enumerate(self.stations)}
        self.h_c = d.contact_wire_height
        self.h_m = self.h_c + d.system_height
        self.stag = d.support_stagger()
        half = d.stitch.length / 2 if d.stitch is not None else 0.0
        self.stitch_ranges = ([(x - half, x, x + half) for x in self.xs[1:-1]]
                              if d.stitch is not None else [])

    def y(self, x):
        return np.interp(x, self.xs, self.stag)

    def _span(self, x):
        return np.clip(np.searchsorted(self.xs, x, side="right") - 1, 0, len(self.xs) - 2)

    def y_slope(self, x):
        s = self._span(x)
        return (self.stag[s + 1] - self.stag[s]) / (self.xs[s + 1] - self.xs[s])

    def z_contact(self, x) -> float:
        return float(self.d.design_contact_height(np.array([x]))[0])

    def z_messenger(self, x) -> float:
        """Sag estimate: the whole line load carried by the messenger tension."""
        d, xs = self.d, self.xs
        x = np.atleast_1d(x)
        s = self._span(x)
        L = xs[s + 1] - xs[s]
        w = d.gravity * (d.contact.mass_per_length + d.messenger.mass_per_length
                         + (d.dropper_mass_per_length * DROPPER_LENGTH_GUESS
                            + d.clamp_mass_contact + d.clamp_mass_messenger)
                         * len(d.dropper_positions[0]) / L)
        sag = w * L * L / (8 * d.messenger.tension)
        xi = (x - xs[s]) / L
        return float((self.h_m - 4 * sag * xi * (1 - xi))[0])

    def z_stitch(self, x, rng) -> float:
        d = self.d
        a, c, b = rng
        u = (x - c) / (b - c) if x >= c else (x - c) / (c - a)
        P = d.gravity * d.contact.mass_per_length * (b - a) / 2
        dip = STITCH_DIP_FACTOR * P * (b - a) / 2 / d.stitch.tension
        return self.z_messenger(x) - dip * (1 - u * u)

    def tangent(self, x, f) -> np.ndarray:
        h = TANGENT_STEP
        dz = (f(x + h) - f(x - h)) / (2 * h)
        t = np.array([1.0, self.y_slope(x), dz])
        return t / np.linalg.norm(t)


# ==================================================================== topology
@dataclass
class _Nodes:
    """Nodes with their full DOFs, guessed positions and slopes, numbered station by
    station (contact, messenger, messenger hinge, stitch wire) to keep the band narrow."""

    dofs: list = field(default_factory=list)
    pos: list = field(default_factory=list)
    slope: list = field(default_factory=list)
    ndof: int = 0
    contact: list = field(default_factory=list)
    messenger: list = field(default_factory=list)
    messenger_right: list = field(default_factory=list)   # start of the next element
    stitch: list = field(default_factory=list)

    def node(self, pos, slope, shares: int | None = None) -> int:
        """A node with 6 new DOFs, or with the position DOFs of node ``shares`` and 3 new
        slope DOFs (a pinned joint)."""
        shared = [] if shares is None else self.dofs[shares][:3]
        new = 6 - len(shared)
        dofs = shared + list(range(self.ndof, self.ndof + new))
        self.ndof += new
        self.dofs.append(dofs)
        self.pos.append(pos)
        self.slope.append(slope)
        return len(self.dofs) - 1


def _topology(geo: _Geometry) -> _Nodes:
    t = _Nodes(stitch=[[] for _ in geo.stitch_ranges])
    for x in geo.stations:
        t.contact.append(t.node([x, geo.y(x), geo.z_contact(x)],
                                geo.tangent(x, geo.z_contact)))
        m = _messenger_node(t, geo, x)
        for k, rng in enumerate(geo.stitch_ranges):
            if rng[0] - X_TOL <= x <= rng[2] + X_TOL:
                t.stitch[k].append(_stitch_node(t, geo, x, rng, m))
    return t


def _messenger_node(t: _Nodes, geo: _Geometry, x) -> int:
    """The messenger node at x; over an intermediate support a hinge: a second node with the
    same position and its own slopes starts the next span (the messenger kinks there)."""
    zm, y = geo.z_messenger, geo.y
    pos = [x, y(x), zm(x)]
    if any(abs(x - xsup) < X_TOL for xsup in geo.xs[1:-1]):
        hh = HINGE_STEP
        tl = np.array([hh, y(x) - y(x - hh), zm(x) - zm(x - hh)])
        tr = np.array([hh, y(x + hh) - y(x), zm(x + hh) - zm(x)])
        m = t.node(pos, tl / np.linalg.norm(tl))
        right = t.node(pos, tr / np.linalg.norm(tr), shares=m)
    else:
        m = right = t.node(pos, geo.tangent(x, zm))
    t.messenger.append(m)
    t.messenger_right.append(right)
    return m


def _stitch_node(t: _Nodes, geo: _Geometry, x, rng, m: int) -> int:
    """A stitch-wire node at x; its ends are pinned to the messenger node ``m``."""
    a, _, b = rng
    fz = lambda xx: geo.z_stitch(xx, rng)
    if abs(x - a) < X_TOL or abs(x - b) < X_TOL:
        xe = x + (STITCH_END_STEP if abs(x - a) < X_TOL else -STITCH_END_STEP)
        tv = np.array([xe - x, geo.y(xe) - geo.y(x), fz(xe) - fz(x)])
        tv *= np.sign(tv[0])
        return t.node(t.pos[m], tv / np.linalg.norm(tv), shares=m)
    return t.node([x, geo.y(x), fz(x)], geo.tangent(x, fz))


def _structure(d: CatenaryDefinition, t: _Nodes, n_own: int) -> tuple[Structure, np.ndarray]:
    """The structure with the guessed coordinates (x relative to the station) and the node
    DOF table; ``n_own`` support nodes (3 position DOFs each) follow the wire nodes."""
    n_wire = len(t.dofs)
    S = Structure(t.ndof + 3 * n_own, gravity=d.gravity)
    nd = -np.ones((n_wire + n_own, 6), dtype=np.int64)
    for i, dd in enumerate(t.dofs):
        nd[i, :len(dd)] = dd
    for i in range(n_own):
        nd[n_wire + i, :3] = t.ndof + 3 * i + np.arange(3)
    x = S.x_full
    for i, dd in enumerate(t.dofs):
        x[dd[0]:dd[0] + 3] = t.pos[i]
        S.offset[dd[0]] = t.pos[i][0]          # x stored relative to the station
        x[dd[0]] = 0.0
        x[dd[3]:dd[3] + 3] = t.slope[i]
        S.zpos[dd[2]] = True
    S.zpos[nd[n_wire:, 2]] = True
    return S, nd


# ==================================================================== elements
class _Chains:
    """Cable elements chained along the nodes of each wire, one pre-tension group per span
    (an unknown of the initial configuration)."""

    def __init__(self, nd: np.ndarray, pos: list):
        self.nd, self.pos = nd, pos
        self.rows: list[tuple] = []
        self.tension: list[float] = []
        self.names: list[str] = []
        self.elems: list[list[int]] = []

    def chain(self, nodes, wire, name_of, starts=None) -> np.ndarray:
        """Elements nodes[i] -> nodes[i + 1] (from ``starts[i]`` when given: hinges);
        ``name_of(x_mid)`` names the group. Returns the new element numbers."""
        first, groups = len(self.rows), {}
        for a, b in zip((nodes if starts is None else starts)[:-1], nodes[1:]):
            key = name_of(0.5 * (self.pos[a][0] + self.pos[b][0]))
            if key not in groups:
                groups[key] = len(self.tension)
                self.tension.append(wire.tension)
                self.names.append(key)
                self.elems.append([])
            self.elems[groups[key]].append(len(self.rows))
            Le = float(np.linalg.norm(np.subtract(self.pos[b], self.pos[a])))
            self.rows.append((list(self.nd[a]) + list(self.nd[b]), Le, wire.mass_per_length,
                              wire.EA, wire.EI, groups[key]))
        return np.arange(first, len(self.rows))

    def cable_set(self) -> CableSet:
        dofs, Le, mu, EA, EI, grp = zip(*self.rows)
        return CableSet(np.array(dofs, dtype=np.int64), np.array(Le), np.array(mu),
                        np.array(EA), np.array(EI), np.array(grp, dtype=np.int64),
                        np.array(self.tension, dtype=float))


def _cables(geo: _Geometry, t: _Nodes, nd: np.ndarray) -> tuple[_Chains, np.ndarray]:
    """Contact wire, messenger (hinged over the masts) and stitch wires; returns the chains
    and the contact-wire elements."""
    d = geo.d

    def span(xm):
        return int(np.clip(np.searchsorted(geo.xs, xm) - 1, 0, len(geo.xs) - 2)) + 1

    c = _Chains(nd, t.pos)
    contact = c.chain(t.contact, d.contact, lambda xm: f"contact span {span(xm)}")
    c.chain(t.messenger, d.messenger, lambda xm: f"messenger span {span(xm)}",
            starts=t.messenger_right)
    for k, nodes in enumerate(t.stitch):
        c.chain(nodes, d.stitch, lambda xm, k=k: f"stitch wire at support {k + 2}")
    return c, contact


def _droppers(geo: _Geometry, t: _Nodes, S: Structure, nd: np.ndarray,
              parts: MeshParts) -> dict:
    """A tension-only bar from the messenger (or stitch wire) down to the contact wire at
    every dropper position, with the clamp masses at both ends."""
    d = geo.d
    out = {"bars": [], "x": [], "cn": [], "z": []}
    for s, pos in enumerate(d.dropper_positions):
        for p in pos:
            xd = geo.xs[s] + p
            i = geo.station_of[round(xd, X_DIGITS)]
            cn, up = t.contact[i], t.messenger[i]
            for k, (a, _, b) in enumerate(geo.stitch_ranges):
                if a + X_TOL < xd < b - X_TOL:
                    up = [n for n in t.stitch[k] if abs(t.pos[n][0] - xd) < X_TOL][0]
            pu, pc = S.x_full[nd[up, :3]], S.x_full[nd[cn, :3]]   # same station
            l = float(np.linalg.norm(pu - pc))
            EA = d.dropper_EA if d.dropper_EA is not None else d.dropper_stiffness * l
            out["bars"].append(parts.bar(list(nd[up, :3]) + list(nd[cn, :3]), l, EA,
                                         d.dropper_mass_per_length * l, True))
            out["x"].append(xd)
            out["cn"].append(cn)
            out["z"].append(geo.z_contact(xd))
            parts.point_masses(nd[cn, :3], d.clamp_mass_contact)
            parts.point_masses(nd[up, :3], d.clamp_mass_messenger)
    return out


# ==================================================================== supports
def _supports(geo: _Geometry, t: _Nodes, S: Structure, nd: np.ndarray,
              parts: MeshParts) -> list[int]:
    """Both wires anchored at the line ends; at every intermediate mast the messenger's then
    the contact wire's support (:mod:`.supports`) attaches itself. Returns the contact-wire
    node at every mast."""
    d, n_wire, own = geo.d, len(t.dofs), 0
    contact_nodes = []
    for s, xsup in enumerate(geo.xs):
        i = geo.station_of[round(xsup, X_DIGITS)]
        cn, mn = t.contact[i], t.messenger[i]
        contact_nodes.append(cn)
        if s == 0 or s == len(geo.xs) - 1:
            S.fixed[nd[cn, :3]] = True
            S.fixed[nd[mn, :3]] = True
            continue
        for wire, node, support in (("messenger", mn, d.messenger_support),
                                    ("contact", cn, d.contact_support)):
            mine = list(range(n_wire + own, n_wire + own + support.n_own_nodes))
            own += support.n_own_nodes
            support.attach(_site(geo, wire, s, node, nd, mine, S), parts)
    return contact_nodes


def _site(geo: _Geometry, wire: str, s: int, node: int, nd: np.ndarray, own: list,
          S: Structure) -> Site:
    d = geo.d
    contact = wire == "contact"
    preload = d.gravity * d.contact.mass_per_length * SPRING_PRELOAD_LENGTH if contact else 0.0
    return Site(wire=wire, number=s, node=node, dofs=nd[node],
                height=geo.h_c if contact else geo.h_m, slides=contact, preload=preload,
                own_nodes=own, own_dofs=nd[own, :3], structure=S, definition=d)


# ==================================================================== the mesh
def build_mesh(d: CatenaryDefinition, element_size: float | None = None) -> CatenaryMesh:
    """Mesh of ``d`` (optionally with another target element size): geometry, topology,
    cables, supports and droppers, then the structure collects the element sets."""
    if element_size is not None:
        d = dataclasses.replace(d, element_size=float(element_size))
    geo = _Geometry(d)
    t = _topology(geo)
    per_mast = d.messenger_support.n_own_nodes + d.contact_support.n_own_nodes
    S, nd = _structure(d, t, (len(geo.xs) - 2) * per_mast)
    chains, contact_elems = _cables(geo, t, nd)
    parts = MeshParts()
    support_cn = _supports(geo, t, S, nd, parts)
    dr = _droppers(geo, t, S, nd, parts)
    S.add("cables", chains.cable_set())
    parts.add_to(S)
    S.finalize()
    return CatenaryMesh(
        structure=S, node_dofs=nd, contact_nodes=np.array(t.contact),
        contact_elems=contact_elems, support_x=geo.xs,
        support_contact_nodes=np.array(support_cn),
        dropper_bars=np.array(dr["bars"], dtype=np.int64), dropper_x=np.array(dr["x"]),
        dropper_contact_nodes=np.array(dr["cn"], dtype=np.int64),
        dropper_design_z=np.array(dr["z"]),
        group_elems=[np.array(g, dtype=np.int64) for g in chains.elems],
        group_tension=np.array(chains.tension), group_names=chains.names,
        anchors=parts.anchors, arms=parts.arms, definition=d,
        messenger_nodes=np.array(t.messenger),
        dropper_k=np.full(len(dr["bars"]), np.nan if d.dropper_stiffness is None
                          else d.dropper_stiffness))


def straight_wire(length: float, n_elements: int, mass_per_length: float, EA: float,
                  EI: float, tension: float, gravity: float = 0.0,
                  height: float = 0.0) -> CatenaryMesh:
    """One straight wire along x with pinned ends (positions fixed, slopes free) and
    pre-tension ``tension``: the verification case of the tests (tensioned beam, catenary,
    moving load). The wire doubles as "contact wire" of the model."""
    n = int(n_elements)
    nn = n + 1
    S = Structure(6 * nn, gravity=gravity)
    xs = np.linspace(0.0, length, nn)
    nd = np.arange(6 * nn).reshape(nn, 6)
    for i in range(nn):
        S.x_full[nd[i]] = [0.0, 0.0, height, 1.0, 0.0, 0.0]
        S.offset[nd[i, 0]] = xs[i]
        S.zpos[nd[i, 2]] = True
    S.fixed[nd[0, :3]] = True
    S.fixed[nd[-1, :3]] = True
    S.add("cables", CableSet(np.hstack([nd[:-1], nd[1:]]), np.full(n, length / n),
                             np.full(n, mass_per_length), np.full(n, EA), np.full(n, EI),
                             np.zeros(n, dtype=np.int64), np.array([tension], dtype=float)))
    MeshParts().add_to(S)          # no bars, point masses or springs
    S.finalize()
    return CatenaryMesh(
        structure=S, node_dofs=nd, contact_nodes=np.arange(nn), contact_elems=np.arange(n),
        support_x=np.array([0.0, length]), support_contact_nodes=np.array([0, nn - 1]),
        dropper_bars=np.zeros(0, dtype=np.int64), dropper_x=np.zeros(0),
        dropper_contact_nodes=np.zeros(0, dtype=np.int64), dropper_design_z=np.zeros(0),
        group_elems=[np.arange(n)], group_tension=np.array([tension]),
        dropper_k=np.zeros(0), group_names=["wire"], anchors=[], arms=[], definition=None,
        messenger_nodes=np.zeros(0, dtype=np.int64))
