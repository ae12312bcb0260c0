/*
 * The FMI 3.0 co-simulation front of a native FMU: each function translates FMI 3.0's types
 * and statuses to and from the instance layer (pcs_instance.h). FMI 3.0 value references
 * are unique across types: the model's Integer, Boolean and String references are offset
 * by PCS_FMI3_INT32_BASE, PCS_FMI3_BOOLEAN_BASE and PCS_FMI3_STRING_BASE (pcs_model.h);
 * value reference 0 is the time. Memory comes from the C library (FMI 3.0 has no allocation
 * callbacks); resourcePath is a native path, taken as it is.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "fmi3_front.h"
#include "pcs_instance.h"

static const fmi3Status STATUS[] = {fmi3OK, fmi3Discard, fmi3Error};

typedef struct {
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
} Host;

static void *host_alloc(void *ctx, size_t n, size_t size)
{
    (void)ctx;
    return calloc(n, size);
}

static void host_release(void *ctx, void *p)
{
    (void)ctx;
    free(p);
}

static void host_log(void *ctx, const char *name, int status, const char *category,
                     const char *text)
{
    Host *h = (Host *)ctx;
    (void)name;
    if (h->log) h->log(h->env, STATUS[status], category, text);
}

#define C ((PcsInstance *)instance)
#define RETURN(call) return instance ? STATUS[call] : fmi3Error

fmi3Status pcs_fmi3_unsupported(fmi3Instance instance, const char *function)
{
    pcs_refuse(C, function, "not supported by this co-simulation FMU");
    return fmi3Error;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean on, size_t n,
                               const fmi3String categories[])
{
    (void)on; (void)n; (void)categories;
    return instance ? fmi3OK : fmi3Error;
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
    Host *host;
    PcsMemory mem;
    PcsInstance *c;
    (void)visible; (void)logging; (void)early_return; (void)required;
    (void)n_required; (void)update;
    host = (Host *)calloc(1, sizeof *host);
    if (!host) return NULL;
    host->env = env;
    host->log = log;
    if (event_mode) {
        host_log(host, name, PCS_ERROR, "logStatusError", "event mode is not supported (no "
                 "events)");
        free(host);
        return NULL;
    }
    mem.alloc = host_alloc;
    mem.release = host_release;
    mem.ctx = host;
    c = pcs_instance_new(name, token, resources, &mem, host_log, host);
    if (!c) free(host);
    return c;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    Host *host;
    if (!instance) return;
    host = (Host *)C->host;
    pcs_instance_free(C);
    free(host);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean tolerance_defined,
                                       fmi3Float64 tolerance, fmi3Float64 start,
                                       fmi3Boolean stop_defined, fmi3Float64 stop)
{
    (void)tolerance_defined; (void)tolerance; (void)stop_defined; (void)stop;
    if (pcs_set_start(C, "fmi3EnterInitializationMode", start) != PCS_OK) return fmi3Error;
    RETURN(pcs_enter_initialisation(C, "fmi3EnterInitializationMode"));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    RETURN(pcs_exit_initialisation(C, "fmi3ExitInitializationMode"));
}

fmi3Status fmi3Terminate(fmi3Instance instance) { RETURN(pcs_terminate(C, "fmi3Terminate")); }
fmi3Status fmi3Reset(fmi3Instance instance) { RETURN(pcs_reset(C, "fmi3Reset")); }

/* ------------------------------------------------------------------ variables */

/* the model's value reference of vr (FMI 3.0: offset by the type's base) */
static int model_vr(fmi3Instance instance, const char *call, fmi3ValueReference vr,
                    unsigned base, unsigned *out)
{
    if (vr < base || (base == 0 && vr >= PCS_FMI3_INT32_BASE)) {
        char text[120];
        snprintf(text, sizeof text, "value reference %u is not a variable of this type", vr);
        pcs_refuse(C, call, text);
        return -1;
    }
    *out = vr - base;
    return 0;
}

static int arrays(fmi3Instance instance, const char *call, int set, size_t nvr,
                  const void *vr, const void *values, size_t n_values)
{
    if (pcs_values(C, call, set ? PCS_WRITE : PCS_READ_INITIALISED, nvr, vr, values) != PCS_OK)
        return -1;
    if (n_values != nvr) {
        pcs_refuse(C, call, "one value per value reference (no arrays)");
        return -1;
    }
    return 0;
}

