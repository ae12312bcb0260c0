/*
 * The modal catenary as a native model: the closed-form HHT-alpha step of
 * pantocosim.catenary.modal_step (ModalHHT) on the tables of catenary/modal.py and
 * modal_residual.py, computed at export. Coordinates y = [eta (m modes), zeta (one per
 * dropper), xi (one per pantograph)]; per step, at the pantographs' positions, the contact
 * rows phi(x), Q^T N(x) and the contact residual G(t) (modal_kernels.locate_points,
 * point_rows, residual_flexibility), then
 *
 *   A Delta = alpha f_n - c_f f_rest(y_p, v_p) + c_f [slack and committed terms] + c_f W^T F,
 *
 * A diagonal on eta and zeta (c_a + c_f (c_v zeta_j + omega_j^2), c_f k (1 + c_v beta)),
 * c_f G^-1 on xi, less the slack droppers' rank-one rows (Woodbury on the droppers' Gram
 * matrix); the slack set is checked at y_{n+1} and the step solved again when it changed.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "catenary.h"

#define MAX_SLACK_PASSES 20
/* coordinates per block of the slack check's bounds (modal_kernels.SCREEN_BLOCK) */
#define SCREEN_BLOCK 32
#define NP CAT_MAX_PANTOGRAPHS

struct Modal {
    int m, nz, nx, K, N, nS, band, nsup;
    double kbar, beta_r;
    const double *Phi_S, *Q_S, *C_band, *omega2, *zeta_c, *r0, *T_K, *Phi_sup, *Q_sup, *C_sup;
    /* per the step's coefficients: 1 / diag, U = T_K diag^-1, gram = T_K diag^-1 T_K^T */
    double *inv_diag, *U, *gram;
    /* the geometry at the latest time: contact rows, their x-derivatives, G, G^-1 */
    double *Wc, *Wcx, G[NP * NP], Ginv[NP * NP], offset[NP], doffset[NP];
    /* work */
    double *q_p, *v_p, *rhs, *r, *sf, *delta_free, *delta, *Wl, *ys, *small, *zs, *s, *slack,
        *slack_new, *yt;
    int *rows, n_rows;
    /* the slack check's screen (modal_step._screen_tables, modal_kernels.screen_slack): T_K
       in single precision, per block |k_a| times the 2-norms and the largest entries of
       each row, the rounding factors; the reference forces, their error bounds, the marks,
       the reference y, the block norms, y in single precision */
    float *T32, *y32;
    double *Tb, *Tm, tol[2], *ref, *y_ref, *xb;
    int nb, most;
    /* the time of the geometry in Wc, G (NAN: none) */
    double geometry_t;
};

/* the screen's tables (modal_step._screen_tables) and an empty reference */
static void screen_tables(Catenary *m)
{
    struct Modal *md = m->modal;
    int K = md->K, nd = m->nd, d, b, j, n;
    for (d = 0; d < nd; d++) {
        const double *t = md->T_K + (size_t)d * K;
        double ka = fabs(m->d_ka[d]);
        for (j = 0; j < K; j++) md->T32[(size_t)d * K + j] = (float)t[j];
        for (b = 0; b < md->nb; b++) {
            double ss = 0.0, mx = 0.0;
            int j1 = (b + 1) * SCREEN_BLOCK < K ? (b + 1) * SCREEN_BLOCK : K;
            for (j = b * SCREEN_BLOCK; j < j1; j++) {
                ss += t[j] * t[j];
                if (fabs(t[j]) > mx) mx = fabs(t[j]);
            }
            md->Tb[(size_t)d * md->nb + b] = sqrt(ss) * ka * (1.0 + 1e-9);
            md->Tm[(size_t)d * md->nb + b] = mx * ka;
        }
        md->ref[d] = NAN;              /* no reference yet: the first check takes every row */
        md->ref[nd + d] = 0.0;
        md->ref[2 * nd + d] = 0.0;
    }
    n = K + 2;
    md->tol[0] = 2.0 * n * ldexp(1.0, -24) / (1.0 - n * ldexp(1.0, -24));
    md->tol[1] = 2.0 * n * ldexp(1.0, -53) / (1.0 - n * ldexp(1.0, -53));
    md->most = nd / 8 > 1 ? nd / 8 : 1;
}

#define TABLE(dst, name, count)                                                           \
    do {                                                                                  \
        dst = pcs_data_section(d, name, PCS_TYPE_F64, count, NULL, err, PCS_MSG);         \
        if (!dst) goto fail;                                                              \
    } while (0)

