/*
 * The FMI 2.0 co-simulation front of a native FMU: each function translates FMI 2.0's types
 * and statuses to and from the instance layer (pcs_instance.h), which holds the phases, the
 * data file, the model and the FMU states. Memory comes from the host's allocateMemory /
 * freeMemory, kept per instance.
 */
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "pcs_instance.h"

static const fmi2Status STATUS[] = {fmi2OK, fmi2Discard, fmi2Error};

/* what the instance layer keeps of the host: its callbacks */
typedef struct {
    fmi2CallbackFunctions cb;
} Host;

static void *host_alloc(void *ctx, size_t n, size_t size)
{
    return ((Host *)ctx)->cb.allocateMemory(n, size);
}

static void host_release(void *ctx, void *p) { ((Host *)ctx)->cb.freeMemory(p); }

static void host_log(void *ctx, const char *name, int status, const char *category,
                     const char *text)
{
    Host *h = (Host *)ctx;
    if (h->cb.logger)
        h->cb.logger(h->cb.componentEnvironment, name, STATUS[status], category, "%s", text);
}

#define C ((PcsInstance *)comp)
#define RETURN(call) return comp ? STATUS[call] : fmi2Error

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean on, size_t n,
                               const fmi2String categories[])
{
    (void)on; (void)n; (void)categories;
    return comp ? fmi2OK : fmi2Error;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean logging)
{
    Host *host;
    PcsMemory mem;
    PcsInstance *c;
    char dir[480];
    (void)visible; (void)logging;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    host = (Host *)functions->allocateMemory(1, sizeof *host);
    if (!host) return NULL;
    host->cb = *functions;
    if (type != fmi2CoSimulation || pcs_uri_to_path(resources, dir, sizeof dir) != 0
        || !dir[0]) {
        host_log(host, name ? name : "", PCS_ERROR, "logStatusError", type != fmi2CoSimulation
                 ? "this FMU is for co-simulation only"
                 : "fmuResourceLocation is not a file URI (or longer than 479 bytes): the "
                   "FMU's data file resources/model.pcsdata cannot be found");
        functions->freeMemory(host);
        return NULL;
    }
    mem.alloc = host_alloc;
    mem.release = host_release;
    mem.ctx = host;
    c = pcs_instance_new(name, guid, dir, &mem, host_log, host);
    if (!c) functions->freeMemory(host);
    return c;
}

void fmi2FreeInstance(fmi2Component comp)
{
    Host *host;
    if (!comp) return;
    host = (Host *)C->host;
    pcs_instance_free(C);
    host->cb.freeMemory(host);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tolerance_defined,
                               fmi2Real tolerance, fmi2Real start, fmi2Boolean stop_defined,
                               fmi2Real stop)
{
    (void)tolerance_defined; (void)tolerance; (void)stop_defined; (void)stop;
    RETURN(pcs_set_start(C, "fmi2SetupExperiment", start));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp)
{
    RETURN(pcs_enter_initialisation(C, "fmi2EnterInitializationMode"));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp)
{
    RETURN(pcs_exit_initialisation(C, "fmi2ExitInitializationMode"));
}

fmi2Status fmi2Terminate(fmi2Component comp) { RETURN(pcs_terminate(C, "fmi2Terminate")); }
fmi2Status fmi2Reset(fmi2Component comp) { RETURN(pcs_reset(C, "fmi2Reset")); }

/* ------------------------------------------------------------------ variables */

