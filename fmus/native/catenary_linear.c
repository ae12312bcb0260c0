/*
 * The linear catenary (its model table: pcs_linear_catenary): the closed-form HHT-alpha step of
 * pantocosim.core.affine_hht with exact dropper slackening (pantocosim.catenary.linear,
 * linear_droppers), the contact points of contact_point.py (3.11)-(3.13) and the penalty law
 * of interaction/penalty_contact.py (contact_mode 1), on the constants the Python model computed at
 * export (resources/model.pcsdata, pcs_data.h).
 *
 * A step (3.16): with the Newmark predictors q_p, v_p and q_{n+1} = q_p + Delta,
 *   A_s Delta = alpha f_n - c_f (C v_p + K d_p + r0) + c_f sum_k F_k n_k
 *               + c_f [sum_slack N_p b b + sum_committed beta k_a (b . v_p) b],
 * A = c_a M + c_f (c_v C + K) factored once (banded Cholesky), A_s = A less the slack
 * droppers' rank-one terms (Woodbury on the kept columns A^-1 b); the slack set is checked at
 * q_{n+1} and the step solved again when it changed. f_{n+1} = (alpha f_n - M a_{n+1}) / c_f.
 * Memory is allocated at instantiation only.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "catenary.h"

#define MAX_SLACK_PASSES 20
/* steps after which the kept products are formed again from the state (affine_hht.py) */
#define RESYNC_STEPS 4096
#define DROPPER_WIDTH 6

/* ------------------------------------------------------------------ linear algebra */

/* y = A x, A symmetric in lower band storage B[k n + j] = A[j + k, j]; ``below`` is work
   (the two triangles apart, so that each loop vectorizes, as affine_kernels.sym_product) */
static void band_product(const double *B, int bw, int n, const double *x, double *y,
                         double *below, const unsigned char *used)
{
    int j, k;
    for (j = 0; j < n; j++) {
        y[j] = B[j] * x[j];
        below[j] = 0.0;
    }
    for (k = 1; k <= bw; k++) {
        if (!used[k]) continue;        /* an empty diagonal */
        const double *d = B + (size_t)k * n, *xk = x + k;
        double *bk = below + k;
        for (j = 0; j + k < n; j++) y[j] += d[j] * xk[j];
        for (j = 0; j + k < n; j++) bk[j] += d[j] * x[j];
    }
    for (j = 0; j < n; j++) y[j] += below[j];
}

static double band_at(const double *B, int bw, int n, int i, int j)
{
    int k = i - j;
    return (k < 0 || k > bw) ? 0.0 : B[(size_t)k * n + j];
}

static void factor_rows(Catenary *m);

/* L = chol(c_a M + c_f (c_v (ar M + br K) + K)); -1 if not positive definite */
static int factor(Catenary *m, double c_a, double c_v, double c_f)
{
    int n = m->n, bw = m->bw, i, j, k;
    double *L = m->L;
    for (j = 0; j < n; j++)
        for (k = 0; k <= bw; k++) {
            double Mv = 0.0, Kv = 0.0;
            if (j + k < n) {
                Mv = band_at(m->M, m->bw_m, n, j + k, j);
                Kv = band_at(m->K, m->bw_k, n, j + k, j);
            }
            L[(size_t)j * (bw + 1) + k] = c_a * Mv + c_f * (c_v * (m->ar * Mv + m->br * Kv) + Kv);
        }
    for (j = 0; j < n; j++) {
        double *cj = L + (size_t)j * (bw + 1);
        int last = j + bw < n - 1 ? j + bw : n - 1;
        if (!(cj[0] > 0.0)) return -1;
        cj[0] = sqrt(cj[0]);
        for (i = 1; i <= last - j; i++) cj[i] /= cj[0];
        for (k = j + 1; k <= last; k++) {       /* column k -= L[k, j] L[k.., j] */
            double *ck = L + (size_t)k * (bw + 1);
            double lkj = cj[k - j];
            for (i = k; i <= last; i++) ck[i - k] -= cj[i - j] * lkj;
        }
    }
    factor_rows(m);
    return 0;
}

