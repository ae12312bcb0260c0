/*
 * The nonlinear pantographs (the rigid DSA-380 of dsa380_rigid.c, the flexible one of
 * dsa380_flexible.c) as native pantograph FMU models (pcs_model.h), stepped by the HHT-alpha
 * Newton engine of hht_dense.c with the settings, start and force timing of the Python
 * pantograph FMU (fmus/fmi/pantograph_slave.py):
 *
 * - the contact force set before doStep(t, H) is the force at t + H, the force at t the
 *   previous accepted step's (in the FMU state); a communication step of n internal steps
 *   interpolates it linearly; with force_extrapolation, F(t + H) = max(0, 2 F(t) - F(t - H));
 * - a step whose Newton iteration fails, or that leaves the heights the model represents, is
 *   refused (PCS_DISCARD) with the state as it was.
 *
 * The constants, the start (static in contact, or lowered for ramp raising) and the settings
 * are written at export (pantocosim.master.native.export).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dsa380_flexible.h"
#include "dsa380_rigid.h"
#include "hht_dense.h"
#include "nonlinear_pantograph_vars.h"
#include "pcs_layout.h"
#include "pcs_limits.h"
#include "pcs_model.h"

typedef struct {
    Dsa380 rigid;
    Dsa380Flex flexible;
    const double *constants;   /* the flexible model's, and its arrays (in the data file) */
    DsfArrays arrays;
    PcsArena arena;            /* the work memory: */
    void *body_work;           /* the flexible model's (work_bytes) */
    size_t work_bytes;
    HhtDense engine;
    void *memory;              /* the engine's work and state */
    double *saved;             /* the state before a step, for a refused one */
    const double *sc, *q0;
    const char *preset;
    HhtModelFn evaluate;       /* the body's evaluation and its data */
    void *body;
    int n, initialised, extrapolate, height_index;
    double height_offset;      /* contact height = height_offset + q[height_index] */
    double force_in, iterations;
    double force[2];           /* the state beyond the engine's: F(t), the input at t */
} Pantograph;

#define SECTION(d, name, type, count, err) \
    pcs_data_section(d, name, type, (size_t)(count), NULL, err, PCS_MSG)

static void destroy(void *model, const PcsMemory *mem);

/* the stepping, the start and the fixed parameters; -1 with the reason in err */
static int read_scalars(Pantograph *m, const PcsData *d, char *err)
{
    int i;
    double it;
    const double *sc = (const double *)SECTION(d, "scalars", PCS_TYPE_F64, NLP_SCALARS, err);
    m->sc = sc;
    m->preset = sc ? pcs_data_text(d, "preset", err, PCS_MSG) : NULL;
    if (!m->preset) return -1;
    for (i = 0; i < NLP_SCALARS; i++)
        if (!isfinite(sc[i])) {
            snprintf(err, PCS_MSG, "data file %.400s: section scalars: value %d is %g (must be "
                     "finite)", d->path, i, sc[i]);
            return -1;
        }
    it = sc[NLP_SCALAR_MAX_ITERATIONS];
    if (!(it >= 1.0 && it <= 1000.0 && it == floor(it)) ||
        (sc[NLP_SCALAR_START_MODE] != 0.0 && sc[NLP_SCALAR_START_MODE] != 1.0)) {
        snprintf(err, PCS_MSG, "data file %.400s: section scalars: %g Newton iterations "
                 "(accepted 1 .. 1000), start mode %g (0 or 1)", d->path, it,
                 sc[NLP_SCALAR_START_MODE]);
        return -1;
    }
    if (!(sc[NLP_SCALAR_STEP] > 0.0) || !(sc[NLP_SCALAR_HEIGHT_MIN] < sc[NLP_SCALAR_HEIGHT_MAX])) {
        snprintf(err, PCS_MSG, "data file %.400s: section scalars: internal step %g s, "
                 "heights %g .. %g m (a positive step and an increasing range)", d->path,
                 sc[NLP_SCALAR_STEP], sc[NLP_SCALAR_HEIGHT_MIN], sc[NLP_SCALAR_HEIGHT_MAX]);
        return -1;
    }
    return 0;
}

