/*
 * pantocosim's FMI 2.0 co-simulation embedding library.
 *
 * Every pantocosim FMI 2.0 FMU carries this library (compiled with export_common.c) as
 * binaries/linux64/<modelIdentifier>.so. It implements the FMI 2.0 C API over the FMU's
 * Python slave (a slave core with the FMI 2.0 front) through the bridge module
 * ``pantocosim_fmi2_bridge`` in the FMU's resources. What it shares with the FMI 3.0 library
 * (finding a Python runtime, the instance and state registries, calling the bridge) is in
 * export_common.c.
 *
 * Statuses are FMI's: a call that is not honoured returns fmi2Error (fmi2Discard from
 * fmi2DoStep) with a categorised log message, and the instance stays usable; instances and
 * FMU states are checked before use: a freed, foreign or forged pointer gives fmi2Error,
 * never a crash.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "export_common.h"

/* ------------------------------------------------------------------ FMI 2.0 types (ABI) */
typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum {
    fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated
} fmi2StatusKind;
typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status,
                                   fmi2String, fmi2String, ...);
typedef struct {
    fmi2CallbackLogger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(fmi2ComponentEnvironment, fmi2Status);
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

#define BRIDGE "pantocosim_fmi2_bridge"

static void sink(const Component *c, int status, const char *category, const char *message)
{
    ((fmi2CallbackLogger)c->hostLogger)(c->hostEnvironment, c->instanceName,
                                        (fmi2Status)status, category, "%s", message);
}

/* ------------------------------------------------------------------ the FMI 2.0 API */
EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType,
                                     fmi2String fmuGUID, fmi2String fmuResourceLocation,
                                     const fmi2CallbackFunctions *functions,
                                     fmi2Boolean visible, fmi2Boolean loggingOn)
{
    Component *c = new_component(instanceName, loggingOn, sink,
                                 functions ? (void *)functions->logger : NULL,
                                 functions ? functions->componentEnvironment : NULL);
    char *resources;
    int gil, ok, runtime;
    if (c == NULL) return NULL;
    if (fmuType != fmi2CoSimulation) {
        LOGF(c, ST_ERROR, "fmi2Instantiate: this FMU supports co-simulation only");
        discard_component(c, "fmi2Instantiate");
        return NULL;
    }
    resources = resources_path(fmuResourceLocation);
    if (resources == NULL) {
        LOGF(c, ST_ERROR, "fmi2Instantiate: fmuResourceLocation is NULL: the FMU needs its "
             "resources");
        discard_component(c, "fmi2Instantiate");
        return NULL;
    }
    runtime = resources_complete(c, resources, fmuResourceLocation, BRIDGE, "fmi2Instantiate")
              ? ensure_runtime(resources) : -1;
    if (runtime == 2) log_message(c, ST_WARNING, "logStatusWarning", runtime_problem());
    if (runtime <= 0) {
        if (runtime == 0) log_message(c, ST_ERROR, "logStatusError", runtime_problem());
        free(resources);
        discard_component(c, "fmi2Instantiate");
        return NULL;
    }
    gil = py.GILEnsure();
    ok = make_adapter(c, resources, BRIDGE, 2, fmuGUID, visible, "fmi2Instantiate");
    if (ok) done(c, py.CallMethod(c->adapter, "status", NULL), "fmi2Instantiate");
    py.GILRelease(gil);
    free(resources);
    if (!ok || !register_component(c)) {
        if (ok) LOGF(c, ST_ERROR, "fmi2Instantiate: too many live instances");
        discard_component(c, "fmi2Instantiate");
        return NULL;
    }
    return c;
}

EXPORT void fmi2FreeInstance(fmi2Component comp)
{
    free_instance((Component *)comp, "fmi2FreeInstance");
}

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean loggingOn,
                                      size_t nCategories, const fmi2String categories[])
{
    ENTER(comp, "fmi2SetDebugLogging");
    size_t n = categories ? nCategories : 0;
    PyObject *list = py.ListNew((Py_ssize_t)n);
    for (size_t i = 0; list && i < n; i++)
        list = put_item(list, i, py.UnicodeFromString(categories[i] ? categories[i] : ""));
    c->loggingOn = loggingOn;
    int status = done(c, list ? py.CallMethod(c->adapter, "set_debug_logging", "iO",
                                              (int)loggingOn, list) : NULL,
                      "fmi2SetDebugLogging");
    if (list) py.DecRef(list);
    LEAVE(status);
}