/* the rows of L (row i: L[i, i - bw .. i]) for the backward substitution */
static void factor_rows(Catenary *m)
{
    int n = m->n, bw = m->bw, i, k;
    for (i = 0; i < n; i++)
        for (k = 0; k <= bw; k++) {
            int j = i - bw + k;
            m->LR[(size_t)i * (bw + 1) + k] = j < 0 ? 0.0 : m->L[(size_t)j * (bw + 1) + (i - j)];
        }
    for (i = 0; i < n; i++) m->inv_diag[i] = 1.0 / m->L[(size_t)i * (bw + 1)];
}

/* x <- A^-1 x with the kept factor, forward by the columns of L and backward by its rows,
   four at a time: a block's own triangle first, then one pass over the rows the block
   touches (each entry of x read and written once per block, not once per column) */
static void solve(const Catenary *m, double *x)
{
    int n = m->n, bw = m->bw, w = bw + 1, i, j, j0;
    const double *L = m->L, *LR = m->LR, *inv = m->inv_diag;
    for (j0 = 0; j0 < n; j0 += 4) {
        int jb = n - j0 < 4 ? n - j0 : 4, end = j0 + jb - 1 + bw < n - 1 ? j0 + jb - 1 + bw : n - 1;
        for (j = j0; j < j0 + jb; j++) {           /* the block's triangle */
            const double *cj = L + (size_t)j * w;
            double xj = x[j] * inv[j];
            x[j] = xj;
            for (i = j + 1; i < j0 + jb && i - j <= bw; i++) x[i] -= cj[i - j] * xj;
        }
        if (jb == 4 && bw >= 4) {
            const double *c0 = L + (size_t)j0 * w - j0, *c1 = c0 + w - 1, *c2 = c1 + w - 1,
                         *c3 = c2 + w - 1;         /* c_k[i] = L[i, j0 + k] */
            double x0 = x[j0], x1 = x[j0 + 1], x2 = x[j0 + 2], x3 = x[j0 + 3];
            int full = j0 + bw < end ? j0 + bw : end;
            for (i = j0 + 4; i <= full; i++)
                x[i] -= c0[i] * x0 + c1[i] * x1 + c2[i] * x2 + c3[i] * x3;
            for (i = full + 1; i <= end; i++) {    /* rows some columns do not reach */
                double s = 0.0;
                if (i - (j0 + 1) <= bw) s += c1[i] * x1;
                if (i - (j0 + 2) <= bw) s += c2[i] * x2;
                if (i - (j0 + 3) <= bw) s += c3[i] * x3;
                x[i] -= s;
            }
        } else {
            for (j = j0; j < j0 + jb; j++) {
                const double *cj = L + (size_t)j * w - j;
                double xj = x[j];
                for (i = j0 + jb; i <= end && i - j <= bw; i++) x[i] -= cj[i] * xj;
            }
        }
    }
    for (j0 = n - 1; j0 >= 0; j0 -= 4) {           /* rows j0, j0 - 1, .., j0 - jb + 1 */
        int jb = j0 + 1 < 4 ? j0 + 1 : 4, lo = j0 - jb + 1, first = lo - bw > 0 ? lo - bw : 0;
        for (j = j0; j >= lo; j--) {               /* the block's triangle */
            const double *rj = LR + (size_t)j * w + bw - j;    /* rj[k] = L[j, k] */
            double xj = x[j] * inv[j];
            x[j] = xj;
            for (i = j - 1; i >= lo && j - i <= bw; i--) x[i] -= rj[i] * xj;
        }
        if (jb == 4 && bw >= 4) {
            const double *r0 = LR + (size_t)j0 * w + bw - j0, *r1 = r0 - w + 1, *r2 = r1 - w + 1,
                         *r3 = r2 - w + 1;         /* r_k[i] = L[j0 - k, i] */
            double x0 = x[j0], x1 = x[j0 - 1], x2 = x[j0 - 2], x3 = x[j0 - 3];
            int full = j0 - bw > first ? j0 - bw : first;
            for (i = full; i < lo; i++)
                x[i] -= r0[i] * x0 + r1[i] * x1 + r2[i] * x2 + r3[i] * x3;
            for (i = first; i < full; i++) {       /* columns some rows do not reach */
                double s = 0.0;
                if (j0 - 1 - i <= bw) s += r1[i] * x1;
                if (j0 - 2 - i <= bw) s += r2[i] * x2;
                if (j0 - 3 - i <= bw) s += r3[i] * x3;
                x[i] -= s;
            }
        } else {
            for (j = j0; j >= lo; j--) {
                const double *rj = LR + (size_t)j * w + bw - j;
                double xj = x[j];
                for (i = lo - 1; i >= first && j - i <= bw; i--) x[i] -= rj[i] * xj;
            }
        }
    }
}