/* the model's work and state memory: measured (the arena not open) or taken */
static void carve(Catenary *m, PcsArena *a)
{
    struct Modal *md = m->modal;
    size_t N = (size_t)md->N, nd = (size_t)m->nd, K = (size_t)md->K, np = (size_t)m->np;
    size_t nb = (size_t)md->nb;
    size_t ndK = pcs_mul(nd, K), ndnd = pcs_mul(nd, nd), ndnb = pcs_mul(nd, nb);
    m->state = (double *)pcs_arena_take(a, m->state_len, sizeof(double));
    md->inv_diag = (double *)pcs_arena_take(a, pcs_add(pcs_add(ndK, ndnd), K + 1),
                                            sizeof(double));
    md->Wc = (double *)pcs_arena_take(a, (3 * np + 8) * N + K, sizeof(double));
    md->ys = (double *)pcs_arena_take(a, pcs_add(ndnd, 6 * nd + 8), sizeof(double));
    md->rows = (int *)pcs_arena_take(a, nd + 1, sizeof(int));
    md->T32 = (float *)pcs_arena_take(a, pcs_add(ndK, K + 1), sizeof(float));
    md->Tb = (double *)pcs_arena_take(a, pcs_add(pcs_mul(2, ndnb), 3 * nd + K + 2 * nb + 1),
                                      sizeof(double));
}

static int modal_step(Catenary *m, double *F, const double *zp, const double *vp, char *err);
static void modal_outputs(Catenary *m);
static const CatenaryStep MODAL = {modal_step, modal_outputs};
static void modal_free(void *model, const PcsMemory *mem);

