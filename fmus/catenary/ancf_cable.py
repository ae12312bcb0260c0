"""Gradient-deficient 3D ANCF cable element (thesis 3.1.1, eqs. (3.2)-(3.3)).

Nodal coordinates of one element (3.2)::

    e = [r_i, r_i', r_j, r_j']          (12 entries; r' = dr/dchi, chi in [0, L])

and r(chi) = S(chi) e with the cubic Hermite functions (3.12)-(3.13), xi = chi / L::

    S1 = 1 - 3 xi^2 + 2 xi^3      S2 = L (xi - 2 xi^2 + xi^3)
    S3 = 3 xi^2 - 2 xi^3          S4 = L (xi^3 - xi^2)

Strain energy: U = int [N0 eps + EA eps^2 / 2] dchi + EI/2 int r''.r'' dchi, with the
Green axial strain eps = (r'.r' - 1)/2. ``N0`` is the pre-tension of the reference
(chi-parametrised) configuration, i.e. the element is stress-free when
r'.r' = 1 - 2 N0 / EA; it is the unknown "pre-strain" of the initial-configuration problem
(3.1.3). The section force transmitted by the cable is the vector N r' with
N = N0 + EA eps (so the true tension is N |r'| and the horizontal tension N r'_x). The bending
term is the usual linearised curvature, so its stiffness matrix is constant, as in the thesis.

Mass matrix and gravity vector are constant (absolute nodal coordinates).
All kernels are numba functions looping over every element at once.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.scatter import scatter_add


#: 5-point Gauss-Legendre on [0, 1]: exact for the degree-8 integrands of force and tangent
_GX, _GW = np.polynomial.legendre.leggauss(5)
GAUSS_XI = 0.5 * (_GX + 1.0)
GAUSS_W = 0.5 * _GW


@njit(cache=True)
def shape(xi: float, L: float) -> np.ndarray:
    """Hermite functions [S1, S2, S3, S4] at xi = chi/L, (3.12)-(3.13)."""
    return np.array([1 - 3 * xi**2 + 2 * xi**3, L * (xi - 2 * xi**2 + xi**3),
                     3 * xi**2 - 2 * xi**3, L * (xi**3 - xi**2)])


@njit(cache=True)
def shape_dxi(xi: float, L: float) -> np.ndarray:
    """d[S1..S4]/dxi."""
    return np.array([-6 * xi + 6 * xi**2, L * (1 - 4 * xi + 3 * xi**2),
                     6 * xi - 6 * xi**2, L * (3 * xi**2 - 2 * xi)])


def mass_matrix(mu: float, L: float) -> np.ndarray:
    """Consistent 12x12 mass matrix rho A int S^T S dchi = kron(m4, I3)."""
    m4 = mu * L / 420.0 * np.array([
        [156.0, 22 * L, 54.0, -13 * L],
        [22 * L, 4 * L * L, 13 * L, -3 * L * L],
        [54.0, 13 * L, 156.0, -22 * L],
        [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    return np.kron(m4, np.eye(3))


def gravity_vector(mu: float, L: float, g: float) -> np.ndarray:
    """External weight -mu g int S^T e_z dchi (12 entries)."""
    f = np.zeros(12)
    f[[2, 5, 8, 11]] = -mu * g * np.array([L / 2, L * L / 12, L / 2, -L * L / 12])
    return f


@njit(cache=True)
def _dshape(xi, L):
    # dS/dchi
    return (np.array([(-6.0 * xi + 6.0 * xi * xi) / L, 1.0 - 4.0 * xi + 3.0 * xi * xi,
                      (6.0 * xi - 6.0 * xi * xi) / L, 3.0 * xi * xi - 2.0 * xi]))


@njit(cache=True)
def _slope(E, dX, e, dS):
    """r' = sum_a dS_a e_a at a point of element e (x stored relative to the stations: the
    station difference dX enters through the second node's position shape function)."""
    r0 = dS[2] * dX[e, 0]
    r1 = dS[2] * dX[e, 1]
    r2 = dS[2] * dX[e, 2]
    for a in range(4):
        r0 += dS[a] * E[e, 3 * a]
        r1 += dS[a] * E[e, 3 * a + 1]
        r2 += dS[a] * E[e, 3 * a + 2]
    return r0, r1, r2


