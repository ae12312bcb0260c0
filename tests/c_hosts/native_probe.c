/*
 * The native FMUs' state machines and data files probed from C (tests/test_native_probe.py
 * links it with the shipped sources, both FMI fronts and every model, under ASan and UBSan):
 *
 *   native_probe data DIR...
 *       each folder's resources/model.pcsdata through fmi2Instantiate; an accepted file is
 *       initialised and stepped three times; prints "refused <logged reason>" or
 *       "ran <status of the last step>" per folder
 *   native_probe conformance PERCENT_DIR MODEL=DIR...
 *       the FMI 2.0 and 3.0 call sequences below on each model of the table (MODEL: linear,
 *       modal, lumped, dsa380-rigid, dsa380-flexible; DIR its unpacked FMU), each with its
 *       own value references and inputs; "ok <model>: <check>" or "FAIL <model>: <check>:
 *       status <got>, standard <wanted>" per check (model "any": the calls without an
 *       instance); PERCENT_DIR is a copy of the linear catenary in a folder named with %41;
 *       the exit status counts the failures
 *
 * The FMI 2.0 statuses: 0 OK, 2 Discard, 3 Error (the same numbers in FMI 3.0).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"

/* the token the probe's binary was built with (model_table.c, written by the test as
   pantocosim export-native writes it) */
extern const char pcs_instantiation_token[];

#define DT 0.001
#define FMI3_INT32 10000u
#define FMI3_BOOLEAN 20000u
#define FMI3_STRING 30000u

/* a model of the table and what the walks give it: its value references (catenary_vars.h,
   lumped_vars.h, nonlinear_pantograph_vars.h) and inputs */
typedef struct {
    const char *name;          /* as on the command line */
    const char *dir;           /* its unpacked FMU */
    unsigned output;           /* a Float64 output: the wire height, the contact height */
    unsigned input;            /* the Float64 input: the contact force */
    double force;              /* a contact force it steps under */
    unsigned int_param;        /* an Integer parameter, fixed from initialisation on */
    int int_valid;             /* a value it takes before initialisation */
    int int_fixed;             /* every other value is refused (else int_bad's) */
    int int_bad[3];            /* values it refuses */
    int has_string;            /* a String variable of value reference 1 */
} Model;

/* the models of the table; a pantograph's start_mode is read when it is instantiated
   (int_fixed: the exported one is the only value it takes) */
static Model MODELS[] = {
    {"linear", NULL, 150u, 120u, 150.0, 4u, 0, 0, {-1, 2, 0x7FFFFFFF}, 1},
    {"modal", NULL, 150u, 120u, 150.0, 4u, 0, 0, {-1, 2, 0x7FFFFFFF}, 1},
    {"lumped", NULL, 2u, 1u, 120.0, 1u, 0, 1, {0, 0, 0}, 1},
    {"dsa380-rigid", NULL, 2u, 1u, 120.0, 1u, 0, 1, {0, 0, 0}, 0},
    {"dsa380-flexible", NULL, 2u, 1u, 120.0, 1u, 0, 1, {0, 0, 0}, 0},
};
#define N_MODELS (sizeof MODELS / sizeof MODELS[0])

static int failures;
static char last_log[4096];
static const char *scope = "any";    /* the model the checks are of */

static void check(int got, int want, const char *what)
{
    if (got == want) {
        printf("ok %s: %s\n", scope, what);
        return;
    }
    printf("FAIL %s: %s: status %d, standard %d\n", scope, what, got, want);
    failures++;
}

static void check_true(int ok, const char *what) { check(ok ? 0 : 1, 0, what); }

/* ------------------------------------------------------------------ allocators */

/* an allocator that tags its blocks: a block freed by another allocator is a failure */
typedef struct {
    unsigned tag;
    long live, foreign;
} Pool;

static Pool pools[2] = {{0xA110CA7Au, 0, 0}, {0xB10CB10Cu, 0, 0}};

static void *pool_alloc(Pool *p, size_t n, size_t size)
{
    unsigned char *b;
    if (size && n > ((size_t)-1 - 16) / size) return NULL;
    b = (unsigned char *)calloc(1, n * size + 16);
    if (!b) return NULL;
    memcpy(b, &p->tag, sizeof p->tag);
    p->live++;
    return b + 16;
}

static void pool_free(Pool *p, void *q)
{
    unsigned tag;
    if (!q) return;
    memcpy(&tag, (unsigned char *)q - 16, sizeof tag);
    if (tag != p->tag) {
        p->foreign++;
        return;                /* leaked rather than freed through the wrong allocator */
    }
    p->live--;
    free((unsigned char *)q - 16);
}

static void *alloc_a(size_t n, size_t s) { return pool_alloc(&pools[0], n, s); }
static void free_a(void *q) { pool_free(&pools[0], q); }
static void *alloc_b(size_t n, size_t s) { return pool_alloc(&pools[1], n, s); }
static void free_b(void *q) { pool_free(&pools[1], q); }

static void logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                    fmi2String category, fmi2String message, ...)
{
    va_list ap;
    (void)env; (void)name; (void)status; (void)category;
    va_start(ap, message);
    vsnprintf(last_log, sizeof last_log, message, ap);
    va_end(ap);
}

static void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                    fmi3String message)
{
    (void)env; (void)status; (void)category;
    snprintf(last_log, sizeof last_log, "%s", message ? message : "");
}

static const fmi2CallbackFunctions CB_A = {logger2, alloc_a, free_a, NULL, NULL};
static const fmi2CallbackFunctions CB_B = {logger2, alloc_b, free_b, NULL, NULL};

static char uri[1200];

static const char *to_uri(const char *dir)
{
    snprintf(uri, sizeof uri, "file://%s/resources", dir);
    return uri;
}

static fmi2Component instantiate2_as(const char *dir, const fmi2CallbackFunctions *cb,
                                     const char *guid)
{
    return fmi2Instantiate("probe", fmi2CoSimulation, guid, to_uri(dir), cb, fmi2False,
                           fmi2False);
}

static fmi2Component instantiate2(const char *dir, const fmi2CallbackFunctions *cb)
{
    return instantiate2_as(dir, cb, pcs_instantiation_token);
}

static int start2(fmi2Component c)
{
    int s = fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    if (s == fmi2OK) s = fmi2EnterInitializationMode(c);
    if (s == fmi2OK) s = fmi2ExitInitializationMode(c);
    return s;
}

/* ------------------------------------------------------------------ data files */

static int probe_data(int n, char **dirs)
{
    int i, k;
    for (i = 0; i < n; i++) {
        fmi2Component c;
        int s = 0;
        last_log[0] = '\0';
        c = instantiate2(dirs[i], &CB_A);
        if (!c) {
            printf("refused %s\n", last_log[0] ? last_log : "(no reason logged)");
            continue;
        }
        s = start2(c);
        for (k = 0; k < 3 && s == fmi2OK; k++) s = fmi2DoStep(c, k * DT, DT, fmi2True);
        printf("ran %d\n", s);
        fmi2FreeInstance(c);
    }
    return pools[0].live != 0 || pools[0].foreign != 0;
}

/* ------------------------------------------------------------------ FMI 2.0 */