static void *modal_new(const PcsData *d, const PcsMemory *mem, char *err)
{
    Catenary *m;
    struct Modal *md;
    const int *sizes;
    const double *sc;
    size_t N, nd, K, nS;
    m = (Catenary *)pcs_alloc(mem, 1, sizeof *m);
    md = (struct Modal *)pcs_alloc(mem, 1, sizeof *md);
    if (!m || !md) {
        pcs_free(mem, m);
        pcs_free(mem, md);
        snprintf(err, PCS_MSG, "no memory");
        return NULL;
    }
    m->modal = md;
    m->own = &MODAL;
    sizes = pcs_data_section(d, "sizes", PCS_TYPE_I32, MOD_SIZES, NULL, err, PCS_MSG);
    if (!sizes) goto fail;
    md->N = sizes[MOD_SIZE_COORDINATES];
    md->m = sizes[MOD_SIZE_MODES];
    md->nz = sizes[MOD_SIZE_DROPPER_COORDINATES];
    md->nx = sizes[MOD_SIZE_PANTOGRAPH_COORDINATES];
    m->nd = sizes[MOD_SIZE_DROPPERS];
    m->np = sizes[MOD_SIZE_PANTOGRAPHS];
    m->ne = sizes[MOD_SIZE_WIRE_ELEMENTS];
    md->nsup = m->ns = sizes[MOD_SIZE_SUPPORTS];
    md->nS = sizes[MOD_SIZE_WIRE_DOFS];
    md->band = sizes[MOD_SIZE_BAND];
    m->spans = sizes[MOD_SIZE_SPANS];
    m->model_code = sizes[MOD_SIZE_MODEL_CODE];
    if (cat_check_sizes(m, d, err) != 0) goto fail;
    if (md->m < 1 || md->m > PCS_MAX_DOFS || md->nz < 0 || md->nz > PCS_MAX_DROPPERS
        || md->nx < 0 || md->nx > m->np || md->nS < 1 || md->nS > PCS_MAX_DOFS
        || md->band < 0 || md->band > PCS_MAX_BAND || md->N != md->m + md->nz + md->nx) {
        snprintf(err, PCS_MSG, "data file %.400s: section sizes: coordinates %d = modes %d "
                 "(1..%d) + droppers %d (0..%d) + pantographs %d (0..%d), wire DOFs %d (1..%d), "
                 "band %d (0..%d)", d->path, md->N, md->m, PCS_MAX_DOFS, md->nz,
                 PCS_MAX_DROPPERS, md->nx, m->np, md->nS, PCS_MAX_DOFS, md->band, PCS_MAX_BAND);
        goto fail;
    }
    md->K = md->m + md->nz;
    m->n = md->N;
    N = (size_t)md->N;
    nd = (size_t)m->nd;
    K = (size_t)md->K;
    nS = (size_t)md->nS;
    TABLE(sc, "scalars", MOD_SCALARS);
    md->kbar = sc[MOD_SCALAR_DROPPER_STIFFNESS];
    md->beta_r = sc[CAT_SCALAR_RAYLEIGH_STIFFNESS];
    if (md->nz > 0 && !(md->kbar > 0.0)) {
        snprintf(err, PCS_MSG, "data file %.400s: section scalars: dropper stiffness scale %g "
                 "(must be > 0)", d->path, md->kbar);
        goto fail;
    }
    if (cat_read_common(m, d, sc, md->nS, err) != 0) goto fail;
    TABLE(md->Phi_S, "Phi_S", pcs_mul(nS, (size_t)md->m));
    TABLE(md->Q_S, "Q_S", pcs_mul(nS, (size_t)md->nz));
    TABLE(md->C_band, "C_band", pcs_mul(nS, 2 * (size_t)md->band + 1));
    TABLE(md->omega2, "omega2", (size_t)md->m);
    TABLE(md->zeta_c, "zeta_c", (size_t)md->m);
    TABLE(md->r0, "r0", N);
    TABLE(md->T_K, "T_K", pcs_mul(nd, K));
    TABLE(md->Phi_sup, "Phi_sup", pcs_mul((size_t)m->ns, (size_t)md->m));
    TABLE(md->Q_sup, "Q_sup", pcs_mul((size_t)m->ns, (size_t)md->nz));
    TABLE(md->C_sup, "C_sup", pcs_mul((size_t)m->ns, nS));
    TABLE(m->q0, "q0", N);
    m->state_len = 4 + 2 * NP + 4 * N + nd;
    md->nb = (md->K + SCREEN_BLOCK - 1) / SCREEN_BLOCK;
    if (cat_arena(m, d, mem, carve, err) != 0) goto fail;
    md->U = md->inv_diag + K;
    md->gram = md->U + nd * K;
    md->Wcx = md->Wc + (size_t)m->np * N;
    md->q_p = md->Wcx + (size_t)m->np * N;
    md->v_p = md->q_p + N; md->rhs = md->v_p + N; md->r = md->rhs + N; md->sf = md->r + N;
    md->delta_free = md->sf + N; md->delta = md->delta_free + N; md->Wl = md->delta + N;
    md->yt = md->Wl + (size_t)m->np * N;
    md->y32 = md->T32 + nd * K;
    md->Tm = md->Tb + nd * (size_t)md->nb;
    md->ref = md->Tm + nd * (size_t)md->nb;
    md->y_ref = md->ref + 3 * nd;
    md->xb = md->y_ref + K;
    screen_tables(m);
    md->zs = md->ys + nd; md->s = md->zs + nd; md->slack = md->s + nd;
    md->slack_new = md->slack + nd; md->small = md->slack_new + nd;
    m->t = m->state; m->n_steps = m->state + 1; m->failed = m->state + 2;
    m->synced = m->state + 3; m->prev = m->state + 4;
    m->q = m->prev + 2 * NP; m->v = m->q + N; m->a = m->v + N; m->f = m->a + N;
    m->committed = m->f + N;
    return m;
fail:
    modal_free(m, mem);
    return NULL;
}

static void modal_free(void *model, const PcsMemory *mem)
{
    Catenary *m = (Catenary *)model;
    if (!m) return;
    pcs_arena_close(&m->arena, mem);
    pcs_free(mem, m->modal);
    pcs_free(mem, m);
}

/* the contact rows and residual at the points m->pts (modal_kernels.point_rows,
   residual_flexibility); -1 when two pantographs lie outside the tabulated band */