/* b_d . x */
static double dropper_dot(const Catenary *m, int d, const double *x)
{
    const int *idx = m->d_idx + (size_t)d * DROPPER_WIDTH;
    const double *val = m->d_val + (size_t)d * DROPPER_WIDTH;
    double s = 0.0;
    int k;
    for (k = 0; k < DROPPER_WIDTH; k++)
        if (idx[k] >= 0) s += val[k] * x[idx[k]];
    return s;
}

static void dropper_add(const Catenary *m, int d, double c, double *x)
{
    const int *idx = m->d_idx + (size_t)d * DROPPER_WIDTH;
    const double *val = m->d_val + (size_t)d * DROPPER_WIDTH;
    int k;
    for (k = 0; k < DROPPER_WIDTH; k++)
        if (idx[k] >= 0) x[idx[k]] += c * val[k];
}

/* solve the small dense system A z = y (Gauss with partial pivoting, A overwritten);
   -1 if singular */
static int woodbury(Catenary *m, int r, double *x)
{
    int i, j;
    if (r == 0) return 0;
    for (i = 0; i < r; i++) {
        for (j = 0; j < r; j++)
            m->small[(size_t)i * r + j] = (i == j ? 1.0 : 0.0)
                - m->s[i] * dropper_dot(m, m->rows[i], m->Z + (size_t)m->rows[j] * m->n);
        m->zs[i] = m->s[i] * dropper_dot(m, m->rows[i], x);
    }
    if (pcs_dense_solve(m->small, m->zs, r) != 0) return -1;
    for (j = 0; j < r; j++) {
        const double *zj = m->Z + (size_t)m->rows[j] * m->n;
        double c = m->zs[j];
        for (i = 0; i < m->n; i++) x[i] += c * zj[i];
    }
    return 0;
}

static void wire_point(const Catenary *m, const Point *p, const double *q, const double *v,
                       double *z, double *vz)
{
    double zf = 0.0, vf = 0.0, sf = 0.0, off = 0.0, doff = 0.0;
    int i;
    for (i = 0; i < 4; i++) {
        if (p->dof[i] >= 0) {
            zf += p->w[i] * q[p->dof[i]];
            vf += p->w[i] * v[p->dof[i]];
            sf += p->dw[i] * q[p->dof[i]];
        } else {
            off += p->w[i] * p->zfix[i];
            doff += p->dw[i] * p->zfix[i];
        }
    }
    *z = zf + off;
    *vz = vf + m->speed * (sf + doff);
}

static void point_add(const Point *p, double c, double *x)
{
    int i;
    for (i = 0; i < 4; i++)
        if (p->dof[i] >= 0) x[p->dof[i]] += c * p->w[i];
}

/* ------------------------------------------------------------------ the model */

static int is_slack(const Catenary *m, int d, double N) { return m->d_tension[d] && N < 0.0; }