EXPORT fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean toleranceDefined,
                                      fmi2Real tolerance, fmi2Real startTime,
                                      fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    ENTER(comp, "fmi2SetupExperiment");
    LEAVE(done(c, py.CallMethod(c->adapter, "setup_experiment", "iddid", toleranceDefined,
                                tolerance, startTime, stopTimeDefined, stopTime),
               "fmi2SetupExperiment"));
}

#define SIMPLE_CALL(fn, method)                                                \
    EXPORT fmi2Status fn(fmi2Component comp)                                   \
    {                                                                          \
        ENTER(comp, #fn);                                                      \
        LEAVE(done(c, py.CallMethod(c->adapter, method, NULL), #fn));         \
    }

SIMPLE_CALL(fmi2EnterInitializationMode, "enter_initialization_mode")
SIMPLE_CALL(fmi2ExitInitializationMode, "exit_initialization_mode")
SIMPLE_CALL(fmi2Terminate, "terminate")
SIMPLE_CALL(fmi2CancelStep, "cancel_step")

EXPORT fmi2Status fmi2Reset(fmi2Component comp)
{
    ENTER(comp, "fmi2Reset");
    /* FMU states stay valid: the instance keeps its identity */
    LEAVE(done(c, py.CallMethod(c->adapter, "reset", NULL), "fmi2Reset"));
}

/* --- get/set */
#define GETTER(fn, T, method, kind)                                                    \
    EXPORT fmi2Status fn(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, \
                         T value[])                                                    \
    {                                                                                  \
        ENTER(comp, #fn);                                                              \
        LEAVE(get_values(c, #fn, method, vr, nvr, value, kind));                       \
    }
#define SETTER(fn, T, method, kind)                                                    \
    EXPORT fmi2Status fn(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, \
                         const T value[])                                              \
    {                                                                                  \
        ENTER(comp, #fn);                                                              \
        LEAVE(set_values(c, #fn, method, vr, nvr, value, kind));                       \
    }

GETTER(fmi2GetReal, fmi2Real, "get_real", V_DOUBLE)
GETTER(fmi2GetInteger, fmi2Integer, "get_integer", V_INT)
GETTER(fmi2GetBoolean, fmi2Boolean, "get_boolean", V_INTBOOL)
SETTER(fmi2SetReal, fmi2Real, "set_real", V_DOUBLE)
SETTER(fmi2SetInteger, fmi2Integer, "set_integer", V_INT)
SETTER(fmi2SetBoolean, fmi2Boolean, "set_boolean", V_INTBOOL)

EXPORT fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                fmi2String value[])
{
    ENTER(comp, "fmi2GetString");
    LEAVE(get_strings(c, "fmi2GetString", vr, nvr, value));
}

EXPORT fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                const fmi2String value[])
{
    ENTER(comp, "fmi2SetString");
    LEAVE(set_strings(c, "fmi2SetString", vr, nvr, value));
}

/* --- FMU states */
EXPORT fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate)
{
    ENTER(comp, "fmi2GetFMUstate");
    LEAVE(state_get(c, "fmi2GetFMUstate", FMUstate));
}

EXPORT fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate FMUstate)
{
    ENTER(comp, "fmi2SetFMUstate");
    LEAVE(state_set(c, "fmi2SetFMUstate", FMUstate));
}

EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate)
{
    ENTER(comp, "fmi2FreeFMUstate");
    LEAVE(state_free(c, "fmi2FreeFMUstate", FMUstate));
}

EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate FMUstate,
                                             size_t *size)
{
    ENTER(comp, "fmi2SerializedFMUstateSize");
    LEAVE(state_size(c, "fmi2SerializedFMUstateSize", FMUstate, size));
}

EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate FMUstate,
                                        fmi2Byte serializedState[], size_t size)
{
    ENTER(comp, "fmi2SerializeFMUstate");
    LEAVE(state_serialize(c, "fmi2SerializeFMUstate", FMUstate,
                          (unsigned char *)serializedState, size));
}

EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte serializedState[],
                                          size_t size, fmi2FMUstate *FMUstate)
{
    ENTER(comp, "fmi2DeSerializeFMUstate");
    LEAVE(state_deserialize(c, "fmi2DeSerializeFMUstate",
                            (const unsigned char *)serializedState, size, FMUstate));
}

/* --- co-simulation */
EXPORT fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real currentCommunicationPoint,
                             fmi2Real communicationStepSize,
                             fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    ENTER(comp, "fmi2DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    LEAVE(done(c, py.CallMethod(c->adapter, "do_step", "dd", currentCommunicationPoint,
                                communicationStepSize), "fmi2DoStep"));
}