/* the rigid DSA-380 from the section "constants" */
static int rigid_body(Pantograph *m, const PcsData *d, char *err)
{
    char msg[HHT_MSG];
    const double *k = (const double *)SECTION(d, "constants", PCS_TYPE_F64, DSA_K_COUNT, err);
    if (!k) return -1;
    if (dsa380_setup(&m->rigid, k, DSA_K_COUNT, msg)) {
        snprintf(err, PCS_MSG, "data file %.400s: %s", d->path, msg);
        return -1;
    }
    m->n = m->rigid.n_dofs;
    m->evaluate = dsa380_evaluate;
    m->body = &m->rigid;
    m->height_index = 2;
    m->height_offset = 0.0;
    return 0;
}

/* the flexible DSA-380's constants and arrays (sizes read from the constants and checked
   before anything is allocated; dsf_setup checks the rest once its work memory is there) */
static int flexible_body(Pantograph *m, const PcsData *d, char *err)
{
    DsfArrays *a = &m->arrays;
    long n, ne, ng;
    const double *k = (const double *)SECTION(d, "constants", PCS_TYPE_F64, DSF_K_COUNT, err);
    if (!k) return -1;
    if (!(k[DSF_K_N] >= 2 && k[DSF_K_N] <= DSF_MAX_N && k[DSF_K_NE] >= 1 &&
          k[DSF_K_NE] <= DSF_MAX_NE && k[DSF_K_NG] >= 1 && k[DSF_K_NG] <= DSF_MAX_NG)) {
        snprintf(err, PCS_MSG, "data file %.400s: the flexible model's sizes %g unknowns, "
                 "%g elements, %g Gauss points (accepted 2..%d, 1..%d, 1..%d)", d->path,
                 k[DSF_K_N], k[DSF_K_NE], k[DSF_K_NG], DSF_MAX_N, DSF_MAX_NE, DSF_MAX_NG);
        return -1;
    }
    n = (long)k[DSF_K_N];
    ne = (long)k[DSF_K_NE];
    ng = (long)k[DSF_K_NG];
    if (!(a->q_ref = SECTION(d, "q_ref", PCS_TYPE_F64, n, err)) ||
        !(a->M = SECTION(d, "M", PCS_TYPE_F64, n * n, err)) ||
        !(a->Qg = SECTION(d, "Qg", PCS_TYPE_F64, n, err)) ||
        !(a->E0 = SECTION(d, "E0", PCS_TYPE_F64, 8 * ne, err)) ||
        !(a->length = SECTION(d, "length", PCS_TYPE_F64, ne, err)) ||
        !(a->EA = SECTION(d, "EA", PCS_TYPE_F64, ne, err)) ||
        !(a->EI = SECTION(d, "EI", PCS_TYPE_F64, ne, err)) ||
        !(a->pg = SECTION(d, "pg", PCS_TYPE_I32, 4 * ne, err)) ||
        !(a->pR = SECTION(d, "pR", PCS_TYPE_F64, 16 * ne, err)) ||
        !(a->xi_g = SECTION(d, "xi_g", PCS_TYPE_F64, ng, err)) ||
        !(a->w_g = SECTION(d, "w_g", PCS_TYPE_F64, ng, err)))
        return -1;
    m->constants = k;
    m->n = (int)n;
    m->work_bytes = dsf_work_bytes((int)n, (int)ne);
    m->evaluate = dsf_evaluate;
    m->body = &m->flexible;
    return 0;
}

static int rigid_bind(Pantograph *m, const PcsData *d, char *err)
{
    (void)m; (void)d; (void)err;
    return 0;
}

