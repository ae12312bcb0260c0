/*
 * A constant-matrix pantograph (the lumped chains of pantocosim.pantograph.lumped, their
 * linear_form: M a + C v + K q + B w = 0 with w = (h_ref, F_up, F)) as a native model
 * (its model table: pcs_lumped_pantograph), stepped with the closed-form HHT-alpha step of core/hht.py (_linear_step):
 *
 *   S a_{n+1} = alpha f_n - (1 + alpha) (C v_p + K q_p + B w_{n+1}),
 *   S = M + (1 + alpha) (gamma h C + beta h^2 K),
 *
 * then q, v from the Newmark predictors q_p, v_p (3.16)-(3.17) and f_{n+1} = C v + K q + B w.
 * The start (q0, a0, f0, w) and S^-1 are the Python integrator's, written at export.
 */
#include "pcs_model.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lumped_vars.h"
#include "pcs_layout.h"
#include "pcs_limits.h"

typedef struct {
    int n;
    double h, alpha, beta, gamma, lo, hi, static_force, aero_c1, aero_c2, speed_kmh,
        height0, F0, friction, smoothing;
    const double *M, *C, *K, *B, *w0, *q0, *a0, *f0, *S_inv_data;
    const char *preset;
    double S_inv[PAN_MAX_DOFS * PAN_MAX_DOFS];
    /* state: t, failed, F at t, input at t, q, v, a, f */
    double state[4 + 4 * PAN_MAX_DOFS];
    double *q, *v, *a, *f;
    double w[3], force_in, iterations;
    int initialised, extrapolate;
} Lumped;

#define SECTION(dst, name, type, count)                                                   \
    do {                                                                                  \
        dst = pcs_data_section(d, name, type, count, NULL, err, PCS_MSG);                 \
        if (!dst) goto fail;                                                              \
    } while (0)

static void *lumped_new(const PcsData *d, const PcsMemory *mem, char *err)
{
    Lumped *m;
    const int *sizes;
    const double *sc;
    size_t n;
    m = (Lumped *)pcs_alloc(mem, 1, sizeof *m);
    if (!m) { snprintf(err, PCS_MSG, "no memory"); return NULL; }
    SECTION(sizes, "sizes", PCS_TYPE_I32, PAN_SIZES);
    m->n = sizes[PAN_SIZE_MASSES];
    if (m->n < 1 || m->n > PAN_MAX_DOFS) {
        snprintf(err, PCS_MSG, "data file %.400s: section sizes: %d masses, this FMU takes "
                 "1..%d", d->path, m->n, PAN_MAX_DOFS);
        goto fail;
    }
    n = (size_t)m->n;
    SECTION(sc, "scalars", PCS_TYPE_F64, PAN_SCALARS);
    m->h = sc[PAN_SCALAR_STEP];
    m->alpha = sc[PAN_SCALAR_ALPHA];
    m->beta = sc[PAN_SCALAR_BETA];
    m->gamma = sc[PAN_SCALAR_GAMMA];
    m->lo = sc[PAN_SCALAR_HEIGHT_MIN];
    m->hi = sc[PAN_SCALAR_HEIGHT_MAX];
    m->static_force = sc[PAN_SCALAR_STATIC_FORCE];
    m->aero_c1 = sc[PAN_SCALAR_AERO_C1];
    m->aero_c2 = sc[PAN_SCALAR_AERO_C2];
    m->speed_kmh = sc[PAN_SCALAR_SPEED_KMH];
    m->height0 = sc[PAN_SCALAR_INITIAL_HEIGHT];
    m->F0 = sc[PAN_SCALAR_INITIAL_FORCE];
    m->friction = sc[PAN_SCALAR_FRICTION_FORCE];
    m->smoothing = sc[PAN_SCALAR_FRICTION_SMOOTHING];
    if (!(m->h > 0.0) || !(m->hi >= m->lo)) {
        snprintf(err, PCS_MSG, "data file %.400s: section scalars: internal step %g s (> 0), "
                 "heights %g .. %g m", d->path, m->h, m->lo, m->hi);
        goto fail;
    }
    SECTION(m->M, "M", PCS_TYPE_F64, n * n);
    SECTION(m->C, "C", PCS_TYPE_F64, n * n);
    SECTION(m->K, "K", PCS_TYPE_F64, n * n);
    SECTION(m->B, "B", PCS_TYPE_F64, n * 3);
    SECTION(m->w0, "w0", PCS_TYPE_F64, 3);
    SECTION(m->q0, "q0", PCS_TYPE_F64, n);
    SECTION(m->a0, "a0", PCS_TYPE_F64, n);
    SECTION(m->f0, "f0", PCS_TYPE_F64, n);
    SECTION(m->S_inv_data, "S_inv", PCS_TYPE_F64, n * n);
    m->preset = pcs_data_text(d, "preset", err, PCS_MSG);
    if (!m->preset) goto fail;
    m->q = m->state + 4;
    m->v = m->q + n;
    m->a = m->v + n;
    m->f = m->a + n;
    m->force_in = m->F0;
    return m;
fail:
    pcs_free(mem, m);
    return NULL;
}

