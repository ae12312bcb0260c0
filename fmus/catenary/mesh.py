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
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .definition import CatenaryDefinition
from .structure import Structure


@dataclass
class Anchor:
    """A support whose height is an unknown of the initial-configuration problem: the pin of
    a steady arm (``kind='pin'``, ``index`` = full DOF of the pin coordinate ``comp``: 1 for
    y, 2 for z) or the ground end of a spring (``kind='spring'``, ``index`` = spring
    number), chosen so that the supported coordinate (full DOF ``target``) takes the
    ``design`` value (stagger or height)."""

    kind: str
    index: int
    target: int
    design: float
    bar: int = -1
    comp: int = 2


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

    def dof(self, node: int, k: int) -> int:
        return int(self.node_dofs[node, k])


def _stations(d: CatenaryDefinition) -> np.ndarray:
    xs = d.support_x
    pts = set(np.round(xs, 9))
    for s, pos in enumerate(d.dropper_positions):
        pts.update(np.round(xs[s] + np.asarray(pos), 9))
    if d.stitch is not None:
        for x in xs[1:-1]:
            pts.update(np.round([x - d.stitch.length / 2, x + d.stitch.length / 2], 9))
    key = np.array(sorted(pts))
    out = [key[:1]]
    for a, b in zip(key[:-1], key[1:]):
        n = max(1, int(np.ceil((b - a) / d.element_size - 1e-9)))
        out.append(a + (b - a) * np.arange(1, n + 1) / n)
    return np.concatenate(out)


