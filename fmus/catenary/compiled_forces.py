"""The catenary's dynamic forces in one compiled call (thesis (3.25)-(3.26)).

:class:`CompiledForces` gathers, once, the arrays of a structure's element sets (ANCF
cables, bars, point masses, ground springs: :mod:`.ancf_cable`, :mod:`.bar`,
:mod:`.point_mass`, :mod:`.ground_spring`) and of the model's constant band matrices, and
evaluates at a Newton iterate, in one numba call, what
:meth:`~pantocosim.catenary.structure.Structure.internal` and the model's residual compute
part by part: the full coordinate vector, every set's internal forces (and tangent on the
shared pattern) scattered in the structure's order, the bars' slack flags, M a, C v without
the Rayleigh share of the committed slack droppers, the weight and the step loads. The
element kernels are the sets' own; the arithmetic and its order are theirs, so the result
is bit for bit the part-by-part one.

A structure with a part of another type is not gathered (:meth:`CompiledForces.of` returns
None) and is evaluated part by part.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.affine_kernels import sym_product
from ..core.newmark_residual import iterate_kinematics, weighted_residual
from ..core.scatter import scatter_add
from .ancf_cable import GAUSS_W, GAUSS_XI, CableSet, cable_forces
from .bar import BarSet, bar_forces
from .ground_spring import GroundSprings
from .point_mass import PointMasses

#: the element sets gathered: type -> kind code of :func:`_forces`
KINDS = {CableSet: 0, BarSet: 1, PointMasses: 2, GroundSprings: 3}


class CompiledForces:
    """The gathered arrays (:meth:`of`) and :meth:`evaluate`."""

    def __init__(self, structure, parts: dict):
        S = structure
        self.structure = S
        self.kinds = np.array([KINDS[type(el)] for el in S.parts.values()], dtype=np.int64)
        self.cables = _cable_arrays(parts.get(0))
        self.bars = parts[1]
        self.bar_arrays = _bar_arrays(self.bars)
        self.springs = _spring_arrays(parts.get(3))
        self.x = S.x_full.copy()
        self.f = np.zeros(S.n_full)
        self.K_empty = np.zeros(0)

    @classmethod
    def of(cls, structure) -> "CompiledForces | None":
        """The gathered structure, or None if it has a part of another type or two of one
        type, or no bars."""
        parts: dict = {}
        for el in structure.parts.values():
            kind = KINDS.get(type(el))
            if kind is None or kind in parts:
                return None
            parts[kind] = el
        if 1 not in parts:
            return None
        return cls(structure, parts)

    def evaluate(self, q, v, a, want_K: bool, M_band, C_band, slack, d_free, d_C, weight,
                 loads):
        """(M a, f_rest, K data or None, slack flags of the bars) at (q, v, a):
        f_rest = C v (slack droppers' Rayleigh share out) + F_elast - weight - loads.
        The bars' ``slack`` array is updated as by their ``add_forces``."""
        S = self.structure
        K = np.zeros(S.nnz) if want_K else self.K_empty
        Ma, rest = _forces(self.kinds, S.x_full, S.free, q, self.x, self.f, want_K, K,
                           self.cables, self.bar_arrays, self.springs, M_band, C_band, a, v,
                           slack, d_free, d_C, weight, loads, GAUSS_XI, GAUSS_W)
        return Ma, rest, (K if want_K else None), self.bars.slack

    def iterate(self, q, q_p, v_p, c_a, c_v, c_f, hist, want_K: bool, M_band, C_band, slack,
                d_free, d_C, weight, loads):
        """(a, v, M a, f_rest, R, max |R|, size of the forces, K data or None, slack flags)
        at the iterate q of :func:`~pantocosim.core.newmark_residual.iterate_kinematics`
        with R of :func:`~pantocosim.core.newmark_residual.weighted_residual`."""
        S = self.structure
        K = np.zeros(S.nnz) if want_K else self.K_empty
        out = _iterate(self.kinds, S.x_full, S.free, q, q_p, v_p, c_a, c_v, c_f, hist, self.x,
                       self.f, want_K, K, self.cables, self.bar_arrays, self.springs, M_band,
                       C_band, slack, d_free, d_C, weight, loads, GAUSS_XI, GAUSS_W)
        return out + ((K if want_K else None), self.bars.slack)

    def compressed(self, q, bars) -> np.ndarray:
        """Whether each of ``bars`` is shorter than unstretched at q (axial force N < 0 of
        the bilateral law, ``BarSet.axial_forces``)."""
        S = self.structure
        return _compressed(S.x_full, S.free, q, self.x, self.bar_arrays, bars)


@njit(cache=True)
def _compressed(x_base, free, q, x, bar, bars):
    """N < 0 of ``bars`` at q, with N as ``BarSet.axial_forces``."""
    dofs, dX, l0, EA = bar[0], bar[1], bar[2], bar[3]
    for i in range(x.shape[0]):
        x[i] = x_base[i]
    for i in range(free.shape[0]):
        x[free[i]] = q[i]
    out = np.empty(bars.shape[0], dtype=np.bool_)
    for i in range(bars.shape[0]):
        b = bars[i]
        d0 = (x[dofs[b, 3]] - x[dofs[b, 0]]) + dX[b, 0]
        d1 = (x[dofs[b, 4]] - x[dofs[b, 1]]) + dX[b, 1]
        d2 = (x[dofs[b, 5]] - x[dofs[b, 2]]) + dX[b, 2]
        ln = np.sqrt((d0 * d0 + d1 * d1) + d2 * d2)
        out[i] = EA[b] * (ln - l0[b]) / l0[b] < 0.0
    return out


def _cable_arrays(cab: CableSet | None) -> tuple:
    if cab is None or not len(cab):
        z = np.zeros(0)
        return (np.zeros((0, 12), np.int64), np.zeros((0, 3)), z, z, z, np.zeros(0, np.int64),
                z, np.zeros((0, 12)), np.zeros((0, 12)), np.zeros((0, 12, 12)),
                np.zeros(0, np.int64))
    return (cab.dofs, cab.dX, cab.Le, cab.EA, cab.EI, cab.group, cab.N0_group,
            np.empty((len(cab), 12)), cab._f, cab._K, cab.pos)


def _bar_arrays(bar: BarSet) -> tuple:
    return (bar.dofs, bar.dX, bar.l0, bar.EA, bar.tension_only, np.empty((len(bar), 6)),
            bar._f, bar._K, bar.slack, bar.pos)


def _spring_arrays(spr: GroundSprings | None) -> tuple:
    if spr is None:
        return (np.zeros(0, np.int64), np.zeros(0), np.zeros(0), np.zeros(0, np.int64))
    return (np.ascontiguousarray(spr.dofs[:, 0]), spr.k, spr.anchor, spr.pos)


@njit(cache=True)
def _cables_into(x, cab, want_K, f, K, gx, gw):
    """Cable forces (:func:`~.ancf_cable.cable_forces`) scattered as ``CableSet.add_forces``."""
    dofs, dX, Le, EA, EI, group, N0_group, E, fe, Ke, pos = cab
    ne = dofs.shape[0]
    if ne == 0:
        return
    N0 = np.empty(ne)
    for e in range(ne):
        N0[e] = N0_group[group[e]]
        for i in range(12):
            E[e, i] = x[dofs[e, i]]
    cable_forces(E, dX, Le, EA, EI, N0, gx, gw, want_K, fe, Ke)
    for e in range(ne):
        for i in range(12):
            f[dofs[e, i]] += fe[e, i]
    if want_K:
        scatter_add(K, pos, Ke.reshape(ne * 144))


@njit(cache=True)
def _bars_into(x, bar, want_K, f, K):
    """Bar forces (:func:`~.bar.bar_forces`, tension-only law) scattered as
    ``BarSet.add_forces``."""
    dofs, dX, l0, EA, law, X, fb, Kb, slack, pos = bar
    nb = dofs.shape[0]
    for b in range(nb):
        for i in range(6):
            X[b, i] = x[dofs[b, i]]
    bar_forces(X, dX, l0, EA, law, want_K, fb, Kb, slack)
    for b in range(nb):
        for i in range(6):
            f[dofs[b, i]] += fb[b, i]
    if want_K and nb:
        scatter_add(K, pos, Kb.reshape(nb * 36))


@njit(cache=True)
def _springs_into(x, spr, want_K, f, K):
    """Ground-spring forces k (x - anchor) as ``GroundSprings.add_forces``."""
    d, k, anchor, pos = spr
    for i in range(d.shape[0]):
        f[d[i]] += k[i] * (x[d[i]] - anchor[i])
    if want_K:
        scatter_add(K, pos, k)


@njit(cache=True)
def _forces(kinds, x_base, free, q, x, f, want_K, K, cab, bar, spr, M, C, a, v, slack,
            d_free, d_C, weight, loads, gx, gw):
    """The residual pieces of (3.25)-(3.26) at one iterate (:class:`CompiledForces`)."""
    for i in range(x.shape[0]):
        x[i] = x_base[i]
        f[i] = 0.0
    for i in range(free.shape[0]):
        x[free[i]] = q[i]
    for kind in kinds:
        if kind == 0:
            _cables_into(x, cab, want_K, f, K, gx, gw)
        elif kind == 1:
            _bars_into(x, bar, want_K, f, K)
        elif kind == 3:
            _springs_into(x, spr, want_K, f, K)
    return _inertia_and_rest(M, a, C, v, slack, d_free, d_C, f, free, weight, loads)


@njit(cache=True)
def _iterate(kinds, x_base, free, q, q_p, v_p, c_a, c_v, c_f, hist, x, f, want_K, K, cab, bar,
             spr, M, C, slack, d_free, d_C, weight, loads, gx, gw):
    """:func:`_forces` at a Newton iterate, between the integrator's kernels."""
    a, v = iterate_kinematics(q, q_p, v_p, c_a, c_v)
    Ma, rest = _forces(kinds, x_base, free, q, x, f, want_K, K, cab, bar, spr, M, C, a, v,
                       slack, d_free, d_C, weight, loads, gx, gw)
    R, r_max, scale = weighted_residual(Ma, rest, hist, c_f)
    return a, v, Ma, rest, R, r_max, scale


@njit(cache=True)
def _inertia_and_rest(M, a, C, v, slack, d_free, d_C, f_full, free, weight, loads):
    """(M a, C v + f_full[free] - weight - loads) of (3.25)-(3.26): M and C are symmetric
    sparse bands (:class:`~pantocosim.core.banded.SparseBand` parts, C with every dropper
    taut); the Rayleigh share of the ``slack`` droppers (their 6 x 6 blocks ``d_C`` on the
    free DOFs ``d_free``, -1: fixed) is taken out of C v. ``loads``: empty when none."""
    n = free.shape[0]
    Ma = np.empty(n)
    rest = np.empty(n)
    below = np.empty(n)
    sym_product(M, a, Ma, below)
    sym_product(C, v, rest, below)
    for d in range(slack.shape[0]):
        if not slack[d]:
            continue
        for i in range(6):
            r = d_free[d, i]
            if r < 0:
                continue
            s = 0.0
            for j in range(6):
                c = d_free[d, j]
                if c >= 0:
                    s += d_C[d, 6 * i + j] * v[c]
            rest[r] -= s
    for i in range(n):
        rest[i] = (rest[i] + f_full[free[i]]) - weight[i]
    if loads.shape[0]:
        for i in range(n):
            rest[i] = rest[i] - loads[i]
    return Ma, rest