static int flexible_bind(Pantograph *m, const PcsData *d, char *err)
{
    char msg[HHT_MSG];
    if (dsf_setup(&m->flexible, m->constants, DSF_K_COUNT, &m->arrays, m->body_work,
                  m->work_bytes, msg)) {
        snprintf(err, PCS_MSG, "data file %.400s: %s", d->path, msg);
        return -1;
    }
    m->height_index = m->flexible.y10;
    m->height_offset = m->arrays.q_ref[m->height_index];
    return 0;
}

/* a body: its sections read and checked, then bound to its work memory */
typedef struct {
    int (*read)(Pantograph *m, const PcsData *d, char *err);
    int (*bind)(Pantograph *m, const PcsData *d, char *err);
} Body;

static const Body RIGID = {rigid_body, rigid_bind}, FLEXIBLE = {flexible_body, flexible_bind};

/* the work memory: the body's, the engine's, a state copy */
static void carve(Pantograph *m, PcsArena *a)
{
    m->body_work = m->work_bytes ? pcs_arena_take(a, 1, m->work_bytes) : NULL;
    m->memory = pcs_arena_take(a, 1, hht_dense_bytes(m->n));
    m->saved = (double *)pcs_arena_take(a, 2 + 3 + 5 * (size_t)m->n, sizeof(double));
}

static void *create(const PcsData *d, const PcsMemory *mem, char *err, const Body *body)
{
    char msg[HHT_MSG];
    HhtSettings s;
    Pantograph *m = (Pantograph *)pcs_alloc(mem, 1, sizeof *m);
    if (!m) { snprintf(err, PCS_MSG, "no memory"); return NULL; }
    if (read_scalars(m, d, err) || body->read(m, d, err)) goto fail;
    m->q0 = (const double *)SECTION(d, "q0", PCS_TYPE_F64, m->n, err);
    if (!m->q0) goto fail;
    carve(m, &m->arena);
    if (pcs_arena_open(&m->arena, mem)) { snprintf(err, PCS_MSG, "no memory"); goto fail; }
    carve(m, &m->arena);
    if (pcs_arena_full(&m->arena) || body->bind(m, d, err)) {
        if (pcs_arena_full(&m->arena)) snprintf(err, PCS_MSG, "work memory miscounted");
        goto fail;
    }
    s.alpha = m->sc[NLP_SCALAR_ALPHA];
    s.rtol = m->sc[NLP_SCALAR_RTOL];
    s.etol = m->sc[NLP_SCALAR_ETOL];
    s.max_iterations = (int)m->sc[NLP_SCALAR_MAX_ITERATIONS];
    s.linear_predictor = m->sc[NLP_SCALAR_LINEAR_PREDICTOR] != 0.0;
    if (hht_dense_init(&m->engine, m->n, &s, m->evaluate, m->body, m->memory,
                       hht_dense_bytes(m->n), msg)) {
        snprintf(err, PCS_MSG, "data file %.400s: %s", d->path, msg);
        goto fail;
    }
    m->force_in = m->sc[NLP_SCALAR_START_FORCE];
    if (hht_dense_start(&m->engine, 0.0, m->q0, NULL, &m->force_in, msg)) {
        snprintf(err, PCS_MSG, "data file %.400s: its start state q0 cannot be taken: %s",
                 d->path, msg);
        goto fail;
    }
    return m;
fail:
    destroy(m, mem);
    return NULL;
}

static void *create_rigid(const PcsData *d, const PcsMemory *mem, char *err)
{
    return create(d, mem, err, &RIGID);
}

static void *create_flexible(const PcsData *d, const PcsMemory *mem, char *err)
{
    return create(d, mem, err, &FLEXIBLE);
}

static void destroy(void *model, const PcsMemory *mem)
{
    Pantograph *m = (Pantograph *)model;
    if (!m) return;
    pcs_arena_close(&m->arena, mem);
    pcs_free(mem, m);
}

