/*
 * The FMI 3.0 co-simulation interface of a native model (pcs_model.h): the same instance,
 * state machine and FMU states as fmi2_front.c. FMI 3.0 value references are unique across
 * types: the model's Integer, Boolean and String references are offset by
 * PCS_FMI3_INT32_BASE, PCS_FMI3_BOOLEAN_BASE and PCS_FMI3_STRING_BASE (pcs_model.h).
 * Memory comes from the C library (FMI 3.0 has no allocation callbacks), at instantiation.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "fmi3_front.h"
#include "pcs_model.h"

#define STATE_MAGIC 0x50435353u

typedef enum { INSTANTIATED, INITIALISATION, STEPPING, TERMINATED, FAILED } Phase;

typedef struct {
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
    PcsMemory mem;
    char name[128];
    char data_path[512];
    PcsData data;
    PcsModel *model;
    Phase phase;
    double time;
    char msg[PCS_MSG];
} Instance;

typedef struct {
    unsigned magic;
    size_t bytes;
    double time;
    int phase;
} StateHead;

static void *mem_alloc(size_t n, size_t size) { return calloc(n, size); }
static void mem_release(void *p) { free(p); }

static void logmsg(Instance *c, fmi3Status status, const char *category, const char *text)
{
    if (c && c->log) c->log(c->env, status, category, text);
}

static fmi3Status fail(Instance *c, const char *text)
{
    logmsg(c, fmi3Error, "logStatusError", text);
    c->phase = FAILED;
    return fmi3Error;
}

fmi3Status pcs_fmi3_unsupported(fmi3Instance instance, const char *function)
{
    Instance *c = (Instance *)instance;
    char text[200];
    snprintf(text, sizeof text, "%s is not supported by this co-simulation FMU", function);
    logmsg(c, fmi3Error, "logStatusError", text);
    return fmi3Error;
}

static fmi3Status usable(Instance *c, const char *call)
{
    if (!c) return fmi3Error;
    if (c->phase == FAILED) {
        char text[256];
        snprintf(text, sizeof text, "%s: the instance failed before; only fmi3Reset or "
                 "fmi3FreeInstance are possible", call);
        logmsg(c, fmi3Error, "logStatusError", text);
        return fmi3Error;
    }
    return fmi3OK;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean on, size_t n,
                               const fmi3String categories[])
{
    (void)on; (void)n; (void)categories;
    return instance ? fmi3OK : fmi3Error;
}

static int load(Instance *c)
{
    if (pcs_data_load(&c->data, c->data_path, &c->mem, c->msg, sizeof c->msg) != 0) return -1;
    c->model = pcs_model_new(&c->data, &c->mem, c->msg);
    if (!c->model) {
        pcs_data_free(&c->data, &c->mem);
        return -1;
    }
    return 0;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token,
                                         fmi3String resources, fmi3Boolean visible,
                                         fmi3Boolean logging, fmi3Boolean event_mode,
                                         fmi3Boolean early_return,
                                         const fmi3ValueReference required[], size_t n_required,
                                         fmi3InstanceEnvironment env,
                                         fmi3LogMessageCallback log,
                                         fmi3IntermediateUpdateCallback update)
{
    Instance *c;
    char dir[480];
    size_t len;
    (void)token; (void)visible; (void)logging; (void)early_return; (void)required;
    (void)n_required; (void)update;
    c = (Instance *)calloc(1, sizeof *c);
    if (!c) return NULL;
    c->env = env;
    c->log = log;
    c->mem.alloc = mem_alloc;
    c->mem.release = mem_release;
    strncpy(c->name, name ? name : "", sizeof c->name - 1);
    if (event_mode) {
        logmsg(c, fmi3Error, "logStatusError", "event mode is not supported (no events)");
        free(c);
        return NULL;
    }
    if (pcs_uri_to_path(resources, dir, sizeof dir) != 0 || !dir[0]) {
        logmsg(c, fmi3Error, "logStatusError", "resourcePath is missing (or longer than 479 "
               "bytes): the FMU's data file resources/model.pcsdata cannot be found");
        free(c);
        return NULL;
    }
    len = strlen(dir);
    snprintf(c->data_path, sizeof c->data_path, "%s%smodel.pcsdata", dir,
             len && (dir[len - 1] == '/' || dir[len - 1] == '\\') ? "" : "/");
    if (load(c) != 0) {
        logmsg(c, fmi3Error, "logStatusError", c->msg);
        free(c);
        return NULL;
    }
    c->phase = INSTANTIATED;
    return c;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    Instance *c = (Instance *)instance;
    if (!c) return;
    pcs_model_free(c->model, &c->mem);
    pcs_data_free(&c->data, &c->mem);
    free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean tolerance_defined,
                                       fmi3Float64 tolerance, fmi3Float64 start,
                                       fmi3Boolean stop_defined, fmi3Float64 stop)
{
    Instance *c = (Instance *)instance;
    (void)tolerance_defined; (void)tolerance; (void)stop_defined; (void)stop;
    if (usable(c, "fmi3EnterInitializationMode") != fmi3OK) return fmi3Error;
    if (c->phase != INSTANTIATED)
        return fail(c, "fmi3EnterInitializationMode: the instance is not in the instantiated "
                    "state");
    c->time = start;
    c->phase = INITIALISATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    Instance *c = (Instance *)instance;
    if (usable(c, "fmi3ExitInitializationMode") != fmi3OK) return fmi3Error;
    if (c->phase != INITIALISATION)
        return fail(c, "fmi3ExitInitializationMode outside initialisation mode");
    if (pcs_initialize(c->model, c->msg) != PCS_OK) return fail(c, c->msg);
    c->phase = STEPPING;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    Instance *c = (Instance *)instance;
    if (usable(c, "fmi3Terminate") != fmi3OK) return fmi3Error;
    c->phase = TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    Instance *c = (Instance *)instance;
    if (!c) return fmi3Error;
    pcs_model_free(c->model, &c->mem);
    pcs_data_free(&c->data, &c->mem);
    c->model = NULL;
    if (load(c) != 0) return fail(c, c->msg);
    c->phase = INSTANTIATED;
    c->time = 0.0;
    return fmi3OK;
}

/* ------------------------------------------------------------------ variables */