static int geometry(Catenary *m)
{
    struct Modal *md = m->modal;
    int np = m->np, mm = md->m, nz = md->nz, N = md->N, k, j, i, a, b;
    for (k = 0; k < np; k++) {
        const Point *p = &m->pts[k];
        double *wc = md->Wc + (size_t)k * N, *wx = md->Wcx + (size_t)k * N;
        memset(wc, 0, (size_t)N * sizeof(double));
        memset(wx, 0, (size_t)N * sizeof(double));
        md->offset[k] = md->doffset[k] = 0.0;
        for (i = 0; i < 4; i++) {
            int s = p->dof[i];
            md->offset[k] += p->w[i] * p->zfix[i];
            md->doffset[k] += p->dw[i] * p->zfix[i];
            if (s < 0) continue;
            for (j = 0; j < mm; j++) {
                double v = md->Phi_S[(size_t)s * mm + j];
                wc[j] += p->w[i] * v;
                wx[j] += p->dw[i] * v;
            }
            for (j = 0; j < nz; j++) {
                double v = md->Q_S[(size_t)s * nz + j];
                wc[mm + j] += p->w[i] * v;
                wx[mm + j] += p->dw[i] * v;
            }
        }
        if (k < md->nx) wc[md->K + k] = 1.0;
    }
    if (!md->nx) return 0;
    for (j = 0; j < np; j++)
        for (k = 0; k < np; k++) {
            const Point *pj = &m->pts[j], *pk = &m->pts[k];
            const double *wj = md->Wc + (size_t)j * N, *wk = md->Wc + (size_t)k * N;
            double g = 0.0;
            for (a = 0; a < 4; a++) {
                int sa = pj->dof[a];
                if (sa < 0) continue;
                for (b = 0; b < 4; b++) {
                    int sb = pk->dof[b], off;
                    if (sb < 0) continue;
                    off = sb - sa + md->band;
                    if (off < 0 || off > 2 * md->band) return -1;
                    g += pj->w[a] * md->C_band[(size_t)sa * (2 * md->band + 1) + off] * pk->w[b];
                }
            }
            for (i = 0; i < mm; i++) g -= wj[i] * wk[i] / md->omega2[i];
            for (i = 0; i < nz; i++) g -= wj[mm + i] * wk[mm + i] / md->kbar;
            md->G[j * np + k] = g;
        }
    for (j = 0; j < np; j++)
        for (k = 0; k < j; k++) {
            double s = 0.5 * (md->G[j * np + k] + md->G[k * np + j]);
            md->G[j * np + k] = md->G[k * np + j] = s;
        }
    for (j = 0; j < np; j++) {          /* G^-1, column by column */
        double A[NP * NP], e[NP];
        memcpy(A, md->G, sizeof(double) * (size_t)(np * np));
        for (k = 0; k < np; k++) e[k] = k == j ? 1.0 : 0.0;
        if (pcs_dense_solve(A, e, np) != 0) return -1;
        for (k = 0; k < np; k++) md->Ginv[k * np + j] = e[k];
    }
    return 0;
}

static int locate_all(Catenary *m, double t, char *err)
{
    int k;
    for (k = 0; k < m->np; k++)
        if (pcs_locate(m, m->x0[k] + m->speed * t, &m->pts[k], err) != 0) return -1;
    if (geometry(m) != 0) {
        if (err)
            snprintf(err, PCS_MSG, "modal catenary: pantographs farther apart than the "
                     "residual tables cover");
        return -1;
    }
    return 0;
}

static double row_dot(const double *row, const double *x, int n)
{
    double s = 0.0;
    int i;
    for (i = 0; i < n; i++) s += row[i] * x[i];
    return s;
}

static int slack_at(const Catenary *m, int d, const double *y)
{
    const struct Modal *md = m->modal;
    return m->d_tension[d]
           && m->d_N0[d] + m->d_ka[d] * row_dot(md->T_K + (size_t)d * md->K, y, md->K) < 0.0;
}

/* out[:K] = the forces the slack and committed droppers no longer carry (slack_forces) */
static void slack_forces(const Catenary *m, const double *slack, const double *y,
                         const double *v, double *out)
{
    const struct Modal *md = m->modal;
    int d, j, K = md->K;
    memset(out, 0, (size_t)md->N * sizeof(double));
    for (d = 0; d < m->nd; d++) {
        const double *t = md->T_K + (size_t)d * K;
        double c = 0.0;
        if (slack[d] != 0.0) c += m->d_N0[d] + m->d_ka[d] * row_dot(t, y, K);
        if (m->committed[d] != 0.0) c += md->beta_r * m->d_ka[d] * row_dot(t, v, K);
        if (c != 0.0)
            for (j = 0; j < K; j++) out[j] += c * t[j];
    }
}

/* the Woodbury rows (rows, s) of the slack set and the committed set (removed_stiffness) */
static void woodbury_rows(Catenary *m, const double *slack)
{
    struct Modal *md = m->modal;
    int d;
    md->n_rows = 0;
    for (d = 0; d < m->nd; d++) {
        double sd = m->c_f * m->d_ka[d] * ((slack[d] != 0.0 ? 1.0 : 0.0)
                                           + (m->committed[d] != 0.0 ? m->c_v * md->beta_r : 0.0));
        if (sd != 0.0) {
            md->rows[md->n_rows] = d;
            md->s[md->n_rows] = sd;
            md->n_rows++;
        }
    }
}