/* f = K (q - q_ref) + r0 - sum_slack N b - sum_k F_k n_k at rest (v = 0), the committed set */
static void rest_forces(Catenary *m, const double *F)
{
    int i, d, k;
    for (i = 0; i < m->n; i++) m->tmp[i] = m->q[i] - m->q_ref[i];
    band_product(m->K, m->bw_k, m->n, m->tmp, m->f, m->tmp2, m->used_k);
    for (i = 0; i < m->n; i++) m->f[i] += m->r0[i];
    for (d = 0; d < m->nd; d++) {
        double N = m->d_N0[d] + m->d_ka[d] * dropper_dot(m, d, m->tmp);
        m->committed[d] = is_slack(m, d, N) ? 1.0 : 0.0;
        if (m->committed[d] != 0.0) dropper_add(m, d, -N, m->f);
    }
    for (k = 0; k < m->np; k++) point_add(&m->pts[k], -F[k], m->f);
}

static void linear_outputs(Catenary *m)
{
    int k, j;
    for (k = 0; k < m->np; k++)
        wire_point(m, &m->pts[k], m->q, m->v, &m->out_z[k], &m->out_v[k]);
    for (j = 0; j < m->ns && j < CAT_MAX_SUPPORTS; j++)
        m->uplift[j] = m->s_dof[j] >= 0 ? m->q[m->s_dof[j]] - m->s_z[j] : 0.0;
}

#define SECTION(dst, name, type, count)                                                   \
    do {                                                                                  \
        dst = pcs_data_section(d, name, type, count, NULL, err, PCS_MSG);                 \
        if (!dst) goto fail;                                                              \
    } while (0)

/* the model's work and state memory: measured (the arena not open) or taken */
static void carve(Catenary *m, PcsArena *a)
{
    size_t n = (size_t)m->n, nd = (size_t)m->nd, w = (size_t)m->bw + 1;
    size_t np = (size_t)m->np;
    m->L = (double *)pcs_arena_take(a, pcs_mul(w, n), sizeof(double));
    m->LR = (double *)pcs_arena_take(a, pcs_mul(w, n), sizeof(double));
    m->inv_diag = (double *)pcs_arena_take(a, n, sizeof(double));
    m->Z = (double *)pcs_arena_take(a, pcs_add(pcs_mul(nd, n), 1), sizeof(double));
    m->state = (double *)pcs_arena_take(a, m->state_len, sizeof(double));
    m->qp = (double *)pcs_arena_take(a, (10 + np) * n, sizeof(double));
    m->Np = (double *)pcs_arena_take(a, pcs_add(pcs_mul(nd, nd), (7 + np) * nd + 8),
                                     sizeof(double));
    m->rows = (int *)pcs_arena_take(a, nd + 1, sizeof(int));
    m->used_m = (unsigned char *)pcs_arena_take(a, (size_t)m->bw_m + 1, 1);
    m->used_k = (unsigned char *)pcs_arena_take(a, (size_t)m->bw_k + 1, 1);
}

/* used[k] = 1 when the band diagonal k of B holds a nonzero */
static void used_diagonals(const double *B, int bw, size_t n, unsigned char *used)
{
    int k;
    size_t j;
    for (k = 0; k <= bw; k++)
        for (j = 0; j < n; j++)
            if (B[(size_t)k * n + j] != 0.0) {
                used[k] = 1;
                break;
            }
}

static void linear_free(void *model, const PcsMemory *mem);

static int linear_step(Catenary *m, double *F, const double *zp, const double *vpan,
                       char *err);
static const CatenaryStep LINEAR = {linear_step, linear_outputs};

