"""Planar ANCF beam elements (gradient-deficient, Berzeri & Shabana 2000) for the flexible
DSA-380 pantograph (substitute for the thesis' ANSYS *Beam* model, section 2.2).

Each node carries its position r and slope r_x = dr/dx (x: arc length of the straight,
stress-free element), four coordinates per node, eight per element::

    e = (r1, r1_x, r2, r2_x),   r(x) = S(x) e,   S = [N1 I, N2 I, N3 I, N4 I]

with the cubic Hermite functions N1 = 1 - 3 xi^2 + 2 xi^3, N2 = l (xi - 2 xi^2 + xi^3),
N3 = 3 xi^2 - 2 xi^3, N4 = l (xi^3 - xi^2), xi = x / l. The interpolation reproduces every
rigid motion exactly (r linear in x, |r_x| = 1), so a stiff element moves as a rigid bar.

Kinetic energy (constant, consistent mass matrix; Rayleigh rotary inertia through the slope,
since |r_x| = 1 gives |d r_x / dt| = |d phi / dt|):

    T = 1/2 int rho A |r_t|^2 dx + 1/2 int rho I |r_x,t|^2 dx
      => M_e = int (rho A S^T S + rho I S_x^T S_x) dx.

A uniform tube then has exactly the rigid bar's mass m and inertia m (L^2/12 + (r_e^2 +
r_i^2)/4) about its centre, the values of the rigid model (thesis Table 2.1, (2.29)).

Strain energy (Euler-Bernoulli, geometrically exact in rotation, small strain):

    U = 1/2 int (EA eps^2 + EI kappa^2) dx,
    eps = (r_x . r_x - 1) / 2,   kappa = (r_x x r_xx) / |r_x|^3,

measured from the straight reference (see :func:`elastic_elements`) and integrated with
5 Gauss points. :func:`elastic_elements` returns, for every element, the
elastic force dU/de and its exact Hessian (material + geometric stiffness), vectorised over
elements; :func:`gather` and :func:`scatter_add` map element and global coordinates through
per-node-pair 2x2 transformations (identity for shared positions/slopes, a fixed rotation for
welded joints, none for grounded points).
"""

from __future__ import annotations


import numpy as np
from numba import njit

# 5-point Gauss-Legendre rule on [0, 1]
_GX, _GW = np.polynomial.legendre.leggauss(5)
GAUSS_XI = 0.5 * (_GX + 1.0)
GAUSS_W = 0.5 * _GW


@njit(cache=True, error_model="numpy")
def shape_derivatives(xi, l):
    """Hermite functions and their x-derivatives at xi: arrays N, N_x, N_xx (length 4)."""
    N = np.empty(4)
    Nx = np.empty(4)
    Nxx = np.empty(4)
    x2 = xi * xi
    x3 = x2 * xi
    N[0] = 1.0 - 3.0 * x2 + 2.0 * x3
    N[1] = l * (xi - 2.0 * x2 + x3)
    N[2] = 3.0 * x2 - 2.0 * x3
    N[3] = l * (x3 - x2)
    Nx[0] = (-6.0 * xi + 6.0 * x2) / l
    Nx[1] = 1.0 - 4.0 * xi + 3.0 * x2
    Nx[2] = (6.0 * xi - 6.0 * x2) / l
    Nx[3] = 3.0 * x2 - 2.0 * xi
    Nxx[0] = (-6.0 + 12.0 * xi) / (l * l)
    Nxx[1] = (-4.0 + 6.0 * xi) / l
    Nxx[2] = (6.0 - 12.0 * xi) / (l * l)
    Nxx[3] = (6.0 * xi - 2.0) / l
    return N, Nx, Nxx


def element_mass(l: float, rho_a: float, rho_i: float) -> np.ndarray:
    """Consistent mass matrix M_e = int (rho A S^T S + rho I S_x^T S_x) dx (8 x 8)."""
    M = np.zeros((8, 8))
    for xi, w in zip(GAUSS_XI, GAUSS_W):
        N, Nx, _ = shape_derivatives(float(xi), float(l))
        S = np.kron(N[None, :], np.eye(2))
        Sx = np.kron(Nx[None, :], np.eye(2))
        M += w * l * (rho_a * S.T @ S + rho_i * Sx.T @ Sx)
    return M


def element_gravity(l: float, rho_a: float, g: float) -> np.ndarray:
    """Generalised gravity force Q_g = int rho A S^T (0, -g) dx (8,); V_g = -Q_g . e."""
    Q = np.zeros(8)
    for xi, w in zip(GAUSS_XI, GAUSS_W):
        N, _, _ = shape_derivatives(float(xi), float(l))
        Q[1::2] += -w * l * rho_a * g * N
    return Q


