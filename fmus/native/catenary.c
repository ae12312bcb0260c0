/*
 * What the linear and modal catenaries share (catenary.h): the contact-wire points of
 * contact_point.py (3.11)-(3.13), the penalty law of interaction/penalty_contact.py
 * (contact_mode 1), the communication step as internal steps of the model's own step
 * (CatenaryStep), the FMU state and the variables.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "catenary.h"

int pcs_dense_solve(double *A, double *y, int n)
{
    int i, j, k;
    for (k = 0; k < n; k++) {
        int p = k;
        double best = fabs(A[(size_t)k * n + k]);
        for (i = k + 1; i < n; i++)
            if (fabs(A[(size_t)i * n + k]) > best) { best = fabs(A[(size_t)i * n + k]); p = i; }
        if (!(best > 0.0)) return -1;
        if (p != k) {
            double t;
            for (j = 0; j < n; j++) {
                t = A[(size_t)k * n + j]; A[(size_t)k * n + j] = A[(size_t)p * n + j];
                A[(size_t)p * n + j] = t;
            }
            t = y[k]; y[k] = y[p]; y[p] = t;
        }
        for (i = k + 1; i < n; i++) {
            double l = A[(size_t)i * n + k] / A[(size_t)k * n + k];
            if (l == 0.0) continue;
            for (j = k; j < n; j++) A[(size_t)i * n + j] -= l * A[(size_t)k * n + j];
            y[i] -= l * y[k];
        }
    }
    for (i = n - 1; i >= 0; i--) {
        double s = y[i];
        for (j = i + 1; j < n; j++) s -= A[(size_t)i * n + j] * y[j];
        y[i] = s / A[(size_t)i * n + i];
    }
    return 0;
}

/* x <- A_s^-1 x for the removed rank-one terms (rows, s) of count r (Woodbury, lowrank.py) */
/* ------------------------------------------------------------------ contact wire */

static void hermite(double xi, double L, double *S)
{
    double x2 = xi * xi, x3 = x2 * xi;
    S[0] = 1 - 3 * x2 + 2 * x3;
    S[1] = L * (xi - 2 * x2 + x3);
    S[2] = 3 * x2 - 2 * x3;
    S[3] = L * (x3 - x2);
}

static void hermite_dxi(double xi, double L, double *S)
{
    double x2 = xi * xi;
    S[0] = -6 * xi + 6 * x2;
    S[1] = L * (1 - 4 * xi + 3 * x2);
    S[2] = 6 * xi - 6 * x2;
    S[3] = L * (3 * x2 - 2 * xi);
}

static double dot4(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
}

/* the contact-wire point at track position x (contact_point.py); -1 outside the wire */
int pcs_locate(const Catenary *m, double x, Point *p, char *err)
{
    int lo = 0, hi = m->ne, k, it, i;
    double xi, L, S[4], D[4], slope;
    const double *c;
    if (!(x >= m->x_min - 1e-9 && x <= m->x_max + 1e-9)) {
        if (err)
            snprintf(err, PCS_MSG, "pantograph position x = %.17g m: outside the contact wire "
                     "[%g, %g] m", x, m->x_min, m->x_max);
        return -1;
    }
    /* k = searchsorted(x_start, x, right) - 1 */
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (m->w_xs[mid] <= x) lo = mid + 1; else hi = mid;
    }
    k = lo - 1;
    if (k < 0) k = 0;
    if (k > m->ne - 1) k = m->ne - 1;
    L = m->w_Le[k];
    c = m->w_Ex + (size_t)k * 4;
    {
        double span = m->w_xe[k] - m->w_xs[k];
        xi = (x - m->w_xs[k]) / (span > 1e-300 ? span : 1e-300);
    }
    for (it = 0; it < 30; it++) {
        double step;
        hermite(xi, L, S);
        hermite_dxi(xi, L, D);
        step = (dot4(S, c) - x) / dot4(D, c);
        xi -= step;
        if (fabs(step) < 1e-15) break;
    }
    xi = xi < 0.0 ? 0.0 : (xi > 1.0 ? 1.0 : xi);
    hermite(xi, L, S);
    hermite_dxi(xi, L, D);
    slope = dot4(D, c);
    for (i = 0; i < 4; i++) {
        p->dof[i] = m->w_dof[(size_t)k * 4 + i];
        p->zfix[i] = m->w_zfix[(size_t)k * 4 + i];
        p->w[i] = S[i];
        p->dw[i] = D[i] / slope;
    }
    return 0;
}

