/*
 * HHT-alpha with full Newton-Raphson on a small dense model (hht_dense.h): the arithmetic of
 * pantocosim.core.hht.HHTIntegrator.step, term by term.
 */
#include "hht_dense.h"
#include "pcs_float.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define HHT_MAX_N 4096

static size_t doubles_of(int n)
{
    size_t m = (size_t)n;
    /* state 3 + 5n, evaluation 2n + 4n^2, work 8n + n^2 */
    return 3 + 15 * m + 5 * m * m;
}

size_t hht_dense_bytes(int n)
{
    size_t ints = (size_t)(n > 0 ? n : 0) * sizeof(int);
    if (n < 1 || n > HHT_MAX_N) return 0;
    return doubles_of(n) * sizeof(double) + ints + sizeof(double);
}

int hht_dense_init(HhtDense *e, int n, const HhtSettings *s, HhtModelFn model,
                   void *model_data, void *memory, size_t bytes, char *msg)
{
    double *p;
    size_t m = (size_t)n, nn;
    if (n < 1 || n > HHT_MAX_N || !memory || bytes < hht_dense_bytes(n)) {
        snprintf(msg, HHT_MSG, "HHT engine: %d unknowns in %lu bytes (needs 1..%d unknowns "
                 "and hht_dense_bytes)", n, (unsigned long)bytes, HHT_MAX_N);
        return -1;
    }
    if (!(s->alpha >= -1.0 / 3.0 && s->alpha <= 0.0) || !(s->rtol > 0.0) ||
        !(s->etol >= 0.0) || s->max_iterations < 1) {
        snprintf(msg, HHT_MSG, "HHT engine: alpha = %g (accepted -1/3 .. 0), rtol = %g (> 0), "
                 "etol = %g (>= 0), max_iterations = %d (>= 1)", s->alpha, s->rtol, s->etol,
                 s->max_iterations);
        return -1;
    }
    memset(e, 0, sizeof *e);
    e->n = n;
    e->s = *s;
    e->gamma = 0.5 - s->alpha;
    e->beta = 0.25 * (1.0 - s->alpha) * (1.0 - s->alpha);
    e->model = model;
    e->model_data = model_data;
    nn = m * m;
    p = (double *)memory;
    memset(p, 0, hht_dense_bytes(n));
    e->state.n = n;
    e->state.block = p;
    e->state.q = p + 3;
    e->state.v = e->state.q + m;
    e->state.a = e->state.v + m;
    e->state.a_prev = e->state.a + m;
    e->state.f_rest = e->state.a_prev + m;
    p = e->state.f_rest + m;
    e->ev.f_inertia = p;
    e->ev.f_rest = p + m;
    e->ev.mass = p + 2 * m;
    e->ev.inertia_q = e->ev.mass + nn;
    e->ev.damping = e->ev.inertia_q + nn;
    e->ev.stiffness = e->ev.damping + nn;
    p = e->ev.stiffness + nn;
    e->q_p = p;
    e->v_p = p + m;
    e->q = p + 2 * m;
    e->v = p + 3 * m;
    e->a = p + 4 * m;
    e->hist = p + 5 * m;
    e->R = p + 6 * m;
    e->x = p + 7 * m;
    e->S = p + 8 * m;
    e->piv = (int *)(e->S + nn);
    return 0;
}

int hht_lu_factor(double *A, int *piv, int n)
{
    int i, j, k;
    for (k = 0; k < n; k++) {
        int p = k;
        double big = fabs(A[k * n + k]);
        for (i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > big) { big = fabs(A[i * n + k]); p = i; }
        piv[k] = p;
        if (!(big > 0.0) || !isfinite(big)) return -1;
        if (p != k)
            for (j = 0; j < n; j++) {
                double tmp = A[k * n + j];
                A[k * n + j] = A[p * n + j];
                A[p * n + j] = tmp;
            }
        for (i = k + 1; i < n; i++) {
            double l = A[i * n + k] / A[k * n + k];
            A[i * n + k] = l;
            for (j = k + 1; j < n; j++) A[i * n + j] -= l * A[k * n + j];
        }
    }
    return 0;
}

