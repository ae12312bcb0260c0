/*
 * The native FMUs' state machines and data files probed from C (tests/test_native_probe.py
 * links it with the shipped sources, both FMI fronts and every model, under ASan and UBSan):
 *
 *   native_probe data DIR...
 *       each folder's resources/model.pcsdata through fmi2Instantiate; an accepted file is
 *       initialised and stepped three times; prints "refused <logged reason>" or
 *       "ran <status of the last step>" per folder
 *   native_probe conformance CATENARY_DIR PANTOGRAPH_DIR
 *       the FMI 2.0 and 3.0 call sequences below, "ok <check>" or "FAIL <check>: status
 *       <got>, standard <wanted>" per check; the exit status counts the failures
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

#define DT 0.001
/* the catenary's value references (catenary_vars.h) and the pantograph's (lumped_vars.h) */
#define CAT_FORCE 120u
#define CAT_HEIGHT 150u
#define CAT_MODE 4u
#define PAN_FORCE 1u
#define FMI3_INT32 10000u

static int failures;
static char last_log[4096];

static void check(int got, int want, const char *what)
{
    if (got == want) {
        printf("ok %s\n", what);
        return;
    }
    printf("FAIL %s: status %d, standard %d\n", what, got, want);
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

static fmi2Component instantiate2(const char *dir, const fmi2CallbackFunctions *cb)
{
    return fmi2Instantiate("probe", fmi2CoSimulation, "", to_uri(dir), cb, fmi2False,
                           fmi2False);
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
    fmi2ValueReference vr = CAT_FORCE;
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

static void before_initialisation2(const char *dir)
{
    fmi2Component c = instantiate2(dir, &CB_A);
    fmi2ValueReference vr = CAT_HEIGHT, bad = 99999;
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

static void steps2(const char *dir)
{
    fmi2Component c = instantiate2(dir, &CB_A);
    fmi2ValueReference F = CAT_FORCE, z = CAT_HEIGHT;
    fmi2Real f = 150.0, bad[] = {NAN, INFINITY, -1.0, 1e300}, h[] = {NAN, -DT, 0.0, 1.5 * DT,
                                                                      1e9, INFINITY};
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

static void failed_reset2(const char *dir)
{
    char path[1100], moved[1120];
    fmi2Component c = instantiate2(dir, &CB_A);
    fmi2ValueReference vr = CAT_HEIGHT;
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

/* a pantograph's serialised state into the catenary; a catenary state with a NaN time and
   a checksum that matches it */
static void foreign_states2(fmi2Component a, fmi2FMUstate sa, fmi2Component b,
                            fmi2FMUstate sb)
{
    size_t na = 0, nb = 0;
    fmi2Byte *ba, *bb;
    fmi2FMUstate got = NULL;
    double nan = NAN;
    unsigned long long sum;
    fmi2SerializedFMUstateSize(a, sa, &na);
    fmi2SerializedFMUstateSize(b, sb, &nb);
    ba = (fmi2Byte *)calloc(na, 1);
    bb = (fmi2Byte *)calloc(nb, 1);
    fmi2SerializeFMUstate(a, sa, ba, na);
    fmi2SerializeFMUstate(b, sb, bb, nb);
    check(fmi2DeSerializeFMUstate(a, bb, nb, &got), fmi2Error, "fmi2 DeSerializeFMUstate of "
          "another model's state");
    memcpy(ba + 40, &nan, 8);          /* the time (serialised layout: pcs_instance.c) */
    sum = fnv1a((const unsigned char *)ba + 40, na - 40);
    memcpy(ba + 32, &sum, 8);
    check(fmi2DeSerializeFMUstate(a, ba, na, &got), fmi2Error, "fmi2 DeSerializeFMUstate of a "
          "state with a NaN time");
    check_true(got == NULL, "fmi2 no state from a refused one");
    free(ba);
    free(bb);
}

static void two_instances2(const char *cat, const char *pan)
{
    fmi2Component a = instantiate2(cat, &CB_A), b = instantiate2(pan, &CB_B);
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

static fmi3Instance instantiate3(const char *dir, fmi3Boolean event_mode)
{
    char path[1100];
    snprintf(path, sizeof path, "%s/resources/", dir);
    return fmi3InstantiateCoSimulation("probe", "", path, fmi3False, fmi3False, event_mode,
                                       fmi3False, NULL, 0, NULL, logger3, NULL);
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

static void fmi3_sequences(const char *dir, const char *percent_dir)
{
    fmi3Instance c;
    fmi3ValueReference F = CAT_FORCE, t0 = 0, mode = FMI3_INT32 + CAT_MODE, z = CAT_HEIGHT;
    fmi3Float64 x = 0.0, f = 150.0, nan = NAN;
    fmi3Int32 i32 = 0;
    fmi3FMUState st = NULL;
    check(step3(NULL, 0.0, DT), fmi3Error, "fmi3 NULL instance: DoStep");
    check(fmi3GetFloat64(NULL, &F, 1, &x, 1), fmi3Error, "fmi3 NULL instance: GetFloat64");
    check(fmi3SetFMUState(NULL, NULL), fmi3Error, "fmi3 NULL instance: SetFMUState");
    fmi3FreeInstance(NULL);
    check_true(instantiate3(dir, fmi3True) == NULL, "fmi3 event mode refused: NULL");
    c = instantiate3(percent_dir, fmi3False);
    check_true(c != NULL, "fmi3 a resource path holding %41 is taken as it is");
    fmi3FreeInstance(c);
    c = instantiate3(dir, fmi3False);
    if (!c) return;
    check(step3(c, 0.0, DT), fmi3Error, "fmi3 DoStep when instantiated");
    check(fmi3Terminate(c), fmi3Error, "fmi3 Terminate when instantiated");
    check(fmi3GetFloat64(c, &F, 1, &x, 2), fmi3Error, "fmi3 GetFloat64 of nValues != nvr");
    check(fmi3GetInt32(c, &F, 1, &i32, 1), fmi3Error, "fmi3 GetInt32 of a Float64 reference");
    check(fmi3GetInt32(c, &mode, 1, &i32, 1), fmi3OK, "fmi3 GetInt32 contact_mode");
    check(start3(c), fmi3OK, "fmi3 initialisation");
    check(fmi3SetFloat64(c, &F, 1, &f, 1), fmi3OK, "fmi3 SetFloat64");
    check(step3(c, 0.0, DT), fmi3OK, "fmi3 DoStep");
    check(fmi3GetFloat64(c, &t0, 1, &x, 1), fmi3OK, "fmi3 GetFloat64 time");
    check_true(x == DT, "fmi3 time after one step");
    check(step3(c, DT, 1.5 * DT), fmi3Discard, "fmi3 DoStep of 1.5 internal steps");
    fmi3SetFloat64(c, &F, 1, &nan, 1);
    check(step3(c, DT, DT), fmi3Discard, "fmi3 DoStep under a NaN force");
    fmi3SetFloat64(c, &F, 1, &f, 1);
    check(fmi3GetFMUState(c, &st), fmi3OK, "fmi3 GetFMUState");
    check(step3(c, DT, DT), fmi3OK, "fmi3 DoStep after the refused ones");
    check(fmi3GetFloat64(c, &z, 1, &x, 1), fmi3OK, "fmi3 GetFloat64 wire height");
    check(fmi3SetFMUState(c, st), fmi3OK, "fmi3 SetFMUState");
    check(fmi3Terminate(c), fmi3OK, "fmi3 Terminate");
    check(step3(c, 2 * DT, DT), fmi3Error, "fmi3 DoStep after Terminate");
    check(fmi3Reset(c), fmi3OK, "fmi3 Reset");
    check(fmi3SetFMUState(c, st), fmi3Error, "fmi3 SetFMUState before the model is "
          "initialised again");
    check(fmi3FreeFMUState(c, &st), fmi3OK, "fmi3 FreeFMUState");
    fmi3FreeInstance(c);
}

int main(int argc, char **argv)
{
    if (argc >= 2 && strcmp(argv[1], "data") == 0) return probe_data(argc - 2, argv + 2);
    if (argc != 5 || strcmp(argv[1], "conformance") != 0) {
        fprintf(stderr, "usage: see the comment at the top of native_probe.c\n");
        return 2;
    }
    null_instance2();
    before_initialisation2(argv[2]);
    steps2(argv[2]);
    failed_reset2(argv[2]);
    two_instances2(argv[2], argv[3]);
    fmi3_sequences(argv[2], argv[4]);
    printf("failures: %d\n", failures);
    return failures;
}