/* (w . q, w . v + V dw . q) of a point, fixed DOFs at their reference height */
/* the penalty law (penalty_contact.py) */
static double penalty(const Catenary *m, double zp, double zw, double vp, double vw)
{
    double gap = zp - zw, F;
    if (gap <= 0.0) return 0.0;
    F = m->k_h * gap + m->c_h * (vp - vw);
    return F > 0.0 ? F : 0.0;
}

int pcs_penalty_forces(const Catenary *m, const double *dz, const double *dv,
                        const double *G, const double *H, double *F)
{
    int np = m->np, it, i, j, active[CAT_MAX_PANTOGRAPHS], trial[CAT_MAX_PANTOGRAPHS];
    double A[CAT_MAX_PANTOGRAPHS * CAT_MAX_PANTOGRAPHS], y[CAT_MAX_PANTOGRAPHS];
    for (i = 0; i < np; i++) active[i] = dz[i] > 0.0;
    for (it = 0; it < 2 * np + 2; it++) {
        int changed = 0;
        for (i = 0; i < np; i++) {
            for (j = 0; j < np; j++)
                A[i * np + j] = (active[i] && active[j]) ? m->k_h * G[i * np + j]
                                                             + m->c_h * H[i * np + j] : 0.0;
            A[i * np + i] += 1.0;
            y[i] = active[i] ? m->k_h * dz[i] + m->c_h * dv[i] : 0.0;
        }
        if (pcs_dense_solve(A, y, np) != 0) {
            for (i = 0; i < np; i++) F[i] = NAN;
            return -1;
        }
        for (i = 0; i < np; i++) F[i] = y[i];
        for (i = 0; i < np; i++) {
            double gap = dz[i], rel = dv[i];
            for (j = 0; j < np; j++) {
                gap -= G[i * np + j] * F[j];
                rel -= H[i * np + j] * F[j];
            }
            trial[i] = gap > 0.0 && m->k_h * gap + m->c_h * rel > 0.0;
            changed = changed || trial[i] != active[i];
        }
        if (!changed) return 0;
        for (i = 0; i < np; i++) active[i] = trial[i];
    }
    return -1;                 /* the active set did not settle: the last forces in F */
}

/* one internal step of h with forces F (mode 0) or pantograph heights zp, vp (mode 1);
   the contact points at t + h are in m->pts; F is written in mode 1 */