void hht_lu_solve(const double *LU, const int *piv, int n, double *b)
{
    int i, j;
    for (i = 0; i < n; i++) {
        double tmp = b[piv[i]];
        b[piv[i]] = b[i];
        b[i] = tmp;
    }
    for (i = 1; i < n; i++)
        for (j = 0; j < i; j++) b[i] -= LU[i * n + j] * b[j];
    for (i = n - 1; i >= 0; i--) {
        for (j = i + 1; j < n; j++) b[i] -= LU[i * n + j] * b[j];
        b[i] /= LU[i * n + i];
    }
}

/* S = c_a M + c_f (c_v C + K) + dM/dq a: the Newton matrix (model.effective_matrix) */
static void newton_matrix(HhtDense *e, double c_a, double c_v, double c_f)
{
    size_t i, nn = (size_t)e->n * (size_t)e->n;
    const HhtEval *ev = &e->ev;
    for (i = 0; i < nn; i++)
        e->S[i] = c_a * ev->mass[i] + c_f * (c_v * ev->damping[i] + ev->stiffness[i]) +
                  ev->inertia_q[i];
}

int hht_dense_start(HhtDense *e, double t0, const double *q0, const double *v0,
                    const double *inputs0, char *msg)
{
    int i, n = e->n;
    HhtState *st = &e->state;
    for (i = 0; i < n; i++) {
        e->q[i] = q0[i];
        e->v[i] = v0 ? v0[i] : 0.0;
        e->a[i] = 0.0;
    }
    if (e->model(e->model_data, t0, e->q, e->v, e->a, inputs0, 1, &e->ev, msg)) return HHT_FAILED;
    newton_matrix(e, 1.0, 0.0, 0.0);
    if (hht_lu_factor(e->S, e->piv, n)) {
        snprintf(msg, HHT_MSG, "HHT start: the mass matrix at t0 = %g is singular", t0);
        return HHT_FAILED;
    }
    for (i = 0; i < n; i++) e->x[i] = e->ev.f_rest[i] + e->ev.f_inertia[i];
    hht_lu_solve(e->S, e->piv, n, e->x);
    for (i = 0; i < n; i++) {
        if (!isfinite(e->x[i])) {
            snprintf(msg, HHT_MSG, "HHT start: non-finite acceleration at t0 = %g", t0);
            return HHT_FAILED;
        }
    }
    st->block[0] = t0;
    st->block[1] = 0.0;
    st->block[2] = 0.0;
    for (i = 0; i < n; i++) {
        st->q[i] = e->q[i];
        st->v[i] = e->v[i];
        st->a[i] = -e->x[i];
        st->a_prev[i] = 0.0;
        st->f_rest[i] = e->ev.f_rest[i];
    }
    e->iterations = 0;
    e->residual = 0.0;
    return HHT_OK;
}

/* Newmark predictors q_p, v_p (3.16)-(3.17), the first iterate and alpha f_rest_n */
static void predict(HhtDense *e, double h)
{
    const HhtState *st = &e->state;
    int i, linear = e->s.linear_predictor && st->block[2] != 0.0;
    double cq = (0.5 - e->beta) * h * h, cv = (1.0 - e->gamma) * h, cg = e->beta * h * h;
    for (i = 0; i < e->n; i++) {
        double guess = linear ? 2.0 * st->a[i] - st->a_prev[i] : st->a[i];
        e->q_p[i] = st->q[i] + h * st->v[i] + cq * st->a[i];
        e->v_p[i] = st->v[i] + cv * st->a[i];
        e->q[i] = e->q_p[i] + cg * guess;
        e->hist[i] = e->s.alpha * st->f_rest[i];
    }
}

/* R = f_inertia + c_f f_rest - hist, its max norm and the size of the forces in it;
   0 when every term is finite */
