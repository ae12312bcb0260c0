/* The instance of a native FMU under both FMI fronts (pcs_instance.h). */
#include "pcs_instance.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define STATE_MAGIC 0x50435353u      /* "PCSS" */
#define SER_VERSION 2u
/* serialized: "PCSSTATE", uint32 version, uint32 model kind, uint64 data checksum, uint64
   state bytes, uint64 FNV-1a of the rest, float64 time, the state */
#define SER_HEAD 48u

typedef struct {
    unsigned magic;
    const PcsModelType *type;
    const PcsInstance *owner;
    unsigned long long data_sum;
    size_t bytes;
    double time;
    int phase;
} StateHead;

int pcs_report(PcsInstance *c, int status, const char *text)
{
    static const char *const categories[] = {"logAll", "logStatusDiscard", "logStatusError"};
    if (!c) return PCS_ERROR;
    if (c->log) c->log(c->host, c->name, status, categories[status], text);
    if (status == PCS_ERROR) c->phase = PCS_FAILED;
    return status;
}

int pcs_refuse(PcsInstance *c, const char *call, const char *text)
{
    char line[PCS_MSG];
    if (!c) return PCS_ERROR;
    snprintf(line, sizeof line, "%s: %s", call, text);
    if (c->log) c->log(c->host, c->name, PCS_ERROR, "logStatusError", line);
    return PCS_ERROR;
}

static const char *const PHASES[] = {"instantiated", "initialisation mode", "step mode",
                                     "terminated", "failed"};

/* the instance is in one of the phases of mask (bit per PcsPhase) and has its model */
static int ready(PcsInstance *c, const char *call, unsigned mask)
{
    char text[300];
    if (!c) return PCS_ERROR;
    if (!c->model) return pcs_refuse(c, call, "the instance has no model (its data file could not "
                                 "be read at the last reset); only Reset or FreeInstance");
    if (mask & (1u << c->phase)) return PCS_OK;
    snprintf(text, sizeof text, "not possible in %s%s", PHASES[c->phase],
             c->phase == PCS_FAILED ? " (an earlier call failed; Reset, FreeInstance or set "
                                      "a saved FMU state)" : "");
    return pcs_refuse(c, call, text);
}

#define ANY 0x1Fu
#define BIT(p) (1u << (p))

/* ------------------------------------------------------------------ load and reset */

static const PcsModelType *model_of(unsigned kind)
{
    int i;
    for (i = 0; pcs_model_table[i]; i++)
        if (pcs_model_table[i]->kind == kind) return pcs_model_table[i];
    return NULL;
}

static int load(PcsInstance *c)
{
    const PcsModelType *type;
    if (pcs_data_load(&c->data, c->data_path, &c->mem, c->msg, sizeof c->msg) != 0) return -1;
    type = model_of(c->data.kind);
    if (!type) {
        int i, k;
        k = snprintf(c->msg, sizeof c->msg, "data file %.400s: model kind %u, this FMU steps",
                     c->data_path, c->data.kind);
        for (i = 0; pcs_model_table[i] && k > 0 && (size_t)k < sizeof c->msg; i++)
            k += snprintf(c->msg + k, sizeof c->msg - (size_t)k, "%s the %s (kind %u)",
                          i ? "," : "", pcs_model_table[i]->name, pcs_model_table[i]->kind);
        pcs_data_free(&c->data, &c->mem);
        return -1;
    }
    c->model = type->create(&c->data, &c->mem, c->msg);
    if (!c->model) {
        pcs_data_free(&c->data, &c->mem);
        return -1;
    }
    c->type = type;
    return 0;
}

static void unload(PcsInstance *c)
{
    if (c->model) c->type->destroy(c->model, &c->mem);
    c->model = NULL;
    c->initialised = 0;
    pcs_data_free(&c->data, &c->mem);
}

/* the token the host passed is the one this binary was built with (as the Modelica
   Reference-FMUs check it) */
static int own_token(PcsInstance *c, const char *token)
{
    if (token && strcmp(token, pcs_instantiation_token) == 0) return 0;
    snprintf(c->msg, sizeof c->msg, "the instantiation token (FMI 2.0: GUID) %s%.200s%s is not "
             "this FMU's \"%s\": the host read the modelDescription.xml of another FMU or "
             "export", token ? "\"" : "", token ? token : "NULL", token ? "\"" : "",
             pcs_instantiation_token);
    pcs_report(c, PCS_ERROR, c->msg);
    return -1;
}

