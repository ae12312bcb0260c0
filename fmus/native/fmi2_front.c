/*
 * The FMI 2.0 co-simulation interface of a native model (pcs_model.h): the instance, its
 * state machine, FMU states (get, set, free, serialize) and the data file read at
 * instantiation from resources/model.pcsdata. Every call that is not honoured returns
 * fmi2Error (or fmi2Discard for a refused step that left the state as it was) with a message
 * through the logger; nothing here allocates after fmi2ExitInitializationMode except the
 * FMU-state calls, which own their memory.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "pcs_model.h"

#define STATE_MAGIC 0x50435353u   /* "PCSS" */

typedef enum { INSTANTIATED, INITIALISATION, STEPPING, TERMINATED, FAILED } Phase;

typedef struct {
    fmi2CallbackFunctions cb;
    PcsMemory mem;
    char name[128];
    char data_path[512];
    PcsData data;
    PcsModel *model;
    Phase phase;
    int logging;
    double time;
    char msg[PCS_MSG];
} Instance;

typedef struct {
    unsigned magic;
    size_t bytes;
    double time;
    int phase;
    Instance *owner;
} StateHead;

static void *(*alloc_fn)(size_t, size_t);
static void (*release_fn)(void *);

static void *mem_alloc(size_t n, size_t size) { return alloc_fn(n, size); }
static void mem_release(void *p) { release_fn(p); }

static void logmsg(Instance *c, fmi2Status status, const char *category, const char *text)
{
    if (c && c->cb.logger)
        c->cb.logger(c->cb.componentEnvironment, c->name, status, category, "%s", text);
}

static fmi2Status fail(Instance *c, const char *text)
{
    logmsg(c, fmi2Error, "logStatusError", text);
    c->phase = FAILED;
    return fmi2Error;
}

/* the model's status as the FMI status of the call */
static fmi2Status from_model(Instance *c, int status)
{
    if (status == PCS_OK) return fmi2OK;
    if (status == PCS_DISCARD) {
        logmsg(c, fmi2Discard, "logStatusDiscard", c->msg);
        return fmi2Discard;
    }
    return fail(c, c->msg);
}

static fmi2Status usable(Instance *c, const char *call)
{
    if (!c) return fmi2Error;
    if (c->phase == FAILED) {
        char text[256];
        snprintf(text, sizeof text, "%s: the instance failed before; only fmi2Reset or "
                 "fmi2FreeInstance are possible", call);
        logmsg(c, fmi2Error, "logStatusError", text);
        return fmi2Error;
    }
    return fmi2OK;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean on, size_t n,
                               const fmi2String categories[])
{
    Instance *c = (Instance *)comp;
    (void)n;
    (void)categories;
    if (!c) return fmi2Error;
    c->logging = on;
    return fmi2OK;
}

static int load(Instance *c)
{
    if (pcs_data_load(&c->data, c->data_path, &c->mem, c->msg, sizeof c->msg) != 0)
        return -1;
    c->model = pcs_model_new(&c->data, &c->mem, c->msg);
    if (!c->model) {
        pcs_data_free(&c->data, &c->mem);
        return -1;
    }
    return 0;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean logging)
{
    Instance *c;
    char dir[480];
    (void)visible;
    (void)guid;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    alloc_fn = functions->allocateMemory;
    release_fn = functions->freeMemory;
    c = (Instance *)functions->allocateMemory(1, sizeof *c);
    if (!c) return NULL;
    c->cb = *functions;
    c->mem.alloc = mem_alloc;
    c->mem.release = mem_release;
    c->logging = logging;
    strncpy(c->name, name ? name : "", sizeof c->name - 1);
    if (type != fmi2CoSimulation) {
        logmsg(c, fmi2Error, "logStatusError", "this FMU is for co-simulation only");
        functions->freeMemory(c);
        return NULL;
    }
    if (pcs_uri_to_path(resources, dir, sizeof dir) != 0 || !dir[0]) {
        logmsg(c, fmi2Error, "logStatusError", "fmuResourceLocation is not a file URI (or longer than 479 bytes): the "
               "FMU's data file resources/model.pcsdata cannot be found");
        functions->freeMemory(c);
        return NULL;
    }
    {
        size_t len = strlen(dir);
        snprintf(c->data_path, sizeof c->data_path, "%s%smodel.pcsdata", dir,
                 len && (dir[len - 1] == '/' || dir[len - 1] == '\\') ? "" : "/");
    }
    if (load(c) != 0) {
        logmsg(c, fmi2Error, "logStatusError", c->msg);
        functions->freeMemory(c);
        return NULL;
    }
    c->phase = INSTANTIATED;
    return c;
}