static void null_instance2(void)
{
    fmi2ValueReference vr = 1;
    fmi2Real x = 0.0;
    fmi2FMUstate st = NULL;
    size_t size = 0;
    check(fmi2DoStep(NULL, 0.0, DT, fmi2True), fmi2Error, "fmi2 NULL instance: DoStep");
    check(fmi2GetReal(NULL, &vr, 1, &x), fmi2Error, "fmi2 NULL instance: GetReal");
    check(fmi2SetReal(NULL, &vr, 1, &x), fmi2Error, "fmi2 NULL instance: SetReal");
    check(fmi2Terminate(NULL), fmi2Error, "fmi2 NULL instance: Terminate");
    check(fmi2Reset(NULL), fmi2Error, "fmi2 NULL instance: Reset");
    check(fmi2GetFMUstate(NULL, &st), fmi2Error, "fmi2 NULL instance: GetFMUstate");
    check(fmi2SetFMUstate(NULL, st), fmi2Error, "fmi2 NULL instance: SetFMUstate");
    check(fmi2SerializedFMUstateSize(NULL, st, &size), fmi2Error,
          "fmi2 NULL instance: SerializedFMUstateSize");
    fmi2FreeInstance(NULL);
    check_true(fmi2Instantiate("x", fmi2CoSimulation, "", "file:///nowhere", NULL, 0, 0) == NULL,
               "fmi2 Instantiate without callbacks: NULL");
    check_true(instantiate2("/nowhere", &CB_A) == NULL, "fmi2 Instantiate of a missing folder: "
               "NULL");
}

static void before_initialisation2(const Model *m)
{
    fmi2Component c = instantiate2(m->dir, &CB_A);
    fmi2ValueReference vr = m->output, bad = 99999;
    fmi2Real x = 0.0;
    fmi2FMUstate st = NULL;
    check_true(c != NULL, "fmi2 Instantiate");
    if (!c) return;
    check(fmi2DoStep(c, 0.0, DT, fmi2True), fmi2Error, "fmi2 DoStep when instantiated");
    check(fmi2Terminate(c), fmi2Error, "fmi2 Terminate when instantiated");
    check(fmi2ExitInitializationMode(c), fmi2Error, "fmi2 ExitInitializationMode when "
          "instantiated");
    check(fmi2GetReal(c, &vr, 1, &x), fmi2OK, "fmi2 GetReal when instantiated");
    check(fmi2GetReal(c, &bad, 1, &x), fmi2Error, "fmi2 GetReal of an unknown value reference");
    check(fmi2GetReal(c, NULL, 0, NULL), fmi2OK, "fmi2 GetReal of nvr = 0, NULL arrays");
    check(fmi2GetReal(c, &vr, 1, NULL), fmi2Error, "fmi2 GetReal into a NULL array");
    check(fmi2GetFMUstate(c, &st), fmi2OK, "fmi2 GetFMUstate when instantiated");
    check(fmi2SetFMUstate(c, st), fmi2Error, "fmi2 SetFMUstate of a state before initialisation");
    check(fmi2FreeFMUstate(c, &st), fmi2OK, "fmi2 FreeFMUstate");
    check(start2(c), fmi2OK, "fmi2 initialisation after refused calls");
    check(fmi2EnterInitializationMode(c), fmi2Error, "fmi2 EnterInitializationMode twice");
    check(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), fmi2Error, "fmi2 SetupExperiment in step "
          "mode");
    fmi2FreeInstance(c);
}

static void steps2(const Model *m)
{
    fmi2Component c = instantiate2(m->dir, &CB_A);
    fmi2ValueReference F = m->input, z = m->output;
    fmi2Real f = m->force, bad[] = {NAN, INFINITY, -1.0, 1e300},
             h[] = {NAN, -DT, 0.0, 1.2345 * DT, 1e9, INFINITY};
    fmi2Real z1 = 0.0, z2 = 1.0;
    fmi2FMUstate st = NULL, back = NULL;
    size_t size = 0, i;
    fmi2Byte *blob;
    char what[120];
    if (!c) return;
    start2(c);
    check(fmi2SetReal(c, &F, 1, &f), fmi2OK, "fmi2 SetReal contact force");
    check(fmi2DoStep(c, 0.0, DT, fmi2True), fmi2OK, "fmi2 DoStep");
    check(fmi2DoStep(c, 0.5, DT, fmi2True), fmi2Discard, "fmi2 DoStep at the wrong time");
    for (i = 0; i < sizeof h / sizeof h[0]; i++) {
        snprintf(what, sizeof what, "fmi2 DoStep of h = %g", h[i]);
        check(fmi2DoStep(c, DT, h[i], fmi2True), fmi2Discard, what);
    }
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(what, sizeof what, "fmi2 DoStep under a contact force of %g N", bad[i]);
        fmi2SetReal(c, &F, 1, &bad[i]);
        check(fmi2DoStep(c, DT, DT, fmi2True), fmi2Discard, what);
    }
    fmi2SetReal(c, &F, 1, &f);
    check(fmi2GetFMUstate(c, &st), fmi2OK, "fmi2 GetFMUstate");
    check(fmi2DoStep(c, DT, DT, fmi2True), fmi2OK, "fmi2 DoStep after the refused ones");
    fmi2GetReal(c, &z, 1, &z1);
    check(fmi2SerializedFMUstateSize(c, st, &size), fmi2OK, "fmi2 SerializedFMUstateSize");
    blob = (fmi2Byte *)calloc(size, 1);
    check(fmi2SerializeFMUstate(c, st, blob, size), fmi2OK, "fmi2 SerializeFMUstate");
    check(fmi2SerializeFMUstate(c, st, blob, size - 1), fmi2Error, "fmi2 SerializeFMUstate into "
          "a short buffer");
    check(fmi2DeSerializeFMUstate(c, blob, size - 1, &back), fmi2Error, "fmi2 "
          "DeSerializeFMUstate of a truncated state");
    blob[size - 1] ^= 0x40;
    check(fmi2DeSerializeFMUstate(c, blob, size, &back), fmi2Error, "fmi2 DeSerializeFMUstate "
          "of a damaged state");
    blob[size - 1] ^= 0x40;
    check(fmi2DeSerializeFMUstate(c, blob, size, &back), fmi2OK, "fmi2 DeSerializeFMUstate");
    check(fmi2SetFMUstate(c, back), fmi2OK, "fmi2 SetFMUstate");
    check(fmi2DoStep(c, DT, DT, fmi2True), fmi2OK, "fmi2 DoStep after SetFMUstate");
    fmi2GetReal(c, &z, 1, &z2);
    check_true(z1 == z2, "fmi2 the restored state repeats the step bit for bit");
    check(fmi2Terminate(c), fmi2OK, "fmi2 Terminate");
    check(fmi2DoStep(c, 2 * DT, DT, fmi2True), fmi2Error, "fmi2 DoStep after Terminate");
    check(fmi2Terminate(c), fmi2Error, "fmi2 Terminate twice");
    check(fmi2SetFMUstate(c, st), fmi2OK, "fmi2 SetFMUstate after Terminate");
    check(fmi2Reset(c), fmi2OK, "fmi2 Reset");
    check(fmi2SetFMUstate(c, back), fmi2Error, "fmi2 SetFMUstate before the model is "
          "initialised again");
    check(start2(c), fmi2OK, "fmi2 initialisation after Reset");
    check(fmi2DoStep(c, 0.0, DT, fmi2True), fmi2OK, "fmi2 DoStep after Reset");
    fmi2FreeFMUstate(c, &st);
    fmi2FreeFMUstate(c, &back);
    check_true(st == NULL && back == NULL, "fmi2 FreeFMUstate clears the pointer");
    free(blob);
    fmi2FreeInstance(c);
}

