"""Geometrically exact 3D beam with directors (Simo-Reissner kinematics; seed 002, eqs. 5-8).

A node carries its position x and the orthonormal triad R = [d1 d2 d3] of its cross-section
(d3 along the axis in the reference configuration, d1, d2 the principal axes of the section).
A point of the section at material coordinates (xi1, xi2) sits at x + xi1 d1 + xi2 d2
(seed 002, eq. 5), so the triad is the rotation of seed 002 (1) written through its columns:
finite rotations without rotation parameters, no singularity at 2 pi, and a constant mass
matrix. Orthonormality is a constraint of the system (``constraint_set.orthonormality``).

Element (two nodes, linear interpolation of x and of the directors, seed 002 eq. 12, one
Gauss point at mid-length: no shear locking). The material strains of seed 002 (7),
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

With the linear elastic law N = C_Gamma Gamma, M = C_K K (seed 002, eq. 8) the strain energy
of an element is

    W_e = L/2 sum_k c_k (e_k - e_k0)^2,   c = [k G A, k G A, E A, E I1, E I2, G J],

whose gradient and Hessian (internal force and tangent) are written out in
:meth:`DirectorBeam.element_forces` (exact; checked against central differences). e_k0 are
the strains of the reference configuration (a straight or curved stress-free beam).

Mass: the kinetic energy of seed 002 (after eq. 9), T = 1/2 (m x'.x' + Omega.J Omega), is in
director form 1/2 int (rho A |x'|^2 + rho I2 |d1'|^2 + rho I1 |d2'|^2) ds (I2 = int xi1^2 dA,
I1 = int xi2^2 dA), which gives J = rho diag(I1, I2, I1 + I2) exactly; with linear shape
functions the consistent mass matrix is constant. d3 carries no mass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


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


def arc_factor(s, L=1.0):
    """h(s) = asin(s)/s and the two derived factors g = L^2 h'(s)/s and
    gq = L^4 (h'' - h'/s)/s^2 (power series below s = 0.5, closed forms above)."""
    s = np.asarray(s, dtype=float)
    if np.any(s >= 1.0):
        raise FloatingPointError("beam element rotated by more than 90 degrees")
    L = np.broadcast_to(np.asarray(L, dtype=float), s.shape)
    h = np.empty_like(s)
    hp_s = np.empty_like(s)        # h'/s
    q = np.empty_like(s)           # (h'' - h'/s)/s^2
    small = s < 0.5
    ss = s[small] ** 2
    n = np.arange(_N_SERIES)
    powers = ss[:, None] ** n[None, :]                    # s^(2n)
    h[small] = powers @ _C
    hp_s[small] = powers[:, :-1] @ (2 * n[1:] * _C[1:])   # sum 2n c_n s^(2n-2)
    q[small] = powers[:, :-2] @ (2 * n[2:] * (2 * n[2:] - 2) * _C[2:])
    big = ~small
    x = s[big]
    a = np.arcsin(x)
    p = 1.0 / np.sqrt(1.0 - x * x)
    hb = a / x
    hpb = p / x - a / x ** 2
    hppb = p ** 3 - 2.0 * p / x ** 2 + 2.0 * a / x ** 3
    h[big] = hb
    hp_s[big] = hpb / x
    q[big] = (hppb - hpb / x) / x ** 2
    return h, L ** 2 * hp_s, L ** 4 * q


class DirectorBeam:
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
        self.A = np.stack([strain_forms(L) for L in self.L])            # (ne, 6, 24, 24)
        q0 = system.reference()
        self.e0 = np.zeros((len(self.L), 6))
        self.e0 = self.strains(q0[self.dofs])

    # ------------------------------------------------------------------ kinematics
    def strains(self, qe) -> np.ndarray:
        """(ne, 6) Gamma_1, Gamma_2, Gamma_3 (axial, with the 1 of the reference), K_1..3."""
        return self.corrected_strains(qe)[0]

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

    def corrected_strains(self, qe):
        """(e, Aq, et): the strains e = h(s) e~ of the element, the A_k q_e and e~."""
        Aq = np.einsum("ekij,ej->eki", self.A, qe)
        et = np.einsum("eki,ei->ek", Aq, qe)
        s = self.L * np.linalg.norm(et[:, 3:], axis=1)
        h, _, _ = arc_factor(s)
        return h[:, None] * et, Aq, et

    def element_forces(self, qe, tangent=True):
        """(f_e (ne, 24), K_e (ne, 24, 24) or None) at element coordinates qe (ne, 24).

        e = h(s) e~ with s = L |K~|; J = de/de~ = h I + e~ gv^T (gv = g K~ on the curvature
        components, g = L h'(s)/|K~|), so f = sum_m tau_m 2 A_m q with tau = J^T sigma,
        sigma_k = L c_k (e_k - e_k0), and K = sum_mn B_mn (2 A_m q)(2 A_n q)^T
        + sum_m tau_m 2 A_m with B = J^T (L c) J + sum_k sigma_k d2e_k/de~ de~."""
        Aq = np.einsum("ekij,ej->eki", self.A, qe)
        et = np.einsum("eki,ei->ek", Aq, qe)
        kap = et[:, 3:]
        s = self.L * np.linalg.norm(kap, axis=1)
        h, g, gq = arc_factor(s, self.L)
        e = h[:, None] * et
        gv = np.zeros_like(et)
        gv[:, 3:] = g[:, None] * kap
        J = h[:, None, None] * np.eye(6)[None] + et[:, :, None] * gv[:, None, :]
        w = self.L[:, None] * self.c[None, :]
        sigma = w * (e - self.e0)
        tau = np.einsum("ek,ekm->em", sigma, J)
        f = np.einsum("em,emi->ei", 2.0 * tau, Aq)
        if not tangent:
            return f, None
        # d2 e_k / de~_m de~_n = delta_km gv_n + delta_kn gv_m + e~_k dgv_m/de~_n
        dgv = np.zeros((len(self.L), 6, 6))
        dgv[:, 3:, 3:] = (g[:, None, None] * np.eye(3)[None]
                          + gq[:, None, None] * kap[:, :, None] * kap[:, None, :])
        B = np.einsum("ekm,ek,ekn->emn", J, w, J)
        B += sigma[:, :, None] * gv[:, None, :] + sigma[:, None, :] * gv[:, :, None]
        B += np.einsum("ek,ek->e", sigma, et)[:, None, None] * dgv
        K = (np.einsum("emn,emi,enj->eij", 4.0 * B, Aq, Aq)
             + np.einsum("em,emij->eij", 2.0 * tau, self.A))
        return f, K

    def add_forces(self, t, q, v, f, K, C) -> None:
        fe, Ke = self.element_forces(q[self.dofs], tangent=K is not None)
        np.add.at(f, self.dofs, fe)
        if K is not None:
            K.add(self.dofs, self.dofs, Ke)

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
