"""The numba kernels of :class:`~.affine_hht.AffineHHT`: the step's right-hand side from kept
products of the state, and their update after the step.

The HHT equation (3.16) of a linear structure needs C v_p + K d_p at the Newmark predictors
(3.16)-(3.17), and M a_{n+1} for f_{n+1}. With C = ar M + br K (Rayleigh, (3.1)) these are sums of
the kept products P = [K d, K v, K a, M v, M a] of the state, so the right-hand side needs no
pass over K. After the step (q_{n+1} = q_p + Delta, v = v_p + c_v Delta, a = c_a Delta) the
products advance by K Delta and M Delta; M Delta is one pass over the sparse band of M, and
K Delta follows from the step's own equation

    A Delta = (c_a + c_f c_v ar) M Delta + c_f (1 + c_v br) K Delta,

A Delta being the right-hand side the step solved (with the loads and the slack elements'
rank-one terms put back). The products carry only the round-off of that division; the
stepper re-forms them from the state now and then (:func:`state_products`).
"""

from __future__ import annotations

from numba import njit

#: rows of the kept products P
KD, KV, KA, MV, MA = range(5)


@njit(cache=True, fastmath=True, inline="always")
def _band_terms(offsets, diags, x, above, below):
    """The dense off-diagonals of a symmetric product: above[j] += d_j x[j + k],
    below[j + k] += d_j x[j] (apart, so each streaming loop vectorizes)."""
    n = x.shape[0]
    for r in range(offsets.shape[0]):
        k = offsets[r]
        d = diags[r]
        x_, b_ = x[k:], below[k:]
        for j in range(n - k):
            above[j] += d[j] * x_[j]
            b_[j] += d[j] * x[j]


@njit(cache=True, inline="always")
def _coordinate_terms(ci, cj, cv, x, out):
    """The off-diagonal entries kept as coordinates, both triangles."""
    for e in range(ci.shape[0]):
        i, j, v = ci[e], cj[e], cv[e]
        out[i] += v * x[j]
        out[j] += v * x[i]


@njit(cache=True, fastmath=True)
def sym_product(A, x, out, below):
    """out = A x for a symmetric :class:`~.banded.SparseBand` (its ``parts``); ``below`` is
    a work vector."""
    main, offsets, diags, ci, cj, cv = A
    for j in range(x.shape[0]):
        out[j] = main[j] * x[j]
        below[j] = 0.0
    _band_terms(offsets, diags, x, out, below)
    _coordinate_terms(ci, cj, cv, x, out)
    for j in range(x.shape[0]):
        out[j] += below[j]


@njit(cache=True)
def state_products(M, K, q, q_ref, v, a, P, x, below):
    """P = [K (q - q_ref), K v, K a, M v, M a] formed from the state (``x``, ``below``:
    work vectors)."""
    for i in range(q.shape[0]):
        x[i] = q[i] - q_ref[i]
    sym_product(K, x, P[KD], below)
    sym_product(K, v, P[KV], below)
    sym_product(K, a, P[KA], below)
    sym_product(M, v, P[MV], below)
    sym_product(M, a, P[MA], below)


@njit(cache=True, fastmath=True)
def predict_rhs(q, v, a, q_ref, P, r0, f, h, beta, gamma, ar, br, alpha, c_f,
                q_p, v_p, d_p, out):
    """Newmark predictors (3.16)-(3.17) with a_{n+1} = 0, d_p = q_p - q_ref, and
    out = alpha f_n - c_f (C v_p + K d_p + r0) from the kept products."""
    cq = (0.5 - beta) * h * h
    cv = (1.0 - gamma) * h
    for i in range(q.shape[0]):
        q_p[i] = q[i] + h * v[i] + cq * a[i]
        v_p[i] = v[i] + cv * a[i]
        d_p[i] = q_p[i] - q_ref[i]
    Kd, Kv, Ka, Mv, Ma = P[KD], P[KV], P[KA], P[MV], P[MA]
    for i in range(q.shape[0]):
        y = (ar * (Mv[i] + cv * Ma[i]) + br * (Kv[i] + cv * Ka[i])
             + Kd[i] + h * Kv[i] + cq * Ka[i])
        out[i] = alpha * f[i] - c_f * (y + r0[i])


@njit(cache=True, fastmath=True)
def advance(M, q_p, v_p, delta_free, W, F, delta, R, corr, h, alpha, beta, gamma, coef, ar,
            br, f, q, v, a, P, P_next, MD, below):
    """Take the step: Delta = Delta_free + sum_k F_k W_k, q, v, a from q_p, v_p and Delta,
    and the kept products P advanced into P_next by M Delta and
    K Delta = (A Delta - (c_a + c_f c_v ar) M Delta) / (c_f (1 + c_v br)) with
    A Delta = R + corr (``corr`` is zeroed on the way); f_{n+1} = (alpha f_n - M a_{n+1}) / c_f
    from (3.16) itself."""
    n = delta.shape[0]
    for i in range(n):
        delta[i] = delta_free[i]
    for k in range(F.shape[0]):
        Fk, Wk = F[k], W[k]
        for i in range(n):
            delta[i] += Fk * Wk[i]
    c_a, c_v, c_f = coef[0], coef[1], coef[2]
    cq = (0.5 - beta) * h * h
    cv = (1.0 - gamma) * h
    c_M = c_a + c_f * c_v * ar
    inv_K = 1.0 / (c_f * (1.0 + c_v * br))
    sym_product(M, delta, MD, below)
    KDelta = below                                  # the work vector, free again
    for i in range(n):
        KDelta[i] = (R[i] + corr[i] - c_M * MD[i]) * inv_K
        corr[i] = 0.0
    _advance_products(P, P_next, KDelta, MD, h, cq, cv, c_a, c_v)
    inv_f = 1.0 / c_f
    Ma1 = P_next[MA]
    for i in range(n):
        f[i] = (alpha * f[i] - Ma1[i]) * inv_f
    for i in range(n):
        d = delta[i]
        q[i] = q_p[i] + d
        v[i] = v_p[i] + c_v * d
        a[i] = c_a * d


@njit(cache=True, fastmath=True, inline="always")
def _advance_products(P, P_next, KDelta, MD, h, cq, cv, c_a, c_v):
    """P_next = P advanced by K Delta and M Delta (one loop per row, few arrays each: loops
    over many arrays are left scalar by the compiler's aliasing checks)."""
    Kd, Kv, Ka, Mv, Ma = P[KD], P[KV], P[KA], P[MV], P[MA]
    Kd1, Kv1, Ka1, Mv1, Ma1 = P_next[KD], P_next[KV], P_next[KA], P_next[MV], P_next[MA]
    for i in range(KDelta.shape[0]):
        Kd1[i] = Kd[i] + h * Kv[i] + cq * Ka[i] + KDelta[i]
    for i in range(KDelta.shape[0]):
        Kv1[i] = Kv[i] + cv * Ka[i] + c_v * KDelta[i]
    for i in range(KDelta.shape[0]):
        Ka1[i] = c_a * KDelta[i]
    for i in range(KDelta.shape[0]):
        Mv1[i] = Mv[i] + cv * Ma[i] + c_v * MD[i]
    for i in range(KDelta.shape[0]):
        Ma1[i] = c_a * MD[i]


@njit(cache=True)
def scatter_scaled(dofs, weights, c, out):
    """out[dofs] += c * weights (repeated dofs add up)."""
    for i in range(dofs.shape[0]):
        out[dofs[i]] += c * weights[i]