static void failed_reset2(const Model *m)
{
    char path[1100], moved[1120];
    const char *dir = m->dir;
    fmi2Component c = instantiate2(dir, &CB_A);
    fmi2ValueReference vr = m->output;
    fmi2Real x;
    fmi2FMUstate st = NULL;
    fmi2Byte blob[64] = {0};
    if (!c) return;
    snprintf(path, sizeof path, "%s/resources/model.pcsdata", dir);
    snprintf(moved, sizeof moved, "%s.moved", path);
    rename(path, moved);
    check(fmi2Reset(c), fmi2Error, "fmi2 Reset with the data file gone");
    rename(moved, path);
    check(fmi2GetReal(c, &vr, 1, &x), fmi2Error, "fmi2 GetReal after a failed Reset");
    check(fmi2SetReal(c, &vr, 1, &x), fmi2Error, "fmi2 SetReal after a failed Reset");
    check(fmi2GetFMUstate(c, &st), fmi2Error, "fmi2 GetFMUstate after a failed Reset");
    check(fmi2SetFMUstate(c, (fmi2FMUstate)blob), fmi2Error, "fmi2 SetFMUstate after a failed "
          "Reset");
    check(fmi2DeSerializeFMUstate(c, blob, sizeof blob, &st), fmi2Error,
          "fmi2 DeSerializeFMUstate after a failed Reset");
    check(fmi2DoStep(c, 0.0, DT, fmi2True), fmi2Error, "fmi2 DoStep after a failed Reset");
    check(fmi2EnterInitializationMode(c), fmi2Error, "fmi2 EnterInitializationMode after a "
          "failed Reset");
    check(fmi2Reset(c), fmi2OK, "fmi2 Reset with the data file back");
    check(start2(c), fmi2OK, "fmi2 initialisation after the second Reset");
    fmi2FreeInstance(c);
}

/* FNV-1a 64, as the FMU checks its serialised states */
static unsigned long long fnv1a(const unsigned char *p, size_t n)
{
    unsigned long long h = 14695981039346656037ULL;
    size_t i;
    for (i = 0; i < n; i++) h = (h ^ p[i]) * 1099511628211ULL;
    return h;
}

/* a serialised state given a NaN time and the checksum that matches it (the layout of
   pcs_instance.c: the FNV-1a at byte 32 covers the time at byte 40 and the state after it) */
static void with_nan_time(unsigned char *state, size_t n)
{
    double nan = NAN;
    unsigned long long sum;
    memcpy(state + 40, &nan, 8);
    sum = fnv1a(state + 40, n - 40);
    memcpy(state + 32, &sum, 8);
}

/* the other model's serialised state into this one; a state of this one with a NaN time
   and a checksum that matches it */
static void foreign_states2(fmi2Component a, fmi2FMUstate sa, fmi2Component b,
                            fmi2FMUstate sb)
{
    size_t na = 0, nb = 0;
    fmi2Byte *ba, *bb;
    fmi2FMUstate got = NULL;
    fmi2SerializedFMUstateSize(a, sa, &na);
    fmi2SerializedFMUstateSize(b, sb, &nb);
    ba = (fmi2Byte *)calloc(na, 1);
    bb = (fmi2Byte *)calloc(nb, 1);
    fmi2SerializeFMUstate(a, sa, ba, na);
    fmi2SerializeFMUstate(b, sb, bb, nb);
    check(fmi2DeSerializeFMUstate(a, bb, nb, &got), fmi2Error, "fmi2 DeSerializeFMUstate of "
          "another model's state");
    with_nan_time((unsigned char *)ba, na);
    check(fmi2DeSerializeFMUstate(a, ba, na, &got), fmi2Error, "fmi2 DeSerializeFMUstate of a "
          "state with a NaN time");
    check_true(got == NULL, "fmi2 no state from a refused one");
    free(ba);
    free(bb);
}

static void two_instances2(const Model *m, const Model *other)
{
    fmi2Component a = instantiate2(m->dir, &CB_A), b = instantiate2(other->dir, &CB_B);
    fmi2FMUstate sa = NULL, sb = NULL;
    int k;
    if (!a || !b) {
        check_true(0, "fmi2 two instances with different allocators");
        return;
    }
    start2(a);
    start2(b);
    for (k = 0; k < 5; k++) {
        fmi2DoStep(a, k * DT, DT, fmi2True);
        fmi2DoStep(b, k * DT, DT, fmi2True);
    }
    fmi2GetFMUstate(a, &sa);
    fmi2GetFMUstate(b, &sb);
    foreign_states2(a, sa, b, sb);
    check(fmi2SetFMUstate(a, sb), fmi2Error, "fmi2 SetFMUstate of another instance's state");
    check(fmi2FreeFMUstate(a, &sb), fmi2Error, "fmi2 FreeFMUstate of another instance's state");
    fmi2FreeFMUstate(a, &sa);
    fmi2FreeFMUstate(b, &sb);
    fmi2FreeInstance(a);
    fmi2FreeInstance(b);
    check_true(pools[0].foreign == 0 && pools[1].foreign == 0, "fmi2 no block freed through "
               "another instance's allocator");
    check_true(pools[0].live == 0 && pools[1].live == 0, "fmi2 every block freed");
}

/* ------------------------------------------------------------------ FMI 3.0 */

static fmi3Instance instantiate3_as(const char *dir, fmi3Boolean event_mode, const char *token)
{
    char path[1100];
    snprintf(path, sizeof path, "%s/resources/", dir);
    return fmi3InstantiateCoSimulation("probe", token, path, fmi3False, fmi3False, event_mode,
                                       fmi3False, NULL, 0, NULL, logger3, NULL);
}

static fmi3Instance instantiate3(const char *dir, fmi3Boolean event_mode)
{
    return instantiate3_as(dir, event_mode, pcs_instantiation_token);
}

static int start3(fmi3Instance c)
{
    int s = fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    return s == fmi3OK ? (int)fmi3ExitInitializationMode(c) : s;
}

static int step3(fmi3Instance c, double t, double h)
{
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    return fmi3DoStep(c, t, h, fmi3True, &ev, &term, &early, &last);
}

/* the phases an instance is brought to before one call (fmi3 standard, co-simulation without
   event mode): instantiated, initialisation mode, step mode (one step taken), terminated, and
   an instance whose Reset failed (its data file gone) */
enum { I3_INSTANTIATED, I3_INIT, I3_STEP, I3_TERMINATED, I3_FAILED_RESET, I3_PHASES };
static const char *const PHASE3[] = {"instantiated", "initialisation mode", "step mode",
                                     "terminated", "after a failed Reset"};