static void *linear_new(const PcsData *d, const PcsMemory *mem, char *err)
{
    Catenary *m;
    const int *sizes;
    const double *sc;
    size_t n, nd, i;
    m = (Catenary *)pcs_alloc(mem, 1, sizeof *m);
    if (!m) { snprintf(err, PCS_MSG, "no memory"); return NULL; }
    SECTION(sizes, "sizes", PCS_TYPE_I32, LIN_SIZES);
    m->n = sizes[LIN_SIZE_DOFS];
    m->bw_m = sizes[LIN_SIZE_BAND_M];
    m->bw_k = sizes[LIN_SIZE_BAND_K];
    m->nd = sizes[LIN_SIZE_DROPPERS];
    m->np = sizes[LIN_SIZE_PANTOGRAPHS];
    m->ne = sizes[LIN_SIZE_WIRE_ELEMENTS];
    m->ns = sizes[LIN_SIZE_SUPPORTS];
    m->spans = sizes[LIN_SIZE_SPANS];
    m->model_code = sizes[LIN_SIZE_MODEL_CODE];
    if (cat_check_sizes(m, d, err) != 0) goto fail;
    if (m->n < 1 || m->n > PCS_MAX_DOFS || m->bw_m < 0 || m->bw_m > PCS_MAX_BAND
        || m->bw_k < 0 || m->bw_k > PCS_MAX_BAND || sizes[LIN_SIZE_DROPPER_WIDTH] != DROPPER_WIDTH) {
        snprintf(err, PCS_MSG, "data file %.400s: section sizes: %d DOFs (1..%d), bands %d and "
                 "%d (0..%d), dropper width %d (%d)", d->path, m->n, PCS_MAX_DOFS, m->bw_m,
                 m->bw_k, PCS_MAX_BAND, sizes[LIN_SIZE_DROPPER_WIDTH], DROPPER_WIDTH);
        goto fail;
    }
    m->bw = m->bw_m > m->bw_k ? m->bw_m : m->bw_k;
    n = (size_t)m->n;
    nd = (size_t)m->nd;
    SECTION(sc, "scalars", PCS_TYPE_F64, LIN_SCALARS);
    if (cat_read_common(m, d, sc, m->n, err) != 0) goto fail;
    SECTION(m->M, "M_band", PCS_TYPE_F64, pcs_mul((size_t)m->bw_m + 1, n));
    SECTION(m->K, "K_band", PCS_TYPE_F64, pcs_mul((size_t)m->bw_k + 1, n));
    SECTION(m->q_ref, "q_ref", PCS_TYPE_F64, n);
    SECTION(m->r0, "r0", PCS_TYPE_F64, n);
    SECTION(m->q0, "q0", PCS_TYPE_F64, n);
    SECTION(m->d_idx, "drop_idx", PCS_TYPE_I32, nd * DROPPER_WIDTH);
    SECTION(m->d_val, "drop_val", PCS_TYPE_F64, nd * DROPPER_WIDTH);
    SECTION(m->s_dof, "support_dof", PCS_TYPE_I32, (size_t)m->ns);
    SECTION(m->s_z, "support_z", PCS_TYPE_F64, (size_t)m->ns);
    for (i = 0; i < nd * DROPPER_WIDTH; i++)       /* every index inside its array */
        if (m->d_idx[i] < -1 || m->d_idx[i] >= m->n) {
            snprintf(err, PCS_MSG, "data file %.400s: section drop_idx: index %d outside "
                     "-1..%d", d->path, m->d_idx[i], m->n - 1);
            goto fail;
        }
    for (i = 0; i < (size_t)m->ns; i++)
        if (m->s_dof[i] < -1 || m->s_dof[i] >= m->n) {
            snprintf(err, PCS_MSG, "data file %.400s: section support_dof: index %d outside "
                     "-1..%d", d->path, m->s_dof[i], m->n - 1);
            goto fail;
        }
    m->state_len = 4 + CAT_MAX_PANTOGRAPHS * 2 + 9 * n + nd + 1;
    if (cat_arena(m, d, mem, carve, err) != 0) goto fail;
    used_diagonals(m->M, m->bw_m, n, m->used_m);
    used_diagonals(m->K, m->bw_k, n, m->used_k);
    m->t = m->state; m->n_steps = m->state + 1; m->failed = m->state + 2;
    m->synced = m->state + 3;
    m->prev = m->state + 4;                      /* inputs at t: 2 per pantograph */
    m->q = m->prev + 2 * CAT_MAX_PANTOGRAPHS;
    m->v = m->q + n; m->a = m->v + n; m->f = m->a + n;
    m->Kd = m->f + n; m->Kv = m->Kd + n; m->Ka = m->Kv + n; m->Mv = m->Ka + n;
    m->Ma = m->Mv + n; m->committed = m->Ma + n;
    m->vp = m->qp + n; m->dp = m->vp + n; m->rhs = m->dp + n; m->R = m->rhs + n;
    m->x = m->R + n; m->tmp = m->x + n; m->tmp2 = m->tmp + n; m->W = m->tmp2 + n;
    m->bx = m->Np + nd; m->sl = m->bx + nd; m->sl_new = m->sl + nd; m->s = m->sl_new + nd;
    m->y = m->s + nd; m->zs = m->y + nd; m->small = m->zs + nd; m->bW = m->small + nd * nd;
    m->own = &LINEAR;
    return m;
fail:
    linear_free(m, mem);
    return NULL;
}