def build_mesh(d: CatenaryDefinition, element_size: float | None = None) -> CatenaryMesh:
    """Mesh of ``d`` (optionally with another target element size)."""
    if element_size is not None:
        import dataclasses
        d = dataclasses.replace(d, element_size=float(element_size))
    g = d.gravity
    xs = d.support_x
    st = _stations(d)
    h_c = d.contact_wire_height
    h_m = h_c + d.system_height
    stag = d.support_stagger()

    def y_of(x):
        return np.interp(x, xs, stag)

    def y_slope(x):
        s = np.clip(np.searchsorted(xs, x, side="right") - 1, 0, len(xs) - 2)
        return (stag[s + 1] - stag[s]) / (xs[s + 1] - xs[s])

    # messenger sag estimate: whole line load carried by the messenger tension
    def mess_z(x):
        x = np.atleast_1d(x)
        s = np.clip(np.searchsorted(xs, x, side="right") - 1, 0, len(xs) - 2)
        L = xs[s + 1] - xs[s]
        w = g * (d.contact.mass_per_length + d.messenger.mass_per_length
                 + (d.dropper_mass_per_length * 0.8 + d.clamp_mass_contact
                    + d.clamp_mass_messenger) * len(d.dropper_positions[0]) / L)
        sag = w * L * L / (8 * d.messenger.tension)
        xi = (x - xs[s]) / L
        return h_m - 4 * sag * xi * (1 - xi)

    # stitch ranges (intermediate supports)
    stitch_ranges = []
    if d.stitch is not None:
        for x in xs[1:-1]:
            stitch_ranges.append((x - d.stitch.length / 2, x, x + d.stitch.length / 2))

    def stitch_z(x, rng):
        a, c, b = rng
        u = (x - c) / (b - c) if x >= c else (x - c) / (c - a)
        # dip under the support from the hanging droppers (estimate)
        P = g * d.contact.mass_per_length * (b - a) / 2
        dip = 0.25 * P * (b - a) / 2 / d.stitch.tension
        return mess_z(x)[0] - dip * (1 - u * u)

    # ---------------------------------------------------------------- nodes and DOFs
    node_dofs = []
    node_pos = []   # guessed position
    node_slope = []
    contact_nodes, messenger_nodes, messenger_right = [], [], []
    stitch_nodes = [[] for _ in stitch_ranges]
    ndof = 0

    def tangent(x, f):
        h = 1e-4
        dz = (f(x + h) - f(x - h)) / (2 * h)
        t = np.array([1.0, y_slope(x), dz])
        return t / np.linalg.norm(t)

    zc = lambda x: float(d.design_contact_height(np.array([x]))[0])
    zm = lambda x: float(mess_z(x)[0])
    for x in st:
        # contact
        node_dofs.append(list(range(ndof, ndof + 6)))
        ndof += 6
        node_pos.append([x, y_of(x), zc(x)])
        node_slope.append(tangent(x, zc))
        contact_nodes.append(len(node_dofs) - 1)
        # messenger
        node_dofs.append(list(range(ndof, ndof + 6)))
        ndof += 6
        node_pos.append([x, y_of(x), zm(x)])
        mnode = len(node_dofs) - 1
        messenger_nodes.append(mnode)
        messenger_right.append(mnode)
        if any(abs(x - xsup) < 1e-9 for xsup in xs[1:-1]):
            # hinge over an intermediate support: the right span gets its own slopes
            hh = 1e-6
            tl = np.array([hh, y_of(x) - y_of(x - hh), zm(x) - zm(x - hh)])
            tr = np.array([hh, y_of(x + hh) - y_of(x), zm(x + hh) - zm(x)])
            node_slope.append(tl / np.linalg.norm(tl))
            node_dofs.append(node_dofs[mnode][:3] + list(range(ndof, ndof + 3)))
            ndof += 3
            node_pos.append(node_pos[mnode])
            node_slope.append(tr / np.linalg.norm(tr))
            messenger_right[-1] = len(node_dofs) - 1
        else:
            node_slope.append(tangent(x, zm))
        # stitch
        for k, rng in enumerate(stitch_ranges):
            a, c, b = rng
            if a - 1e-9 <= x <= b + 1e-9:
                fz = lambda xx, rng=rng: stitch_z(xx, rng)
                end = abs(x - a) < 1e-9 or abs(x - b) < 1e-9
                if end:
                    dofs = node_dofs[mnode][:3] + list(range(ndof, ndof + 3))
                    ndof += 3
                    pos = node_pos[mnode]
                else:
                    dofs = list(range(ndof, ndof + 6))
                    ndof += 6
                    pos = [x, y_of(x), fz(x)]
                node_dofs.append(dofs)
                node_pos.append(pos)
                # one-sided tangent at the ends
                if end:
                    xe = x + (1e-3 if abs(x - a) < 1e-9 else -1e-3)
                    t = np.array([xe - x, y_of(xe) - y_of(x), fz(xe) - fz(x)])
                    t *= np.sign(t[0])
                    node_slope.append(t / np.linalg.norm(t))
                else:
                    node_slope.append(tangent(x, fz))
                stitch_nodes[k].append(len(node_dofs) - 1)
    # pins of steady arms (3 fixed DOFs each) are appended below
    contact_nodes = np.array(contact_nodes)
    messenger_nodes = np.array(messenger_nodes)
    station_of = {round(x, 9): i for i, x in enumerate(st)}

    # ---------------------------------------------------------------- supports (counts)
    cs = d.contact_support
    n_pins = (len(xs) - 2) if cs["type"] == "steady_arm" else 0
    pin_base = ndof
    ndof += 3 * n_pins
    S = Structure(ndof, gravity=g)
    nd_arr = -np.ones((len(node_dofs) + n_pins, 6), dtype=np.int64)
    for i, dd in enumerate(node_dofs):
        nd_arr[i, :len(dd)] = dd
    for i in range(n_pins):
        nd_arr[len(node_dofs) + i, :3] = pin_base + 3 * i + np.arange(3)
    x = S.x_full
    for i, dd in enumerate(node_dofs):
        x[dd[0]:dd[0] + 3] = node_pos[i]
        S.offset[dd[0]] = node_pos[i][0]          # x stored relative to the station
        x[dd[0]] = 0.0
        x[dd[3]:dd[3] + 3] = node_slope[i]
        S.zpos[dd[2]] = True

    # ---------------------------------------------------------------- cables and groups
    cable_dofs, Le, mu, EA, EI, grp = [], [], [], [], [], []
    group_elems, group_T, group_names, N0 = [], [], [], []
    contact_elems = []

    def add_chain(nodes, wire, name_of_span, starts=None):
        # nodes in x order; one group per span (name_of_span(i) -> key); an element starts
        # at ``starts[i]`` instead of ``nodes[i]`` when given (hinges)
        groups = {}
        for a, b in zip(nodes[:-1] if starts is None else starts[:-1], nodes[1:]):
            key = name_of_span(0.5 * (node_pos[a][0] + node_pos[b][0]))
            if key not in groups:
                groups[key] = len(group_T)
                group_T.append(wire.tension)
                group_names.append(key)
                group_elems.append([])
                N0.append(wire.tension)
            gi = groups[key]
            cable_dofs.append(list(nd_arr[a]) + list(nd_arr[b]))
            Le.append(float(np.linalg.norm(np.subtract(node_pos[b], node_pos[a]))))
            mu.append(wire.mass_per_length)
            EA.append(wire.EA)
            EI.append(wire.EI)
            grp.append(gi)
            group_elems[gi].append(len(cable_dofs) - 1)

    def span_of(xm):
        return int(np.clip(np.searchsorted(xs, xm) - 1, 0, len(xs) - 2))

    n0 = len(cable_dofs)
    add_chain(list(contact_nodes), d.contact, lambda xm: f"contact span {span_of(xm) + 1}")
    contact_elems = np.arange(n0, len(cable_dofs))
    add_chain(list(messenger_nodes), d.messenger,
              lambda xm: f"messenger span {span_of(xm) + 1}", starts=messenger_right)
    for k, nodes in enumerate(stitch_nodes):
        add_chain(nodes, d.stitch, lambda xm, k=k: f"stitch wire at support {k + 2}")
    S.cable_dofs = np.array(cable_dofs, dtype=np.int64)
    S.cable_Le = np.array(Le)
    S.cable_mu = np.array(mu)
    S.cable_EA = np.array(EA)
    S.cable_EI = np.array(EI)
    S.cable_group = np.array(grp, dtype=np.int64)
    S.N0_group = np.array(N0, dtype=float)

    # ---------------------------------------------------------------- supports
    bars_dofs, bl0, bEA, bmass, btonly = [], [], [], [], []
    pdofs, pmass = [], []
    sdofs, sk, sanchor = [], [], []
    anchors, arms = [], []
    fixed = S.fixed
    support_contact_nodes = []
    for s, xsup in enumerate(xs):
        i = station_of[round(xsup, 9)]
        cn, mn = contact_nodes[i], messenger_nodes[i]
        support_contact_nodes.append(cn)
        cdof, mdof = nd_arr[cn], nd_arr[mn]
        end = s == 0 or s == len(xs) - 1
        if end:
            fixed[cdof[:3]] = True
            fixed[mdof[:3]] = True
            continue
        if d.messenger_support["type"] == "fixed":
            fixed[mdof[:3]] = True
        else:
            fixed[mdof[:2]] = True
            sdofs.append(mdof[2])
            sk.append(d.messenger_support["stiffness"])
            sanchor.append(h_m)
            anchors.append(Anchor("spring", len(sdofs) - 1, int(mdof[2]), h_m))
        if cs["type"] == "fixed":
            fixed[cdof[1:3]] = True
        elif cs["type"] == "spring":
            fixed[cdof[1]] = True
            sdofs.append(cdof[2])
            sk.append(cs["stiffness"])
            w_est = g * d.contact.mass_per_length * 10.0
            sanchor.append(h_c + w_est / cs["stiffness"])
            anchors.append(Anchor("spring", len(sdofs) - 1, int(cdof[2]), h_c))
            if cs["mass"] > 0:
                pdofs += list(cdof[:3])
                pmass += [cs["mass"]] * 3
        else:  # steady arm pinned at the mast
            pin = len(node_dofs) + (s - 1)
            pdof = nd_arr[pin, :3]
            fixed[pdof] = True
            ys = stag[s]
            L = cs["length"]
            dl = xsup - xs[s - 1] - d.dropper_positions[s - 1][-1]
            dr = d.dropper_positions[s][0]
            Fv = g * (d.contact.mass_per_length * (dl + dr) / 2 + cs["mass"] / 2)
            Fy = d.contact.tension * (abs(ys - stag[s - 1]) / (xsup - xs[s - 1])
                                      + abs(ys - stag[s + 1]) / (xs[s + 1] - xsup))
            phi = np.arctan2(Fv, Fy)
            Lt = L * (1.0 + np.hypot(Fv, Fy) / cs["EA"])   # stretched by the estimated pull
            x[pdof] = [0.0, ys + np.sign(ys) * Lt * np.cos(phi), h_c + Lt * np.sin(phi)]
            S.offset[pdof[0]] = xsup
            bars_dofs.append(list(pdof) + list(cdof[:3]))
            bl0.append(L)
            bEA.append(cs["EA"])
            bmass.append(cs["mass"])
            btonly.append(False)
            anchors.append(Anchor("pin", int(pdof[2]), int(cdof[2]), h_c,
                                  bar=len(bars_dofs) - 1, comp=2))
            anchors.append(Anchor("pin", int(pdof[1]), int(cdof[1]), ys,
                                  bar=len(bars_dofs) - 1, comp=1))
            arms.append((len(bars_dofs) - 1, pin, cn, ys))

    # ---------------------------------------------------------------- droppers
    dropper_bars, dropper_x, dropper_cn, dropper_z = [], [], [], []
    for s, pos in enumerate(d.dropper_positions):
        for p in pos:
            xd = xs[s] + p
            i = station_of[round(xd, 9)]
            cn = contact_nodes[i]
            up = messenger_nodes[i]
            for k, (a, c, b) in enumerate(stitch_ranges):
                if a + 1e-9 < xd < b - 1e-9:
                    up = [n for n in stitch_nodes[k] if abs(node_pos[n][0] - xd) < 1e-9][0]
            pu, pc = x[nd_arr[up, :3]], x[nd_arr[cn, :3]]   # same station: x offsets cancel
            l = float(np.linalg.norm(pu - pc))
            bars_dofs.append(list(nd_arr[up, :3]) + list(nd_arr[cn, :3]))
            bl0.append(l)
            bEA.append(d.dropper_EA if d.dropper_EA is not None else d.dropper_stiffness * l)
            bmass.append(d.dropper_mass_per_length * l)
            btonly.append(True)
            dropper_bars.append(len(bars_dofs) - 1)
            dropper_x.append(xd)
            dropper_cn.append(cn)
            dropper_z.append(float(d.design_contact_height(np.array([xd]))[0]))
            pdofs += list(nd_arr[cn, :3]) + list(nd_arr[up, :3])
            pmass += [d.clamp_mass_contact] * 3 + [d.clamp_mass_messenger] * 3
    S.bar_dofs = np.array(bars_dofs, dtype=np.int64).reshape(-1, 6)
    S.bar_l0 = np.array(bl0)
    S.bar_EA = np.array(bEA)
    S.bar_mass = np.array(bmass)
    S.bar_tension_only = np.array(btonly, dtype=np.bool_)
    keep = np.array(pmass) > 0
    S.point_dofs = np.array(pdofs, dtype=np.int64)[keep]
    S.point_mass = np.array(pmass)[keep]
    S.zpos[nd_arr[len(node_dofs):, 2]] = True
    S.spring_dofs = np.array(sdofs, dtype=np.int64)
    S.spring_k = np.array(sk, dtype=float)
    S.spring_anchor = np.array(sanchor, dtype=float)
    S.finalize()
    return CatenaryMesh(
        structure=S, node_dofs=nd_arr, contact_nodes=contact_nodes,
        contact_elems=contact_elems, support_x=xs,
        support_contact_nodes=np.array(support_contact_nodes),
        dropper_bars=np.array(dropper_bars, dtype=np.int64), dropper_x=np.array(dropper_x),
        dropper_contact_nodes=np.array(dropper_cn, dtype=np.int64),
        dropper_design_z=np.array(dropper_z),
        group_elems=[np.array(g_, dtype=np.int64) for g_ in group_elems],
        group_tension=np.array(group_T), group_names=group_names, anchors=anchors,
        arms=arms, definition=d, messenger_nodes=messenger_nodes,
        dropper_k=np.full(len(dropper_bars), np.nan if d.dropper_stiffness is None
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
    S.cable_dofs = np.hstack([nd[:-1], nd[1:]])
    S.cable_Le = np.full(n, length / n)
    S.cable_mu = np.full(n, mass_per_length)
    S.cable_EA = np.full(n, EA)
    S.cable_EI = np.full(n, EI)
    S.cable_group = np.zeros(n, dtype=np.int64)
    S.N0_group = np.array([tension], dtype=float)
    S.finalize()
    return CatenaryMesh(
        structure=S, node_dofs=nd, contact_nodes=np.arange(nn), contact_elems=np.arange(n),
        support_x=np.array([0.0, length]), support_contact_nodes=np.array([0, nn - 1]),
        dropper_bars=np.zeros(0, dtype=np.int64), dropper_x=np.zeros(0),
        dropper_contact_nodes=np.zeros(0, dtype=np.int64), dropper_design_z=np.zeros(0),
        group_elems=[np.arange(n)], group_tension=np.array([tension]),
        dropper_k=np.zeros(0), group_names=["wire"], anchors=[], arms=[], definition=None,
        messenger_nodes=np.zeros(0, dtype=np.int64))