/* the data file of dir moved away (back = 0) or back (back = 1) */
static void move_data(const char *dir, int back)
{
    char path[1100], moved[1120];
    snprintf(path, sizeof path, "%s/resources/model.pcsdata", dir);
    snprintf(moved, sizeof moved, "%s.moved", path);
    if (back) rename(moved, path);
    else rename(path, moved);
}

static fmi3Instance in_phase3(const char *dir, int phase)
{
    fmi3Instance c = instantiate3(dir, fmi3False);
    if (!c) return NULL;
    if (phase == I3_INIT)
        fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    if (phase == I3_STEP || phase == I3_TERMINATED) {
        start3(c);
        step3(c, 0.0, DT);
    }
    if (phase == I3_TERMINATED) fmi3Terminate(c);
    if (phase == I3_FAILED_RESET) {
        move_data(dir, 0);
        fmi3Reset(c);
        move_data(dir, 1);
    }
    return c;
}

enum { C3_ENTER, C3_EXIT, C3_STEP, C3_TERMINATE, C3_GET, C3_GET_TIME, C3_GET_INT, C3_GET_BOOL,
       C3_GET_STRING, C3_SET, C3_SET_INT, C3_GETSTATE, C3_SETSTATE, C3_SIZE, C3_SERIALIZE,
       C3_DESERIALIZE, C3_FREESTATE, C3_DEBUG, C3_UNSUPPORTED, C3_RESET, C3_CALLS };
static const char *const CALL3[] = {
    "EnterInitializationMode", "ExitInitializationMode", "DoStep", "Terminate", "GetFloat64",
    "GetFloat64 of the time", "GetInt32", "GetBoolean", "GetString", "SetFloat64", "SetInt32",
    "GetFMUState", "SetFMUState of a step-mode state", "SerializedFMUStateSize",
    "SerializeFMUState", "DeserializeFMUState", "FreeFMUState", "SetDebugLogging",
    "EnterEventMode (not supported)", "Reset"};

/* the standard's status of each call in each phase (FMI 3.0, the state machine of
   co-simulation; a call not allowed in the current state "must return fmi3Error"): Get in
   initialisation mode, step mode and terminated (a String of a model that has none: Error);
   Set of inputs and tunable parameters up to step mode, of a fixed one (contact_mode,
   start_mode) before step mode; FMU states in every phase but after an Error that left no
   model; Reset in every phase. One refusal is the FMU's own: a step-mode state is not set
   before the model is initialised (Error). */
static int want3(const Model *m, int call, int phase)
{
    const int inst = phase == I3_INSTANTIATED, init = phase == I3_INIT,
              step = phase == I3_STEP, term = phase == I3_TERMINATED,
              failed = phase == I3_FAILED_RESET;
    switch (call) {
    case C3_ENTER: return inst ? fmi3OK : fmi3Error;
    case C3_EXIT: return init ? fmi3OK : fmi3Error;
    case C3_STEP: case C3_TERMINATE: return step ? fmi3OK : fmi3Error;
    case C3_GET_STRING: if (!m->has_string) return fmi3Error; /* fall through */
    case C3_GET: case C3_GET_TIME: case C3_GET_INT: case C3_GET_BOOL:
        return (init || step || term) ? fmi3OK : fmi3Error;
    case C3_SET: return (inst || init || step) ? fmi3OK : fmi3Error;
    case C3_SET_INT: return (inst || init) ? fmi3OK : fmi3Error;
    case C3_GETSTATE: case C3_SIZE: case C3_SERIALIZE: case C3_DESERIALIZE:
        return failed ? fmi3Error : fmi3OK;
    case C3_SETSTATE: return (step || term) ? fmi3OK : fmi3Error;
    case C3_FREESTATE: case C3_DEBUG: case C3_RESET: return fmi3OK;
    default: return fmi3Error;
    }
}

/* a serialised step-mode state of the FMU in dir (for the calls that take one) */
static fmi3Byte *saved_blob;
static size_t saved_size;

static int call3(const Model *m, fmi3Instance c, int call, fmi3FMUState own)
{
    fmi3ValueReference z = m->output, t = 0, F = m->input, mode = FMI3_INT32 + m->int_param,
                       np = FMI3_INT32 + 1, extrapolate = FMI3_BOOLEAN + 1,
                       definition = FMI3_STRING + 1;
    fmi3Float64 x = 0.0, f = m->force;
    fmi3Int32 i = 0, valid = m->int_valid;
    fmi3Boolean b = fmi3False;
    fmi3String str = NULL;
    fmi3FMUState st = NULL;
    size_t size = 0;
    fmi3Byte buffer[64];
    int s;
    switch (call) {
    case C3_ENTER: return fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    case C3_EXIT: return fmi3ExitInitializationMode(c);
    case C3_STEP: return step3(c, DT, DT);
    case C3_TERMINATE: return fmi3Terminate(c);
    case C3_GET: return fmi3GetFloat64(c, &z, 1, &x, 1);
    case C3_GET_TIME: return fmi3GetFloat64(c, &t, 1, &x, 1);
    case C3_GET_INT: return fmi3GetInt32(c, &np, 1, &i, 1);
    case C3_GET_BOOL: return fmi3GetBoolean(c, &extrapolate, 1, &b, 1);
    case C3_GET_STRING: return fmi3GetString(c, &definition, 1, &str, 1);
    case C3_SET: return fmi3SetFloat64(c, &F, 1, &f, 1);
    case C3_SET_INT: return fmi3SetInt32(c, &mode, 1, &valid, 1);
    case C3_GETSTATE:
        s = fmi3GetFMUState(c, &st);
        if (st) fmi3FreeFMUState(c, &st);
        return s;
    case C3_SETSTATE: return fmi3SetFMUState(c, own);
    case C3_SIZE: return fmi3SerializedFMUStateSize(c, own, &size);
    case C3_SERIALIZE:
        if (fmi3SerializedFMUStateSize(c, own, &size) != fmi3OK) return fmi3SerializeFMUState(
            c, own, buffer, sizeof buffer);
        {
            fmi3Byte *out = (fmi3Byte *)calloc(size, 1);
            s = fmi3SerializeFMUState(c, own, out, size);
            free(out);
        }
        return s;
    case C3_DESERIALIZE:
        s = fmi3DeserializeFMUState(c, saved_blob, saved_size, &st);
        if (st) fmi3FreeFMUState(c, &st);
        return s;
    case C3_FREESTATE:
        st = NULL;
        return fmi3FreeFMUState(c, &st);
    case C3_DEBUG: return fmi3SetDebugLogging(c, fmi3True, 0, NULL);
    case C3_UNSUPPORTED: return fmi3EnterEventMode(c);
    case C3_RESET: return fmi3Reset(c);
    }
    return -1;
}

/* every call in every phase, each on a fresh instance; then the instance goes on: after an
   Error that keeps the model a Reset brings it back, and it initialises and steps again */