#define GET(NAME, PCS, TYPE, FROM)                                                        \
    fmi2Status NAME(fmi2Component comp, const fmi2ValueReference vr[], size_t n,          \
                    TYPE value[])                                                         \
    {                                                                                     \
        size_t i;                                                                         \
        PcsValue v;                                                                       \
        if (pcs_values(C, #NAME, PCS_READ_ANY, n, vr, value) != PCS_OK)                   \
            return fmi2Error;                                                             \
        for (i = 0; i < n; i++) {                                                         \
            if (pcs_get(C, #NAME, PCS, vr[i], &v) != PCS_OK) return fmi2Error;            \
            value[i] = FROM;                                                              \
        }                                                                                 \
        return fmi2OK;                                                                    \
    }

GET(fmi2GetReal, PCS_REAL, fmi2Real, v.real)
GET(fmi2GetInteger, PCS_INTEGER, fmi2Integer, v.integer)
GET(fmi2GetBoolean, PCS_BOOLEAN, fmi2Boolean, v.integer ? fmi2True : fmi2False)
GET(fmi2GetString, PCS_STRING, fmi2String, v.string)

#define SET(NAME, PCS, TYPE, FIELD, TO)                                                   \
    fmi2Status NAME(fmi2Component comp, const fmi2ValueReference vr[], size_t n,          \
                    const TYPE value[])                                                   \
    {                                                                                     \
        size_t i;                                                                         \
        PcsValue v;                                                                       \
        if (pcs_values(C, #NAME, PCS_WRITE, n, vr, value) != PCS_OK)                      \
            return fmi2Error;                                                             \
        for (i = 0; i < n; i++) {                                                         \
            v.FIELD = TO;                                                                 \
            if (pcs_set(C, #NAME, PCS, vr[i], &v) != PCS_OK) return fmi2Error;            \
        }                                                                                 \
        return fmi2OK;                                                                    \
    }

SET(fmi2SetReal, PCS_REAL, fmi2Real, real, value[i])
SET(fmi2SetInteger, PCS_INTEGER, fmi2Integer, integer, value[i])
SET(fmi2SetBoolean, PCS_BOOLEAN, fmi2Boolean, integer, value[i] != fmi2False)
SET(fmi2SetString, PCS_STRING, fmi2String, string, value[i])

/* ------------------------------------------------------------------ stepping */

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean no_prior)
{
    (void)no_prior;
    RETURN(pcs_step(C, "fmi2DoStep", t, h));
}

static fmi2Status unsupported(fmi2Component comp, const char *call, const char *text)
{
    pcs_refuse(C, call, text);
    return fmi2Error;
}

fmi2Status fmi2CancelStep(fmi2Component comp)
{
    return unsupported(comp, "fmi2CancelStep", "steps are synchronous, none to cancel");
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value)
{
    if (!comp || !value || s != fmi2DoStepStatus) return comp && value ? fmi2Discard : fmi2Error;
    *value = C->phase == PCS_FAILED ? fmi2Error : fmi2OK;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value)
{
    if (!comp || !value) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = C->time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s; (void)value;
    return comp ? fmi2Discard : fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value)
{
    if (!comp || !value) return fmi2Error;
    if (s != fmi2Terminated) return fmi2Discard;
    *value = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value)
{
    (void)s; (void)value;
    return comp ? fmi2Discard : fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                       size_t n, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    (void)vr; (void)n; (void)order; (void)value;
    return unsupported(comp, "fmi2SetRealInputDerivatives", "input derivatives are not "
                       "supported (canInterpolateInputs = false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)n; (void)order; (void)value;
    return unsupported(comp, "fmi2GetRealOutputDerivatives", "output derivatives are not "
                       "supported (maxOutputDerivativeOrder = 0)");
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference u[],
                                        size_t nu, const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real du[], fmi2Real dz[])
{
    (void)u; (void)nu; (void)z; (void)nz; (void)du; (void)dz;
    return unsupported(comp, "fmi2GetDirectionalDerivative", "directional derivatives are "
                       "not supported");
}

/* ------------------------------------------------------------------ FMU states */

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *state)
{
    RETURN(pcs_state_get(C, "fmi2GetFMUstate", state));
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state)
{
    RETURN(pcs_state_set(C, "fmi2SetFMUstate", state));
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *state)
{
    RETURN(pcs_state_free(C, "fmi2FreeFMUstate", state));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate state, size_t *size)
{
    RETURN(pcs_state_size(C, "fmi2SerializedFMUstateSize", state, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate state, fmi2Byte out[],
                                 size_t size)
{
    RETURN(pcs_state_serialize(C, "fmi2SerializeFMUstate", state, (unsigned char *)out, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte in[], size_t size,
                                   fmi2FMUstate *state)
{
    RETURN(pcs_state_deserialize(C, "fmi2DeSerializeFMUstate", (const unsigned char *)in,
                                 size, state));
}