static int initialised(const Instance *c)
{
    return !(c->phase == INSTANTIATED || c->phase == INITIALISATION);
}

#define CHECK_ARRAYS(NAME)                                                                \
    if (!c) return fmi3Error;                                                             \
    if (nvr > 0 && (!vr || !values)) return fail(c, NAME ": NULL arrays");                 \
    if (n_values != nvr) return fail(c, NAME ": one value per value reference (no arrays)")

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t n_values)
{
    Instance *c = (Instance *)instance;
    size_t i;
    CHECK_ARRAYS("fmi3GetFloat64");
    for (i = 0; i < nvr; i++) {
        if (vr[i] == 0) {                  /* the independent variable */
            values[i] = c->time;
            continue;
        }
        if (pcs_get_real(c->model, vr[i], &values[i], c->msg) != PCS_OK) return fail(c, c->msg);
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Int32 values[], size_t n_values)
{
    Instance *c = (Instance *)instance;
    size_t i;
    CHECK_ARRAYS("fmi3GetInt32");
    for (i = 0; i < nvr; i++) {
        int v;
        if (vr[i] < PCS_FMI3_INT32_BASE
            || pcs_get_integer(c->model, vr[i] - PCS_FMI3_INT32_BASE, &v, c->msg) != PCS_OK)
            return fail(c, "fmi3GetInt32: not an Int32 variable");
        values[i] = v;
    }
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Boolean values[], size_t n_values)
{
    Instance *c = (Instance *)instance;
    size_t i;
    CHECK_ARRAYS("fmi3GetBoolean");
    for (i = 0; i < nvr; i++) {
        int v;
        if (vr[i] < PCS_FMI3_BOOLEAN_BASE
            || pcs_get_boolean(c->model, vr[i] - PCS_FMI3_BOOLEAN_BASE, &v, c->msg) != PCS_OK)
            return fail(c, "fmi3GetBoolean: not a Boolean variable");
        values[i] = v ? fmi3True : fmi3False;
    }
    return fmi3OK;
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         fmi3String values[], size_t n_values)
{
    Instance *c = (Instance *)instance;
    size_t i;
    CHECK_ARRAYS("fmi3GetString");
    for (i = 0; i < nvr; i++)
        if (vr[i] < PCS_FMI3_STRING_BASE
            || pcs_get_string(c->model, vr[i] - PCS_FMI3_STRING_BASE, &values[i], c->msg)
                   != PCS_OK)
            return fail(c, "fmi3GetString: not a String variable");
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t n_values)
{
    Instance *c = (Instance *)instance;
    size_t i;
    CHECK_ARRAYS("fmi3SetFloat64");
    if (usable(c, "fmi3SetFloat64") != fmi3OK) return fmi3Error;
    for (i = 0; i < nvr; i++)
        if (pcs_set_real(c->model, vr[i], values[i], initialised(c), c->msg) != PCS_OK)
            return fail(c, c->msg);
    return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int32 values[], size_t n_values)
{
    Instance *c = (Instance *)instance;
    size_t i;
    CHECK_ARRAYS("fmi3SetInt32");
    if (usable(c, "fmi3SetInt32") != fmi3OK) return fmi3Error;
    for (i = 0; i < nvr; i++)
        if (vr[i] < PCS_FMI3_INT32_BASE
            || pcs_set_integer(c->model, vr[i] - PCS_FMI3_INT32_BASE, values[i], initialised(c),
                               c->msg) != PCS_OK)
            return fail(c, vr[i] < PCS_FMI3_INT32_BASE ? "fmi3SetInt32: not an Int32 variable"
                                                       : c->msg);
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t n_values)
{
    Instance *c = (Instance *)instance;
    size_t i;
    CHECK_ARRAYS("fmi3SetBoolean");
    if (usable(c, "fmi3SetBoolean") != fmi3OK) return fmi3Error;
    for (i = 0; i < nvr; i++)
        if (vr[i] < PCS_FMI3_BOOLEAN_BASE
            || pcs_set_boolean(c->model, vr[i] - PCS_FMI3_BOOLEAN_BASE, values[i] != 0,
                               initialised(c), c->msg) != PCS_OK)
            return fail(c, vr[i] < PCS_FMI3_BOOLEAN_BASE ? "fmi3SetBoolean: not a Boolean "
                        "variable" : c->msg);
    return fmi3OK;
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3String values[], size_t n_values)
{
    Instance *c = (Instance *)instance;
    size_t i;
    CHECK_ARRAYS("fmi3SetString");
    if (usable(c, "fmi3SetString") != fmi3OK) return fmi3Error;
    for (i = 0; i < nvr; i++)
        if (vr[i] < PCS_FMI3_STRING_BASE
            || pcs_set_string(c->model, vr[i] - PCS_FMI3_STRING_BASE, values[i], initialised(c),
                              c->msg) != PCS_OK)
            return fail(c, vr[i] < PCS_FMI3_STRING_BASE ? "fmi3SetString: not a String "
                        "variable" : c->msg);
    return fmi3OK;
}

/* ------------------------------------------------------------------ stepping */

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 h,
                      fmi3Boolean no_prior, fmi3Boolean *event_needed, fmi3Boolean *terminate,
                      fmi3Boolean *early_return, fmi3Float64 *last_time)
{
    Instance *c = (Instance *)instance;
    int status;
    (void)no_prior;
    if (usable(c, "fmi3DoStep") != fmi3OK) return fmi3Error;
    if (c->phase != STEPPING) return fail(c, "fmi3DoStep outside step mode");
    if (event_needed) *event_needed = fmi3False;
    if (terminate) *terminate = fmi3False;
    if (early_return) *early_return = fmi3False;
    if (last_time) *last_time = c->time;
    if (!isfinite(t) || fabs(t - c->time) > 1e-9 * (fabs(t) > 1.0 ? fabs(t) : 1.0)) {
        snprintf(c->msg, sizeof c->msg, "fmi3DoStep: currentCommunicationPoint = %.17g s, "
                 "the FMU is at %.17g s", t, c->time);
        logmsg(c, fmi3Discard, "logStatusDiscard", c->msg);
        return fmi3Discard;
    }
    status = pcs_do_step(c->model, t, h, c->msg);
    if (status == PCS_OK) {
        c->time = t + h;
        if (last_time) *last_time = c->time;
        return fmi3OK;
    }
    if (status == PCS_DISCARD) {
        logmsg(c, fmi3Discard, "logStatusDiscard", c->msg);
        return fmi3Discard;
    }
    return fail(c, c->msg);
}

