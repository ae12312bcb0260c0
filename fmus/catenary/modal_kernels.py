"""The modal catenary's per-step loops (numba): the contact points at a time, the predictor
with the free forces, the step's solves (:func:`solve_step`) and its end with the slack check
(:func:`finish_step`). Nothing here allocates but the small results."""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.small_dense import gauss_jordan
from .ancf_cable import shape, shape_dxi
from .contact_point import _local_coordinate


@njit(cache=True)
def locate_points(xs, x_start, x_end, E_x, Le, elem_s, z4, S_idx, w, dw, offset, doffset):
    """For each track position xs[k]: the S indices of its contact element's 4 DOFs
    (-1: fixed), the interpolation weights and their x-derivatives (3.12)-(3.13), and the
    static wire height and slope there (offset, doffset). Returns the element positions."""
    n_el = x_start.shape[0]
    out = np.empty(xs.shape[0], dtype=np.int64)
    for k in range(xs.shape[0]):
        x = xs[k]
        e = np.searchsorted(x_start, x, side="right") - 1
        e = min(max(e, 0), n_el - 1)
        c = E_x[e]
        L = Le[e]
        xi0 = (x - x_start[e]) / max(x_end[e] - x_start[e], 1e-300)
        xi = _local_coordinate(c, L, x, xi0)
        sw = shape(xi, L)
        sd = shape_dxi(xi, L)
        dxdxi = (sd * c).sum()
        o = 0.0
        od = 0.0
        for i in range(4):
            S_idx[k, i] = elem_s[e, i]
            w[k, i] = sw[i]
            dw[k, i] = sd[i] / dxdxi
            o += w[k, i] * z4[e, i]
            od += dw[k, i] * z4[e, i]
        offset[k] = o
        doffset[k] = od
        out[k] = e
    return out


@njit(cache=True)
def point_rows(S_idx, w, dw, Phi_S, Q_S, phi, phix, qd, qdx):
    """phi_k = w_k . Phi[S_k], its x-derivative, and the same on Q (the droppers' residual
    shapes) at each contact point."""
    npan = S_idx.shape[0]
    m = Phi_S.shape[1]
    nz = qd.shape[1]
    for k in range(npan):
        for j in range(m):
            phi[k, j] = 0.0
            phix[k, j] = 0.0
        for j in range(nz):
            qd[k, j] = 0.0
            qdx[k, j] = 0.0
        for i in range(4):
            s = S_idx[k, i]
            if s < 0:
                continue
            a, b = w[k, i], dw[k, i]
            for j in range(m):
                p = Phi_S[s, j]
                phi[k, j] += a * p
                phix[k, j] += b * p
            for j in range(nz):
                p = Q_S[s, j]
                qd[k, j] += a * p
                qdx[k, j] += b * p


@njit(cache=True)
def residual_flexibility(S_idx, w, C_band, band, phi, inv_omega2, qd, kbar, G, Ginv):
    """G_jk = N_j^T K0^-1 N_k - phi_j Omega^-2 phi_k^T - qd_j qd_k / k: the contact points'
    residual flexibility, and its inverse. False if a pair lies outside the tabulated band."""
    npan = S_idx.shape[0]
    m = inv_omega2.shape[0]
    nz = qd.shape[1]
    for j in range(npan):
        for k in range(npan):
            g = 0.0
            for a in range(4):
                sa = S_idx[j, a]
                if sa < 0:
                    continue
                for b in range(4):
                    sb = S_idx[k, b]
                    if sb < 0:
                        continue
                    off = sb - sa + band
                    if off < 0 or off > 2 * band:
                        return False
                    g += w[j, a] * C_band[sa, off] * w[k, b]
            for i in range(m):
                g -= phi[j, i] * phi[k, i] * inv_omega2[i]
            if nz:
                for i in range(nz):
                    g -= qd[j, i] * qd[k, i] / kbar
            G[j, k] = g
    for j in range(npan):
        for k in range(j):
            s = 0.5 * (G[j, k] + G[k, j])
            G[j, k] = s
            G[k, j] = s
    if npan == 1:
        Ginv[0, 0] = 1.0 / G[0, 0]
    else:
        Ginv[...] = np.linalg.inv(G)
    return True