static int status_call(Component *c, const char *call, fmi2StatusKind s, int *integer,
                       double *real)
{
    PyObject *result = py.CallMethod(c->adapter, "status_of", "i", (int)s);
    int status = status_of(c, result, call);
    if (result && status < ST_DISCARD) {
        PyObject *value = py.TupleGetItem(result, 1);
        long i = value && integer ? py.LongAsLong(value) : 0;
        double r = value && real ? py.FloatAsDouble(value) : 0.0;
        if (value == NULL || py.ErrOccurred()) { /* never left set for the next call */
            py.ErrClear();
            LOGF(c, ST_ERROR, "%s: status kind %d has no %s value (fmi2DoStepStatus is read "
                 "with fmi2GetStatus, fmi2LastSuccessfulTime with fmi2GetRealStatus, "
                 "fmi2Terminated with fmi2GetBooleanStatus)", call, (int)s,
                 integer ? "integer" : "real");
            status = ST_ERROR;
        } else {
            if (integer) *integer = (int)i;
            if (real) *real = r;
        }
    }
    if (result) py.DecRef(result);
    return status;
}

EXPORT fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value)
{
    ENTER(comp, "fmi2GetStatus");
    int v = 0;
    int status = value ? status_call(c, "fmi2GetStatus", s, &v, NULL) : ST_ERROR;
    if (value && status < ST_DISCARD) *value = (fmi2Status)v;
    LEAVE(status);
}

EXPORT fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s,
                                    fmi2Real *value)
{
    ENTER(comp, "fmi2GetRealStatus");
    LEAVE(value ? status_call(c, "fmi2GetRealStatus", s, NULL, value) : ST_ERROR);
}

EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s,
                                       fmi2Integer *value)
{
    ENTER(comp, "fmi2GetIntegerStatus");
    LEAVE(value ? status_call(c, "fmi2GetIntegerStatus", s, value, NULL) : ST_ERROR);
}

EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s,
                                       fmi2Boolean *value)
{
    ENTER(comp, "fmi2GetBooleanStatus");
    LEAVE(value ? status_call(c, "fmi2GetBooleanStatus", s, value, NULL) : ST_ERROR);
}

EXPORT fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s,
                                      fmi2String *value)
{
    ENTER(comp, "fmi2GetStringStatus");
    (void)s;
    if (value) *value = "";
    LOGF(c, ST_DISCARD, "fmi2GetStringStatus: no string status (the FMU never returns "
         "fmi2Pending)");
    LEAVE(ST_DISCARD);
}

/* --- calls this FMU does not honour: fmi2Error with the reason */
static fmi2Status unsupported(fmi2Component comp, const char *call, const char *why)
{
    Component *c = (Component *)comp;
    if (!enter_component(c)) return fmi2Error;
    LOGF(c, ST_ERROR, "%s: not supported (%s)", call, why);
    leave_component(c);
    return fmi2Error;
}

EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[],
                                               size_t nu, const fmi2ValueReference z[],
                                               size_t nz, const fmi2Real du[], fmi2Real dz[])
{
    (void)u, (void)nu, (void)z, (void)nz, (void)du, (void)dz;
    return unsupported(c, "fmi2GetDirectionalDerivative",
                       "providesDirectionalDerivative is false");
}

EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                              size_t nvr, const fmi2Integer order[],
                                              const fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives", "canInterpolateInputs is false");
}

EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                               size_t nvr, const fmi2Integer order[],
                                               fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0");
}