static void phases3(const Model *m)
{
    int phase, call;
    char what[200];
    const char *dir = m->dir;
    fmi3Instance c = instantiate3(dir, fmi3False);
    fmi3FMUState st = NULL;
    if (!c) return;
    start3(c);
    step3(c, 0.0, DT);
    fmi3GetFMUState(c, &st);
    fmi3SerializedFMUStateSize(c, st, &saved_size);
    saved_blob = (fmi3Byte *)calloc(saved_size, 1);
    fmi3SerializeFMUState(c, st, saved_blob, saved_size);
    fmi3FreeFMUState(c, &st);
    fmi3FreeInstance(c);
    for (phase = 0; phase < I3_PHASES; phase++)
        for (call = 0; call < C3_CALLS; call++) {
            fmi3FMUState own = NULL;
            int s;
            c = in_phase3(dir, phase);
            if (!c) {
                check_true(0, "fmi3 an instance in every phase");
                continue;
            }
            /* a state of this instance in step mode, taken by deserialising (possible in
               every phase with a model) */
            if (phase != I3_FAILED_RESET) fmi3DeserializeFMUState(c, saved_blob, saved_size, &own);
            s = call3(m, c, call, own);
            snprintf(what, sizeof what, "fmi3 %s %s", CALL3[call], PHASE3[phase]);
            check(s, want3(m, call, phase), what);
            snprintf(what, sizeof what, "fmi3 after %s %s: Reset, initialisation and a step",
                     CALL3[call], PHASE3[phase]);
            if (own) fmi3FreeFMUState(c, &own);
            s = fmi3Reset(c);
            if (s == fmi3OK) s = start3(c);
            if (s == fmi3OK) s = step3(c, 0.0, DT);
            check(s, fmi3OK, what);
            fmi3FreeInstance(c);
        }
    free(saved_blob);
    saved_blob = NULL;
}

static void null_instance3(const Model *m)
{
    const char *dir = m->dir;
    fmi3ValueReference F = m->input;
    fmi3Float64 x = 0.0;
    fmi3Int32 i = 0;
    fmi3Boolean b = fmi3False;
    fmi3String str = NULL;
    fmi3FMUState st = NULL;
    size_t size = 0;
    fmi3Byte blob[8] = {0};
    int call;
    char what[120];
    check(step3(NULL, 0.0, DT), fmi3Error, "fmi3 NULL instance: DoStep");
    check(fmi3GetFloat64(NULL, &F, 1, &x, 1), fmi3Error, "fmi3 NULL instance: GetFloat64");
    check(fmi3SetFloat64(NULL, &F, 1, &x, 1), fmi3Error, "fmi3 NULL instance: SetFloat64");
    check(fmi3GetInt32(NULL, &F, 1, &i, 1), fmi3Error, "fmi3 NULL instance: GetInt32");
    check(fmi3SetInt32(NULL, &F, 1, &i, 1), fmi3Error, "fmi3 NULL instance: SetInt32");
    check(fmi3GetBoolean(NULL, &F, 1, &b, 1), fmi3Error, "fmi3 NULL instance: GetBoolean");
    check(fmi3SetBoolean(NULL, &F, 1, &b, 1), fmi3Error, "fmi3 NULL instance: SetBoolean");
    check(fmi3GetString(NULL, &F, 1, &str, 1), fmi3Error, "fmi3 NULL instance: GetString");
    check(fmi3SetString(NULL, &F, 1, &str, 1), fmi3Error, "fmi3 NULL instance: SetString");
    check(fmi3EnterInitializationMode(NULL, fmi3False, 0.0, 0.0, fmi3False, 0.0), fmi3Error,
          "fmi3 NULL instance: EnterInitializationMode");
    check(fmi3ExitInitializationMode(NULL), fmi3Error, "fmi3 NULL instance: "
          "ExitInitializationMode");
    check(fmi3Terminate(NULL), fmi3Error, "fmi3 NULL instance: Terminate");
    check(fmi3Reset(NULL), fmi3Error, "fmi3 NULL instance: Reset");
    check(fmi3GetFMUState(NULL, &st), fmi3Error, "fmi3 NULL instance: GetFMUState");
    check(fmi3SetFMUState(NULL, NULL), fmi3Error, "fmi3 NULL instance: SetFMUState");
    check(fmi3FreeFMUState(NULL, &st), fmi3Error, "fmi3 NULL instance: FreeFMUState");
    check(fmi3SerializedFMUStateSize(NULL, st, &size), fmi3Error,
          "fmi3 NULL instance: SerializedFMUStateSize");
    check(fmi3SerializeFMUState(NULL, st, blob, sizeof blob), fmi3Error,
          "fmi3 NULL instance: SerializeFMUState");
    check(fmi3DeserializeFMUState(NULL, blob, sizeof blob, &st), fmi3Error,
          "fmi3 NULL instance: DeserializeFMUState");
    check(fmi3SetDebugLogging(NULL, fmi3True, 0, NULL), fmi3Error,
          "fmi3 NULL instance: SetDebugLogging");
    for (call = C3_UNSUPPORTED; call == C3_UNSUPPORTED; call++) {
        snprintf(what, sizeof what, "fmi3 NULL instance: %s", CALL3[call]);
        check(call3(m, NULL, call, NULL), fmi3Error, what);
    }
    fmi3FreeInstance(NULL);
    check_true(instantiate3(dir, fmi3True) == NULL, "fmi3 event mode refused: NULL");
    check_true(fmi3InstantiateCoSimulation("probe", pcs_instantiation_token, NULL, fmi3False,
                                           fmi3False, fmi3False, fmi3False, NULL, 0, NULL,
                                           logger3, NULL) == NULL,
               "fmi3 Instantiate without a resource path: NULL");
    check_true(instantiate3("/nowhere", fmi3False) == NULL, "fmi3 Instantiate of a missing "
               "folder: NULL");
    check_true(fmi3InstantiateModelExchange("probe", "", dir, fmi3False, fmi3False, NULL,
                                            logger3) == NULL,
               "fmi3 InstantiateModelExchange of a co-simulation FMU: NULL");
}