@njit(cache=True, fastmath=True)
def predict_rhs(q, v, a, f, h, alpha, beta, gamma, c_f, zeta_c, omega2, r0, kbar, beta_r,
                m, nz, Ginv, q_p, v_p, rhs):
    """Newmark predictors (3.16)-(3.17) and rhs = alpha f_n - c_f f_rest(y_p, v_p) without
    loads or slack terms, in one pass."""
    n = q.shape[0]
    cq = (0.5 - beta) * h * h
    cv = (1.0 - gamma) * h
    for i in range(m):
        qp = q[i] + h * v[i] + cq * a[i]
        vp = v[i] + cv * a[i]
        q_p[i] = qp
        v_p[i] = vp
        rhs[i] = alpha * f[i] - c_f * (zeta_c[i] * vp + omega2[i] * qp + r0[i])
    for i in range(m, m + nz):
        qp = q[i] + h * v[i] + cq * a[i]
        vp = v[i] + cv * a[i]
        q_p[i] = qp
        v_p[i] = vp
        rhs[i] = alpha * f[i] - c_f * (kbar * (qp + beta_r * vp) + r0[i])
    k0 = m + nz
    for i in range(k0, n):
        q_p[i] = q[i] + h * v[i] + cq * a[i]
        v_p[i] = v[i] + cv * a[i]
    for i in range(n - k0):
        s = 0.0
        for j in range(n - k0):
            s += Ginv[i, j] * q_p[k0 + j]
        rhs[k0 + i] = alpha * f[k0 + i] - c_f * (s + r0[k0 + i])


@njit(cache=True, fastmath=True)
def advance(q_p, v_p, delta, c_a, c_v, c_f, alpha, m, q, v, a, f):
    """q, v, a at t + h and f_{n+1} = (alpha f_n - f_inertia(a_{n+1})) / c_f, (3.16)."""
    for i in range(m):
        d = delta[i]
        q[i] = q_p[i] + d
        v[i] = v_p[i] + c_v * d
        a[i] = c_a * d
        f[i] = (alpha * f[i] - a[i]) / c_f
    for i in range(m, q.shape[0]):
        d = delta[i]
        q[i] = q_p[i] + d
        v[i] = v_p[i] + c_v * d
        a[i] = c_a * d
        f[i] = alpha * f[i] / c_f


@njit(cache=True)
def slack_mask(N0, ka, tension_only, e, out):
    """out_d = dropper d slack at elongation e_d; returns whether any is."""
    anyslack = False
    for d in range(N0.shape[0]):
        s = tension_only[d] and (N0[d] + ka[d] * e[d] < 0.0)
        out[d] = s
        anyslack = anyslack or s
    return anyslack


@njit(cache=True, fastmath=True)
def diag_woodbury(r, scale, inv_diag, K, G, c_f, U, T, rows, small_inv, s, y, out):
    """out = A^-1 (scale r): 1/diag on the first K rows less the Woodbury correction
    U_rows^T small^-1 (s * T_rows x) (U = T diag^-1: the rows of the slack droppers, ``y``
    their work vector), G r / c_f on the rest (identity when c_f = 0)."""
    n = r.shape[0]
    for i in range(K):
        out[i] = (r[i] * scale) * inv_diag[i]
    nx = n - K
    for i in range(nx):
        if c_f != 0.0:
            acc = 0.0
            for j in range(nx):
                acc += G[i, j] * (r[K + j] * scale)
            out[K + i] = acc / c_f
        else:
            out[K + i] = r[K + i] * scale
    ns = rows.shape[0]
    for a in range(ns):
        d = rows[a]
        acc = 0.0
        for i in range(K):
            acc += T[d, i] * out[i]
        y[a] = s[a] * acc
    for a in range(ns):
        z = 0.0
        for b in range(ns):
            z += small_inv[a, b] * y[b]
        d = rows[a]
        for i in range(K):
            out[i] += U[d, i] * z


@njit(cache=True)
def slack_block_inverse(gram, rows, s, work, out):
    """out = (I - diag(s) gram[rows][:, rows])^-1, the small matrix of the Woodbury solve
    (:func:`~pantocosim.core.small_dense.gauss_jordan` on ``work``, ns x 2 ns). Returns
    False when singular."""
    ns = rows.shape[0]
    for a in range(ns):
        for b in range(ns):
            work[a, b] = -s[a] * gram[rows[a], rows[b]]
            work[a, ns + b] = 0.0
        work[a, a] += 1.0
        work[a, ns + a] = 1.0
    if not gauss_jordan(work, ns):
        return False
    for a in range(ns):
        for b in range(ns):
            out[a, b] = work[a, ns + b]
    return True