static int residual(HhtDense *e, double c_f, double *r_max, double *scale)
{
    int i;
    double total = 0.0;
    *r_max = 0.0;
    *scale = 0.0;
    for (i = 0; i < e->n; i++) {
        double fi = e->ev.f_inertia[i], fr = c_f * e->ev.f_rest[i], h = e->hist[i];
        double r = fi + fr - h, m = fabs(fi);
        e->R[i] = r;
        total += r;
        if (fabs(r) > *r_max) *r_max = fabs(r);
        if (fabs(fr) > m) m = fabs(fr);
        if (fabs(h) > m) m = fabs(h);
        if (m > *scale) *scale = m;
    }
    return isfinite(total) ? 0 : -1;
}

static void commit(HhtDense *e, double t1, int k, double res)
{
    HhtState *st = &e->state;
    int i;
    st->block[0] = t1;
    st->block[1] += 1.0;
    st->block[2] = 1.0;
    for (i = 0; i < e->n; i++) {
        st->a_prev[i] = st->a[i];
        st->q[i] = e->q[i];
        st->v[i] = e->v[i];
        st->a[i] = e->a[i];
        st->f_rest[i] = e->ev.f_rest[i];
    }
    e->iterations = k;
    e->residual = res;
}

int hht_dense_step(HhtDense *e, double h, const double *inputs, char *msg)
{
    int i, k, n = e->n, converged = 0, have_e = 0;
    double t1 = e->state.block[0] + h, c_a, c_v, c_f = 1.0 + e->s.alpha;
    double res = 0.0, scale, e0 = 0.0, e_prev = 0.0, dq_size = 0.0, q_size = 0.0;
    if (!(h > 0.0) || !isfinite(h)) {
        snprintf(msg, HHT_MSG, "HHT step: h = %g (must be finite and > 0)", h);
        return HHT_FAILED;
    }
    c_a = 1.0 / (e->beta * h * h);
    c_v = e->gamma / (e->beta * h);
    predict(e, h);
    for (k = 0; k <= e->s.max_iterations; k++) {
        double en = 0.0;
        for (i = 0; i < n; i++) {
            double d = e->q[i] - e->q_p[i];
            e->a[i] = c_a * d;
            e->v[i] = e->v_p[i] + c_v * d;
        }
        if (e->model(e->model_data, t1, e->q, e->v, e->a, inputs, 1, &e->ev, msg))
            return HHT_FAILED;
        if (residual(e, c_f, &res, &scale)) {
            snprintf(msg, HHT_MSG, "HHT: non-finite residual at t = %.6g s (step %.0f)", t1,
                     e->state.block[1] + 1.0);
            return HHT_FAILED;
        }
        if (scale < 1e-300) scale = 1e-300;
        converged = res <= e->s.rtol * scale;
        if (!converged && have_e)
            converged = e_prev <= e->s.etol * e0 || dq_size <= 1e-15 * q_size;
        if (converged || k == e->s.max_iterations) break;
        newton_matrix(e, c_a, c_v, c_f);
        if (hht_lu_factor(e->S, e->piv, n)) {
            snprintf(msg, HHT_MSG, "HHT: singular Newton matrix at t = %.6g s", t1);
            return HHT_FAILED;
        }
        for (i = 0; i < n; i++) e->x[i] = e->R[i];
        hht_lu_solve(e->S, e->piv, n, e->x);
        dq_size = q_size = 0.0;
        for (i = 0; i < n; i++) {
            e->q[i] -= e->x[i];
            en += e->x[i] * e->R[i];
            if (fabs(e->x[i]) > dq_size) dq_size = fabs(e->x[i]);
            if (fabs(e->q[i]) > q_size) q_size = fabs(e->q[i]);
        }
        if (!have_e) e0 = fabs(en) > 1e-300 ? fabs(en) : 1e-300;
        e_prev = fabs(en);
        have_e = 1;
    }
    if (!converged) {
        snprintf(msg, HHT_MSG, "HHT Newton-Raphson did not converge at t = %.6g s (step %.0f, "
                 "h = %.3g s): residual %.3e after %d iterations", t1,
                 e->state.block[1] + 1.0, h, res, e->s.max_iterations);
        return HHT_FAILED;
    }
    commit(e, t1, k, res);
    return HHT_OK;
}