static void linear_free(void *model, const PcsMemory *mem)
{
    Catenary *m = (Catenary *)model;
    if (!m) return;
    pcs_arena_close(&m->arena, mem);
    pcs_free(mem, m);
}

/* the kept products P = [K (q - q_ref), K v, K a, M v, M a] from the state itself
   (affine_kernels.state_products) */
static void form_products(Catenary *m)
{
    int i, n = m->n;
    for (i = 0; i < n; i++) m->tmp[i] = m->q[i] - m->q_ref[i];
    band_product(m->K, m->bw_k, n, m->tmp, m->Kd, m->tmp2, m->used_k);
    band_product(m->K, m->bw_k, n, m->v, m->Kv, m->tmp2, m->used_k);
    band_product(m->K, m->bw_k, n, m->a, m->Ka, m->tmp2, m->used_k);
    band_product(m->M, m->bw_m, n, m->v, m->Mv, m->tmp2, m->used_m);
    band_product(m->M, m->bw_m, n, m->a, m->Ma, m->tmp2, m->used_m);
    *m->synced = *m->n_steps;
}

static int linear_initialize(void *model, char *err)
{
    Catenary *m = (Catenary *)model;
    int k, d, i;
    size_t n = (size_t)m->n;
    if (m->mode == 1) {
        for (k = 0; k < m->np; k++)
            if (!(m->F0[k] > 0.0)) {
                snprintf(err, PCS_MSG, "contact_mode = 1 needs the static start of an exported "
                         "static_force_%d > 0 (exported: %g N)", k + 1, m->F0[k]);
                return PCS_ERROR;
            }
    }
    *m->t = 0.0; *m->n_steps = 0.0; *m->failed = 0.0;
    memcpy(m->q, m->q0, n * sizeof(double));
    memset(m->v, 0, n * sizeof(double));
    for (k = 0; k < m->np; k++)
        if (pcs_locate(m, m->x0[k], &m->pts[k], err) != 0) return PCS_ERROR;
    rest_forces(m, m->F0);
    /* a0 = -M^-1 f0 (the mass matrix factored like the Newton matrix of c_a = 1) */
    if (factor(m, 1.0, 0.0, 0.0) != 0) {
        snprintf(err, PCS_MSG, "the mass matrix is not positive definite");
        return PCS_ERROR;
    }
    for (i = 0; i < m->n; i++) m->a[i] = -m->f[i];
    solve(m, m->a);
    m->c_a = 1.0 / (m->beta * m->h * m->h);
    m->c_v = m->gamma / (m->beta * m->h);
    m->c_f = 1.0 + m->alpha;
    if (factor(m, m->c_a, m->c_v, m->c_f) != 0) {
        snprintf(err, PCS_MSG, "the Newton matrix of h = %g s is not positive definite", m->h);
        return PCS_ERROR;
    }
    for (d = 0; d < m->nd; d++) {          /* the dropper columns A^-1 b_d */
        double *z = m->Z + (size_t)d * n;
        memset(z, 0, n * sizeof(double));
        dropper_add(m, d, 1.0, z);
        solve(m, z);
    }
    form_products(m);
    linear_outputs(m);
    cat_start(m);
    return PCS_OK;
}