@njit(cache=True, fastmath=True)
def add_loads(delta_free, W, F, delta):
    """delta = delta_free + sum_k F_k W_k."""
    n = delta.shape[0]
    for i in range(n):
        delta[i] = delta_free[i]
    for k in range(F.shape[0]):
        Fk = F[k]
        if Fk != 0.0:
            for i in range(n):
                delta[i] += Fk * W[k, i]


@njit(cache=True, fastmath={"reassoc", "contract"})
def _row_dot32(T32, d, y32):
    acc = np.float32(0.0)
    for j in range(y32.shape[0]):
        acc += T32[d, j] * y32[j]
    return acc


@njit(cache=True, fastmath=True)
def _row_dot(T_K, d, q_p, delta):
    acc = 0.0
    for j in range(T_K.shape[1]):
        acc += T_K[d, j] * (q_p[j] + delta[j])
    return acc


#: coordinates per block of the slack check's bounds (a constant: the loops unroll)
SCREEN_BLOCK = 32


@njit(inline="always")
def _drift_block(q_p, delta, y_ref, j0, j1, y32):
    """y = q_p + delta on j0 <= j < j1 into y32; (||y||_2^2, ||y||_1, ||y - y_ref||_2^2)."""
    ss = 0.0
    s1 = 0.0
    s2 = 0.0
    for j in range(j0, j1):
        yj = q_p[j] + delta[j]
        y32[j] = yj
        ss += yj * yj
        s1 += abs(yj)
        dj = yj - y_ref[j]
        s2 += dj * dj
    return ss, s1, s2


@njit(cache=True, fastmath={"reassoc", "contract"})
def _drift_pass(q_p, delta, y_ref, y32, xb):
    """y = q_p + delta on the first K coordinates, in single precision into y32; on blocks
    of SCREEN_BLOCK coordinates xb[0, b] = ||(y - y_ref)_b||_2 and xb[1, b] = ||y_b||_1.
    Returns ||y||_2."""
    K = y32.shape[0]
    ss = 0.0
    for b in range(xb.shape[1]):
        j0 = b * SCREEN_BLOCK
        if j0 + SCREEN_BLOCK <= K:
            s, s1, s2 = _drift_block(q_p, delta, y_ref, j0, j0 + SCREEN_BLOCK, y32)
        else:
            s, s1, s2 = _drift_block(q_p, delta, y_ref, j0, K, y32)
        ss += s
        xb[0, b] = np.sqrt(s2)
        xb[1, b] = s1
    return np.sqrt(ss)


@njit(cache=True, fastmath={"reassoc", "contract"})
def _block_dot(Tb, d, x):
    acc = 0.0
    for b in range(x.shape[0]):
        acc += Tb[d, b] * x[b]
    return acc


@njit(cache=True)
def _row_force(T32, T_K, Tm, tol, N0, ka, d, q_p, delta, y32, y1, ny):
    """(N0_d + k_a t_d . y, a bound of its error): in single precision when that decides
    the sign, else in double precision. The bound: tol sum_b Tm_db ||y_b||_1 >=
    2 gamma_{K+2} |k_a| sum_j |t_dj y_j| (the rounding of t_d, of y and of a sum of K
    products in any order; gamma_n = n u / (1 - n u))."""
    sy = _block_dot(Tm, d, y1)
    if ny < 1e30:                            # False for inf/NaN
        r = N0[d] + ka[d] * np.float64(_row_dot32(T32, d, y32))
        b = tol[0] * sy + 1e-25              # + the underflow of single precision
        if abs(r) > b:
            return r, b
    return N0[d] + ka[d] * _row_dot(T_K, d, q_p, delta), tol[1] * sy + 1e-25


@njit(cache=True)
def screen_slack(T32, T_K, Tb, Tm, tol, N0, ka, tension_only, most, q_p, delta, y_ref, ref,
                 xb, y32, slack):
    """slack_d: tension-only dropper d slack at y = q_p + delta (N0_d + k_a t_d . y < 0)
    without the whole product T y[:K] each step. Kept: the forces ref[0] at y_ref and
    bounds ref[1] of their error; |k_a t_d . (y - y_ref)| <= sum_b Tb_db ||(y - y_ref)_b||_2
    (Cauchy-Schwarz on blocks) settles most droppers. The others (marked in ref[2]) take
    their row (:func:`_row_force`); more than ``most`` of them: every row, and y becomes the
    reference. The set is the double-precision one."""
    ny = _drift_pass(q_p, delta, y_ref, y32, xb)
    nd = slack.shape[0]
    open_ = 0
    for d in range(nd):
        slack[d] = False
        if tension_only[d]:
            if abs(ref[0, d]) > ref[1, d] + _block_dot(Tb, d, xb[0]):   # False for NaN
                slack[d] = ref[0, d] < 0.0
            else:
                open_ += 1
                ref[2, d] = 1.0
    refresh = open_ > most
    for d in range(nd):
        if tension_only[d] and (refresh or ref[2, d] != 0.0):
            r, b = _row_force(T32, T_K, Tm, tol, N0, ka, d, q_p, delta, y32, xb[1], ny)
            slack[d] = r < 0.0
            ref[2, d] = 0.0
            if refresh:
                ref[0, d] = r
                ref[1, d] = b
    if refresh:
        for j in range(y_ref.shape[0]):
            y_ref[j] = q_p[j] + delta[j]