static void lumped_free(void *model, const PcsMemory *mem) { pcs_free(mem, model); }

/* f = C v + K q + B w */
static void rest(Lumped *m, const double *q, const double *v, double *f)
{
    int n = m->n, i, j;
    for (i = 0; i < n; i++) {
        double r = 0.0;
        for (j = 0; j < n; j++) r += m->C[i * n + j] * v[j] + m->K[i * n + j] * q[j];
        for (j = 0; j < 3; j++) r += m->B[i * 3 + j] * m->w[j];
        f[i] = r;
    }
}

static int lumped_initialize(void *model, char *err)
{
    Lumped *m = (Lumped *)model;
    size_t n = (size_t)m->n;
    (void)err;
    m->state[0] = 0.0;
    m->state[1] = 0.0;
    m->state[2] = m->F0;
    m->state[3] = m->F0;
    memcpy(m->q, m->q0, n * sizeof(double));
    memset(m->v, 0, n * sizeof(double));
    memcpy(m->a, m->a0, n * sizeof(double));
    memcpy(m->f, m->f0, n * sizeof(double));
    memcpy(m->S_inv, m->S_inv_data, n * n * sizeof(double));
    m->w[0] = m->w0[0];
    m->w[1] = m->w0[1];
    m->w[2] = m->F0;
    m->force_in = m->F0;
    m->iterations = 0.0;
    m->initialised = 1;
    return PCS_OK;
}

static void step(Lumped *m, double F)
{
    int n = m->n, i, j;
    double h = m->h, cq = (0.5 - m->beta) * h * h, cv = (1.0 - m->gamma) * h;
    double c1 = 1.0 + m->alpha, cg = m->beta * h * h, cs = m->gamma * h;
    double *q = m->q, *v = m->v, *a = m->a, *f = m->f;
    m->w[2] = F;
    for (i = 0; i < n; i++) {
        q[i] = q[i] + h * v[i] + cq * a[i];
        v[i] = v[i] + cv * a[i];
    }
    for (i = 0; i < n; i++) {
        double r = 0.0;
        for (j = 0; j < n; j++) r += m->C[i * n + j] * v[j] + m->K[i * n + j] * q[j];
        for (j = 0; j < 3; j++) r += m->B[i * 3 + j] * m->w[j];
        f[i] = m->alpha * f[i] - c1 * r;
    }
    for (i = 0; i < n; i++) {
        double r = 0.0;
        for (j = 0; j < n; j++) r += m->S_inv[i * n + j] * f[j];
        a[i] = r;
    }
    for (i = 0; i < n; i++) {
        q[i] += cg * a[i];
        v[i] += cs * a[i];
    }
    rest(m, q, v, f);
}