PcsInstance *pcs_instance_new(const char *name, const char *token, const char *resources,
                              const PcsMemory *mem, PcsLogger log, void *host)
{
    PcsInstance *c;
    size_t len;
    if (!mem || !mem->alloc || !mem->release) return NULL;
    c = (PcsInstance *)pcs_alloc(mem, 1, sizeof *c);
    if (!c) return NULL;
    c->mem = *mem;
    c->log = log;
    c->host = host;
    strncpy(c->name, name ? name : "", sizeof c->name - 1);
    if (own_token(c, token) != 0) {
        pcs_free(mem, c);
        return NULL;
    }
    len = resources ? strlen(resources) : 0;
    if (!len || len > sizeof c->data_path - 20) {
        pcs_report(c, PCS_ERROR, len ? "the resource folder's path is longer than 490 bytes"
                   : "no resource folder: the FMU's data file resources/model.pcsdata "
                     "cannot be found");
        pcs_free(mem, c);
        return NULL;
    }
    snprintf(c->data_path, sizeof c->data_path, "%s%smodel.pcsdata", resources,
             resources[len - 1] == '/' || resources[len - 1] == '\\' ? "" : "/");
    if (load(c) != 0) {
        pcs_report(c, PCS_ERROR, c->msg);
        pcs_free(mem, c);
        return NULL;
    }
    c->phase = PCS_INSTANTIATED;
    return c;
}

void pcs_instance_free(PcsInstance *c)
{
    PcsMemory mem;
    if (!c) return;
    unload(c);
    mem = c->mem;
    pcs_free(&mem, c);
}

int pcs_reset(PcsInstance *c, const char *call)
{
    (void)call;
    if (!c) return PCS_ERROR;
    unload(c);
    c->time = 0.0;
    if (load(c) != 0) return pcs_report(c, PCS_ERROR, c->msg);
    c->phase = PCS_INSTANTIATED;
    return PCS_OK;
}

/* ------------------------------------------------------------------ phases */

int pcs_set_start(PcsInstance *c, const char *call, double start)
{
    if (ready(c, call, BIT(PCS_INSTANTIATED)) != PCS_OK) return PCS_ERROR;
    if (!isfinite(start)) return pcs_refuse(c, call, "the start time is not finite");
    c->time = start;
    return PCS_OK;
}

int pcs_enter_initialisation(PcsInstance *c, const char *call)
{
    if (ready(c, call, BIT(PCS_INSTANTIATED)) != PCS_OK) return PCS_ERROR;
    c->phase = PCS_INITIALISATION;
    return PCS_OK;
}

int pcs_exit_initialisation(PcsInstance *c, const char *call)
{
    if (ready(c, call, BIT(PCS_INITIALISATION)) != PCS_OK) return PCS_ERROR;
    if (c->type->initialize(c->model, c->msg) != PCS_OK) return pcs_report(c, PCS_ERROR, c->msg);
    c->initialised = 1;
    c->phase = PCS_STEPPING;
    return PCS_OK;
}

int pcs_terminate(PcsInstance *c, const char *call)
{
    if (ready(c, call, BIT(PCS_STEPPING)) != PCS_OK) return PCS_ERROR;
    c->phase = PCS_TERMINATED;
    return PCS_OK;
}

int pcs_step(PcsInstance *c, const char *call, double t, double h)
{
    int status;
    if (ready(c, call, BIT(PCS_STEPPING)) != PCS_OK) return PCS_ERROR;
    if (!isfinite(t) || fabs(t - c->time) > 1e-9 * (fabs(t) > 1.0 ? fabs(t) : 1.0)) {
        snprintf(c->msg, sizeof c->msg, "%s: currentCommunicationPoint = %.17g s, the FMU is "
                 "at %.17g s", call, t, c->time);
        return pcs_report(c, PCS_DISCARD, c->msg);
    }
    status = c->type->step(c->model, t, h, c->msg);
    if (status == PCS_OK) {
        c->time = t + h;
        return PCS_OK;
    }
    return pcs_report(c, status, c->msg);
}

/* ------------------------------------------------------------------ variables */