int cat_step(void *model, double t, double H, char *err)
{
    Catenary *m = (Catenary *)model;
    int k, i, n_sub, status;
    double u[CAT_MAX_PANTOGRAPHS], zp[CAT_MAX_PANTOGRAPHS], vp[CAT_MAX_PANTOGRAPHS];
    double nw[2 * CAT_MAX_PANTOGRAPHS];
    (void)t;
    if (!m->initialised) {
        snprintf(err, PCS_MSG, "doStep before the FMU was initialised");
        return PCS_ERROR;
    }
    if (*m->failed != 0.0) {
        snprintf(err, PCS_MSG, "doStep after a failed step: roll back with a saved FMU state");
        return PCS_DISCARD;
    }
    if ((n_sub = (int)pcs_substeps(H, m->h, err)) < 0) return PCS_DISCARD;
    for (k = 0; k < m->np; k++) {            /* inputs at t + H, checked before any change */
        char name[40];
        snprintf(name, sizeof name, "contact_force_%d", k + 1);
        if (m->mode == 0
            && pcs_within(name, m->u_force[k], 0.0, PCS_MAX_CONTACT_FORCE, " N", err) != 0)
            return PCS_DISCARD;
        snprintf(name, sizeof name, "pantograph_height_%d", k + 1);
        if (m->mode == 1
            && pcs_within(name, m->u_z[k], -PCS_MAX_HEIGHT, PCS_MAX_HEIGHT, " m", err) != 0)
            return PCS_DISCARD;
        snprintf(name, sizeof name, "pantograph_velocity_%d", k + 1);
        if (m->mode == 1 && pcs_within(name, m->u_v[k], -PCS_MAX_VELOCITY, PCS_MAX_VELOCITY,
                                       " m/s", err) != 0)
            return PCS_DISCARD;
        nw[2 * k] = m->mode == 0 ? m->u_force[k] : m->u_z[k];
        nw[2 * k + 1] = m->mode == 0 ? 0.0 : m->u_v[k];
    }
    {   /* the points of the whole step must lie on the wire */
        double t_end = *m->t;
        Point p;
        for (i = 0; i < n_sub; i++) t_end += m->h;
        for (k = 0; k < m->np; k++)
            if (pcs_locate(m, m->x0[k] + m->speed * t_end, &p, err) != 0) return PCS_DISCARD;
    }
    if (m->mode == 1 && m->extrapolate && *m->n_steps == 0.0)
        for (k = 0; k < m->np; k++) {       /* the start's heights stand at the first step */
            nw[2 * k] = m->prev[2 * k];
            nw[2 * k + 1] = m->prev[2 * k + 1];
        }
    m->iterations = 0.0;
    for (i = 1; i <= n_sub; i++) {
        double tt = *m->t + m->h;
        for (k = 0; k < m->np; k++) {
            pcs_locate(m, m->x0[k] + m->speed * tt, &m->pts[k], NULL);
            if (m->mode == 0) {
                u[k] = i == n_sub ? nw[2 * k]
                                  : m->prev[2 * k] + (nw[2 * k] - m->prev[2 * k]) * ((double)i / n_sub);
            } else if (m->extrapolate) {
                zp[k] = nw[2 * k] + nw[2 * k + 1] * i * m->h;
                vp[k] = nw[2 * k + 1];
            } else {
                double s = (double)i / n_sub;
                zp[k] = i == n_sub ? nw[2 * k] : m->prev[2 * k] + (nw[2 * k] - m->prev[2 * k]) * s;
                vp[k] = i == n_sub ? nw[2 * k + 1]
                                   : m->prev[2 * k + 1] + (nw[2 * k + 1] - m->prev[2 * k + 1]) * s;
            }
        }
        status = m->own->step(m, u, zp, vp, err);
        if (status != PCS_OK) {
            if (i > 1) *m->failed = 1.0;    /* part of the step was taken */
            return status;
        }
    }
    for (k = 0; k < 2 * m->np; k++) m->prev[k] = nw[k];
    m->own->outputs(m);
    for (k = 0; k < m->np; k++)
        m->out_F[k] = m->mode == 0 ? nw[2 * k]
                                   : penalty(m, zp[k], m->out_z[k], vp[k], m->out_v[k]);
    return PCS_OK;
}

size_t cat_state_bytes(const void *model)
{
    return ((const Catenary *)model)->state_len * sizeof(double);
}

void cat_state_save(const void *model, void *buffer)
{
    memcpy(buffer, ((const Catenary *)model)->state, cat_state_bytes(model));
}

void cat_state_restore(void *model, const void *buffer)
{
    memcpy(((Catenary *)model)->state, buffer, cat_state_bytes(model));
}

/* the outputs at the state's time (the inputs at t as the last step left them) */
void cat_outputs(void *model)
{
    Catenary *m = (Catenary *)model;
    int k;
    for (k = 0; k < m->np; k++)
        pcs_locate(m, m->x0[k] + m->speed * *m->t, &m->pts[k], NULL);
    m->own->outputs(m);
    for (k = 0; k < m->np; k++)
        m->out_F[k] = m->mode == 0 ? m->prev[2 * k]
                                   : penalty(m, m->prev[2 * k], m->out_z[k], m->prev[2 * k + 1],
                                             m->out_v[k]);
}

/* ------------------------------------------------------------------ variables */