/* out = A^-1 (scale r) (modal_kernels.diag_woodbury); -1 if the small matrix is singular */
static int diag_woodbury(Catenary *m, const double *r, double scale, double *out)
{
    struct Modal *md = m->modal;
    int K = md->K, nx = md->nx, np = m->np, nr = md->n_rows, i, j, a, b;
    for (i = 0; i < K; i++) out[i] = (r[i] * scale) * md->inv_diag[i];
    for (i = 0; i < nx; i++) {
        double acc = 0.0;
        for (j = 0; j < nx; j++) acc += md->G[i * np + j] * (r[K + j] * scale);
        out[K + i] = acc / m->c_f;
    }
    if (!nr) return 0;
    for (a = 0; a < nr; a++) {
        md->zs[a] = md->s[a] * row_dot(md->T_K + (size_t)md->rows[a] * K, out, K);
        for (b = 0; b < nr; b++)
            md->small[a * nr + b] = (a == b ? 1.0 : 0.0)
                                    - md->s[a] * md->gram[(size_t)md->rows[a] * m->nd + md->rows[b]];
    }
    if (pcs_dense_solve(md->small, md->zs, nr) != 0) return -1;
    for (a = 0; a < nr; a++) {
        const double *u = md->U + (size_t)md->rows[a] * K;
        double z = md->zs[a];
        for (i = 0; i < K; i++) out[i] += u[i] * z;
    }
    return 0;
}

/* delta_free and W for the slack set md->slack (solve_step) */
static int solve_step(Catenary *m)
{
    struct Modal *md = m->modal;
    int N = md->N, k, d, i, active = 0;
    woodbury_rows(m, md->slack);
    for (d = 0; d < m->nd; d++) active = active || md->slack[d] != 0.0 || m->committed[d] != 0.0;
    if (active) {
        slack_forces(m, md->slack, md->q_p, md->v_p, md->sf);
        for (i = 0; i < N; i++) md->r[i] = md->sf[i] * m->c_f + md->rhs[i];
        if (diag_woodbury(m, md->r, 1.0, md->delta_free) != 0) return -1;
    } else if (diag_woodbury(m, md->rhs, 1.0, md->delta_free) != 0) {
        return -1;
    }
    for (k = 0; k < m->np; k++)
        if (diag_woodbury(m, md->Wc + (size_t)k * N, m->c_f, md->Wl + (size_t)k * N) != 0)
            return -1;
    return 0;
}

/* the diagonal and the droppers' Gram matrix of the step's coefficients (woodbury_base) */
static void woodbury_base(Catenary *m)
{
    struct Modal *md = m->modal;
    int K = md->K, mm = md->m, nd = m->nd, i, d, e;
    for (i = 0; i < mm; i++)
        md->inv_diag[i] = 1.0 / (m->c_a + m->c_f * (m->c_v * md->zeta_c[i] + md->omega2[i]));
    for (i = mm; i < K; i++)
        md->inv_diag[i] = 1.0 / (m->c_f * md->kbar * (1.0 + m->c_v * md->beta_r));
    for (d = 0; d < nd; d++)
        for (i = 0; i < K; i++)
            md->U[(size_t)d * K + i] = md->T_K[(size_t)d * K + i] * md->inv_diag[i];
    for (d = 0; d < nd; d++)
        for (e = 0; e < nd; e++)
            md->gram[(size_t)d * nd + e] = row_dot(md->T_K + (size_t)d * K,
                                                   md->U + (size_t)e * K, K);
}