int pcs_values(PcsInstance *c, const char *call, PcsAccess access, size_t n, const void *vr,
               const void *values)
{
    unsigned mask = access == PCS_WRITE
                        ? BIT(PCS_INSTANTIATED) | BIT(PCS_INITIALISATION) | BIT(PCS_STEPPING)
                    : access == PCS_READ_INITIALISED ? ANY & ~BIT(PCS_INSTANTIATED)
                                                     : ANY;
    if (ready(c, call, mask) != PCS_OK) return PCS_ERROR;
    if (n > 0 && (!vr || !values)) return pcs_refuse(c, call, "NULL arrays");
    return PCS_OK;
}

int pcs_get(PcsInstance *c, const char *call, PcsType type, unsigned vr, PcsValue *v)
{
    const PcsModelType *t = c->type;
    int status = PCS_ERROR;
    switch (type) {
    case PCS_REAL: status = t->get_real(c->model, vr, &v->real, c->msg); break;
    case PCS_INTEGER: status = t->get_integer(c->model, vr, &v->integer, c->msg); break;
    case PCS_BOOLEAN: status = t->get_boolean(c->model, vr, &v->integer, c->msg); break;
    case PCS_STRING: status = t->get_string(c->model, vr, &v->string, c->msg); break;
    }
    return status == PCS_OK ? PCS_OK : pcs_refuse(c, call, c->msg);
}

int pcs_set(PcsInstance *c, const char *call, PcsType type, unsigned vr, const PcsValue *v)
{
    const PcsModelType *t = c->type;
    int init = c->phase == PCS_STEPPING, status = PCS_ERROR;
    switch (type) {
    case PCS_REAL: status = t->set_real(c->model, vr, v->real, init, c->msg); break;
    case PCS_INTEGER: status = t->set_integer(c->model, vr, v->integer, init, c->msg); break;
    case PCS_BOOLEAN: status = t->set_boolean(c->model, vr, v->integer, init, c->msg); break;
    case PCS_STRING: status = t->set_string(c->model, vr, v->string, init, c->msg); break;
    }
    return status == PCS_OK ? PCS_OK : pcs_refuse(c, call, c->msg);
}

/* ------------------------------------------------------------------ FMU states */

/* a state this instance took and has not freed */
static int own_state(PcsInstance *c, const char *call, const void *state)
{
    const StateHead *s = (const StateHead *)state;
    if (!s || s->magic != STATE_MAGIC || s->owner != c)
        return pcs_refuse(c, call, "not an FMU state of this instance (or freed)");
    if (s->type != c->type || s->data_sum != c->data.checksum
        || s->bytes != c->type->state_bytes(c->model))
        return pcs_refuse(c, call, "an FMU state of another model or export");
    return PCS_OK;
}

int pcs_state_get(PcsInstance *c, const char *call, void **state)
{
    StateHead *s;
    size_t bytes;
    if (ready(c, call, ANY) != PCS_OK) return PCS_ERROR;
    if (!state) return pcs_refuse(c, call, "NULL state pointer");
    bytes = c->type->state_bytes(c->model);
    s = (StateHead *)*state;
    if (s && own_state(c, call, s) != PCS_OK) return PCS_ERROR;
    if (!s) {
        if (bytes > (size_t)-1 - sizeof(StateHead)
            || !(s = (StateHead *)pcs_alloc(&c->mem, 1, sizeof(StateHead) + bytes)))
            return pcs_refuse(c, call, "no memory for the FMU state");
    }
    s->magic = STATE_MAGIC;
    s->type = c->type;
    s->owner = c;
    s->data_sum = c->data.checksum;
    s->bytes = bytes;
    s->time = c->time;
    s->phase = (int)c->phase;
    c->type->state_save(c->model, (unsigned char *)s + sizeof(StateHead));
    *state = s;
    return PCS_OK;
}

int pcs_state_set(PcsInstance *c, const char *call, const void *state)
{
    const StateHead *s = (const StateHead *)state;
    if (ready(c, call, BIT(PCS_STEPPING) | BIT(PCS_TERMINATED) | BIT(PCS_FAILED)) != PCS_OK)
        return PCS_ERROR;
    if (own_state(c, call, s) != PCS_OK) return PCS_ERROR;
    if (!c->initialised)
        return pcs_refuse(c, call, "the model is not initialised since it was read (a state is "
                          "set in step mode)");
    if (!isfinite(s->time)) return pcs_refuse(c, call, "the FMU state's time is not finite");
    if (s->phase != PCS_STEPPING && s->phase != PCS_TERMINATED)
        return pcs_refuse(c, call, "a state saved before initialisation cannot be set");
    c->type->state_restore(c->model, (const unsigned char *)s + sizeof(StateHead));
    c->type->outputs(c->model);
    c->time = s->time;
    c->phase = PCS_STEPPING;
    return PCS_OK;
}