static int fixed_int(const char *name, int exported, int value, char *err)
{
    if (value == exported) return PCS_OK;
    snprintf(err, PCS_MSG, "%s = %d: this native FMU was exported with %s = %d (export it "
             "again with pantocosim export-native to change it)", name, value, name, exported);
    return PCS_ERROR;
}

static int per_pantograph(const Catenary *m, unsigned vr, unsigned base)
{
    return vr >= base && vr < base + (unsigned)m->np ? (int)(vr - base) : -1;
}

int cat_get_real(void *model, unsigned vr, double *value, char *err)
{
    Catenary *m = (Catenary *)model;
    int k;
    switch (vr) {
    case CAT_VR_SPEED_KMH: *value = m->speed * 3.6; return PCS_OK;
    case CAT_VR_TRAIN_SPEED_KMH: *value = m->speed * 3.6; return PCS_OK;
    case CAT_VR_HHT_ALPHA: *value = m->alpha; return PCS_OK;
    case CAT_VR_CONTACT_STIFFNESS: *value = m->k_h; return PCS_OK;
    case CAT_VR_CONTACT_DAMPING: *value = m->c_h; return PCS_OK;
    case CAT_VR_NEWTON_RTOL: *value = m->rtol; return PCS_OK;
    case CAT_VR_MODAL_CUTOFF_HZ: *value = m->cutoff; return PCS_OK;
    case CAT_VR_N_SUPPORTS: *value = m->ns; return PCS_OK;
    case CAT_VR_NEWTON_ITERATIONS: *value = m->iterations; return PCS_OK;
    case CAT_VR_INTERNAL_STEP: *value = m->h; return PCS_OK;
    default: break;
    }
    if ((k = per_pantograph(m, vr, CAT_VR_POSITION)) >= 0) { *value = m->x0[k]; return PCS_OK; }
    if ((k = per_pantograph(m, vr, CAT_VR_STATIC_FORCE)) >= 0) { *value = m->F0[k]; return PCS_OK; }
    if ((k = per_pantograph(m, vr, CAT_VR_CONTACT_FORCE)) >= 0) { *value = m->u_force[k]; return PCS_OK; }
    if ((k = per_pantograph(m, vr, CAT_VR_PANTOGRAPH_HEIGHT)) >= 0) { *value = m->u_z[k]; return PCS_OK; }
    if ((k = per_pantograph(m, vr, CAT_VR_PANTOGRAPH_VELOCITY)) >= 0) { *value = m->u_v[k]; return PCS_OK; }
    if ((k = per_pantograph(m, vr, CAT_VR_WIRE_HEIGHT)) >= 0) { *value = m->out_z[k]; return PCS_OK; }
    if ((k = per_pantograph(m, vr, CAT_VR_WIRE_VELOCITY)) >= 0) { *value = m->out_v[k]; return PCS_OK; }
    if ((k = per_pantograph(m, vr, CAT_VR_CONTACT_FORCE_OUT)) >= 0) { *value = m->out_F[k]; return PCS_OK; }
    if (vr >= CAT_VR_SUPPORT_UPLIFT && vr < CAT_VR_SUPPORT_UPLIFT + CAT_MAX_SUPPORTS) {
        *value = m->uplift[vr - CAT_VR_SUPPORT_UPLIFT];
        return PCS_OK;
    }
    snprintf(err, PCS_MSG, "no Real variable of value reference %u", vr);
    return PCS_ERROR;
}

