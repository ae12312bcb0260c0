"""The modal catenary's per-step loops (numba): the contact points at a time, the predictor
with the free forces, the end of a step. Nothing here allocates but the small results."""

from __future__ import annotations

import numpy as np
from numba import njit

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
    loads or slack terms."""
    n = q.shape[0]
    cq = (0.5 - beta) * h * h
    cv = (1.0 - gamma) * h
    for i in range(n):
        q_p[i] = q[i] + h * v[i] + cq * a[i]
        v_p[i] = v[i] + cv * a[i]
    for i in range(m):
        rhs[i] = alpha * f[i] - c_f * (zeta_c[i] * v_p[i] + omega2[i] * q_p[i] + r0[i])
    for i in range(m, m + nz):
        rhs[i] = alpha * f[i] - c_f * (kbar * (q_p[i] + beta_r * v_p[i]) + r0[i])
    k0 = m + nz
    nx = n - k0
    for i in range(nx):
        s = 0.0
        for j in range(nx):
            s += Ginv[i, j] * q_p[k0 + j]
        rhs[k0 + i] = alpha * f[k0 + i] - c_f * (s + r0[k0 + i])


@njit(cache=True, fastmath=True)
def finish_step(q_p, v_p, delta, c_a, c_v, c_f, alpha, m, q, v, a, f):
    """q, v, a at t + h and f_{n+1} = (alpha f_n - f_inertia(a_{n+1})) / c_f, (3.16)."""
    n = q.shape[0]
    for i in range(n):
        d = delta[i]
        q[i] = q_p[i] + d
        v[i] = v_p[i] + c_v * d
        a[i] = c_a * d
        f[i] = alpha * f[i]
    for i in range(m):
        f[i] -= a[i]
    for i in range(n):
        f[i] /= c_f


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
def support_rows(S_idx, w, C_sup, Phi_sup_w, Q_sup_k, phi, qd, Ginv, out):
    """psi(t) G^-1 at the supports: out (nsup, np) = [C_sup N - Phi_sup Omega^-2 phi^T
    - Q_sup qd^T / k] G^-1 (Phi_sup_w = Phi_sup Omega^-2, Q_sup_k = Q_sup / k)."""
    nsup = C_sup.shape[0]
    npan = S_idx.shape[0]
    m = Phi_sup_w.shape[1]
    nz = qd.shape[1]
    H = np.zeros((nsup, npan))
    for k in range(npan):
        pk = phi[k]
        qk = qd[k]
        for r in range(nsup):
            s = 0.0
            for i in range(4):
                if S_idx[k, i] >= 0:
                    s += C_sup[r, S_idx[k, i]] * w[k, i]
            acc = 0.0
            pr = Phi_sup_w[r]
            for j in range(m):
                acc += pr[j] * pk[j]
            qr = Q_sup_k[r]
            for j in range(nz):
                acc += qr[j] * qk[j]
            H[r, k] = s - acc
    for r in range(nsup):
        for k in range(npan):
            s = 0.0
            for j in range(npan):
                s += H[r, j] * Ginv[j, k]
            out[r, k] = s


@njit(cache=True, fastmath=True)
def diag_woodbury(r, inv_diag, K, G, c_f, U, Ts, small_inv, s, out):
    """out = A^-1 r: 1/diag on the first K rows less the Woodbury correction
    U small^-1 (s * Ts x), G r / c_f on the rest (identity when c_f = 0)."""
    n = r.shape[0]
    for i in range(K):
        out[i] = r[i] * inv_diag[i]
    nx = n - K
    for i in range(nx):
        if c_f != 0.0:
            acc = 0.0
            for j in range(nx):
                acc += G[i, j] * r[K + j]
            out[K + i] = acc / c_f
        else:
            out[K + i] = r[K + i]
    ns = s.shape[0]
    if ns:
        y = np.empty(ns)
        for a in range(ns):
            acc = 0.0
            for i in range(K):
                acc += Ts[a, i] * out[i]
            y[a] = s[a] * acc
        z = np.zeros(ns)
        for a in range(ns):
            for b in range(ns):
                z[a] += small_inv[a, b] * y[b]
        for i in range(K):
            acc = 0.0
            for a in range(ns):
                acc += U[i, a] * z[a]
            out[i] += acc


@njit(cache=True, fastmath=True)
def step_and_check(delta_free, W, F, q_p, T_K, N0, ka, tension_only, delta, y, e, slack,
                   previous):
    """delta = delta_free + sum_k F_k W_k, y = q_p + delta, the droppers' elongations
    e = T_K y[:K] and their slack set at y; returns True when it differs from
    ``previous``."""
    n = delta.shape[0]
    for i in range(n):
        delta[i] = delta_free[i]
    for k in range(F.shape[0]):
        Fk = F[k]
        if Fk != 0.0:
            for i in range(n):
                delta[i] += Fk * W[k, i]
    for i in range(n):
        y[i] = q_p[i] + delta[i]
    nd, K = T_K.shape
    changed = False
    for d in range(nd):
        acc = 0.0
        for j in range(K):
            acc += T_K[d, j] * y[j]
        e[d] = acc
        s = tension_only[d] and (N0[d] + ka[d] * acc < 0.0)
        slack[d] = s
        if s != previous[d]:
            changed = True
    return changed


@njit(cache=True)
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


@njit(cache=True, fastmath=True)
def support_uplift(Phi_sup, Q_sup, rows, y, m, nz, out):
    """Uplift at the supports: Phi_sup eta + Q_sup zeta + rows xi."""
    nsup = Phi_sup.shape[0]
    nx = rows.shape[1]
    for r in range(nsup):
        acc = 0.0
        for j in range(m):
            acc += Phi_sup[r, j] * y[j]
        for j in range(nz):
            acc += Q_sup[r, j] * y[m + j]
        for j in range(nx):
            acc += rows[r, j] * y[m + nz + j]
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
    finish_step(f1, f1, f1, 1.0, 1.0, 1.0, 0.0, 1, f1.copy(), f1.copy(), f1.copy(), f1.copy())
    slack_mask(np.ones(1), np.ones(1), b, np.zeros(1), b.copy())
    support_rows(i4, w4, np.zeros((1, 1)), f2, np.zeros((1, 1)), f2, np.zeros((1, 1)),
                 np.ones((1, 1)), np.zeros((1, 1)))
    diag_woodbury(f1, np.ones(1), 1, np.ones((1, 1)), 1.0, np.zeros((1, 1)), np.zeros((1, 1)),
                  np.zeros((1, 1)), np.zeros(1), f1.copy())
    step_and_check(f1, f2, np.zeros(1), f1, np.zeros((1, 2)), np.ones(1), np.ones(1), b, f1.copy(),
                   f1.copy(), np.zeros(1), b.copy(), b.copy())
    slack_forces(np.zeros((1, 2)), np.ones(1), np.ones(1), 0.0, b, b, f1, f1, f1.copy())
    support_uplift(f2, np.zeros((1, 0)), np.zeros((1, 0)), f1, 2, 0, np.zeros(1))