@njit(cache=True)
def cable_forces(E, dX, Le, EA, EI, N0, gx, gw, want_K, f_out, K_out):
    """Internal forces f = dU/de (ne x 12) and, if want_K, the tangent dF/de (ne x 12 x 12).

    E: element coordinates (ne x 12) relative to per-node position offsets whose
    difference (node j - node i) is dX (ne x 3): the absolute coordinates are
    E + [off_i, 0, off_j, 0]. Working on offsets keeps the strain free of the round-off of
    large absolute x (a 600 m line). Le, EA, EI, N0: per element.
    """
    ne = E.shape[0]
    ng = gx.shape[0]
    # shape-function derivatives at the Gauss points, without the 1/L of S1', S3'
    tab = np.empty((ng, 4))
    for g in range(ng):
        xi = gx[g]
        tab[g, 0] = -6.0 * xi + 6.0 * xi * xi
        tab[g, 1] = 1.0 - 4.0 * xi + 3.0 * xi * xi
        tab[g, 2] = 6.0 * xi - 6.0 * xi * xi
        tab[g, 3] = 3.0 * xi * xi - 2.0 * xi
    dS = np.empty(4)
    A = np.empty((4, 4))           # sum_g w N dS_a dS_b
    B = np.empty((4, 4, 3, 3))     # sum_g w EA dS_a dS_b r'_k r'_l
    for e in range(ne):
        L = Le[e]
        iL = 1.0 / L
        ea = EA[e]
        n0 = N0[e]
        for i in range(12):
            f_out[e, i] = 0.0
        if want_K:
            A[:, :] = 0.0
            B[:, :, :, :] = 0.0
        for g in range(ng):
            dS[0] = tab[g, 0] * iL
            dS[1] = tab[g, 1]
            dS[2] = tab[g, 2] * iL
            dS[3] = tab[g, 3]
            w = gw[g] * L
            r0, r1, r2 = _slope(E, dX, e, dS)
            eps = 0.5 * (r0 * r0 + r1 * r1 + r2 * r2 - 1.0)
            N = n0 + ea * eps
            for a in range(4):
                c = w * N * dS[a]
                f_out[e, 3 * a] += c * r0
                f_out[e, 3 * a + 1] += c * r1
                f_out[e, 3 * a + 2] += c * r2
            if want_K:
                wea = w * ea
                r00 = wea * r0 * r0
                r01 = wea * r0 * r1
                r02 = wea * r0 * r2
                r11 = wea * r1 * r1
                r12 = wea * r1 * r2
                r22 = wea * r2 * r2
                for a in range(4):
                    for b in range(4):
                        s = dS[a] * dS[b]
                        A[a, b] += w * N * s
                        B[a, b, 0, 0] += s * r00
                        B[a, b, 0, 1] += s * r01
                        B[a, b, 0, 2] += s * r02
                        B[a, b, 1, 1] += s * r11
                        B[a, b, 1, 2] += s * r12
                        B[a, b, 2, 2] += s * r22
        # bending: EI/L^3 kron(k4, I3) e (offsets enter as dX since k4[:, 0] = -k4[:, 2])
        ei = EI[e]
        c = ei * iL * iL * iL
        k00 = 12.0 * c
        k01 = 6.0 * L * c
        k11 = 4.0 * L * L * c
        k13 = 2.0 * L * L * c
        if ei != 0.0:
            for k in range(3):
                x0 = E[e, k]
                s0 = E[e, 3 + k]
                x1 = E[e, 6 + k] + dX[e, k]
                s1 = E[e, 9 + k]
                dx = x0 - x1
                f_out[e, k] += k00 * dx + k01 * (s0 + s1)
                f_out[e, 3 + k] += k01 * dx + k11 * s0 + k13 * s1
                f_out[e, 6 + k] += -k00 * dx - k01 * (s0 + s1)
                f_out[e, 9 + k] += k01 * dx + k13 * s0 + k11 * s1
        if want_K:
            for a in range(4):
                for b in range(4):
                    for k in range(3):
                        for l in range(3):
                            v = B[a, b, k, l] if k <= l else B[a, b, l, k]
                            if k == l:
                                v += A[a, b]
                            K_out[e, 3 * a + k, 3 * b + l] = v
            if ei != 0.0:
                kb = ((k00, k01, -k00, k01), (k01, k11, -k01, k13),
                      (-k00, -k01, k00, -k01), (k01, k13, -k01, k11))
                for a in range(4):
                    for b in range(4):
                        for k in range(3):
                            K_out[e, 3 * a + k, 3 * b + k] += kb[a][b]