int cat_set_real(void *model, unsigned vr, double value, int initialised, char *err)
{
    Catenary *m = (Catenary *)model;
    int k;
    if ((k = per_pantograph(m, vr, CAT_VR_CONTACT_FORCE)) >= 0) { m->u_force[k] = value; return PCS_OK; }
    if ((k = per_pantograph(m, vr, CAT_VR_PANTOGRAPH_HEIGHT)) >= 0) { m->u_z[k] = value; return PCS_OK; }
    if ((k = per_pantograph(m, vr, CAT_VR_PANTOGRAPH_VELOCITY)) >= 0) { m->u_v[k] = value; return PCS_OK; }
    if (initialised) {
        snprintf(err, PCS_MSG, "value reference %u is a parameter: it is set before "
                 "initialisation only", vr);
        return PCS_ERROR;
    }
    switch (vr) {
    case CAT_VR_SPEED_KMH: return pcs_fixed_real("speed_kmh", m->speed * 3.6, value, err);
    case CAT_VR_HHT_ALPHA: return pcs_fixed_real("hht_alpha", m->alpha, value, err);
    case CAT_VR_CONTACT_STIFFNESS: return pcs_fixed_real("contact_stiffness", m->k_h, value, err);
    case CAT_VR_CONTACT_DAMPING: return pcs_fixed_real("contact_damping", m->c_h, value, err);
    case CAT_VR_MODAL_CUTOFF_HZ: return pcs_fixed_real("modal_cutoff_hz", m->cutoff, value, err);
    case CAT_VR_NEWTON_RTOL:
        if (!(value > 0.0 && value <= 1e-2)) {
            snprintf(err, PCS_MSG, "newton_rtol = %.17g: must lie in (0, 0.01]", value);
            return PCS_ERROR;
        }
        m->rtol = value;     /* the closed-form step has no Newton iteration to stop */
        return PCS_OK;
    default: break;
    }
    if ((k = per_pantograph(m, vr, CAT_VR_POSITION)) >= 0) {
        char name[32];
        snprintf(name, sizeof name, "position_%d", k + 1);
        return pcs_fixed_real(name, m->x0[k], value, err);
    }
    if ((k = per_pantograph(m, vr, CAT_VR_STATIC_FORCE)) >= 0) {
        char name[32];
        snprintf(name, sizeof name, "static_force_%d", k + 1);
        return pcs_fixed_real(name, m->F0[k], value, err);
    }
    snprintf(err, PCS_MSG, "value reference %u is not a Real input or parameter", vr);
    return PCS_ERROR;
}

int cat_get_integer(void *model, unsigned vr, int *value, char *err)
{
    Catenary *m = (Catenary *)model;
    switch (vr) {
    case CAT_VR_N_PANTOGRAPHS: *value = m->np; return PCS_OK;
    case CAT_VR_SPANS: *value = m->spans; return PCS_OK;
    case CAT_VR_CATENARY_MODEL: *value = m->model_code; return PCS_OK;
    case CAT_VR_CONTACT_MODE: *value = m->mode; return PCS_OK;
    default: break;
    }
    snprintf(err, PCS_MSG, "no Integer variable of value reference %u", vr);
    return PCS_ERROR;
}

int cat_set_integer(void *model, unsigned vr, int value, int initialised, char *err)
{
    Catenary *m = (Catenary *)model;
    if (initialised) {
        snprintf(err, PCS_MSG, "Integer %u is a parameter: it is set before initialisation "
                 "only", vr);
        return PCS_ERROR;
    }
    switch (vr) {
    case CAT_VR_N_PANTOGRAPHS: return fixed_int("n_pantographs", m->np, value, err);
    case CAT_VR_SPANS: return fixed_int("spans", m->spans, value, err);
    case CAT_VR_CATENARY_MODEL: return fixed_int("catenary_model", m->model_code, value, err);
    case CAT_VR_CONTACT_MODE:
        if (value != 0 && value != 1) {
            snprintf(err, PCS_MSG, "contact_mode = %d: must be 0 (force inputs) or 1 "
                     "(built-in penalty)", value);
            return PCS_ERROR;
        }
        m->mode = value;
        return PCS_OK;
    default: break;
    }
    snprintf(err, PCS_MSG, "no Integer parameter of value reference %u", vr);
    return PCS_ERROR;
}

int cat_get_boolean(void *model, unsigned vr, int *value, char *err)
{
    Catenary *m = (Catenary *)model;
    if (vr == CAT_VR_EXTRAPOLATE_HEIGHTS) { *value = m->extrapolate; return PCS_OK; }
    snprintf(err, PCS_MSG, "no Boolean variable of value reference %u", vr);
    return PCS_ERROR;
}