static int initialize(void *model, char *err)
{
    Pantograph *m = (Pantograph *)model;
    char msg[HHT_MSG];
    double F0 = m->sc[NLP_SCALAR_START_FORCE];
    if (hht_dense_start(&m->engine, 0.0, m->q0, NULL, &F0, msg)) {
        snprintf(err, PCS_MSG, "the start state: %s", msg);
        return PCS_ERROR;
    }
    m->force[0] = m->force[1] = F0;
    m->force_in = F0;
    m->iterations = 0.0;
    m->initialised = 1;
    return PCS_OK;
}

static size_t state_bytes(const void *model)
{
    return (2 + 3 + 5 * (size_t)((const Pantograph *)model)->n) * sizeof(double);
}

static void state_save(const void *model, void *buffer)
{
    const Pantograph *m = (const Pantograph *)model;
    double *out = (double *)buffer;
    out[0] = m->force[0];
    out[1] = m->force[1];
    memcpy(out + 2, m->engine.state.block, state_bytes(model) - 2 * sizeof(double));
}

static void state_restore(void *model, const void *buffer)
{
    Pantograph *m = (Pantograph *)model;
    const double *in = (const double *)buffer;
    m->force[0] = in[0];
    m->force[1] = in[1];
    memcpy(m->engine.state.block, in + 2, state_bytes(model) - 2 * sizeof(double));
}

/* the outputs are read from the state when asked (get_real): nothing to recompute */
static void outputs(void *model) { (void)model; }

/* why the state just reached leaves the heights the model represents, or 0 */
static int outside_range(const Pantograph *m, double t, double H, char *err)
{
    double z = m->height_offset + m->engine.state.q[m->height_index];
    double lo = m->sc[NLP_SCALAR_HEIGHT_MIN], hi = m->sc[NLP_SCALAR_HEIGHT_MAX];
    if (z >= lo && z <= hi) return 0;
    snprintf(err, PCS_MSG, "doStep(t = %.6g, h = %.3g): the contact point would be at %.4g m, "
             "outside the heights pantograph '%s' represents (%.3g .. %.3g m): contact_force "
             "= %.6g N and speed_kmh = %.6g km/h are beyond what it can take", t, H, z,
             m->preset, lo, hi, m->force_in, m->sc[NLP_SCALAR_SPEED_KMH]);
    return 1;
}

static int step(void *model, double t, double H, char *err)
{
    Pantograph *m = (Pantograph *)model;
    char msg[HHT_MSG];
    int i, iterations = 0;
    long n;
    double F = m->force_in, F0 = m->force[0], u = F;
    if (!m->initialised) {
        snprintf(err, PCS_MSG, "doStep before initialisation");
        return PCS_ERROR;
    }
    if ((n = pcs_substeps(H, m->sc[NLP_SCALAR_STEP], err)) < 0 ||
        pcs_within("contact_force", F, 0.0, PCS_MAX_CONTACT_FORCE, " N", err) != 0)
        return PCS_DISCARD;
    if (m->extrapolate) {
        if (m->engine.state.block[0] == 0.0) u = m->force[1];
        F = 2.0 * u - m->force[1];
        if (F < 0.0) F = 0.0;
    }
    state_save(m, m->saved);
    for (i = 1; i <= n; i++) {
        double Fi = F0 + (F - F0) * i / n;
        if (hht_dense_step(&m->engine, H / n, &Fi, msg)) {
            state_restore(m, m->saved);
            snprintf(err, PCS_MSG, "doStep(t = %.6g, h = %.3g) failed: %s", t, H, msg);
            return PCS_DISCARD;
        }
        iterations += m->engine.iterations;
    }
    if (outside_range(m, t, H, err)) {
        state_restore(m, m->saved);
        return PCS_DISCARD;
    }
    m->force[0] = F;
    m->force[1] = u;
    m->iterations = iterations;
    return PCS_OK;
}

/* ------------------------------------------------------------------ variables */