@njit(cache=True)
def cable_tension_measures(E, dX, Le, EA, N0, gx, gw, h_out, dh_de, dh_dN0, df_dN0):
    """Per element: h = int N r'_x dchi (horizontal force times length) with its gradients
    dh/de, dh/dN0, and df/dN0 = int S'^T r' dchi (derivative of the internal force with
    respect to the pre-tension). Used by the initial-configuration problem (3.1.3)."""
    ne = E.shape[0]
    ng = gx.shape[0]
    for e in range(ne):
        L = Le[e]
        ea = EA[e]
        h_out[e] = 0.0
        dh_dN0[e] = 0.0
        for i in range(12):
            dh_de[e, i] = 0.0
            df_dN0[e, i] = 0.0
        for g in range(ng):
            dS = _dshape(gx[g], L)
            w = gw[g] * L
            r0, r1, r2 = _slope(E, dX, e, dS)
            eps = 0.5 * (r0 * r0 + r1 * r1 + r2 * r2 - 1.0)
            N = N0[e] + ea * eps
            h_out[e] += w * N * r0
            dh_dN0[e] += w * r0
            for a in range(4):
                dh_de[e, 3 * a] += w * dS[a] * (ea * r0 * r0 + N)
                dh_de[e, 3 * a + 1] += w * dS[a] * ea * r0 * r1
                dh_de[e, 3 * a + 2] += w * dS[a] * ea * r0 * r2
                df_dN0[e, 3 * a] += w * dS[a] * r0
                df_dN0[e, 3 * a + 1] += w * dS[a] * r1
                df_dN0[e, 3 * a + 2] += w * dS[a] * r2


def element_forces(E, Le, EA, EI, N0, want_K=True):
    """Convenience wrapper: (f, K) for arrays of elements (K is None unless want_K)."""
    E = np.ascontiguousarray(E, dtype=float).reshape(-1, 12)
    ne = E.shape[0]
    arr = lambda x: np.ascontiguousarray(np.broadcast_to(np.asarray(x, float), (ne,)))
    f = np.empty((ne, 12))
    K = np.empty((ne, 12, 12) if want_K else (1, 12, 12))
    cable_forces(E, np.zeros((ne, 3)), arr(Le), arr(EA), arr(EI), arr(N0), GAUSS_XI, GAUSS_W, want_K, f, K)
    return f, (K if want_K else None)


class CableSet:
    """All ANCF cable elements of a structure (the :class:`~.structure.Element` protocol).

    dofs: (n, 12) full DOFs [r_i, r_i', r_j, r_j']; per element the reference length ``Le``,
    mass per length ``mu``, ``EA``, ``EI`` and the index ``group`` of its pre-tension in
    ``N0_group`` (one unknown per wire span in the initial-configuration problem)."""

    def __init__(self, dofs, Le, mu, EA, EI, group, N0_group):
        self.dofs = np.ascontiguousarray(np.asarray(dofs, dtype=np.int64).reshape(-1, 12))
        self.Le = np.asarray(Le, dtype=float)
        self.mu = np.asarray(mu, dtype=float)
        self.EA = np.asarray(EA, dtype=float)
        self.EI = np.asarray(EI, dtype=float)
        self.group = np.asarray(group, dtype=np.int64)
        self.N0_group = np.asarray(N0_group, dtype=float)

    def __len__(self) -> int:
        return self.dofs.shape[0]

    def N0(self) -> np.ndarray:
        return self.N0_group[self.group]

    def bind(self, structure, pos) -> None:
        off = structure.offset
        self.dX = np.ascontiguousarray(off[self.dofs[:, 6:9]] - off[self.dofs[:, 0:3]])
        self.pos = pos
        self._f = np.empty((len(self), 12))
        self._K = np.empty((len(self), 12, 12))

    def add_mass(self, M, f_weight, gravity) -> None:
        n = len(self)
        if not n:
            return
        Me = np.empty((n, 12, 12))
        ge = np.empty((n, 12))
        for e in range(n):   # build time only
            Me[e] = mass_matrix(self.mu[e], self.Le[e])
            ge[e] = gravity_vector(self.mu[e], self.Le[e], gravity)
        scatter_add(M, self.pos, Me.ravel())
        scatter_add(f_weight, self.dofs.ravel(), ge.ravel())

    def add_forces(self, x_full, f, K, tension_only) -> None:
        cable_forces(x_full[self.dofs], self.dX, self.Le, self.EA, self.EI, self.N0(),
                     GAUSS_XI, GAUSS_W, K is not None, self._f, self._K)
        scatter_add(f, self.dofs.ravel(), self._f.ravel())
        if K is not None:
            scatter_add(K, self.pos, self._K.ravel())

    def tensions(self, x_full) -> np.ndarray:
        """True axial tension N |r'| at the mid-point of every element."""
        E = x_full[self.dofs]
        L = self.Le
        d = shape_dxi(0.5, 1.0)            # [dS1, dS2/L, dS3, dS4/L] / dxi
        rp = (d[0] * E[:, 0:3] + d[1] * L[:, None] * E[:, 3:6] + d[2] * E[:, 6:9]
              + d[3] * L[:, None] * E[:, 9:12] + d[2] * self.dX) / L[:, None]
        lam2 = np.einsum("ij,ij->i", rp, rp)
        return (self.N0() + self.EA * 0.5 * (lam2 - 1.0)) * np.sqrt(lam2)

    def outputs(self, x_full) -> dict[str, np.ndarray]:
        return {"tension": self.tensions(x_full)}