int cat_set_boolean(void *model, unsigned vr, int value, int initialised, char *err)
{
    Catenary *m = (Catenary *)model;
    if (vr == CAT_VR_EXTRAPOLATE_HEIGHTS && !initialised) {
        m->extrapolate = value != 0;
        return PCS_OK;
    }
    snprintf(err, PCS_MSG, "Boolean %u cannot be set %s", vr,
             initialised ? "after initialisation" : "(no such parameter)");
    return PCS_ERROR;
}

int cat_get_string(void *model, unsigned vr, const char **value, char *err)
{
    Catenary *m = (Catenary *)model;
    if (vr == CAT_VR_CATENARY_DEFINITION) { *value = m->definition; return PCS_OK; }
    snprintf(err, PCS_MSG, "no String variable of value reference %u", vr);
    return PCS_ERROR;
}

int cat_set_string(void *model, unsigned vr, const char *value, int initialised, char *err)
{
    Catenary *m = (Catenary *)model;
    if (vr == CAT_VR_CATENARY_DEFINITION && !initialised && value
        && strcmp(value, m->definition) == 0)
        return PCS_OK;
    if (vr == CAT_VR_CATENARY_DEFINITION) {
        snprintf(err, PCS_MSG, "catenary_definition = '%s': this native FMU was exported "
                 "for '%s' (export it again with pantocosim export-native)",
                 value ? value : "(null)", m->definition);
        return PCS_ERROR;
    }
    snprintf(err, PCS_MSG, "no String parameter of value reference %u", vr);
    return PCS_ERROR;
}

void cat_start(Catenary *m)
{
    int k;
    for (k = 0; k < m->np; k++) {
        m->out_F[k] = m->F0[k];
        m->z_start[k] = m->out_z[k] + m->F0[k] / m->k_h;
        if (m->mode == 0) {
            m->prev[2 * k] = m->F0[k];
            m->u_force[k] = m->F0[k];
        } else {
            m->prev[2 * k] = m->z_start[k];
            m->prev[2 * k + 1] = 0.0;
            m->u_z[k] = m->z_start[k];
            m->u_v[k] = 0.0;
        }
    }
    m->iterations = 0.0;
    m->initialised = 1;
}

/* ------------------------------------------------------------------ reading */

int cat_check_sizes(const Catenary *m, const PcsData *d, char *err)
{
    if (m->np >= 1 && m->np <= CAT_MAX_PANTOGRAPHS && m->nd >= 0 && m->nd <= PCS_MAX_DROPPERS
        && m->ne >= 1 && m->ne <= PCS_MAX_DOFS && m->ns >= 0 && m->ns <= CAT_MAX_SUPPORTS)
        return 0;
    snprintf(err, PCS_MSG, "data file %.400s: section sizes: pantographs %d (1..%d), droppers "
             "%d (0..%d), wire elements %d (1..%d), supports %d (0..%d)", d->path, m->np,
             CAT_MAX_PANTOGRAPHS, m->nd, PCS_MAX_DROPPERS, m->ne, PCS_MAX_DOFS, m->ns,
             CAT_MAX_SUPPORTS);
    return -1;
}

#define READ(dst, name, type, count)                                                      \
    do {                                                                                  \
        dst = pcs_data_section(d, name, type, count, NULL, err, PCS_MSG);                 \
        if (!dst) return -1;                                                              \
    } while (0)

static int wire_dofs(const Catenary *m, const PcsData *d, int dofs, char *err)
{
    size_t i;
    for (i = 0; i < 4 * (size_t)m->ne; i++)
        if (m->w_dof[i] < -1 || m->w_dof[i] >= dofs) {
            snprintf(err, PCS_MSG, "data file %.400s: section wire_dof: index %d outside "
                     "-1..%d", d->path, m->w_dof[i], dofs - 1);
            return -1;
        }
    return 0;
}