/* the Real parameters fixed at export: value reference, name, index in scalars */
static const struct { unsigned vr; const char *name; int index; } FIXED[] = {
    {NLP_VR_STATIC_FORCE, "static_force", NLP_SCALAR_STATIC_FORCE},
    {NLP_VR_AERO_C1, "aero_c1", NLP_SCALAR_AERO_C1},
    {NLP_VR_AERO_C2, "aero_c2", NLP_SCALAR_AERO_C2},
    {NLP_VR_SPEED_KMH, "speed_kmh", NLP_SCALAR_SPEED_KMH},
    {NLP_VR_FRICTION_FORCE, "friction_force", NLP_SCALAR_FRICTION_FORCE},
    {NLP_VR_FRICTION_SMOOTHING, "friction_smoothing", NLP_SCALAR_FRICTION_SMOOTHING},
    {NLP_VR_HHT_ALPHA, "hht_alpha", NLP_SCALAR_ALPHA},
    {NLP_VR_INITIAL_HEIGHT, "initial_height", NLP_SCALAR_INITIAL_HEIGHT},
    {NLP_VR_INITIAL_CONTACT_FORCE, "initial_contact_force", NLP_SCALAR_INITIAL_CONTACT_FORCE},
    {NLP_VR_RAMP_START_TIME, "ramp_start_time", NLP_SCALAR_RAMP_START_TIME},
    {NLP_VR_RAMP_DURATION, "ramp_duration", NLP_SCALAR_RAMP_DURATION},
    {NLP_VR_LOWERED_HEIGHT, "lowered_height", NLP_SCALAR_LOWERED_HEIGHT},
    {NLP_VR_INTERNAL_STEP, "internal_step", NLP_SCALAR_STEP},
};
#define N_FIXED (sizeof FIXED / sizeof FIXED[0])

static int fixed_index(unsigned vr)
{
    size_t i;
    for (i = 0; i < N_FIXED; i++)
        if (FIXED[i].vr == vr) return (int)i;
    return -1;
}


static int get_real(void *model, unsigned vr, double *value, char *err)
{
    Pantograph *m = (Pantograph *)model;
    int i = fixed_index(vr);
    const HhtState *st = &m->engine.state;
    if (i >= 0) { *value = m->sc[FIXED[i].index]; return PCS_OK; }
    switch (vr) {
    case NLP_VR_CONTACT_FORCE: *value = m->force_in; return PCS_OK;
    case NLP_VR_CONTACT_HEIGHT:
        *value = m->height_offset + (m->initialised ? st->q : m->q0)[m->height_index];
        return PCS_OK;
    case NLP_VR_CONTACT_VELOCITY:
        *value = m->initialised ? st->v[m->height_index] : 0.0;
        return PCS_OK;
    case NLP_VR_NEWTON_ITERATIONS: *value = m->iterations; return PCS_OK;
    default: break;
    }
    snprintf(err, PCS_MSG, "no Real variable of value reference %u", vr);
    return PCS_ERROR;
}

static int set_real(void *model, unsigned vr, double value, int initialised, char *err)
{
    Pantograph *m = (Pantograph *)model;
    int i = fixed_index(vr);
    if (vr == NLP_VR_CONTACT_FORCE) { m->force_in = value; return PCS_OK; }
    if (i < 0 || vr == NLP_VR_INTERNAL_STEP) {
        snprintf(err, PCS_MSG, "value reference %u is not a Real input or parameter", vr);
        return PCS_ERROR;
    }
    if (initialised) {
        snprintf(err, PCS_MSG, "%s is a parameter: it is set before initialisation only",
                 FIXED[i].name);
        return PCS_ERROR;
    }
    if (vr == NLP_VR_INITIAL_CONTACT_FORCE && value < 0.0 &&
        m->sc[NLP_SCALAR_INITIAL_CONTACT_FORCE] < 0.0)
        return PCS_OK;             /* < 0: the mean uplift, as exported */
    return pcs_fixed_real(FIXED[i].name, m->sc[FIXED[i].index], value, err);
}