/* ------------------------------------------------------------------ FMU states */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state)
{
    Instance *c = (Instance *)instance;
    StateHead *s;
    size_t bytes;
    if (usable(c, "fmi3GetFMUState") != fmi3OK) return fmi3Error;
    if (!state) return fail(c, "fmi3GetFMUState: NULL state pointer");
    bytes = pcs_state_bytes(c->model);
    s = (StateHead *)*state;
    if (!s || s->magic != STATE_MAGIC || s->bytes != bytes) {
        s = (StateHead *)calloc(1, sizeof(StateHead) + bytes);
        if (!s) return fail(c, "fmi3GetFMUState: no memory");
    }
    s->magic = STATE_MAGIC;
    s->bytes = bytes;
    s->time = c->time;
    s->phase = (int)c->phase;
    pcs_state_save(c->model, (unsigned char *)s + sizeof(StateHead));
    *state = s;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state)
{
    Instance *c = (Instance *)instance;
    const StateHead *s = (const StateHead *)state;
    if (!c) return fmi3Error;
    if (!s || s->magic != STATE_MAGIC || s->bytes != pcs_state_bytes(c->model))
        return fail(c, "fmi3SetFMUState: not a state of this FMU");
    if (s->phase != STEPPING && s->phase != TERMINATED)
        return fail(c, "fmi3SetFMUState: a state saved before initialisation is not supported");
    pcs_state_restore(c->model, (const unsigned char *)s + sizeof(StateHead));
    c->time = s->time;
    c->phase = STEPPING;
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state)
{
    if (!instance) return fmi3Error;
    if (!state || !*state) return fmi3OK;
    ((StateHead *)*state)->magic = 0;
    free(*state);
    *state = NULL;
    return fmi3OK;
}