int cat_read_common(Catenary *m, const PcsData *d, const double *sc, int dofs, char *err)
{
    size_t nd = (size_t)m->nd, np = (size_t)m->np, ne = (size_t)m->ne;
    m->h = sc[CAT_SCALAR_STEP];
    m->alpha = sc[CAT_SCALAR_ALPHA];
    m->beta = sc[CAT_SCALAR_BETA];
    m->gamma = sc[CAT_SCALAR_GAMMA];
    m->ar = sc[CAT_SCALAR_RAYLEIGH_MASS];
    m->br = sc[CAT_SCALAR_RAYLEIGH_STIFFNESS];
    m->speed = sc[CAT_SCALAR_SPEED];
    m->wave = sc[CAT_SCALAR_WAVE_SPEED];
    m->k_h = sc[CAT_SCALAR_CONTACT_STIFFNESS];
    m->c_h = sc[CAT_SCALAR_CONTACT_DAMPING];
    m->x_min = sc[CAT_SCALAR_WIRE_START];
    m->x_max = sc[CAT_SCALAR_WIRE_END];
    m->cutoff = sc[CAT_SCALAR_MODAL_CUTOFF];
    m->rtol = sc[CAT_SCALAR_NEWTON_RTOL];
    if (!(m->speed >= 0.0 && m->speed < m->wave)) {
        snprintf(err, PCS_MSG, "data file %.400s: speed_kmh = %.17g: must be below the contact "
                 "wire's wave speed c = %.0f km/h (at or above it the wire cannot carry the "
                 "moving load)", d->path, m->speed * 3.6, m->wave * 3.6);
        return -1;
    }
    if (!(m->h > 0.0) || !(m->x_max > m->x_min) || !(m->beta > 0.0) || !(m->k_h > 0.0)) {
        snprintf(err, PCS_MSG, "data file %.400s: section scalars: internal step %g s, wire "
                 "[%g, %g] m, HHT beta %g, contact stiffness %g N/m (all must be > 0)",
                 d->path, m->h, m->x_min, m->x_max, m->beta, m->k_h);
        return -1;
    }
    READ(m->F0, "F0", PCS_TYPE_F64, np);
    READ(m->x0, "x0", PCS_TYPE_F64, np);
    READ(m->d_ka, "drop_ka", PCS_TYPE_F64, nd);
    READ(m->d_N0, "drop_N0", PCS_TYPE_F64, nd);
    READ(m->d_tension, "drop_tension", PCS_TYPE_I32, nd);
    READ(m->w_xs, "wire_xs", PCS_TYPE_F64, ne);
    READ(m->w_xe, "wire_xe", PCS_TYPE_F64, ne);
    READ(m->w_Ex, "wire_Ex", PCS_TYPE_F64, 4 * ne);
    READ(m->w_Le, "wire_Le", PCS_TYPE_F64, ne);
    READ(m->w_dof, "wire_dof", PCS_TYPE_I32, 4 * ne);
    READ(m->w_zfix, "wire_zfix", PCS_TYPE_F64, 4 * ne);
    m->definition = pcs_data_text(d, "definition", err, PCS_MSG);
    if (!m->definition) return -1;
    m->extrapolate = 1;
    memcpy(m->u_force, m->F0, np * sizeof(double));
    return wire_dofs(m, d, dofs, err);
}

int cat_arena(Catenary *m, const PcsData *d, const PcsMemory *mem,
              void (*carve)(Catenary *m, PcsArena *a), char *err)
{
    double mib = 1024.0 * 1024.0;
    carve(m, &m->arena);
    if (m->arena.overflow || (double)m->arena.used + (double)d->size > PCS_MAX_BYTES) {
        snprintf(err, PCS_MSG, "data file %.400s: section sizes: %d coordinates and %d droppers "
                 "need %s%.0f MiB with the data, above the limit of %.0f MiB", d->path, m->n,
                 m->nd, m->arena.overflow ? "more than " : "",
                 ((double)m->arena.used + (double)d->size) / mib, PCS_MAX_BYTES / mib);
        return -1;
    }
    if (pcs_arena_open(&m->arena, mem) != 0) {
        snprintf(err, PCS_MSG, "no memory for a model of %d coordinates (%.0f MiB)", m->n,
                 (double)m->arena.size / mib);
        return -1;
    }
    carve(m, &m->arena);
    if (pcs_arena_full(&m->arena) != 0) {
        snprintf(err, PCS_MSG, "the model took other blocks than it measured");
        return -1;
    }
    return 0;
}