/* value references, array sizes, NULL arrays, values and steps the FMU cannot take */
static void arguments3(const Model *m)
{
    fmi3Instance c = instantiate3(m->dir, fmi3False);
    fmi3ValueReference F = m->input, z = m->output, t0 = 0, bad[] = {99999, 9999, 10999,
                       20999, 30999, 0xFFFFFFFFu}, two[2] = {m->output, 99999},
                       mode = FMI3_INT32 + m->int_param;
    fmi3Float64 x = 0.0, xs[2] = {0.0, 0.0}, f = m->force, z1 = 0.0, z2 = 1.0,
                forces[] = {NAN, INFINITY, -INFINITY, -1.0, 1e300},
                h[] = {NAN, -DT, 0.0, 1.2345 * DT, 1e9, INFINITY, -INFINITY},
                times[] = {NAN, INFINITY, 0.5, -DT};
    fmi3Int32 i32 = m->int_valid;
    const int *modes = m->int_bad;
    fmi3FMUState st = NULL;
    size_t k;
    char what[160];
    if (!c) return;
    check(fmi3GetFloat64(c, &z, 1, &x, 1), fmi3Error, "fmi3 GetFloat64 when instantiated");
    check(fmi3SetFloat64(c, &bad[0], 1, &f, 1), fmi3Error, "fmi3 SetFloat64 of value reference "
          "99999 when instantiated");
    check(fmi3SetFloat64(c, NULL, 0, NULL, 0), fmi3OK, "fmi3 SetFloat64 of nvr = 0, NULL arrays "
          "when instantiated");
    check(fmi3GetFMUState(c, NULL), fmi3Error, "fmi3 GetFMUState into a NULL pointer");
    for (k = 0; k < 3; k++) {
        snprintf(what, sizeof what, "fmi3 SetInt32 of the Integer parameter = %d", modes[k]);
        check(fmi3SetInt32(c, &mode, 1, &modes[k], 1), fmi3Error, what);
    }
    check(fmi3EnterInitializationMode(c, fmi3False, 0.0, NAN, fmi3False, 0.0), fmi3Error,
          "fmi3 EnterInitializationMode at a NaN start time");
    check(fmi3EnterInitializationMode(c, fmi3False, 0.0, INFINITY, fmi3False, 0.0), fmi3Error,
          "fmi3 EnterInitializationMode at an infinite start time");
    check(start3(c), fmi3OK, "fmi3 initialisation after refused calls");
    check(fmi3SetInt32(c, &mode, 1, &i32, 1), fmi3Error, "fmi3 SetInt32 of a structural "
          "parameter in step mode");
    check(fmi3SetFloat64(c, &F, 1, &f, 1), fmi3OK, "fmi3 SetFloat64 contact force");
    check(step3(c, 0.0, DT), fmi3OK, "fmi3 DoStep");
    check(fmi3GetFloat64(c, &F, 1, &x, 2), fmi3Error, "fmi3 GetFloat64 of nValues != nvr");
    check(fmi3GetInt32(c, &F, 1, &i32, 1), fmi3Error, "fmi3 GetInt32 of a Float64 reference");
    check(fmi3GetFloat64(c, &mode, 1, &x, 1), fmi3Error, "fmi3 GetFloat64 of an Int32 reference");
    for (k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        snprintf(what, sizeof what, "fmi3 GetFloat64 of value reference %u", bad[k]);
        check(fmi3GetFloat64(c, &bad[k], 1, &x, 1), fmi3Error, what);
        snprintf(what, sizeof what, "fmi3 SetFloat64 of value reference %u", bad[k]);
        check(fmi3SetFloat64(c, &bad[k], 1, &f, 1), fmi3Error, what);
        snprintf(what, sizeof what, "fmi3 GetInt32 of value reference %u", bad[k]);
        check(fmi3GetInt32(c, &bad[k], 1, &i32, 1), fmi3Error, what);
    }
    check(fmi3GetFloat64(c, two, 2, xs, 2), fmi3Error, "fmi3 GetFloat64 of a known and an "
          "unknown value reference");
    check(fmi3SetFloat64(c, &t0, 1, &f, 1), fmi3Error, "fmi3 SetFloat64 of the time");
    check(fmi3GetFloat64(c, NULL, 0, NULL, 0), fmi3OK, "fmi3 GetFloat64 of nvr = 0, NULL arrays");
    check(fmi3SetFloat64(c, NULL, 0, NULL, 0), fmi3OK, "fmi3 SetFloat64 of nvr = 0, NULL arrays");
    check(fmi3GetInt32(c, NULL, 0, NULL, 0), fmi3OK, "fmi3 GetInt32 of nvr = 0, NULL arrays");
    check(fmi3GetFloat64(c, &z, 1, NULL, 1), fmi3Error, "fmi3 GetFloat64 into a NULL array");
    check(fmi3GetFloat64(c, NULL, 1, &x, 1), fmi3Error, "fmi3 GetFloat64 of a NULL reference "
          "array");
    check(fmi3SetFloat64(c, &F, 1, NULL, 1), fmi3Error, "fmi3 SetFloat64 of a NULL array");
    check(fmi3SetInt32(c, &mode, 1, NULL, 1), fmi3Error, "fmi3 SetInt32 of a NULL array");
    check(fmi3SerializedFMUStateSize(c, NULL, NULL), fmi3Error, "fmi3 SerializedFMUStateSize "
          "of a NULL state");
    check(fmi3GetFloat64(c, &t0, 1, &x, 1), fmi3OK, "fmi3 GetFloat64 time");
    check_true(x == DT, "fmi3 time after one step");
    for (k = 0; k < sizeof times / sizeof times[0]; k++) {
        snprintf(what, sizeof what, "fmi3 DoStep at currentCommunicationPoint = %g", times[k]);
        check(step3(c, times[k], DT), fmi3Discard, what);
    }
    for (k = 0; k < sizeof h / sizeof h[0]; k++) {
        snprintf(what, sizeof what, "fmi3 DoStep of h = %g", h[k]);
        check(step3(c, DT, h[k]), fmi3Discard, what);
    }
    for (k = 0; k < sizeof forces / sizeof forces[0]; k++) {
        snprintf(what, sizeof what, "fmi3 DoStep under a contact force of %g N", forces[k]);
        fmi3SetFloat64(c, &F, 1, &forces[k], 1);
        check(step3(c, DT, DT), fmi3Discard, what);
    }
    fmi3SetFloat64(c, &F, 1, &f, 1);
    check(fmi3GetFloat64(c, &t0, 1, &x, 1), fmi3OK, "fmi3 GetFloat64 time after the Discards");
    check_true(x == DT, "fmi3 a Discarded step keeps the time");
    check(fmi3GetFMUState(c, &st), fmi3OK, "fmi3 GetFMUState");
    check(step3(c, DT, DT), fmi3OK, "fmi3 DoStep after the refused ones");
    check(fmi3GetFloat64(c, &z, 1, &z1, 1), fmi3OK, "fmi3 GetFloat64 wire height");
    check(fmi3GetFMUState(c, &st), fmi3OK, "fmi3 GetFMUState into a state it took");
    check(fmi3SetFMUState(c, st), fmi3OK, "fmi3 SetFMUState");
    check(step3(c, 2 * DT, DT), fmi3OK, "fmi3 DoStep after SetFMUState");
    check(step3(c, 3 * DT, DT), fmi3OK, "fmi3 DoStep again");
    check(fmi3SetFMUState(c, st), fmi3OK, "fmi3 SetFMUState back two steps");
    check(fmi3GetFloat64(c, &t0, 1, &x, 1), fmi3OK, "fmi3 GetFloat64 time after SetFMUState");
    check_true(x == 2 * DT, "fmi3 SetFMUState sets the time");
    check(fmi3Terminate(c), fmi3OK, "fmi3 Terminate");
    check(step3(c, 2 * DT, DT), fmi3Error, "fmi3 DoStep after Terminate");
    check(fmi3Terminate(c), fmi3Error, "fmi3 Terminate twice");
    check(fmi3GetFloat64(c, &z, 1, &z2, 1), fmi3OK, "fmi3 GetFloat64 when terminated");
    check(fmi3SetFloat64(c, &F, 1, &f, 1), fmi3Error, "fmi3 SetFloat64 when terminated");
    check(fmi3Reset(c), fmi3OK, "fmi3 Reset");
    check(fmi3SetFMUState(c, st), fmi3Error, "fmi3 SetFMUState before the model is "
          "initialised again");
    check(fmi3GetFloat64(c, &t0, 1, &x, 1), fmi3Error, "fmi3 GetFloat64 time after Reset "
          "(instantiated)");
    check(start3(c), fmi3OK, "fmi3 initialisation after Reset");
    check(fmi3GetFloat64(c, &t0, 1, &x, 1), fmi3OK, "fmi3 GetFloat64 time after Reset");
    check_true(x == 0.0, "fmi3 Reset sets the time back to 0");
    fmi3SetFloat64(c, &F, 1, &f, 1);
    check(step3(c, 0.0, DT), fmi3OK, "fmi3 DoStep after Reset");
    check(step3(c, DT, DT), fmi3OK, "fmi3 second DoStep after Reset");
    fmi3GetFloat64(c, &z, 1, &z2, 1);
    check_true(z1 == z2, "fmi3 Reset and reuse repeats the run bit for bit");
    check(fmi3FreeFMUState(c, &st), fmi3OK, "fmi3 FreeFMUState");
    check_true(st == NULL, "fmi3 FreeFMUState clears the pointer");
    check(fmi3FreeFMUState(c, &st), fmi3OK, "fmi3 FreeFMUState of NULL");
    fmi3FreeInstance(c);
}