static int lumped_step(void *model, double t, double H, char *err)
{
    Lumped *m = (Lumped *)model;
    int n_sub, i;
    double F = m->force_in, F_prev = m->state[2], u = F, z;
    double saved[4 + 4 * PAN_MAX_DOFS];
    if (!m->initialised) {
        snprintf(err, PCS_MSG, "doStep before the FMU was initialised");
        return PCS_ERROR;
    }
    if (m->state[1] != 0.0) {
        snprintf(err, PCS_MSG, "doStep after a refused step: roll back with a saved FMU state");
        return PCS_DISCARD;
    }
    if ((n_sub = (int)pcs_substeps(H, m->h, err)) < 0
        || pcs_within("contact_force", F, 0.0, PCS_MAX_CONTACT_FORCE, " N", err) != 0)
        return PCS_DISCARD;
    if (m->extrapolate) {
        if (m->state[0] == 0.0) u = m->state[3];
        F = 2.0 * u - m->state[3];
        if (F < 0.0) F = 0.0;
    }
    memcpy(saved, m->state, sizeof saved);
    for (i = 1; i <= n_sub; i++) step(m, F_prev + (F - F_prev) * i / n_sub);
    z = m->q[0];
    if (!(z >= m->lo && z <= m->hi)) {
        snprintf(err, PCS_MSG, "doStep(t = %.6g, h = %.3g): the contact point would be at "
                 "%.4g m, outside the heights pantograph '%s' represents (%.3g .. %.3g m): "
                 "contact_force = %.6g N is beyond what it can take", t, H, z, m->preset,
                 m->lo, m->hi, m->force_in);
        memcpy(m->state, saved, sizeof saved);
        m->state[1] = 1.0;          /* as the Python FMU: only a rollback recovers */
        return PCS_DISCARD;
    }
    m->state[0] += H;
    m->state[2] = F;
    m->state[3] = u;
    m->iterations = n_sub;
    return PCS_OK;
}

static size_t lumped_state_bytes(const void *model)
{
    return (4 + 4 * (size_t)((const Lumped *)model)->n) * sizeof(double);
}

static void lumped_state_save(const void *model, void *buffer)
{
    memcpy(buffer, ((const Lumped *)model)->state, lumped_state_bytes(model));
}

static void lumped_state_restore(void *model, const void *buffer)
{
    memcpy(((Lumped *)model)->state, buffer, lumped_state_bytes(model));
}

/* the contact force the state's last step applied */
static void lumped_outputs(void *model)
{
    Lumped *m = (Lumped *)model;
    m->w[2] = m->state[2];
}

/* ------------------------------------------------------------------ variables */


static int lumped_get_real(void *model, unsigned vr, double *value, char *err)
{
    Lumped *m = (Lumped *)model;
    switch (vr) {
    case PAN_VR_CONTACT_FORCE: *value = m->force_in; return PCS_OK;
    case PAN_VR_CONTACT_HEIGHT: *value = m->initialised ? m->q[0] : m->q0[0]; return PCS_OK;
    case PAN_VR_CONTACT_VELOCITY: *value = m->initialised ? m->v[0] : 0.0; return PCS_OK;
    case PAN_VR_STATIC_FORCE: *value = m->static_force; return PCS_OK;
    case PAN_VR_AERO_C1: *value = m->aero_c1; return PCS_OK;
    case PAN_VR_AERO_C2: *value = m->aero_c2; return PCS_OK;
    case PAN_VR_SPEED_KMH: *value = m->speed_kmh; return PCS_OK;
    case PAN_VR_FRICTION_FORCE: *value = m->friction; return PCS_OK;
    case PAN_VR_FRICTION_SMOOTHING: *value = m->smoothing; return PCS_OK;
    case PAN_VR_HHT_ALPHA: *value = m->alpha; return PCS_OK;
    case PAN_VR_INITIAL_HEIGHT: *value = m->height0; return PCS_OK;
    case PAN_VR_INITIAL_CONTACT_FORCE: *value = m->F0; return PCS_OK;
    case PAN_VR_NEWTON_ITERATIONS: *value = m->iterations; return PCS_OK;
    case PAN_VR_INTERNAL_STEP: *value = m->h; return PCS_OK;
    default: break;
    }
    snprintf(err, PCS_MSG, "no Real variable of value reference %u", vr);
    return PCS_ERROR;
}

static int lumped_set_real(void *model, unsigned vr, double value, int initialised, char *err)
{
    Lumped *m = (Lumped *)model;
    if (vr == PAN_VR_CONTACT_FORCE) {
        m->force_in = value;
        return PCS_OK;
    }
    if (initialised) {
        snprintf(err, PCS_MSG, "value reference %u is a parameter: it is set before "
                 "initialisation only", vr);
        return PCS_ERROR;
    }
    switch (vr) {
    case PAN_VR_STATIC_FORCE: return pcs_fixed_real("static_force", m->static_force, value, err);
    case PAN_VR_AERO_C1: return pcs_fixed_real("aero_c1", m->aero_c1, value, err);
    case PAN_VR_AERO_C2: return pcs_fixed_real("aero_c2", m->aero_c2, value, err);
    case PAN_VR_SPEED_KMH: return pcs_fixed_real("speed_kmh", m->speed_kmh, value, err);
    case PAN_VR_FRICTION_FORCE: return pcs_fixed_real("friction_force", m->friction, value, err);
    case PAN_VR_FRICTION_SMOOTHING:
        return pcs_fixed_real("friction_smoothing", m->smoothing, value, err);
    case PAN_VR_HHT_ALPHA: return pcs_fixed_real("hht_alpha", m->alpha, value, err);
    case PAN_VR_INITIAL_HEIGHT: return pcs_fixed_real("initial_height", m->height0, value, err);
    case PAN_VR_INITIAL_CONTACT_FORCE:
        if (value < 0.0) return PCS_OK;    /* < 0: the mean uplift, the export's force */
        return pcs_fixed_real("initial_contact_force", m->F0, value, err);
    default: break;
    }
    snprintf(err, PCS_MSG, "value reference %u is not a Real input or parameter", vr);
    return PCS_ERROR;
}