@njit(cache=True, error_model="numpy")
def elastic_elements(E0, dE, length, EA, EI, xi_g, w_g, out_f, out_K, out_U):
    """Elastic forces and exact stiffness of every element (vectorised over elements).

    E0[k] (8,) coordinates of element k in its straight, stress-free reference configuration,
    dE[k] its displacement from there (e = E0 + dE). The strains are measured from the
    reference, eps = r0_x . dr_x + |dr_x|^2 / 2 and kappa - kappa0, so they keep full relative
    precision however far the element sits from the origin (no round-off floor from absolute
    coordinates). out_f[k] = dU/de, out_K[k] = d2U/de2 (8 x 8), out_U[k] = (axial energy,
    bending energy)."""
    ne = E0.shape[0]
    ng = xi_g.shape[0]
    Sx = np.zeros((2, 8))
    Sxx = np.zeros((2, 8))
    ce = np.empty(8)
    se = np.empty(8)
    ke = np.empty(8)
    epse = np.empty(8)
    for k in range(ne):
        l = length[k]
        for i in range(8):
            out_f[k, i] = 0.0
            for j in range(8):
                out_K[k, i, j] = 0.0
        out_U[k, 0] = 0.0
        out_U[k, 1] = 0.0
        for gp in range(ng):
            N, Nx, Nxx = shape_derivatives(xi_g[gp], l)
            wl = w_g[gp] * l
            for a in range(4):
                Sx[0, 2 * a] = Nx[a]
                Sx[1, 2 * a + 1] = Nx[a]
                Sxx[0, 2 * a] = Nxx[a]
                Sxx[1, 2 * a + 1] = Nxx[a]
            r0x = 0.0
            r0y = 0.0
            r0xx = 0.0
            r0yy = 0.0
            for a in range(4):
                r0x += Nx[a] * E0[k, 2 * a]
                r0y += Nx[a] * E0[k, 2 * a + 1]
                r0xx += Nxx[a] * E0[k, 2 * a]
                r0yy += Nxx[a] * E0[k, 2 * a + 1]
            # N1' = -N3' and N1'' = -N3'': the displacement of node 1 drops out exactly; take
            # the node difference first so the element's translation leaves no round-off
            ux = dE[k, 4] - dE[k, 0]
            uy = dE[k, 5] - dE[k, 1]
            dx = Nx[2] * ux + Nx[1] * dE[k, 2] + Nx[3] * dE[k, 6]
            dy = Nx[2] * uy + Nx[1] * dE[k, 3] + Nx[3] * dE[k, 7]
            dxx = Nxx[2] * ux + Nxx[1] * dE[k, 2] + Nxx[3] * dE[k, 6]
            dyy = Nxx[2] * uy + Nxx[1] * dE[k, 3] + Nxx[3] * dE[k, 7]
            rx0 = r0x + dx
            rx1 = r0y + dy
            rxx0 = r0xx + dxx
            rxx1 = r0yy + dyy
            s0 = r0x * r0x + r0y * r0y
            kap0 = (r0x * r0yy - r0y * r0xx) * s0 ** -1.5
            eps = r0x * dx + r0y * dy + 0.5 * (dx * dx + dy * dy)
            s = rx0 * rx0 + rx1 * rx1
            c = rx0 * rxx1 - rx1 * rxx0
            s32 = s ** -1.5
            s52 = s32 / s
            s72 = s52 / s
            kap = c * s32 - kap0
            # first derivatives: eps_e = Sx^T r_x, s_e = 2 eps_e, c_e = Sx^T J r_xx + Sxx^T J^T r_x
            for i in range(8):
                epse[i] = Sx[0, i] * rx0 + Sx[1, i] * rx1
                se[i] = 2.0 * epse[i]
                ce[i] = Sx[0, i] * rxx1 - Sx[1, i] * rxx0 + Sxx[1, i] * rx0 - Sxx[0, i] * rx1
                ke[i] = s32 * ce[i] - 1.5 * c * s52 * se[i]
            ea = EA[k] * wl
            ei = EI[k] * wl
            out_U[k, 0] += 0.5 * ea * eps * eps
            out_U[k, 1] += 0.5 * ei * kap * kap
            for i in range(8):
                out_f[k, i] += ea * eps * epse[i] + ei * kap * ke[i]
            for i in range(8):
                for j in range(8):
                    sxsx = Sx[0, i] * Sx[0, j] + Sx[1, i] * Sx[1, j]
                    cee = Sx[0, i] * Sxx[1, j] - Sx[1, i] * Sxx[0, j] \
                        + Sxx[1, i] * Sx[0, j] - Sxx[0, i] * Sx[1, j]
                    kee = (s32 * cee - 1.5 * s52 * (ce[i] * se[j] + se[i] * ce[j])
                           + 3.75 * c * s72 * se[i] * se[j] - 3.0 * c * s52 * sxsx)
                    out_K[k, i, j] += ea * (epse[i] * epse[j] + eps * sxsx) \
                        + ei * (ke[i] * ke[j] + kap * kee)
    return 0


@njit(cache=True, error_model="numpy")
def gather(q, pg, pR, pc, out_E):
    """Element coordinates from global ones: pair p of element k is R q[g:g+2] + c (g >= 0)
    or the constant c (g < 0: grounded)."""
    ne = pg.shape[0]
    for k in range(ne):
        for p in range(4):
            g = pg[k, p]
            for i in range(2):
                s = pc[k, p, i]
                if g >= 0:
                    s += pR[k, p, i, 0] * q[g] + pR[k, p, i, 1] * q[g + 1]
                out_E[k, 2 * p + i] = s
    return 0


@njit(cache=True, error_model="numpy")
def scatter_add(pg, pR, Fe, Ke, f, K, with_K):
    """f += T^T Fe and (with_K) K += T^T Ke T over all elements (T from pg, pR)."""
    ne = pg.shape[0]
    tmp = np.empty((2, 2))
    for k in range(ne):
        for p in range(4):
            gp = pg[k, p]
            if gp < 0:
                continue
            for j in range(2):
                f[gp + j] += pR[k, p, 0, j] * Fe[k, 2 * p] + pR[k, p, 1, j] * Fe[k, 2 * p + 1]
            if not with_K:
                continue
            for r in range(4):
                gr = pg[k, r]
                if gr < 0:
                    continue
                # tmp = R_p^T Ke[p, r] R_r
                for j in range(2):
                    for m in range(2):
                        s = 0.0
                        for i in range(2):
                            for n in range(2):
                                s += pR[k, p, i, j] * Ke[k, 2 * p + i, 2 * r + n] * pR[k, r, n, m]
                        tmp[j, m] = s
                for j in range(2):
                    for m in range(2):
                        K[gp + j, gr + m] += tmp[j, m]
    return 0