/* a step and start time away from 0 */
static void start_time3(const Model *m)
{
    fmi3Instance c = instantiate3(m->dir, fmi3False);
    fmi3ValueReference t0 = 0;
    fmi3Float64 x = 0.0;
    if (!c) return;
    check(fmi3EnterInitializationMode(c, fmi3False, 0.0, 2.0, fmi3True, 3.0), fmi3OK,
          "fmi3 EnterInitializationMode at t = 2 s");
    check(fmi3ExitInitializationMode(c), fmi3OK, "fmi3 ExitInitializationMode at t = 2 s");
    check(step3(c, 0.0, DT), fmi3Discard, "fmi3 DoStep at 0 s of an FMU at 2 s");
    check(step3(c, 2.0, DT), fmi3OK, "fmi3 DoStep at 2 s");
    fmi3GetFloat64(c, &t0, 1, &x, 1);
    check_true(x == 2.0 + DT, "fmi3 time after a step from 2 s");
    fmi3FreeInstance(c);
}

/* serialised states: truncated, damaged, empty, garbage, another model's, a NaN time */
static void serialised3(const Model *m, const Model *other)
{
    fmi3Instance a = instantiate3(m->dir, fmi3False), b = instantiate3(other->dir, fmi3False);
    fmi3FMUState sa = NULL, sb = NULL, got = NULL;
    fmi3Byte *ba, *bb, junk[64];
    size_t na = 0, nb = 0;
    if (!a || !b) {
        check_true(0, "fmi3 two instances");
        return;
    }
    start3(a);
    start3(b);
    step3(a, 0.0, DT);
    step3(b, 0.0, DT);
    fmi3GetFMUState(a, &sa);
    fmi3GetFMUState(b, &sb);
    check(fmi3SerializedFMUStateSize(a, sa, &na), fmi3OK, "fmi3 SerializedFMUStateSize");
    check(fmi3SerializedFMUStateSize(a, sb, &nb), fmi3Error, "fmi3 SerializedFMUStateSize of "
          "another instance's state");
    fmi3SerializedFMUStateSize(b, sb, &nb);
    ba = (fmi3Byte *)calloc(na, 1);
    bb = (fmi3Byte *)calloc(nb, 1);
    check(fmi3SerializeFMUState(a, sa, ba, na - 1), fmi3Error, "fmi3 SerializeFMUState into a "
          "short buffer");
    check(fmi3SerializeFMUState(a, sa, NULL, na), fmi3Error, "fmi3 SerializeFMUState into "
          "NULL");
    check(fmi3SerializeFMUState(a, sa, ba, na), fmi3OK, "fmi3 SerializeFMUState");
    check(fmi3SerializeFMUState(b, sb, bb, nb), fmi3OK, "fmi3 SerializeFMUState of the "
          "other model");
    check(fmi3SerializeFMUState(a, sb, ba, na), fmi3Error, "fmi3 SerializeFMUState of another "
          "instance's state");
    check(fmi3SetFMUState(a, sb), fmi3Error, "fmi3 SetFMUState of another instance's state");
    check(fmi3FreeFMUState(a, &sb), fmi3Error, "fmi3 FreeFMUState of another instance's state");
    check(fmi3DeserializeFMUState(a, ba, na - 1, &got), fmi3Error, "fmi3 DeserializeFMUState "
          "of a truncated state");
    check(fmi3DeserializeFMUState(a, ba, 0, &got), fmi3Error, "fmi3 DeserializeFMUState of 0 "
          "bytes");
    check(fmi3DeserializeFMUState(a, NULL, na, &got), fmi3Error, "fmi3 DeserializeFMUState of "
          "NULL");
    check(fmi3DeserializeFMUState(a, ba, na, NULL), fmi3Error, "fmi3 DeserializeFMUState into a "
          "NULL pointer");
    memset(junk, 0x5A, sizeof junk);
    check(fmi3DeserializeFMUState(a, junk, sizeof junk, &got), fmi3Error,
          "fmi3 DeserializeFMUState of garbage");
    check(fmi3DeserializeFMUState(a, bb, nb, &got), fmi3Error, "fmi3 DeserializeFMUState of "
          "another model's state");
    ba[na - 1] ^= 0x40;
    check(fmi3DeserializeFMUState(a, ba, na, &got), fmi3Error, "fmi3 DeserializeFMUState of a "
          "damaged state");
    ba[na - 1] ^= 0x40;
    check_true(got == NULL, "fmi3 no state from a refused one");
    check(fmi3DeserializeFMUState(a, ba, na, &got), fmi3OK, "fmi3 DeserializeFMUState");
    check(fmi3SetFMUState(a, got), fmi3OK, "fmi3 SetFMUState of a deserialised state");
    check(fmi3SetFMUState(b, got), fmi3Error, "fmi3 SetFMUState of this model's state into "
          "the other");
    fmi3FreeFMUState(a, &got);
    with_nan_time((unsigned char *)ba, na);
    check(fmi3DeserializeFMUState(a, ba, na, &got), fmi3Error, "fmi3 DeserializeFMUState of a "
          "state with a NaN time");
    check_true(got == NULL, "fmi3 no state from a NaN time");
    fmi3FreeFMUState(a, &sa);
    fmi3FreeFMUState(b, &sb);
    free(ba);
    free(bb);
    fmi3FreeInstance(a);
    fmi3FreeInstance(b);
}

/* a step it cannot take is a Discard that leaves it usable */
static void discards3(const Model *m)
{
    fmi3Instance c = instantiate3(m->dir, fmi3False);
    fmi3ValueReference F = m->input;
    fmi3Float64 f = m->force, huge = 1e300, nan = NAN;
    if (!c) return;
    start3(c);
    check(fmi3SetFloat64(c, &F, 1, &f, 1), fmi3OK, "fmi3 SetFloat64 contact force");
    check(step3(c, 0.0, 2e6), fmi3Discard, "fmi3 DoStep of 2e6 s");
    check(step3(c, 0.0, INFINITY), fmi3Discard, "fmi3 DoStep of an infinite h");
    fmi3SetFloat64(c, &F, 1, &huge, 1);
    check(step3(c, 0.0, DT), fmi3Discard, "fmi3 DoStep under 1e300 N");
    fmi3SetFloat64(c, &F, 1, &nan, 1);
    check(step3(c, 0.0, DT), fmi3Discard, "fmi3 DoStep under a NaN force");
    fmi3SetFloat64(c, &F, 1, &f, 1);
    check(step3(c, 0.0, DT), fmi3OK, "fmi3 DoStep after the Discards");
    fmi3FreeInstance(c);
}