/* f_rest at (y, v) with the loads F and the committed set (ModalCatenary.evaluate) */
static void rest_forces(Catenary *m, const double *y, const double *v, const double *F,
                        double *f)
{
    struct Modal *md = m->modal;
    int mm = md->m, nz = md->nz, K = md->K, N = md->N, np = m->np, i, j, d;
    for (d = 0; d < m->nd; d++) md->slack[d] = slack_at(m, d, y) ? 1.0 : 0.0;
    slack_forces(m, md->slack, y, v, md->sf);
    for (i = 0; i < mm; i++) f[i] = md->zeta_c[i] * v[i] + md->omega2[i] * y[i];
    for (i = mm; i < mm + nz; i++) f[i] = md->kbar * (y[i] + md->beta_r * v[i]);
    for (i = 0; i < md->nx; i++) {
        double s = 0.0;
        for (j = 0; j < md->nx; j++) s += md->Ginv[i * np + j] * y[K + j];
        f[K + i] = s;
    }
    for (i = 0; i < N; i++) f[i] += md->r0[i];
    for (i = 0; i < N; i++) f[i] -= md->sf[i];
    for (j = 0; j < np; j++)
        for (i = 0; i < N; i++) f[i] -= md->Wc[(size_t)j * N + i] * F[j];
}

static void modal_outputs(Catenary *m)
{
    struct Modal *md = m->modal;
    int N = md->N, K = md->K, mm = md->m, nz = md->nz, np = m->np, k, j, i, r;
    if (md->geometry_t != *m->t) {      /* at the points of the current time */
        geometry(m);
        md->geometry_t = *m->t;
    }
    for (k = 0; k < np; k++) {
        const double *w = md->Wc + (size_t)k * N, *dw = md->Wcx + (size_t)k * N;
        double z = 0.0, vz = 0.0, slope = 0.0;
        for (i = 0; i < N; i++) {
            z += w[i] * m->q[i];
            vz += w[i] * m->v[i];
            slope += dw[i] * m->q[i];
        }
        m->out_z[k] = z + md->offset[k];
        m->out_v[k] = vz + m->speed * (slope + md->doffset[k]);
    }
    /* support uplift (modal_kernels.support_uplift) */
    {
        double c[NP];
        for (i = 0; i < K; i++) md->yt[i] = m->q[i];
        for (j = 0; j < md->nx; j++) {
            double s = 0.0;
            const double *wj = md->Wc + (size_t)j * N;
            for (k = 0; k < md->nx; k++) s += md->Ginv[j * np + k] * m->q[K + k];
            c[j] = s;
            for (i = 0; i < mm; i++) md->yt[i] -= s * wj[i] / md->omega2[i];
            for (i = 0; i < nz; i++) md->yt[mm + i] -= s * wj[mm + i] / md->kbar;
        }
        for (r = 0; r < m->ns && r < CAT_MAX_SUPPORTS; r++) {
            double acc = 0.0;
            for (j = 0; j < md->nx; j++)
                for (i = 0; i < 4; i++)
                    if (m->pts[j].dof[i] >= 0)
                        acc += md->C_sup[(size_t)r * md->nS + m->pts[j].dof[i]] * m->pts[j].w[i] * c[j];
            acc += row_dot(md->Phi_sup + (size_t)r * mm, md->yt, mm);
            acc += row_dot(md->Q_sup + (size_t)r * nz, md->yt + mm, nz);
            m->uplift[r] = acc;
        }
    }
}

static int modal_initialize(void *model, char *err)
{
    Catenary *m = (Catenary *)model;
    struct Modal *md = m->modal;
    int N = md->N, k, d, i;
    for (k = 0; k < m->np; k++)
        if (m->mode == 1 && !(m->F0[k] > 0.0)) {
            snprintf(err, PCS_MSG, "contact_mode = 1 needs the static start of an exported "
                     "static_force_%d > 0 (exported: %g N)", k + 1, m->F0[k]);
            return PCS_ERROR;
        }
    *m->t = 0.0; *m->n_steps = 0.0; *m->failed = 0.0; *m->synced = 0.0;
    memcpy(m->q, m->q0, (size_t)N * sizeof(double));
    memset(m->v, 0, (size_t)N * sizeof(double));
    if (locate_all(m, 0.0, err) != 0) return PCS_ERROR;
    md->geometry_t = 0.0;
    for (d = 0; d < m->nd; d++) m->committed[d] = slack_at(m, d, m->q) ? 1.0 : 0.0;
    rest_forces(m, m->q, m->v, m->F0, m->f);
    for (i = 0; i < N; i++) m->a[i] = -m->f[i];
    m->c_a = 1.0 / (m->beta * m->h * m->h);
    m->c_v = m->gamma / (m->beta * m->h);
    m->c_f = 1.0 + m->alpha;
    woodbury_base(m);
    modal_outputs(m);
    cat_start(m);
    return PCS_OK;
}

/* sum_j a_j b_j in single precision, in eight running sums (the screen's error bound holds
   for a sum in any order) */