static int lumped_get_integer(void *model, unsigned vr, int *value, char *err)
{
    Lumped *m = (Lumped *)model;
    (void)m;
    if (vr == PAN_VR_START_MODE) { *value = 0; return PCS_OK; }
    snprintf(err, PCS_MSG, "no Integer variable of value reference %u", vr);
    return PCS_ERROR;
}

static int lumped_set_integer(void *model, unsigned vr, int value, int initialised, char *err)
{
    Lumped *m = (Lumped *)model;
    (void)m;
    if (vr == PAN_VR_START_MODE && !initialised && value == 0) return PCS_OK;
    if (vr == PAN_VR_START_MODE) {
        snprintf(err, PCS_MSG, "start_mode = %d: this native FMU starts static in contact "
                 "(start_mode 0) at the export's start", value);
        return PCS_ERROR;
    }
    snprintf(err, PCS_MSG, "no Integer parameter of value reference %u", vr);
    return PCS_ERROR;
}

static int lumped_get_boolean(void *model, unsigned vr, int *value, char *err)
{
    Lumped *m = (Lumped *)model;
    if (vr == PAN_VR_ONE_WAY_DAMPER) { *value = 0; return PCS_OK; }
    if (vr == PAN_VR_FORCE_EXTRAPOLATION) { *value = m->extrapolate; return PCS_OK; }
    snprintf(err, PCS_MSG, "no Boolean variable of value reference %u", vr);
    return PCS_ERROR;
}

static int lumped_set_boolean(void *model, unsigned vr, int value, int initialised, char *err)
{
    Lumped *m = (Lumped *)model;
    if (initialised) {
        snprintf(err, PCS_MSG, "Boolean %u is a parameter: set before initialisation only", vr);
        return PCS_ERROR;
    }
    if (vr == PAN_VR_ONE_WAY_DAMPER && !value) return PCS_OK;
    if (vr == PAN_VR_ONE_WAY_DAMPER) {
        snprintf(err, PCS_MSG, "one_way_damper = true: the native pantograph has constant "
                 "matrices (no one-way damper); use the Python FMU");
        return PCS_ERROR;
    }
    if (vr == PAN_VR_FORCE_EXTRAPOLATION) {
        m->extrapolate = value != 0;
        return PCS_OK;
    }
    snprintf(err, PCS_MSG, "no Boolean parameter of value reference %u", vr);
    return PCS_ERROR;
}

static int lumped_get_string(void *model, unsigned vr, const char **value, char *err)
{
    Lumped *m = (Lumped *)model;
    if (vr == PAN_VR_PRESET) { *value = m->preset; return PCS_OK; }
    snprintf(err, PCS_MSG, "no String variable of value reference %u", vr);
    return PCS_ERROR;
}

static int lumped_set_string(void *model, unsigned vr, const char *value, int initialised, char *err)
{
    Lumped *m = (Lumped *)model;
    (void)m; (void)value; (void)initialised;
    snprintf(err, PCS_MSG, "String %u cannot be set (the pantograph is fixed at export)", vr);
    return PCS_ERROR;
}

const PcsModelType pcs_lumped_pantograph = {
    "lumped pantograph", PCS_KIND_LUMPED_PANTOGRAPH, lumped_new, lumped_free,
    lumped_initialize, lumped_step, lumped_outputs, lumped_state_bytes, lumped_state_save,
    lumped_state_restore, lumped_get_real, lumped_set_real, lumped_get_integer,
    lumped_set_integer, lumped_get_boolean, lumped_set_boolean, lumped_get_string,
    lumped_set_string};