/* a Reset that fails (data file gone) leaves an instance that refuses everything but Reset
   and FreeInstance, without touching the missing model */
static void failed_reset3(const Model *m)
{
    const char *dir = m->dir;
    fmi3Instance c = instantiate3(dir, fmi3False);
    fmi3ValueReference z = m->output, t0 = 0;
    fmi3Float64 x = 0.0;
    fmi3FMUState st = NULL;
    fmi3Byte blob[64] = {0};
    if (!c) return;
    start3(c);
    move_data(dir, 0);
    check(fmi3Reset(c), fmi3Error, "fmi3 Reset with the data file gone");
    check(fmi3Reset(c), fmi3Error, "fmi3 Reset again with the data file gone");
    move_data(dir, 1);
    check(fmi3GetFloat64(c, &z, 1, &x, 1), fmi3Error, "fmi3 GetFloat64 after a failed Reset");
    check(fmi3GetFloat64(c, &t0, 1, &x, 1), fmi3Error, "fmi3 GetFloat64 of the time after a "
          "failed Reset");
    check(fmi3SetFloat64(c, &z, 1, &x, 1), fmi3Error, "fmi3 SetFloat64 after a failed Reset");
    check(fmi3GetFMUState(c, &st), fmi3Error, "fmi3 GetFMUState after a failed Reset");
    check(fmi3SetFMUState(c, (fmi3FMUState)blob), fmi3Error, "fmi3 SetFMUState after a failed "
          "Reset");
    check(fmi3DeserializeFMUState(c, blob, sizeof blob, &st), fmi3Error,
          "fmi3 DeserializeFMUState after a failed Reset");
    check(step3(c, 0.0, DT), fmi3Error, "fmi3 DoStep after a failed Reset");
    check(fmi3Terminate(c), fmi3Error, "fmi3 Terminate after a failed Reset");
    check(fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0), fmi3Error,
          "fmi3 EnterInitializationMode after a failed Reset");
    check(fmi3Reset(c), fmi3OK, "fmi3 Reset with the data file back");
    check(start3(c), fmi3OK, "fmi3 initialisation after the second Reset");
    check(step3(c, 0.0, DT), fmi3OK, "fmi3 DoStep after the second Reset");
    fmi3FreeInstance(c);
}

/* another GUID / instantiationToken than the binary's (one digit changed, empty, NULL):
   NULL, with one message naming both */
static void tokens(const Model *m)
{
    char wrong[128];
    const char *given[] = {wrong, "", NULL};
    char what[160];
    size_t k;
    snprintf(wrong, sizeof wrong, "%s", pcs_instantiation_token);
    wrong[1] = wrong[1] == '0' ? '1' : '0';
    for (k = 0; k < 3; k++) {
        const char *label = k == 0 ? "another" : k == 1 ? "an empty" : "a NULL";
        last_log[0] = '\0';
        snprintf(what, sizeof what, "fmi2 Instantiate with %s GUID: NULL", label);
        check_true(instantiate2_as(m->dir, &CB_A, given[k]) == NULL, what);
        snprintf(what, sizeof what, "fmi2 Instantiate with %s GUID: the message names both",
                 label);
        check_true(strstr(last_log, pcs_instantiation_token) != NULL
                   && strstr(last_log, given[k] ? given[k] : "NULL") != NULL, what);
        last_log[0] = '\0';
        snprintf(what, sizeof what, "fmi3 InstantiateCoSimulation with %s instantiationToken: "
                 "NULL", label);
        check_true(instantiate3_as(m->dir, fmi3False, given[k]) == NULL, what);
        snprintf(what, sizeof what, "fmi3 InstantiateCoSimulation with %s instantiationToken: "
                 "the message names both", label);
        check_true(strstr(last_log, pcs_instantiation_token) != NULL
                   && strstr(last_log, given[k] ? given[k] : "NULL") != NULL, what);
    }
    check_true(pools[0].live == 0 && pools[0].foreign == 0, "fmi2 a refused token leaves no "
               "block behind");
}

/* a pantograph's start_mode, the only value it takes (read through FMI 2.0, whose Get is
   allowed when instantiated); the values it refuses around it */
static int read_int_param(Model *m)
{
    fmi2Component c = instantiate2(m->dir, &CB_A);
    fmi2ValueReference vr = m->int_param;
    fmi2Integer v = 0;
    if (!c) return -1;
    if (fmi2GetInteger(c, &vr, 1, &v) != fmi2OK) v = -1;
    fmi2FreeInstance(c);
    if (v < 0) return -1;
    m->int_valid = v;
    m->int_bad[0] = v - 1;
    m->int_bad[1] = v + 1;
    m->int_bad[2] = 0x7FFFFFFF;
    return 0;
}

/* both walks over one model; other: another model (foreign FMU states) */
static void walk(Model *m, const Model *other)
{
    scope = m->name;
    if (m->int_fixed && read_int_param(m) != 0) {
        check_true(0, "the Integer parameter read when instantiated");
        return;
    }
    tokens(m);
    before_initialisation2(m);
    steps2(m);
    failed_reset2(m);
    two_instances2(m, other);
    null_instance3(m);
    phases3(m);
    arguments3(m);
    start_time3(m);
    serialised3(m, other);
    discards3(m);
    failed_reset3(m);
}

int main(int argc, char **argv)
{
    size_t i, k;
    int j;
    fmi3Instance c;
    if (argc >= 2 && strcmp(argv[1], "data") == 0) return probe_data(argc - 2, argv + 2);
    if (argc < 4 || strcmp(argv[1], "conformance") != 0) {
        fprintf(stderr, "usage: see the comment at the top of native_probe.c\n");
        return 2;
    }
    for (j = 3; j < argc; j++) {
        const char *eq = strchr(argv[j], '=');
        for (k = 0; eq && k < N_MODELS; k++)
            if (strlen(MODELS[k].name) == (size_t)(eq - argv[j])
                && strncmp(argv[j], MODELS[k].name, (size_t)(eq - argv[j])) == 0)
                MODELS[k].dir = eq + 1;
    }
    for (k = 0; k < N_MODELS; k++)
        if (!MODELS[k].dir) {
            fprintf(stderr, "no folder given for model %s\n", MODELS[k].name);
            return 2;
        }
    null_instance2();
    scope = "linear";
    c = instantiate3(argv[2], fmi3False);
    check_true(c != NULL, "fmi3 a resource path holding %41 is taken as it is");
    fmi3FreeInstance(c);
    for (i = 0; i < N_MODELS; i++) walk(&MODELS[i], &MODELS[(i + 1) % N_MODELS]);
    printf("failures: %d\n", failures);
    return failures;
}
