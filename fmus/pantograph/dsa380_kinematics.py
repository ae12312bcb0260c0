"""Numba kernels of the rigid DSA-380 pantograph (thesis 2.1.1, annex A).

The mechanism (bars 1-6) is a one-degree-of-freedom subsystem in the lower-arm angle theta:
the lower loop fixed-1-2-3 and the upper loop 1-4-5-6 (A.1) are closed in closed form
(circle intersections, equivalent to (A.2)-(A.3)), and every point, centre of gravity and bar
angle is carried as a truncated Taylor series ("jet") in theta up to third order. Implicit
differentiation of the loops (A.4)-(A.5) is thereby exact to machine precision, and the
generalised inertia A(theta) = sum m_i |dr_Gi/dtheta|^2 + I_i (dphi_i/dtheta)^2 (A.7) comes
with A' and A'' (needed by the Coriolis term and its tangent, (3.30)).

The collector (bar 7) is a rigid body in (x10, y10, theta7) with its centre of gravity at
L_G7, theta_G7 from point 10 (A.6)-(A.9). Two springs k_l join point 5 to the collector ends
11, 12 (A.11), a torsional spring k_r acts at joint 1 (A.10) and a linear damper c joins the
fixed point 13 to point 1p of bar 1 (A.13)-(A.19).

Every kernel works on a flat parameter vector whose layout is given by the index constants
below (filled by :class:`pantocosim.pantograph.dsa380.Dsa380Parameters`).

Residual convention of :mod:`pantocosim.core.model`: f_inertia = M(q) a and
f_rest = Coriolis + dV/dq + damper + friction - actuation - aero + F * dh/dq, with F >= 0 the
contact force pushing point 10 down. The Lagrange equations are derived from
T = 1/2 qdot^T M(q) qdot (not the thesis' inconsistent A thetadot^2 bookkeeping (A.8)-(A.31)):
    d/dt(dT/dqdot) - dT/dq = M qddot + c(q, qdot),
    c_theta = 1/2 A'(theta) thetadot^2,
    c_x10 = -m7 L_G7 cos(theta7 - theta_G7) theta7dot^2,
    c_y10 = -m7 L_G7 sin(theta7 - theta_G7) theta7dot^2,  c_theta7 = 0.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# ---------------------------------------------------------------------------------------
# parameter vector layout
X1, Y1, X2, Y2, X13, Y13 = 0, 1, 2, 3, 4, 5
L1, L2, L3, L4, L5, L6, L7 = 6, 7, 8, 9, 10, 11, 12
TH34, R6, THR, L1P, TH1P = 13, 14, 15, 16, 17
SIG_LO, SIG_UP = 18, 19
M_ = 20   # m1..m7   -> 20..26
I_ = 27   # I1..I7   -> 27..33 (about the centre of gravity)
LG_ = 34  # L_G1..L_G7 -> 34..40
THG_ = 41  # theta_G1..theta_G7 -> 41..47
KR, THR0, KL, LL0, CDAMP, GRAV = 48, 49, 50, 51, 52, 53
NPAR = 54

# ---------------------------------------------------------------------------------------
# truncated Taylor series of order 3: (f, f', f''/2, f'''/6)


@njit(cache=True, inline="always", error_model="numpy")
def _jc(c):
    return (c, 0.0, 0.0, 0.0)


@njit(cache=True, inline="always", error_model="numpy")
def _jadd(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3])


@njit(cache=True, inline="always", error_model="numpy")
def _jsub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3])


@njit(cache=True, inline="always", error_model="numpy")
def _jscale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s, a[3] * s)


@njit(cache=True, inline="always", error_model="numpy")
def _jaddc(a, c):
    return (a[0] + c, a[1], a[2], a[3])


@njit(cache=True, inline="always", error_model="numpy")
def _jmul(a, b):
    return (a[0] * b[0],
            a[0] * b[1] + a[1] * b[0],
            a[0] * b[2] + a[1] * b[1] + a[2] * b[0],
            a[0] * b[3] + a[1] * b[2] + a[2] * b[1] + a[3] * b[0])


@njit(cache=True, inline="always", error_model="numpy")
def _jdiv(a, b):
    c0 = a[0] / b[0]
    c1 = (a[1] - b[1] * c0) / b[0]
    c2 = (a[2] - b[1] * c1 - b[2] * c0) / b[0]
    c3 = (a[3] - b[1] * c2 - b[2] * c1 - b[3] * c0) / b[0]
    return (c0, c1, c2, c3)


@njit(cache=True, inline="always", error_model="numpy")
def _jsqrt(a):
    c0 = math.sqrt(a[0])
    c1 = a[1] / (2.0 * c0)
    c2 = (a[2] - c1 * c1) / (2.0 * c0)
    c3 = (a[3] - 2.0 * c1 * c2) / (2.0 * c0)
    return (c0, c1, c2, c3)


@njit(cache=True, inline="always", error_model="numpy")
def _jsincos(a):
    s0 = math.sin(a[0])
    c0 = math.cos(a[0])
    s1 = a[1] * c0
    c1 = -a[1] * s0
    s2 = (a[1] * c1 + 2.0 * a[2] * c0) / 2.0
    c2 = -(a[1] * s1 + 2.0 * a[2] * s0) / 2.0
    s3 = (a[1] * c2 + 2.0 * a[2] * c1 + 3.0 * a[3] * c0) / 3.0
    c3 = -(a[1] * s2 + 2.0 * a[2] * s1 + 3.0 * a[3] * s0) / 3.0
    return (s0, s1, s2, s3), (c0, c1, c2, c3)


@njit(cache=True, inline="always", error_model="numpy")
def _jderiv(a):
    """d/dtheta of a jet (the top coefficient is lost)."""
    return (a[1], 2.0 * a[2], 3.0 * a[3], 0.0)


@njit(cache=True, inline="always", error_model="numpy")
def _jatan2(y, x):
    r2 = _jadd(_jmul(x, x), _jmul(y, y))
    w = _jdiv(_jsub(_jmul(x, _jderiv(y)), _jmul(y, _jderiv(x))), r2)
    return (math.atan2(y[0], x[0]), w[0], w[1] / 2.0, w[2] / 3.0)


@njit(cache=True, inline="always", error_model="numpy")
def _circle_point(px, py, qx, qy, la, lb, sigma):
    """Joint of a two-bar chain P -(la)- X -(lb)- Q (closed form of (A.2)-(A.3)).

    Returns the jets of X and h^2 (negative when the loop cannot close)."""
    dx = _jsub(qx, px)
    dy = _jsub(qy, py)
    d2 = _jadd(_jmul(dx, dx), _jmul(dy, dy))
    d = _jsqrt(d2)
    aa = _jdiv(_jaddc(d2, la * la - lb * lb), _jscale(d, 2.0))
    h2 = _jsub(_jc(la * la), _jmul(aa, aa))
    if h2[0] <= 0.0:
        return px, py, h2[0]
    h = _jscale(_jsqrt(h2), sigma)
    fa = _jdiv(aa, d)
    fh = _jdiv(h, d)
    xx = _jadd(px, _jsub(_jmul(fa, dx), _jmul(fh, dy)))
    yy = _jadd(py, _jadd(_jmul(fa, dy), _jmul(fh, dx)))
    return xx, yy, h2[0]


@njit(cache=True, error_model="numpy")
def mechanism_jets(P, theta):
    """Positions of the mechanism as jets in theta.

    Returns (ok, pts, ang): ok = min h^2 of the two loops (> 0 when they close);
    pts[k, 0:2, :] = jets of x, y of points 1, 2, 3, 4, 5, 6, 5b (end of bar 5), 1p;
    ang[i, :] = jets of the angle of bar i+1 (bars 1..6)."""
    th = (theta, 1.0, 0.0, 0.0)
    s1, c1 = _jsincos(th)
    x1 = _jc(P[X1])
    y1 = _jc(P[Y1])
    x2 = _jc(P[X2])
    y2 = _jc(P[Y2])
    x4 = _jadd(x1, _jscale(c1, P[L1]))
    y4 = _jadd(y1, _jscale(s1, P[L1]))
    # lower loop fixed-1-2-3 (A.1): 2 -(L2)- 3 -(L3)- 4
    x3, y3, h_lo = _circle_point(x2, y2, x4, y4, P[L2], P[L3], P[SIG_LO])
    phi2 = _jatan2(_jsub(y3, y2), _jsub(x3, x2))
    phi3 = _jatan2(_jsub(y4, y3), _jsub(x4, x3))
    phi4 = _jaddc(phi3, P[TH34] - math.pi)
    s4, c4 = _jsincos(phi4)
    x5 = _jadd(x4, _jscale(c4, P[L4]))
    y5 = _jadd(y4, _jscale(s4, P[L4]))
    # upper loop 1-4-5-6 (A.1): 6 -(L5)- 5b -(L6)- 5, point 6 on bar 1 at (r, theta_r)
    s6, c6 = _jsincos(_jaddc(th, P[THR]))
    x6 = _jadd(x1, _jscale(c6, P[R6]))
    y6 = _jadd(y1, _jscale(s6, P[R6]))
    xb, yb, h_up = _circle_point(x6, y6, x5, y5, P[L5], P[L6], P[SIG_UP])
    phi5 = _jatan2(_jsub(yb, y6), _jsub(xb, x6))
    phi6 = _jatan2(_jsub(y5, yb), _jsub(x5, xb))
    # damper lever point 1p (A.13)
    sp, cp = _jsincos(_jaddc(th, P[TH1P]))
    xp = _jadd(x1, _jscale(cp, P[L1P]))
    yp = _jadd(y1, _jscale(sp, P[L1P]))

    pts = np.empty((8, 2, 4))
    ang = np.empty((6, 4))
    ok = min(h_lo, h_up)
    if ok <= 0.0:
        pts[:] = np.nan
        ang[:] = np.nan
        return ok, pts, ang
    xs = (x1, x2, x3, x4, x5, x6, xb, xp)
    ys = (y1, y2, y3, y4, y5, y6, yb, yp)
    for k in range(8):
        for j in range(4):
            pts[k, 0, j] = xs[k][j]
            pts[k, 1, j] = ys[k][j]
    phis = (th, phi2, phi3, phi4, phi5, phi6)
    for i in range(6):
        for j in range(4):
            ang[i, j] = phis[i][j]
    return ok, pts, ang


# start point (index into pts) of bars 1..6: 1 -> p1, 2 -> p2, 3 -> p3, 4 -> p4, 5 -> p6, 6 -> p5b
_BAR_START = (0, 1, 2, 3, 5, 6)


@njit(cache=True, error_model="numpy")
def mechanism_terms(P, theta):
    """Inertia A(theta) (A.7), gravity + torsional-spring potential (A.10) and point 5.

    Returns (ok, A, V, p5) with A = (A, A', A''), V = (V, V', V'') and
    p5 = (x5, y5, x5', y5', x5'', y5'') (derivatives with respect to theta)."""
    ok, pts, ang = mechanism_jets(P, theta)
    A = np.zeros(3)
    V = np.zeros(3)
    p5 = np.zeros(6)
    if ok <= 0.0:
        A[:] = np.nan
        V[:] = np.nan
        p5[:] = np.nan
        return ok, A, V, p5
    g = P[GRAV]
    for i in range(6):
        st = _BAR_START[i]
        phi = (ang[i, 0], ang[i, 1], ang[i, 2], ang[i, 3])
        sg, cg = _jsincos(_jaddc(phi, -P[THG_ + i]))
        xg = _jadd((pts[st, 0, 0], pts[st, 0, 1], pts[st, 0, 2], pts[st, 0, 3]),
                   _jscale(cg, P[LG_ + i]))
        yg = _jadd((pts[st, 1, 0], pts[st, 1, 1], pts[st, 1, 2], pts[st, 1, 3]),
                   _jscale(sg, P[LG_ + i]))
        xd = _jderiv(xg)
        yd = _jderiv(yg)
        wd = _jderiv(phi)
        ai = _jadd(_jscale(_jadd(_jmul(xd, xd), _jmul(yd, yd)), P[M_ + i]),
                   _jscale(_jmul(wd, wd), P[I_ + i]))
        A[0] += ai[0]
        A[1] += ai[1]
        A[2] += 2.0 * ai[2]
        V[0] += g * P[M_ + i] * yg[0]
        V[1] += g * P[M_ + i] * yg[1]
        V[2] += 2.0 * g * P[M_ + i] * yg[2]
    dth = theta - P[THR0]
    V[0] += 0.5 * P[KR] * dth * dth
    V[1] += P[KR] * dth
    V[2] += P[KR]
    p5[0] = pts[4, 0, 0]
    p5[1] = pts[4, 1, 0]
    p5[2] = pts[4, 0, 1]
    p5[3] = pts[4, 1, 1]
    p5[4] = 2.0 * pts[4, 0, 2]
    p5[5] = 2.0 * pts[4, 1, 2]
    return ok, A, V, p5


@njit(cache=True, error_model="numpy")
def damper_geometry(P, theta):
    """Damper length l_a and its theta-derivatives (A.14), (A.20): (l_a, l_a', l_a'')."""
    c = math.cos(theta + P[TH1P])
    s = math.sin(theta + P[TH1P])
    dx = P[X1] + P[L1P] * c - P[X13]
    dy = P[Y1] + P[L1P] * s - P[Y13]
    la = math.sqrt(dx * dx + dy * dy)
    tx = -P[L1P] * s
    ty = P[L1P] * c
    d1 = (dx * tx + dy * ty) / la
    d2 = (tx * tx + ty * ty - P[L1P] * (dx * c + dy * s)) / la - d1 * d1 / la
    return la, d1, d2


@njit(cache=True, error_model="numpy")
def evaluate_kernel(P, q, v, a, F, M_act, F_aero, f_r, k_t, one_way, out_vec, out_mat):
    """Residual pieces and exact tangents of the 4-DOF model (A.36), (3.27)-(3.34), (B.19).

    out_vec[0] = f_inertia, out_vec[1] = f_rest, out_vec[2] = (T, V, damper power,
    friction force); out_mat[0..3] = mass, inertia_q, damping, stiffness.
    Returns the loop-closure measure (<= 0: the mechanism cannot be assembled)."""
    theta = q[0]
    x10 = q[1]
    y10 = q[2]
    th7 = q[3]
    ok, A, V, p5 = mechanism_terms(P, theta)
    for k in range(4):
        out_vec[0, k] = 0.0
        out_vec[1, k] = 0.0
        out_vec[2, k] = 0.0
        for j in range(4):
            out_mat[0, k, j] = 0.0
            out_mat[1, k, j] = 0.0
            out_mat[2, k, j] = 0.0
            out_mat[3, k, j] = 0.0
    if ok <= 0.0:
        for k in range(4):
            out_vec[0, k] = np.nan
            out_vec[1, k] = np.nan
        return ok
    fin = out_vec[0]
    fr = out_vec[1]
    Mm = out_mat[0]
    Kin = out_mat[1]
    Cd = out_mat[2]
    Ks = out_mat[3]
    g = P[GRAV]
    m7 = P[M_ + 6]
    I7 = P[I_ + 6]
    LG7 = P[LG_ + 6]
    sg = math.sin(th7 - P[THG_ + 6])
    cg = math.cos(th7 - P[THG_ + 6])
    w = v[0]
    w7 = v[3]

    # ---- inertia (A.9) with A, E = -m7 LG7 sin, Phi = m7 LG7 cos, Delta = I7 + m7 LG7^2
    Mm[0, 0] = A[0]
    Mm[1, 1] = m7
    Mm[2, 2] = m7
    Mm[1, 3] = Mm[3, 1] = -m7 * LG7 * sg
    Mm[2, 3] = Mm[3, 2] = m7 * LG7 * cg
    Mm[3, 3] = I7 + m7 * LG7 * LG7
    for k in range(4):
        s = 0.0
        for j in range(4):
            s += Mm[k, j] * a[j]
        fin[k] = s
    # d(M a)/dq (3.28)
    Kin[0, 0] = A[1] * a[0]
    Kin[1, 3] = -m7 * LG7 * cg * a[3]
    Kin[2, 3] = -m7 * LG7 * sg * a[3]
    Kin[3, 3] = -m7 * LG7 * (cg * a[1] + sg * a[2])

    # ---- Coriolis / centrifugal (from T = 1/2 qdot^T M qdot)
    fr[0] += 0.5 * A[1] * w * w
    Ks[0, 0] += 0.5 * A[2] * w * w
    Cd[0, 0] += A[1] * w
    fr[1] += -m7 * LG7 * cg * w7 * w7
    fr[2] += -m7 * LG7 * sg * w7 * w7
    Ks[1, 3] += m7 * LG7 * sg * w7 * w7
    Ks[2, 3] += -m7 * LG7 * cg * w7 * w7
    Cd[1, 3] += -2.0 * m7 * LG7 * cg * w7
    Cd[2, 3] += -2.0 * m7 * LG7 * sg * w7

    # ---- potential: mechanism gravity + torsional spring (A.10), collector gravity
    fr[0] += V[1]
    Ks[0, 0] += V[2]
    fr[2] += m7 * g
    fr[3] += m7 * g * LG7 * cg
    Ks[3, 3] += -m7 * g * LG7 * sg
    Vtot = V[0] + m7 * g * (y10 + LG7 * sg)

    # ---- collector springs point 5 -> ends 11, 12 (A.11), Hessian (B.19)
    half = 0.5 * P[L7]
    c7 = math.cos(th7)
    s7 = math.sin(th7)
    kl = P[KL]
    l0 = P[LL0]
    D = np.empty((2, 4))
    gl = np.empty(4)
    for se in (-1.0, 1.0):
        dx = p5[0] - x10 - se * half * c7
        dy = p5[1] - y10 - se * half * s7
        ll = math.sqrt(dx * dx + dy * dy)
        ux = dx / ll
        uy = dy / ll
        D[0, 0] = p5[2]
        D[1, 0] = p5[3]
        D[0, 1] = -1.0
        D[1, 1] = 0.0
        D[0, 2] = 0.0
        D[1, 2] = -1.0
        D[0, 3] = se * half * s7
        D[1, 3] = -se * half * c7
        for j in range(4):
            gl[j] = ux * D[0, j] + uy * D[1, j]
        tension = kl * (ll - l0)
        Vtot += 0.5 * kl * (ll - l0) * (ll - l0)
        for k in range(4):
            fr[k] += tension * gl[k]
            for j in range(4):
                hkj = (D[0, k] * D[0, j] + D[1, k] * D[1, j] - gl[k] * gl[j]) / ll
                Ks[k, j] += kl * gl[k] * gl[j] + tension * hkj
        Ks[0, 0] += tension * (ux * p5[4] + uy * p5[5])
        Ks[3, 3] += tension * se * half * (ux * c7 + uy * s7)

    # ---- damper between 13 and 1p (A.13)-(A.19): generalised force c l_a'^2 thetadot
    la, la1, la2 = damper_geometry(P, theta)
    wdown = 1.0
    if one_way:
        # active only while the mechanism moves down (point 5 descends)
        if p5[3] * w > 0.0:
            wdown = 0.0
    cth = P[CDAMP] * wdown
    fr[0] += cth * la1 * la1 * w
    Cd[0, 0] += cth * la1 * la1
    Ks[0, 0] += 2.0 * cth * la1 * la2 * w
    damper_power = -cth * (la1 * w) ** 2

    # ---- collector friction (2.15)-(2.17), (3.31)-(3.33): v_r = y10dot - y5dot
    f_roz = 0.0
    if f_r > 0.0:
        vr = v[2] - p5[3] * w
        f_roz = f_r * (2.0 / math.pi) * math.atan(vr / k_t)
        df = f_r * (2.0 / math.pi) / (k_t + vr * vr / k_t)
        dvr_dth = -p5[5] * w
        fr[0] += -f_roz * p5[3]
        fr[2] += f_roz
        # d/dv: v_r depends on thetadot (-y5') and y10dot (1)
        Cd[0, 0] += df * p5[3] * p5[3]
        Cd[0, 2] += -df * p5[3]
        Cd[2, 0] += -df * p5[3]
        Cd[2, 2] += df
        # d/dq: through y5'(theta)
        Ks[0, 0] += -df * dvr_dth * p5[3] - f_roz * p5[5]
        Ks[2, 0] += df * dvr_dth

    # ---- actuation torque on bar 1, aerodynamic uplift and contact force on point 10
    fr[0] -= M_act
    fr[2] += F - F_aero

    # ---- energies
    T = 0.5 * A[0] * w * w
    for k in range(1, 4):
        for j in range(1, 4):
            T += 0.5 * v[k] * Mm[k, j] * v[j]
    out_vec[2, 0] = T
    out_vec[2, 1] = Vtot
    out_vec[2, 2] = damper_power
    out_vec[2, 3] = f_roz
    return ok


@njit(cache=True, error_model="numpy")
def mechanism_points(P, theta):
    """Positions (x, y) of points 1, 2, 3, 4, 5, 6, 5b, 1p at theta (NaN if not assembled)."""
    ok, pts, ang = mechanism_jets(P, theta)
    out = np.empty((8, 2))
    for k in range(8):
        out[k, 0] = pts[k, 0, 0]
        out[k, 1] = pts[k, 1, 0]
    return out