#define GET(NAME, PCS, BASE, TYPE, FROM)                                                  \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,     \
                    TYPE values[], size_t n_values)                                       \
    {                                                                                     \
        size_t i;                                                                         \
        unsigned r;                                                                       \
        PcsValue v;                                                                       \
        if (arrays(instance, #NAME, 0, nvr, vr, values, n_values) != 0) return fmi3Error; \
        for (i = 0; i < nvr; i++) {                                                       \
            if (PCS == PCS_REAL && vr[i] == 0) {                                          \
                v.real = C->time;                                                         \
            } else if (model_vr(instance, #NAME, vr[i], BASE, &r) != 0                    \
                       || pcs_get(C, #NAME, PCS, r, &v) != PCS_OK) {                      \
                return fmi3Error;                                                         \
            }                                                                             \
            values[i] = FROM;                                                             \
        }                                                                                 \
        return fmi3OK;                                                                    \
    }

GET(fmi3GetFloat64, PCS_REAL, 0u, fmi3Float64, v.real)
GET(fmi3GetInt32, PCS_INTEGER, PCS_FMI3_INT32_BASE, fmi3Int32, (fmi3Int32)v.integer)
GET(fmi3GetBoolean, PCS_BOOLEAN, PCS_FMI3_BOOLEAN_BASE, fmi3Boolean, v.integer != 0)
GET(fmi3GetString, PCS_STRING, PCS_FMI3_STRING_BASE, fmi3String, v.string)

#define SET(NAME, PCS, BASE, TYPE, FIELD, TO)                                             \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,     \
                    const TYPE values[], size_t n_values)                                 \
    {                                                                                     \
        size_t i;                                                                         \
        unsigned r;                                                                       \
        PcsValue v;                                                                       \
        if (arrays(instance, #NAME, 1, nvr, vr, values, n_values) != 0) return fmi3Error; \
        for (i = 0; i < nvr; i++) {                                                       \
            v.FIELD = TO;                                                                 \
            if (model_vr(instance, #NAME, vr[i], BASE, &r) != 0                           \
                || pcs_set(C, #NAME, PCS, r, &v) != PCS_OK)                               \
                return fmi3Error;                                                         \
        }                                                                                 \
        return fmi3OK;                                                                    \
    }

SET(fmi3SetFloat64, PCS_REAL, 0u, fmi3Float64, real, values[i])
SET(fmi3SetInt32, PCS_INTEGER, PCS_FMI3_INT32_BASE, fmi3Int32, integer, (int)values[i])
SET(fmi3SetBoolean, PCS_BOOLEAN, PCS_FMI3_BOOLEAN_BASE, fmi3Boolean, integer, values[i] != 0)
SET(fmi3SetString, PCS_STRING, PCS_FMI3_STRING_BASE, fmi3String, string, values[i])

/* ------------------------------------------------------------------ stepping */

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 h,
                      fmi3Boolean no_prior, fmi3Boolean *event_needed, fmi3Boolean *terminate,
                      fmi3Boolean *early_return, fmi3Float64 *last_time)
{
    int status;
    (void)no_prior;
    if (!instance) return fmi3Error;
    status = pcs_step(C, "fmi3DoStep", t, h);
    if (event_needed) *event_needed = fmi3False;
    if (terminate) *terminate = fmi3False;
    if (early_return) *early_return = fmi3False;
    if (last_time) *last_time = C->time;
    return STATUS[status];
}

/* ------------------------------------------------------------------ FMU states */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state)
{
    RETURN(pcs_state_get(C, "fmi3GetFMUState", state));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state)
{
    RETURN(pcs_state_set(C, "fmi3SetFMUState", state));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state)
{
    RETURN(pcs_state_free(C, "fmi3FreeFMUState", state));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t *size)
{
    RETURN(pcs_state_size(C, "fmi3SerializedFMUStateSize", state, size));
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state, fmi3Byte out[],
                                 size_t size)
{
    RETURN(pcs_state_serialize(C, "fmi3SerializeFMUState", state, out, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte in[], size_t size,
                                   fmi3FMUState *state)
{
    RETURN(pcs_state_deserialize(C, "fmi3DeserializeFMUState", in, size, state));
}