@njit(cache=True)
def finish_step(delta_free, W, F, q_p, v_p, T32, T_K, Tb, Tm, tol, N0, ka, tension_only,
                most, y_ref, ref, xb, y32, previous, committed, c_a, c_v, c_f, alpha, m, delta,
                slack, q, v, a, f):
    """delta = delta_free + sum_k F_k W_k and the slack set at q_p + delta
    (:func:`screen_slack`); -1 (nothing advanced) when it is not ``previous`` (the step's
    set), else the step is taken (:func:`advance`) and the result is whether the set
    differs from ``committed``."""
    add_loads(delta_free, W, F, delta)
    screen_slack(T32, T_K, Tb, Tm, tol, N0, ka, tension_only, most, q_p, delta, y_ref, ref,
                 xb, y32, slack)
    for d in range(slack.shape[0]):
        if slack[d] != previous[d]:
            return -1
    advance(q_p, v_p, delta, c_a, c_v, c_f, alpha, m, q, v, a, f)
    for d in range(slack.shape[0]):
        if slack[d] != committed[d]:
            return 1
    return 0


@njit(cache=True, fastmath=True)
def slack_forces(T_K, N0, ka, beta, slack, committed, y, v, out):
    """out[:K] = sum_{d slack} (N0_d + k_a t_d . y) t_d + sum_{d committed} beta k_a
    (t_d . v) t_d: the forces the slack droppers no longer carry."""
    nd, K = T_K.shape
    for i in range(out.shape[0]):
        out[i] = 0.0
    for d in range(nd):
        c = 0.0
        if slack[d]:
            acc = 0.0
            for j in range(K):
                acc += T_K[d, j] * y[j]
            c += N0[d] + ka[d] * acc
        if committed[d]:
            acc = 0.0
            for j in range(K):
                acc += T_K[d, j] * v[j]
            c += beta * ka[d] * acc
        if c != 0.0:
            for j in range(K):
                out[j] += c * T_K[d, j]


@njit(cache=True)
def solve_step(rhs, q_p, v_p, c_f, T_K, N0, ka, beta, slack, committed, inv_diag, G, U, rows,
               small_inv, s, y, L, sf, r, delta_free, W):
    """delta_free = A^-1 (rhs + c_f sf) with sf the slack and committed droppers' terms at
    (q_p, v_p) (:func:`slack_forces`), and W_k = A^-1 (c_f L_k) for each load row L_k
    (A^-1: :func:`diag_woodbury`)."""
    K = inv_diag.shape[0]
    active = False
    for d in range(slack.shape[0]):
        active = active or slack[d] or committed[d]
    if active:
        slack_forces(T_K, N0, ka, beta, slack, committed, q_p, v_p, sf)
        for i in range(rhs.shape[0]):
            r[i] = sf[i] * c_f + rhs[i]
        diag_woodbury(r, 1.0, inv_diag, K, G, c_f, U, T_K, rows, small_inv, s, y, delta_free)
    else:
        diag_woodbury(rhs, 1.0, inv_diag, K, G, c_f, U, T_K, rows, small_inv, s, y, delta_free)
    for k in range(L.shape[0]):
        diag_woodbury(L[k], c_f, inv_diag, K, G, c_f, U, T_K, rows, small_inv, s, y, W[k])