/* the step's slack terms into R (from rhs) and the removed rank-one terms (rows, s) */
static int slack_terms(Catenary *m)
{
    int d, r = 0;
    memcpy(m->R, m->rhs, (size_t)m->n * sizeof(double));
    for (d = 0; d < m->nd; d++) {
        int sl = m->sl[d] != 0.0, dm = m->committed[d] != 0.0;
        double coef = 0.0, sd;
        if (!(sl || dm)) continue;
        if (sl) coef += m->Np[d];
        if (dm) coef += m->br * m->d_ka[d] * dropper_dot(m, d, m->vp);
        dropper_add(m, d, m->c_f * coef, m->R);
        sd = m->c_f * m->d_ka[d] * ((sl ? 1.0 : 0.0) + (dm ? m->c_v * m->br : 0.0));
        if (sd != 0.0) {
            m->rows[r] = d;
            m->s[r] = sd;
            r++;
        }
    }
    return r;
}

/* the penalty forces F of the prescribed pantographs (z_p, v_p) with the wire affine in F:
   z_w = z0 + G F, v_w = v0 + H F (condensed_forces of penalty_contact.py with P = 0) */
static int linear_step(Catenary *m, double *F, const double *zp, const double *vpan, char *err)
{
    int n = m->n, nd = m->nd, np = m->np, i, d, k, j, r, passes = 0;
    double h = m->h, cq = (0.5 - m->beta) * h * h, cv = (1.0 - m->gamma) * h;
    double c_f = m->c_f;
    if (*m->n_steps - *m->synced >= RESYNC_STEPS) form_products(m);
    for (i = 0; i < n; i++) {
        m->qp[i] = m->q[i] + h * m->v[i] + cq * m->a[i];
        m->vp[i] = m->v[i] + cv * m->a[i];
        m->dp[i] = m->qp[i] - m->q_ref[i];
    }
    for (i = 0; i < n; i++) {        /* C v_p + K d_p from the kept products */
        double y = m->ar * (m->Mv[i] + cv * m->Ma[i]) + m->br * (m->Kv[i] + cv * m->Ka[i])
                   + m->Kd[i] + h * m->Kv[i] + cq * m->Ka[i];
        m->rhs[i] = m->alpha * m->f[i] - c_f * (y + m->r0[i]);
    }
    if (m->mode == 0)
        for (k = 0; k < np; k++) point_add(&m->pts[k], c_f * F[k], m->rhs);
    for (d = 0; d < nd; d++) {
        m->Np[d] = m->d_ka[d] * dropper_dot(m, d, m->dp) + m->d_N0[d];
        m->sl[d] = is_slack(m, d, m->Np[d]) ? 1.0 : 0.0;
    }
    for (;;) {
        int changed = 0;
        if (passes >= MAX_SLACK_PASSES) {
            snprintf(err, PCS_MSG, "the slack set does not settle at t = %.6g s after %d "
                     "passes", *m->t + h, passes);
            return PCS_DISCARD;
        }
        passes++;
        r = slack_terms(m);
        memcpy(m->x, m->R, (size_t)n * sizeof(double));
        solve(m, m->x);
        if (woodbury(m, r, m->x) != 0) {
            snprintf(err, PCS_MSG, "the slack droppers' Woodbury matrix is singular at t = "
                     "%.6g s", *m->t + h);
            return PCS_DISCARD;
        }
        if (m->mode == 1) {     /* the load responses W_k, the condensed penalty contact */
            double z0[CAT_MAX_PANTOGRAPHS], v0[CAT_MAX_PANTOGRAPHS], G[16], H[16];
            double dz[CAT_MAX_PANTOGRAPHS], dv[CAT_MAX_PANTOGRAPHS];
            for (k = 0; k < np; k++) {
                double *w = m->W + (size_t)k * n;
                memset(w, 0, (size_t)n * sizeof(double));
                point_add(&m->pts[k], c_f, w);
                solve(m, w);
                if (woodbury(m, r, w) != 0) {
                    snprintf(err, PCS_MSG, "the slack droppers' Woodbury matrix is singular");
                    return PCS_DISCARD;
                }
            }
            for (i = 0; i < n; i++) {
                m->tmp[i] = m->qp[i] + m->x[i];
                m->tmp2[i] = m->vp[i] + m->c_v * m->x[i];
            }
            for (k = 0; k < np; k++) {
                const Point *p = &m->pts[k];
                wire_point(m, p, m->tmp, m->tmp2, &z0[k], &v0[k]);
                for (j = 0; j < np; j++) {
                    const double *w = m->W + (size_t)j * n;
                    double g = 0.0, s = 0.0;
                    for (i = 0; i < 4; i++)
                        if (p->dof[i] >= 0) {
                            g += p->w[i] * w[p->dof[i]];
                            s += p->dw[i] * w[p->dof[i]];
                        }
                    G[k * np + j] = g;
                    H[k * np + j] = m->c_v * g + m->speed * s;
                }
                dz[k] = zp[k] - z0[k];
                dv[k] = vpan[k] - v0[k];
            }
            if (pcs_penalty_forces(m, dz, dv, G, H, F) != 0) {
                snprintf(err, PCS_MSG, "the penalty contact has no solution at t = %.6g s "
                         "(singular, or its active set does not settle in %d passes)",
                         *m->t + h, 2 * np + 2);
                return PCS_DISCARD;
            }
            for (d = 0; d < nd; d++)
                for (k = 0; k < np; k++)
                    m->bW[(size_t)k * nd + d] = dropper_dot(m, d, m->W + (size_t)k * n);
        }
        for (d = 0; d < nd; d++) {
            double bd = dropper_dot(m, d, m->x);
            if (m->mode == 1)
                for (k = 0; k < np; k++) bd += F[k] * m->bW[(size_t)k * nd + d];
            m->bx[d] = bd;
            m->sl_new[d] = is_slack(m, d, m->Np[d] + m->d_ka[d] * bd) ? 1.0 : 0.0;
            changed = changed || m->sl_new[d] != m->sl[d];
        }
        if (!changed) break;
        memcpy(m->sl, m->sl_new, (size_t)nd * sizeof(double));
    }
    if (m->mode == 1)
        for (k = 0; k < np; k++) {
            const double *w = m->W + (size_t)k * n;
            for (i = 0; i < n; i++) m->x[i] += F[k] * w[i];
        }
    /* A Delta = R (+ the loads of mode 1) + the removed rank-one terms at Delta; K Delta
       from the step's own equation, M Delta by one product (affine_kernels.advance) */
    memcpy(m->tmp2, m->R, (size_t)n * sizeof(double));
    if (m->mode == 1)
        for (k = 0; k < np; k++) point_add(&m->pts[k], c_f * F[k], m->tmp2);
    for (j = 0; j < r; j++) dropper_add(m, m->rows[j], m->s[j] * m->bx[m->rows[j]], m->tmp2);
    band_product(m->M, m->bw_m, n, m->x, m->tmp, m->W, m->used_m);
    {
        double c_M = m->c_a + c_f * m->c_v * m->ar, inv_K = 1.0 / (c_f * (1.0 + m->c_v * m->br));
        double c_a = m->c_a, c_v = m->c_v;
        for (i = 0; i < n; i++) {
            double KD = (m->tmp2[i] - c_M * m->tmp[i]) * inv_K, MD = m->tmp[i];
            m->Kd[i] = m->Kd[i] + h * m->Kv[i] + cq * m->Ka[i] + KD;
            m->Kv[i] = m->Kv[i] + cv * m->Ka[i] + c_v * KD;
            m->Ka[i] = c_a * KD;
            m->Mv[i] = m->Mv[i] + cv * m->Ma[i] + c_v * MD;
            m->Ma[i] = c_a * MD;
        }
        for (i = 0; i < n; i++) {
            double dl = m->x[i];
            m->f[i] = (m->alpha * m->f[i] - m->Ma[i]) / c_f;
            m->q[i] = m->qp[i] + dl;
            m->v[i] = m->vp[i] + c_v * dl;
            m->a[i] = c_a * dl;
        }
    }
    memcpy(m->committed, m->sl, (size_t)nd * sizeof(double));
    *m->t += h;
    *m->n_steps += 1.0;
    m->iterations += passes;
    return PCS_OK;
}

const PcsModelType pcs_linear_catenary = CATENARY_TABLE(
    "linear catenary", PCS_KIND_LINEAR_CATENARY, linear_new, linear_free, linear_initialize);