int pcs_state_free(PcsInstance *c, const char *call, void **state)
{
    StateHead *s;
    if (!c) return PCS_ERROR;
    if (!state || !*state) return PCS_OK;
    s = (StateHead *)*state;
    if (s->magic != STATE_MAGIC || s->owner != c)
        return pcs_refuse(c, call, "not an FMU state of this instance (or freed)");
    s->magic = 0;
    pcs_free(&c->mem, s);
    *state = NULL;
    return PCS_OK;
}

int pcs_state_size(PcsInstance *c, const char *call, const void *state, size_t *size)
{
    if (ready(c, call, ANY) != PCS_OK) return PCS_ERROR;
    if (!size) return pcs_refuse(c, call, "NULL size pointer");
    if (own_state(c, call, state) != PCS_OK) return PCS_ERROR;
    *size = SER_HEAD + ((const StateHead *)state)->bytes;
    return PCS_OK;
}

static void put_u32(unsigned char *p, unsigned v) { memcpy(p, &v, 4); }
static void put_u64(unsigned char *p, unsigned long long v) { memcpy(p, &v, 8); }

int pcs_state_serialize(PcsInstance *c, const char *call, const void *state,
                        unsigned char *out, size_t size)
{
    const StateHead *s = (const StateHead *)state;
    if (ready(c, call, ANY) != PCS_OK) return PCS_ERROR;
    if (own_state(c, call, s) != PCS_OK) return PCS_ERROR;
    if (!out || size < SER_HEAD + s->bytes) return pcs_refuse(c, call, "buffer too small");
    memcpy(out, "PCSSTATE", 8);
    put_u32(out + 8, SER_VERSION);
    put_u32(out + 12, c->type->kind);
    put_u64(out + 16, s->data_sum);
    put_u64(out + 24, s->bytes);
    memcpy(out + 40, &s->time, 8);
    memcpy(out + SER_HEAD, (const unsigned char *)s + sizeof(StateHead), s->bytes);
    put_u64(out + 32, pcs_fnv1a(out + 40, 8 + s->bytes));
    return PCS_OK;
}

int pcs_state_deserialize(PcsInstance *c, const char *call, const unsigned char *in,
                          size_t size, void **state)
{
    StateHead *s;
    size_t want;
    double time;
    if (ready(c, call, ANY) != PCS_OK) return PCS_ERROR;
    if (!in || !state) return pcs_refuse(c, call, "NULL arguments");
    want = c->type->state_bytes(c->model);
    if (size < SER_HEAD || memcmp(in, "PCSSTATE", 8) != 0 || pcs_read_u32(in + 8) != SER_VERSION)
        return pcs_refuse(c, call, "not a serialized state of a pantocosim native FMU (of this "
                      "version)");
    if (pcs_read_u32(in + 12) != c->type->kind || pcs_read_u64(in + 16) != c->data.checksum)
        return pcs_refuse(c, call, "a state of another model or export (its data file differs)");
    if (pcs_read_u64(in + 24) != (unsigned long long)want || size - SER_HEAD != want)
        return pcs_refuse(c, call, "a state of another size (truncated or of another model)");
    if (pcs_read_u64(in + 32) != pcs_fnv1a(in + 40, 8 + want))
        return pcs_refuse(c, call, "checksum mismatch (damaged state)");
    memcpy(&time, in + 40, 8);
    if (!isfinite(time)) return pcs_refuse(c, call, "the state's time is not finite");
    s = (StateHead *)pcs_alloc(&c->mem, 1, sizeof(StateHead) + want);
    if (!s) return pcs_refuse(c, call, "no memory for the FMU state");
    s->magic = STATE_MAGIC;
    s->type = c->type;
    s->owner = c;
    s->data_sum = c->data.checksum;
    s->bytes = want;
    s->time = time;
    s->phase = PCS_STEPPING;
    memcpy((unsigned char *)s + sizeof(StateHead), in + SER_HEAD, want);
    *state = s;
    return PCS_OK;
}