static float dot32(const float *a, const float *b, int n)
{
    float s[8] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    int j = 0, k;
    for (; j + 8 <= n; j += 8)
        for (k = 0; k < 8; k++) s[k] += a[j + k] * b[j + k];
    for (; j < n; j++) s[0] += a[j] * b[j];
    return ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]));
}

/* the droppers slack at y = q_p + delta into slack_new, without the whole product T_K y each
   step (modal_kernels.screen_slack): a kept reference and a bound of the drift from it
   settle most droppers; the others take their row in single precision with a bound of its
   error, in double precision when that is too close; when more than an eighth are open,
   every row and a new reference. The set is the double-precision one, to round-off. */
static void screen_slack(Catenary *m)
{
    struct Modal *md = m->modal;
    int K = md->K, nd = m->nd, nb = md->nb, d, b, j, open = 0, refresh;
    double ss = 0.0, ny, *x2 = md->xb, *x1 = md->xb + nb;
    for (b = 0; b < nb; b++) {                 /* _drift_pass */
        double s = 0.0, s1 = 0.0, s2 = 0.0;
        int j1 = (b + 1) * SCREEN_BLOCK < K ? (b + 1) * SCREEN_BLOCK : K;
        for (j = b * SCREEN_BLOCK; j < j1; j++) {
            double yj = md->q_p[j] + md->delta[j], dj = yj - md->y_ref[j];
            md->y32[j] = (float)yj;
            s += yj * yj;
            s1 += fabs(yj);
            s2 += dj * dj;
        }
        ss += s;
        x2[b] = sqrt(s2);
        x1[b] = s1;
    }
    ny = sqrt(ss);
    for (d = 0; d < nd; d++) {
        md->slack_new[d] = 0.0;
        if (!m->d_tension[d]) continue;
        if (fabs(md->ref[d]) > md->ref[nd + d] + row_dot(md->Tb + (size_t)d * nb, x2, nb)) {
            md->slack_new[d] = md->ref[d] < 0.0 ? 1.0 : 0.0;
        } else {
            open++;
            md->ref[2 * nd + d] = 1.0;
        }
    }
    refresh = open > md->most;
    for (d = 0; d < nd; d++) {
        double r, bound, sy;
        int decided = 0;
        if (!m->d_tension[d] || !(refresh || md->ref[2 * nd + d] != 0.0)) continue;
        sy = row_dot(md->Tm + (size_t)d * nb, x1, nb);           /* _row_force */
        if (ny < 1e30) {
            r = m->d_N0[d] + m->d_ka[d] * (double)dot32(md->T32 + (size_t)d * K, md->y32, K);
            bound = md->tol[0] * sy + 1e-25;
            decided = fabs(r) > bound;
        }
        if (!decided) {
            const double *t = md->T_K + (size_t)d * K;
            double acc = 0.0;
            for (j = 0; j < K; j++) acc += t[j] * (md->q_p[j] + md->delta[j]);
            r = m->d_N0[d] + m->d_ka[d] * acc;
            bound = md->tol[1] * sy + 1e-25;
        }
        md->slack_new[d] = r < 0.0 ? 1.0 : 0.0;
        md->ref[2 * nd + d] = 0.0;
        if (refresh) {
            md->ref[d] = r;
            md->ref[nd + d] = bound;
        }
    }
    if (refresh)
        for (j = 0; j < K; j++) md->y_ref[j] = md->q_p[j] + md->delta[j];
}

/* contact_mode 1: the penalty forces F of the pantographs at zp, vp with the wire at t + h
   affine in F, z_w = z_free + G F, v_w = v_free + H F (interaction/condensed.py) */
static int contact_forces(Catenary *m, const double *zp, const double *vp, double *F)
{
    struct Modal *md = m->modal;
    int N = md->N, np = m->np, k, j, i;
    double G[NP * NP] = {0.0}, H[NP * NP] = {0.0}, dz[NP] = {0.0}, dv[NP] = {0.0};
    for (k = 0; k < np; k++) {
        const double *w = md->Wc + (size_t)k * N, *dw = md->Wcx + (size_t)k * N;
        double z = 0.0, v = 0.0, slope = 0.0;
        for (i = 0; i < N; i++) {
            double q = md->q_p[i] + md->delta_free[i];
            z += w[i] * q;
            v += w[i] * (md->v_p[i] + m->c_v * md->delta_free[i]);
            slope += dw[i] * q;
        }
        dz[k] = zp[k] - (z + md->offset[k]);
        dv[k] = vp[k] - (v + m->speed * (slope + md->doffset[k]));
        for (j = 0; j < np; j++) {
            const double *wl = md->Wl + (size_t)j * N;
            G[k * np + j] = row_dot(w, wl, N);
            H[k * np + j] = m->c_v * G[k * np + j] + m->speed * row_dot(dw, wl, N);
        }
    }
    return pcs_penalty_forces(m, dz, dv, G, H, F);
}