void fmi2FreeInstance(fmi2Component comp)
{
    Instance *c = (Instance *)comp;
    if (!c) return;
    pcs_model_free(c->model, &c->mem);
    pcs_data_free(&c->data, &c->mem);
    c->cb.freeMemory(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tolerance_defined,
                               fmi2Real tolerance, fmi2Real start, fmi2Boolean stop_defined,
                               fmi2Real stop)
{
    Instance *c = (Instance *)comp;
    (void)tolerance_defined;
    (void)tolerance;
    (void)stop_defined;
    (void)stop;
    if (usable(c, "fmi2SetupExperiment") != fmi2OK) return fmi2Error;
    if (c->phase != INSTANTIATED) return fail(c, "fmi2SetupExperiment after initialisation");
    c->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp)
{
    Instance *c = (Instance *)comp;
    if (usable(c, "fmi2EnterInitializationMode") != fmi2OK) return fmi2Error;
    if (c->phase != INSTANTIATED)
        return fail(c, "fmi2EnterInitializationMode: the instance is not in the instantiated "
                    "state");
    c->phase = INITIALISATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp)
{
    Instance *c = (Instance *)comp;
    if (usable(c, "fmi2ExitInitializationMode") != fmi2OK) return fmi2Error;
    if (c->phase != INITIALISATION)
        return fail(c, "fmi2ExitInitializationMode outside initialisation mode");
    if (pcs_initialize(c->model, c->msg) != PCS_OK) return fail(c, c->msg);
    c->phase = STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component comp)
{
    Instance *c = (Instance *)comp;
    if (usable(c, "fmi2Terminate") != fmi2OK) return fmi2Error;
    c->phase = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp)
{
    Instance *c = (Instance *)comp;
    if (!c) return fmi2Error;
    pcs_model_free(c->model, &c->mem);
    pcs_data_free(&c->data, &c->mem);
    c->model = NULL;
    if (load(c) != 0) return fail(c, c->msg);
    c->phase = INSTANTIATED;
    c->time = 0.0;
    return fmi2OK;
}

/* ------------------------------------------------------------------ variables */

static int before_init(const Instance *c) { return c->phase == INSTANTIATED || c->phase == INITIALISATION; }

#define GETTER(NAME, TYPE, CALL)                                                          \
    fmi2Status NAME(fmi2Component comp, const fmi2ValueReference vr[], size_t n, TYPE value[]) \
    {                                                                                     \
        Instance *c = (Instance *)comp;                                                   \
        size_t i;                                                                         \
        if (!c) return fmi2Error;                                                         \
        if (n > 0 && (!vr || !value)) return fail(c, #NAME ": NULL arrays");              \
        for (i = 0; i < n; i++)                                                           \
            if (CALL != PCS_OK) return fail(c, c->msg);                                   \
        return fmi2OK;                                                                    \
    }

GETTER(fmi2GetReal, fmi2Real, pcs_get_real(c->model, vr[i], &value[i], c->msg))

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer value[])
{
    Instance *c = (Instance *)comp;
    size_t i;
    if (!c) return fmi2Error;
    if (n > 0 && (!vr || !value)) return fail(c, "fmi2GetInteger: NULL arrays");
    for (i = 0; i < n; i++) {
        int v;
        if (pcs_get_integer(c->model, vr[i], &v, c->msg) != PCS_OK) return fail(c, c->msg);
        value[i] = v;
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean value[])
{
    Instance *c = (Instance *)comp;
    size_t i;
    if (!c) return fmi2Error;
    if (n > 0 && (!vr || !value)) return fail(c, "fmi2GetBoolean: NULL arrays");
    for (i = 0; i < n; i++) {
        int v;
        if (pcs_get_boolean(c->model, vr[i], &v, c->msg) != PCS_OK) return fail(c, c->msg);
        value[i] = v ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

GETTER(fmi2GetString, fmi2String, pcs_get_string(c->model, vr[i], &value[i], c->msg))

#define SETTER(NAME, TYPE, CALL)                                                          \
    fmi2Status NAME(fmi2Component comp, const fmi2ValueReference vr[], size_t n,          \
                    const TYPE value[])                                                   \
    {                                                                                     \
        Instance *c = (Instance *)comp;                                                   \
        size_t i;                                                                         \
        int init;                                                                         \
        if (usable(c, #NAME) != fmi2OK) return fmi2Error;                                 \
        if (n > 0 && (!vr || !value)) return fail(c, #NAME ": NULL arrays");              \
        init = !before_init(c);                                                           \
        for (i = 0; i < n; i++)                                                           \
            if (CALL != PCS_OK) return fail(c, c->msg);                                   \
        return fmi2OK;                                                                    \
    }

SETTER(fmi2SetReal, fmi2Real, pcs_set_real(c->model, vr[i], value[i], init, c->msg))
SETTER(fmi2SetInteger, fmi2Integer, pcs_set_integer(c->model, vr[i], value[i], init, c->msg))
SETTER(fmi2SetBoolean, fmi2Boolean, pcs_set_boolean(c->model, vr[i], value[i], init, c->msg))
SETTER(fmi2SetString, fmi2String, pcs_set_string(c->model, vr[i], value[i], init, c->msg))

/* ------------------------------------------------------------------ stepping */

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean no_prior)
{
    Instance *c = (Instance *)comp;
    int status;
    (void)no_prior;
    if (usable(c, "fmi2DoStep") != fmi2OK) return fmi2Error;
    if (c->phase != STEPPING) return fail(c, "fmi2DoStep outside step mode");
    if (!isfinite(t) || fabs(t - c->time) > 1e-9 * (fabs(t) > 1.0 ? fabs(t) : 1.0)) {
        snprintf(c->msg, sizeof c->msg, "fmi2DoStep: currentCommunicationPoint = %.17g s, "
                 "the FMU is at %.17g s", t, c->time);
        logmsg(c, fmi2Discard, "logStatusDiscard", c->msg);
        return fmi2Discard;
    }
    status = pcs_do_step(c->model, t, h, c->msg);
    if (status == PCS_OK) c->time = t + h;
    return from_model(c, status);
}

fmi2Status fmi2CancelStep(fmi2Component comp)
{
    Instance *c = (Instance *)comp;
    if (!c) return fmi2Error;
    logmsg(c, fmi2Error, "logStatusError", "fmi2CancelStep: steps are synchronous");
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    if (!comp || !value) return fmi2Error;
    *value = ((Instance *)comp)->phase == FAILED ? fmi2Error : fmi2OK;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value)
{
    Instance *c = (Instance *)comp;
    if (!c || !value) return fmi2Error;
    if (s == fmi2LastSuccessfulTime) {
        *value = c->time;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)comp; (void)s; (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value)
{
    if (!comp || !value) return fmi2Error;
    if (s == fmi2Terminated) {
        *value = fmi2False;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value)
{
    (void)comp; (void)s; (void)value;
    return fmi2Discard;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                       size_t n, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    (void)vr; (void)n; (void)order; (void)value;
    if (comp) logmsg((Instance *)comp, fmi2Error, "logStatusError",
                     "input derivatives are not supported (canInterpolateInputs = false)");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)n; (void)order; (void)value;
    if (comp) logmsg((Instance *)comp, fmi2Error, "logStatusError",
                     "output derivatives are not supported (maxOutputDerivativeOrder = 0)");
    return fmi2Error;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference u[],
                                        size_t nu, const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real du[], fmi2Real dz[])
{
    (void)u; (void)nu; (void)z; (void)nz; (void)du; (void)dz;
    if (comp) logmsg((Instance *)comp, fmi2Error, "logStatusError",
                     "directional derivatives are not supported");
    return fmi2Error;
}

/* ------------------------------------------------------------------ FMU states */

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *state)
{
    Instance *c = (Instance *)comp;
    StateHead *s;
    size_t bytes;
    if (usable(c, "fmi2GetFMUstate") != fmi2OK) return fmi2Error;
    if (!state) return fail(c, "fmi2GetFMUstate: NULL state pointer");
    bytes = pcs_state_bytes(c->model);
    s = (StateHead *)*state;
    if (!s || s->magic != STATE_MAGIC || s->bytes != bytes) {
        s = (StateHead *)c->cb.allocateMemory(1, sizeof(StateHead) + bytes);
        if (!s) return fail(c, "fmi2GetFMUstate: no memory");
    }
    s->magic = STATE_MAGIC;
    s->bytes = bytes;
    s->time = c->time;
    s->phase = (int)c->phase;
    s->owner = c;
    pcs_state_save(c->model, (unsigned char *)s + sizeof(StateHead));
    *state = s;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state)
{
    Instance *c = (Instance *)comp;
    const StateHead *s = (const StateHead *)state;
    if (!c) return fmi2Error;
    if (!s || s->magic != STATE_MAGIC || s->bytes != pcs_state_bytes(c->model))
        return fail(c, "fmi2SetFMUstate: not a state of this FMU");
    if (s->phase != STEPPING && s->phase != TERMINATED)
        return fail(c, "fmi2SetFMUstate: a state saved before initialisation is not supported");
    pcs_state_restore(c->model, (const unsigned char *)s + sizeof(StateHead));
    c->time = s->time;
    c->phase = STEPPING;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *state)
{
    Instance *c = (Instance *)comp;
    if (!c) return fmi2Error;
    if (!state || !*state) return fmi2OK;
    ((StateHead *)*state)->magic = 0;
    c->cb.freeMemory(*state);
    *state = NULL;
    return fmi2OK;
}

/* serialized: "PCSSTATE", uint64 bytes, uint64 FNV-1a of the rest, double time, state */
#define SER_HEAD 32u

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate state, size_t *size)
{
    Instance *c = (Instance *)comp;
    const StateHead *s = (const StateHead *)state;
    if (!c || !size) return fmi2Error;
    if (!s || s->magic != STATE_MAGIC) return fail(c, "fmi2SerializedFMUstateSize: not a state "
                                                     "of this FMU");
    *size = SER_HEAD + s->bytes;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate state, fmi2Byte out[],
                                 size_t size)
{
    Instance *c = (Instance *)comp;
    const StateHead *s = (const StateHead *)state;
    unsigned long long bytes, sum;
    if (!c) return fmi2Error;
    if (!s || s->magic != STATE_MAGIC) return fail(c, "fmi2SerializeFMUstate: not a state of "
                                                     "this FMU");
    if (!out || size < SER_HEAD + s->bytes) return fail(c, "fmi2SerializeFMUstate: buffer too "
                                                          "small");
    memcpy(out, "PCSSTATE", 8);
    bytes = s->bytes;
    memcpy(out + 8, &bytes, 8);
    memcpy(out + 24, &s->time, 8);
    memcpy(out + SER_HEAD, (const unsigned char *)s + sizeof(StateHead), s->bytes);
    sum = pcs_fnv1a((const unsigned char *)out + 24, 8 + s->bytes);
    memcpy(out + 16, &sum, 8);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte in[], size_t size,
                                   fmi2FMUstate *state)
{
    Instance *c = (Instance *)comp;
    unsigned long long bytes, sum;
    StateHead *s;
    size_t want;
    if (!c) return fmi2Error;
    if (!in || !state) return fail(c, "fmi2DeSerializeFMUstate: NULL arguments");
    want = pcs_state_bytes(c->model);
    if (size < SER_HEAD || memcmp(in, "PCSSTATE", 8) != 0)
        return fail(c, "fmi2DeSerializeFMUstate: not a serialized state of a pantocosim "
                    "native FMU");
    memcpy(&bytes, in + 8, 8);
    memcpy(&sum, in + 16, 8);
    if (bytes != want || size != SER_HEAD + want)
        return fail(c, "fmi2DeSerializeFMUstate: a state of another model (its size differs)");
    if (sum != pcs_fnv1a((const unsigned char *)in + 24, 8 + want))
        return fail(c, "fmi2DeSerializeFMUstate: checksum mismatch (damaged state)");
    s = (StateHead *)c->cb.allocateMemory(1, sizeof(StateHead) + want);
    if (!s) return fail(c, "fmi2DeSerializeFMUstate: no memory");
    s->magic = STATE_MAGIC;
    s->bytes = want;
    memcpy(&s->time, in + 24, 8);
    s->phase = STEPPING;
    s->owner = c;
    memcpy((unsigned char *)s + sizeof(StateHead), in + SER_HEAD, want);
    *state = s;
    return fmi2OK;
}
