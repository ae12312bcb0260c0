"""Geometrically exact 3D beam with directors (Simo-Reissner kinematics; the pendulum paper,
eqs. 5-8).

A node carries its position x and the orthonormal triad R = [d1 d2 d3] of its cross-section
(d3 along the axis in the reference configuration, d1, d2 the principal axes of the section).
A point of the section at material coordinates (xi1, xi2) sits at x + xi1 d1 + xi2 d2
(the pendulum paper, eq. 5), so the triad is the paper's rotation (1) written through its
columns: finite rotations without rotation parameters, no singularity at 2 pi, and a constant mass
matrix. Orthonormality is a constraint of the system (``constraint_set.orthonormality``).

Element (two nodes, linear interpolation of x and of the directors, the paper's eq. 12, one
Gauss point at mid-length: no shear locking). The material strains of the paper (7),
Gamma = R^T x' - e3 and the curvature K = axial(R^T R'), are evaluated with the interpolated
directors in the frame-indifferent form of Betsch & Steinmann (2002):

    Gamma_i = x' . d_i - delta_i3,
    K_1 = (d2' . d3 - d3' . d2)/2,  K_2 = (d3' . d1 - d1' . d3)/2,  K_3 = (d1' . d2 - d2' . d1)/2,

each a quadratic form e~_k = q_e^T A_k q_e of the 24 element coordinates.

Arc correction. With orthonormal nodal triads the curvature above is axial(skew(R_A^T R_B))/L,
i.e. sin(phi)/L for a relative rotation phi over the element, and the mid-length directors are
shortened by cos(phi/2); both make a uniformly bent element rotate and stretch too much
(an error of order phi^2 per element). Multiplying all six measures by h(s) = asin(s)/s,
s = L |K~| (= phi/sin(phi)), makes a circular arc of any opening below 90 degrees per
element exact (curvature phi/L, chord 2 R sin(phi/2), no spurious axial strain), so the
roll-up of a cantilever under an end moment closes exactly. e = h(s) e~ reduces to e~ for
small element rotations and is frame-indifferent like e~.

With the linear elastic law N = C_Gamma Gamma, M = C_K K (the paper's eq. 8) the strain
energy of an element is

    W_e = L/2 sum_k c_k (e_k - e_k0)^2,   c = [k G A, k G A, E A, E I1, E I2, G J],

whose gradient and Hessian (internal force and tangent) are written out in
:meth:`DirectorBeam.element_forces` (exact; checked against central differences). e_k0 are
the strains of the reference configuration (a straight or curved stress-free beam).

Mass: the paper's kinetic energy (after eq. 9), T = 1/2 (m x'.x' + Omega.J Omega), is in
director form 1/2 int (rho A |x'|^2 + rho I2 |d1'|^2 + rho I1 |d2'|^2) ds (I2 = int xi1^2 dA,
I1 = int xi2^2 dA), which gives J = rho diag(I1, I2, I1 + I2) exactly; with linear shape
functions the consistent mass matrix is constant. d3 carries no mass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from .component import Component


@dataclass(frozen=True)
class Section:
    """Material and cross-section. I1 = int xi2^2 dA resists bending about d1, I2 about d2;
    J is the torsion constant."""

    E: float
    A: float
    I1: float
    I2: float
    J: float
    rho: float
    nu: float = 0.3
    shear_factor: float = 5.0 / 6.0

    @property
    def G(self) -> float:
        return self.E / (2.0 * (1.0 + self.nu))

    def stiffness(self) -> np.ndarray:
        ksGA = self.shear_factor * self.G * self.A
        return np.array([ksGA, ksGA, self.E * self.A, self.E * self.I1, self.E * self.I2,
                         self.G * self.J])


def _selectors(L: float) -> dict:
    """3 x 24 matrices picking x', d_i (mid-length) and d_i' from the element coordinates."""
    S = {}
    eye = np.eye(3)

    def block(node, k):
        m = np.zeros((3, 24))
        m[:, 12 * node + 3 * k:12 * node + 3 * k + 3] = eye
        return m

    S["xp"] = (block(1, 0) - block(0, 0)) / L
    for i in range(3):
        S[f"d{i}"] = 0.5 * (block(0, i + 1) + block(1, i + 1))
        S[f"dp{i}"] = (block(1, i + 1) - block(0, i + 1)) / L
    return S


def strain_forms(L: float) -> np.ndarray:
    """(6, 24, 24) symmetric A_k with e_k = q_e^T A_k q_e: Gamma_1..3, K_1..3."""

    def dot(a, b):  # symmetric matrix of (a q).(b q)
        P = a.T @ b
        return 0.5 * (P + P.T)

    S = _selectors(L)
    A = np.empty((6, 24, 24))
    for i in range(3):
        A[i] = dot(S["xp"], S[f"d{i}"])
    A[3] = 0.5 * (dot(S["dp1"], S["d2"]) - dot(S["dp2"], S["d1"]))
    A[4] = 0.5 * (dot(S["dp2"], S["d0"]) - dot(S["dp0"], S["d2"]))
    A[5] = 0.5 * (dot(S["dp0"], S["d1"]) - dot(S["dp1"], S["d0"]))
    return A


_N_SERIES = 30
_C = np.array([math.comb(2 * n, n) / (4.0 ** n * (2 * n + 1)) for n in range(_N_SERIES)])


@njit(cache=True)
def arc_factor(s, L):
    """h(s) = asin(s)/s and the two derived factors g = L^2 h'(s)/s and
    gq = L^4 (h'' - h'/s)/s^2 (power series below s = 0.5, closed forms above)."""
    if not s < 1.0:
        raise FloatingPointError("beam element rotated by more than 90 degrees")
    if s < 0.5:
        ss = s * s
        h, hp_s, q = _C[0], 0.0, 0.0
        p1, p2 = 1.0, 0.0                      # s^(2n-2), s^(2n-4)
        for n in range(1, _N_SERIES):
            hp_s += 2 * n * _C[n] * p1
            q += 2 * n * (2 * n - 2) * _C[n] * p2
            h += _C[n] * p1 * ss
            p2 = p1
            p1 *= ss
    else:
        a = math.asin(s)
        p = 1.0 / math.sqrt(1.0 - s * s)
        h = a / s
        hp = p / s - a / (s * s)
        hpp = p ** 3 - 2.0 * p / (s * s) + 2.0 * a / s ** 3
        hp_s = hp / s
        q = (hpp - hp / s) / (s * s)
    return h, L * L * hp_s, L ** 4 * q


@njit(cache=True)
def _element(qe, ai, aj, av, cnt, L, c, e0, fe, Ke, want_k, Aq, W, vec, J, B):
    """Internal force fe (24) and, if ``want_k``, tangent Ke (24, 24) of one element at its
    coordinates qe; A_k in sparse form (rows ai, columns aj, values av, cnt[k] entries).
    Work arrays: Aq, W (6, 24), vec (6, 6), J, B (6, 6). Returns e (a view of vec)."""
    et, e, gv, sigma, tau = vec[0], vec[1], vec[2], vec[3], vec[4]
    for k in range(6):
        for i in range(24):
            Aq[k, i] = 0.0
        for p in range(cnt[k]):
            Aq[k, ai[k, p]] += av[k, p] * qe[aj[k, p]]
        acc = 0.0
        for i in range(24):
            acc += Aq[k, i] * qe[i]
        et[k] = acc
    kap = math.sqrt(et[3] ** 2 + et[4] ** 2 + et[5] ** 2)
    h, g, gq = arc_factor(L * kap, L)
    for k in range(6):
        e[k] = h * et[k]
        gv[k] = g * et[k] if k >= 3 else 0.0
    for k in range(6):
        sigma[k] = L * c[k] * (e[k] - e0[k])
    for m in range(6):                          # J = h I + e~ gv^T, tau = J^T sigma
        acc = 0.0
        for k in range(6):
            J[k, m] = (h if k == m else 0.0) + et[k] * gv[m]
            acc += sigma[k] * J[k, m]
        tau[m] = acc
    for i in range(24):
        acc = 0.0
        for m in range(6):
            acc += 2.0 * tau[m] * Aq[m, i]
        fe[i] = acc
    if not want_k:
        return e
    se = 0.0
    for k in range(6):
        se += sigma[k] * et[k]
    for m in range(6):
        for n in range(6):
            acc = 0.0
            for k in range(6):
                acc += J[k, m] * L * c[k] * J[k, n]
            acc += sigma[m] * gv[n] + sigma[n] * gv[m]
            if m >= 3 and n >= 3:
                acc += se * ((g if m == n else 0.0) + gq * et[m] * et[n])
            B[m, n] = 4.0 * acc
    for n in range(6):
        for i in range(24):
            acc = 0.0
            for m in range(6):
                acc += B[m, n] * Aq[m, i]
            W[n, i] = acc
    for i in range(24):
        for j in range(24):
            acc = 0.0
            for n in range(6):
                acc += W[n, i] * Aq[n, j]
            Ke[i, j] = acc
    for m in range(6):
        for p in range(cnt[m]):
            Ke[ai[m, p], aj[m, p]] += 2.0 * tau[m] * av[m, p]
    return e


@njit(cache=True)
def _beam_kernel(q, dofs, ai, aj, av, cnt, L, c, e0, f, kdata, pos, want_k, strains,
                 qe, fe, Ke, Aq, W, vec, J, B):
    """Every element of a beam: forces added to f, tangents to kdata at pos (ne, 576),
    strains e into ``strains`` (ne, 6). Nothing allocated (work arrays passed in)."""
    for el in range(dofs.shape[0]):
        for i in range(24):
            qe[i] = q[dofs[el, i]]
        e = _element(qe, ai[el], aj[el], av[el], cnt[el], L[el], c, e0[el], fe, Ke, want_k,
                     Aq, W, vec, J, B)
        for k in range(6):
            strains[el, k] = e[k]
        for i in range(24):
            f[dofs[el, i]] += fe[i]
        if want_k:
            for i in range(24):
                for j in range(24):
                    kdata[pos[el, 24 * i + j]] += Ke[i, j]


def _sparse_forms(L) -> tuple:
    """(ai, aj, av, cnt): the strain forms A_k of every element in sparse form."""
    A = np.stack([strain_forms(x) for x in L])                      # (ne, 6, 24, 24)
    cnt = np.count_nonzero(A, axis=(2, 3))
    P = int(cnt.max())
    ai = np.zeros(A.shape[:2] + (P,), np.int64)
    aj = np.zeros_like(ai)
    av = np.zeros(ai.shape)
    for e in range(A.shape[0]):
        for k in range(6):
            i, j = np.nonzero(A[e, k])
            ai[e, k, :i.size], aj[e, k, :i.size], av[e, k, :i.size] = i, j, A[e, k, i, j]
    return ai, aj, av, cnt.astype(np.int64)


class DirectorBeam(Component):
    """A chain of two-node beam elements between consecutive ``nodes`` of a system."""

    def __init__(self, nodes, section: Section, name: str = "beam"):
        self.nodes = np.asarray(nodes, dtype=np.int64)
        self.section = section
        self.name = name
        self.c = section.stiffness()

    def bind(self, system) -> None:
        n = self.nodes
        self.dofs = np.hstack([system.node_dofs(n[:-1]), system.node_dofs(n[1:])])  # (ne, 24)
        X = np.array(system.X0)
        self.L = np.linalg.norm(X[n[1:]] - X[n[:-1]], axis=1)
        if np.any(self.L <= 0):
            raise ValueError(f"{self.name}: zero-length element")
        self.forms = _sparse_forms(self.L)
        ne = len(self.L)
        self._work = (np.empty(24), np.empty(24), np.empty((24, 24)), np.empty((6, 24)),
                      np.empty((6, 24)), np.empty((6, 6)), np.empty((6, 6)), np.empty((6, 6)))
        self._strains = np.empty((ne, 6))
        self._no_pos = np.zeros((ne, 576), np.int64)
        self.e0 = np.zeros((ne, 6))
        self.e0 = self.strains(system.reference()[self.dofs])

    def tangent_dofs(self) -> np.ndarray:
        """(ne, 24): each element couples its 24 coordinates."""
        return self.dofs

    def locate(self, pattern) -> None:
        self.pos = pattern.positions(self.dofs[:, :, None], self.dofs[:, None, :]).reshape(
            -1, 576)

    # ------------------------------------------------------------------ kernels
    def _run(self, q, dofs, f, kdata, pos, want_k):
        _beam_kernel(q, dofs, *self.forms, self.L, self.c, self.e0, f, kdata, pos, want_k,
                     self._strains, *self._work)
        return self._strains

    def strains(self, qe) -> np.ndarray:
        """(ne, 6) Gamma_1, Gamma_2, Gamma_3 (axial, with the 1 of the reference), K_1..3 at
        element coordinates qe (ne, 24)."""
        qe = np.ascontiguousarray(qe, dtype=float)
        dofs = np.arange(qe.size).reshape(qe.shape)
        return self._run(qe.ravel(), dofs, np.zeros(qe.size), np.zeros(1), self._no_pos,
                         False).copy()

    def element_forces(self, qe, tangent=True):
        """(f_e (ne, 24), K_e (ne, 24, 24) or None) at element coordinates qe (ne, 24).

        e = h(s) e~ with s = L |K~|; J = de/de~ = h I + e~ gv^T (gv = g K~ on the curvature
        components, g = L h'(s)/|K~|), so f = sum_m tau_m 2 A_m q with tau = J^T sigma,
        sigma_k = L c_k (e_k - e_k0), and K = sum_mn B_mn (2 A_m q)(2 A_n q)^T
        + sum_m tau_m 2 A_m with B = J^T (L c) J + sum_k sigma_k d2e_k/de~ de~.
        (The numba kernel the system runs, element by element into separate arrays.)"""
        qe = np.ascontiguousarray(qe, dtype=float)
        ne = qe.shape[0]
        dofs = np.arange(qe.size).reshape(qe.shape)
        f = np.zeros((ne, 24))
        K = np.zeros((ne, 24, 24)) if tangent else None
        for e in range(ne):
            kd = K[e].ravel() if tangent else np.zeros(1)
            pos = np.arange(576).reshape(1, 576)
            _beam_kernel(qe[e], dofs[:1], *(x[e:e + 1] for x in self.forms), self.L[e:e + 1],
                         self.c, self.e0[e:e + 1], f[e], kd, pos, tangent,
                         np.empty((1, 6)), *self._work)
            if tangent:
                K[e] = kd.reshape(24, 24)
        return f, K

    # ------------------------------------------------------------------ protocol
    def add_mass(self, M) -> None:
        s = self.section
        lin = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
        per_field = [s.rho * s.A, s.rho * s.I2, s.rho * s.I1, 0.0]   # x, d1, d2, d3
        for e, L in enumerate(self.L):
            me = np.zeros((24, 24))
            for k, mu in enumerate(per_field):
                for a in range(2):
                    for b in range(2):
                        ia = 12 * a + 3 * k
                        ib = 12 * b + 3 * k
                        me[ia:ia + 3, ib:ib + 3] += mu * L * lin[a, b] * np.eye(3)
            M.add(self.dofs[e], self.dofs[e], me)

    def add_forces(self, t, q, v, f, K, C) -> None:
        if K is None:
            self._run(q, self.dofs, f, np.zeros(1), self._no_pos, False)
        else:
            self._run(q, self.dofs, f, K.data, self.pos, True)

    def strain_energy(self, q) -> float:
        de = self.strains(q[self.dofs]) - self.e0
        return float(0.5 * np.sum(self.L[:, None] * self.c[None, :] * de * de))

    def energy(self, t, q, v) -> dict:
        return {"strain": self.strain_energy(q)}


def straight_beam(system, start, end, n_elements: int, section: Section, d1=None,
                  name: str = "beam") -> DirectorBeam:
    """Add ``n_elements + 1`` nodes on the segment start-end (d3 along it, d1 given or any
    perpendicular) and the beam on them."""
    start = np.asarray(start, float)
    end = np.asarray(end, float)
    t = (end - start) / np.linalg.norm(end - start)
    if d1 is None:
        trial = np.array([0.0, 0.0, 1.0]) if abs(t[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
        d1 = trial - (trial @ t) * t
    d1 = np.asarray(d1, float)
    d1 = d1 - (d1 @ t) * t
    d1 /= np.linalg.norm(d1)
    d2 = np.cross(t, d1)
    R = np.column_stack([d1, d2, t])
    nodes = [system.add_node(start + s * (end - start), R)
             for s in np.linspace(0.0, 1.0, n_elements + 1)]
    return system.add(DirectorBeam(nodes, section, name))