static int modal_step(Catenary *m, double *F, const double *zp, const double *vp, char *err)
{
    struct Modal *md = m->modal;
    int N = md->N, mm = md->m, K = md->K, np = m->np, i, j, k, d, passes = 0;
    double h = m->h, cq = (0.5 - m->beta) * h * h, cv = (1.0 - m->gamma) * h;
    double c_f = m->c_f;
    md->geometry_t = NAN;               /* m->pts are at t + h */
    if (geometry(m) != 0) {
        snprintf(err, PCS_MSG, "modal catenary: pantographs farther apart than the residual "
                 "tables cover");
        return PCS_DISCARD;
    }
    for (i = 0; i < N; i++) {           /* predict_rhs */
        md->q_p[i] = m->q[i] + h * m->v[i] + cq * m->a[i];
        md->v_p[i] = m->v[i] + cv * m->a[i];
    }
    for (i = 0; i < mm; i++)
        md->rhs[i] = m->alpha * m->f[i]
                     - c_f * (md->zeta_c[i] * md->v_p[i] + md->omega2[i] * md->q_p[i] + md->r0[i]);
    for (i = mm; i < K; i++)
        md->rhs[i] = m->alpha * m->f[i]
                     - c_f * (md->kbar * (md->q_p[i] + md->beta_r * md->v_p[i]) + md->r0[i]);
    for (i = 0; i < md->nx; i++) {
        double s = 0.0;
        for (j = 0; j < md->nx; j++) s += md->Ginv[i * np + j] * md->q_p[K + j];
        md->rhs[K + i] = m->alpha * m->f[K + i] - c_f * (s + md->r0[K + i]);
    }
    memcpy(md->slack, m->committed, (size_t)m->nd * sizeof(double));
    for (;;) {
        int changed = 0;
        if (passes >= MAX_SLACK_PASSES) {
            snprintf(err, PCS_MSG, "modal catenary: the slack set does not settle at t = %.6g s "
                     "after %d passes", *m->t + h, passes);
            return PCS_DISCARD;
        }
        passes++;
        if (solve_step(m) != 0) {
            snprintf(err, PCS_MSG, "modal catenary: singular slack-set correction at t = %.6g s",
                     *m->t + h);
            return PCS_DISCARD;
        }
        if (m->mode == 1 && contact_forces(m, zp, vp, F) != 0) {
            snprintf(err, PCS_MSG, "modal catenary: the penalty contact has no solution at "
                     "t = %.6g s (singular, or its active set does not settle in %d passes)",
                     *m->t + h, 2 * np + 2);
            return PCS_DISCARD;
        }
        for (i = 0; i < N; i++) {       /* add_loads */
            double dl = md->delta_free[i];
            for (k = 0; k < np; k++) dl += F[k] * md->Wl[(size_t)k * N + i];
            md->delta[i] = dl;
        }
        screen_slack(m);
        for (d = 0; d < m->nd; d++) changed = changed || md->slack_new[d] != md->slack[d];
        if (!changed) break;
        memcpy(md->slack, md->slack_new, (size_t)m->nd * sizeof(double));
    }
    for (i = 0; i < N; i++) {           /* advance */
        double dl = md->delta[i];
        m->q[i] = md->q_p[i] + dl;
        m->v[i] = md->v_p[i] + m->c_v * dl;
        m->a[i] = m->c_a * dl;
        m->f[i] = i < mm ? (m->alpha * m->f[i] - m->a[i]) / c_f : m->alpha * m->f[i] / c_f;
    }
    memcpy(m->committed, md->slack, (size_t)m->nd * sizeof(double));
    *m->t += h;
    *m->n_steps += 1.0;
    md->geometry_t = *m->t;
    m->iterations += passes;
    return PCS_OK;
}

const PcsModelType pcs_modal_catenary = CATENARY_TABLE(
    "modal catenary", PCS_KIND_MODAL_CATENARY, modal_new, modal_free, modal_initialize);