static int get_integer(void *model, unsigned vr, int *value, char *err)
{
    Pantograph *m = (Pantograph *)model;
    if (vr == NLP_VR_START_MODE) { *value = (int)m->sc[NLP_SCALAR_START_MODE]; return PCS_OK; }
    snprintf(err, PCS_MSG, "no Integer variable of value reference %u", vr);
    return PCS_ERROR;
}

static int set_integer(void *model, unsigned vr, int value, int initialised, char *err)
{
    Pantograph *m = (Pantograph *)model;
    int mode = (int)m->sc[NLP_SCALAR_START_MODE];
    if (vr != NLP_VR_START_MODE) {
        snprintf(err, PCS_MSG, "no Integer parameter of value reference %u", vr);
        return PCS_ERROR;
    }
    if (!initialised && value == mode) return PCS_OK;
    snprintf(err, PCS_MSG, initialised ? "start_mode is a parameter: it is set before "
             "initialisation only" : "start_mode = %d: this native FMU was exported with "
             "start_mode = %d (export it again with pantocosim export-native to change it)",
             value, mode);
    return PCS_ERROR;
}

static int get_boolean(void *model, unsigned vr, int *value, char *err)
{
    Pantograph *m = (Pantograph *)model;
    if (vr == NLP_VR_ONE_WAY_DAMPER) {
        *value = m->sc[NLP_SCALAR_ONE_WAY_DAMPER] != 0.0;
        return PCS_OK;
    }
    if (vr == NLP_VR_FORCE_EXTRAPOLATION) { *value = m->extrapolate; return PCS_OK; }
    snprintf(err, PCS_MSG, "no Boolean variable of value reference %u", vr);
    return PCS_ERROR;
}

static int set_boolean(void *model, unsigned vr, int value, int initialised, char *err)
{
    Pantograph *m = (Pantograph *)model;
    int one_way = m->sc[NLP_SCALAR_ONE_WAY_DAMPER] != 0.0;
    if (vr != NLP_VR_ONE_WAY_DAMPER && vr != NLP_VR_FORCE_EXTRAPOLATION) {
        snprintf(err, PCS_MSG, "no Boolean parameter of value reference %u", vr);
        return PCS_ERROR;
    }
    if (initialised) {
        snprintf(err, PCS_MSG, "Boolean %u is a parameter: set before initialisation only", vr);
        return PCS_ERROR;
    }
    if (vr == NLP_VR_FORCE_EXTRAPOLATION) { m->extrapolate = value != 0; return PCS_OK; }
    if ((value != 0) == one_way) return PCS_OK;
    snprintf(err, PCS_MSG, "one_way_damper = %s: this native FMU was exported with "
             "one_way_damper = %s (export it again with pantocosim export-native to change "
             "it)", value ? "true" : "false", one_way ? "true" : "false");
    return PCS_ERROR;
}

static int get_string(void *model, unsigned vr, const char **value, char *err)
{
    (void)model; (void)value;
    snprintf(err, PCS_MSG, "no String variable of value reference %u", vr);
    return PCS_ERROR;
}

static int set_string(void *model, unsigned vr, const char *value, int initialised, char *err)
{
    (void)model; (void)value; (void)initialised;
    snprintf(err, PCS_MSG, "no String parameter of value reference %u", vr);
    return PCS_ERROR;
}

const PcsModelType pcs_dsa380_rigid = {
    "rigid DSA-380 pantograph", PCS_KIND_DSA380_RIGID, create_rigid, destroy, initialize,
    step, outputs, state_bytes, state_save, state_restore, get_real, set_real, get_integer,
    set_integer, get_boolean, set_boolean, get_string, set_string};

const PcsModelType pcs_dsa380_flexible = {
    "flexible DSA-380 pantograph", PCS_KIND_DSA380_FLEXIBLE, create_flexible, destroy,
    initialize, step, outputs, state_bytes, state_save, state_restore, get_real, set_real,
    get_integer, set_integer, get_boolean, set_boolean, get_string, set_string};