@njit(cache=True, fastmath=True)
def support_uplift(Phi_sup, Q_sup, C_sup, inv_omega2, kbar, S_idx, w, phi, qd, Ginv, y, m, nz,
                   nx, yt, c, out):
    """Uplift at the supports, Phi_sup eta + Q_sup zeta + psi_sup(t) G^-1 xi, with
    psi_sup = C_sup N - Phi_sup Omega^-2 phi^T - Q_sup qd^T / k (the contact points' residual
    modes at the supports): with c = G^-1 xi, the residual part is folded into the
    coordinates, yt = (eta - Omega^-2 phi^T c, zeta - qd^T c / k), so one pass over Phi_sup
    and Q_sup gives out = Phi_sup yt[:m] + Q_sup yt[m:] + C_sup N c."""
    for i in range(m + nz):
        yt[i] = y[i]
    for j in range(nx):
        s = 0.0
        for k in range(nx):
            s += Ginv[j, k] * y[m + nz + k]
        c[j] = s
        pj = phi[j]
        for i in range(m):
            yt[i] -= s * pj[i] * inv_omega2[i]
        qj = qd[j]
        for i in range(nz):
            yt[m + i] -= s * qj[i] / kbar
    for r in range(Phi_sup.shape[0]):
        acc = 0.0
        for j in range(nx):
            for i in range(4):
                if S_idx[j, i] >= 0:
                    acc += C_sup[r, S_idx[j, i]] * w[j, i] * c[j]
        pr = Phi_sup[r]
        for i in range(m):
            acc += pr[i] * yt[i]
        qr = Q_sup[r]
        for i in range(nz):
            acc += qr[i] * yt[m + i]
        out[r] = acc


def warm_up() -> None:
    """Compile (or load from numba's cache) every kernel at set-up, not in the first step."""
    f1, f2 = np.zeros(2), np.zeros((1, 2))
    i4 = -np.ones((1, 4), dtype=np.int64)
    b = np.zeros(1, dtype=np.bool_)
    w4, z4 = np.zeros((1, 4)), np.zeros((1, 4))
    locate_points(np.zeros(1), np.zeros(1), np.ones(1), np.ones((1, 4)), np.ones(1), i4, z4,
                  i4.copy(), w4, w4.copy(), np.zeros(1), np.zeros(1))
    point_rows(i4, w4, w4, f2, f2, f2.copy(), f2.copy(), f2.copy(), f2.copy())
    residual_flexibility(np.zeros((1, 4), dtype=np.int64), np.ones((1, 4)), np.ones((1, 1)), 0,
                         f2, np.ones(2), f2, 1.0, np.ones((1, 1)), np.ones((1, 1)))
    predict_rhs(f1, f1, f1, f1, 1.0, 0.0, 0.25, 0.5, 1.0, np.zeros(1), np.ones(1), f1, 1.0,
                0.0, 1, 1, np.zeros((0, 0)), f1.copy(), f1.copy(), f1.copy())
    slack_mask(np.ones(1), np.ones(1), b, np.zeros(1), b.copy())
    support_uplift(f2, f2.copy(), np.zeros((1, 1)), np.ones(2), 1.0, i4, w4, f2, f2.copy(),
                   np.ones((1, 1)), np.zeros(4), 1, 1, 1, np.zeros(2), np.zeros(1), np.zeros(1))
    i0 = np.zeros(0, dtype=np.int64)
    slack_block_inverse(np.ones((1, 1)), np.zeros(1, dtype=np.int64), np.zeros(1),
                        np.zeros((1, 2)), np.zeros((1, 1)))
    diag_woodbury(f1, 1.0, np.ones(1), 1, np.ones((1, 1)), 1.0, np.zeros((1, 1)),
                  np.zeros((1, 1)), i0, np.zeros((0, 0)), np.zeros(0), np.zeros(0), f1.copy())
    solve_step(f1, f1, f1, 1.0, np.zeros((1, 2)), np.ones(1), np.ones(1), 0.0, b, b, np.ones(2),
               np.ones((0, 0)), np.zeros((1, 2)), i0, np.zeros((0, 0)), np.zeros(0),
               np.zeros(0), f2, f1.copy(), f1.copy(), f1.copy(), f2.copy())
    ref = np.zeros((3, 1))
    ref[0] = np.nan
    finish_step(f1, f2, np.zeros(1), f1, f1, np.zeros((1, 2), np.float32), np.zeros((1, 2)),
                np.ones((1, 1)), np.ones((1, 1)), np.ones(2), np.ones(1), np.ones(1), b, 0,
                np.zeros(2), ref, np.zeros((2, 1)), np.zeros(2, np.float32), b, b, 1.0, 1.0,
                1.0, 0.0, 1, f1.copy(), b.copy(), f1.copy(), f1.copy(), f1.copy(), f1.copy())
    slack_forces(np.zeros((1, 2)), np.ones(1), np.ones(1), 0.0, b, b, f1, f1, f1.copy())