#define SER_HEAD 32u

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t *size)
{
    Instance *c = (Instance *)instance;
    const StateHead *s = (const StateHead *)state;
    if (!c || !size) return fmi3Error;
    if (!s || s->magic != STATE_MAGIC) return fail(c, "fmi3SerializedFMUStateSize: not a state "
                                                     "of this FMU");
    *size = SER_HEAD + s->bytes;
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state, fmi3Byte out[],
                                 size_t size)
{
    Instance *c = (Instance *)instance;
    const StateHead *s = (const StateHead *)state;
    unsigned long long bytes, sum;
    if (!c) return fmi3Error;
    if (!s || s->magic != STATE_MAGIC) return fail(c, "fmi3SerializeFMUState: not a state of "
                                                     "this FMU");
    if (!out || size < SER_HEAD + s->bytes) return fail(c, "fmi3SerializeFMUState: buffer too "
                                                          "small");
    memcpy(out, "PCSSTATE", 8);
    bytes = s->bytes;
    memcpy(out + 8, &bytes, 8);
    memcpy(out + 24, &s->time, 8);
    memcpy(out + SER_HEAD, (const unsigned char *)s + sizeof(StateHead), s->bytes);
    sum = pcs_fnv1a((const unsigned char *)out + 24, 8 + s->bytes);
    memcpy(out + 16, &sum, 8);
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte in[], size_t size,
                                   fmi3FMUState *state)
{
    Instance *c = (Instance *)instance;
    unsigned long long bytes, sum;
    StateHead *s;
    size_t want;
    if (!c) return fmi3Error;
    if (!in || !state) return fail(c, "fmi3DeserializeFMUState: NULL arguments");
    want = pcs_state_bytes(c->model);
    if (size < SER_HEAD || memcmp(in, "PCSSTATE", 8) != 0)
        return fail(c, "fmi3DeserializeFMUState: not a serialized state of a pantocosim "
                    "native FMU");
    memcpy(&bytes, in + 8, 8);
    memcpy(&sum, in + 16, 8);
    if (bytes != want || size != SER_HEAD + want)
        return fail(c, "fmi3DeserializeFMUState: a state of another model (its size differs)");
    if (sum != pcs_fnv1a((const unsigned char *)in + 24, 8 + want))
        return fail(c, "fmi3DeserializeFMUState: checksum mismatch (damaged state)");
    s = (StateHead *)calloc(1, sizeof(StateHead) + want);
    if (!s) return fail(c, "fmi3DeserializeFMUState: no memory");
    s->magic = STATE_MAGIC;
    s->bytes = want;
    memcpy(&s->time, in + 24, 8);
    s->phase = STEPPING;
    memcpy((unsigned char *)s + sizeof(StateHead), in + SER_HEAD, want);
    *state = s;
    return fmi3OK;
}
