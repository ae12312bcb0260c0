/*
 * pantocosim's FMI 3.0 co-simulation embedding library.
 *
 * Every pantocosim FMI 3.0 FMU carries this library (compiled with export_common.c) as
 * binaries/x86_64-linux/<modelIdentifier>.so. It implements the FMI 3.0 C API over the FMU's
 * Python slave (a slave core with the FMI 3.0 front) through the bridge module
 * ``pantocosim_fmi3_bridge`` in the FMU's resources; what it shares with the FMI 2.0 library
 * (finding a Python runtime, the instance and state registries, calling the bridge) is in
 * export_common.c.
 *
 * The FMUs are co-simulation FMUs with scalar Float64, Int32, Boolean and String variables,
 * FMU state get/set/serialise and event mode (no events of their own), no early return, no
 * clocks. Statuses are
 * FMI's: a call that is not honoured returns fmi3Error (fmi3Discard from fmi3DoStep) with a
 * categorised log message, and the instance stays usable; instances and FMU states are
 * checked before use: a freed, foreign or forged pointer gives fmi3Error, never a crash.
 */
#define _GNU_SOURCE
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "export_common.h"

/* ------------------------------------------------------------------ FMI 3.0 types (ABI) */
/* declared here; compiling with the standard's fmi3Functions.h included (-include) checks
   every signature below against it */
#ifndef fmi3FunctionTypes_h
typedef void *fmi3Instance;
typedef void *fmi3InstanceEnvironment;
typedef void *fmi3FMUState;
typedef uint32_t fmi3ValueReference;
typedef float fmi3Float32;
typedef double fmi3Float64;
typedef int8_t fmi3Int8;
typedef uint8_t fmi3UInt8;
typedef int16_t fmi3Int16;
typedef uint16_t fmi3UInt16;
typedef int32_t fmi3Int32;
typedef uint32_t fmi3UInt32;
typedef int64_t fmi3Int64;
typedef uint64_t fmi3UInt64;
typedef bool fmi3Boolean;
typedef char fmi3Char;
typedef const fmi3Char *fmi3String;
typedef uint8_t fmi3Byte;
typedef const fmi3Byte *fmi3Binary;
typedef bool fmi3Clock;
typedef enum { fmi3OK, fmi3Warning, fmi3Discard, fmi3Error, fmi3Fatal } fmi3Status;
typedef enum {
    fmi3Independent, fmi3Constant, fmi3Fixed, fmi3Tunable, fmi3Discrete, fmi3Dependent
} fmi3DependencyKind;
typedef enum {
    fmi3IntervalNotYetKnown, fmi3IntervalUnchanged, fmi3IntervalChanged
} fmi3IntervalQualifier;
typedef void (*fmi3LogMessageCallback)(fmi3InstanceEnvironment, fmi3Status, fmi3String,
                                       fmi3String);
typedef void (*fmi3ClockUpdateCallback)(fmi3InstanceEnvironment);
typedef void (*fmi3IntermediateUpdateCallback)(fmi3InstanceEnvironment, fmi3Float64,
                                               fmi3Boolean, fmi3Boolean, fmi3Boolean,
                                               fmi3Boolean, fmi3Boolean *, fmi3Float64 *);
typedef void (*fmi3LockPreemptionCallback)(void);
typedef void (*fmi3UnlockPreemptionCallback)(void);
#endif

#define BRIDGE "pantocosim_fmi3_bridge"

static void sink(const Component *c, int status, const char *category, const char *message)
{
    ((fmi3LogMessageCallback)c->hostLogger)(c->hostEnvironment, (fmi3Status)status, category,
                                            message);
}

/* ------------------------------------------------------------------ life cycle */
EXPORT const char *fmi3GetVersion(void) { return "3.0"; }

EXPORT fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate)
{
    const char *call = "fmi3InstantiateCoSimulation";
    Component *c = new_component(instanceName, loggingOn, sink, (void *)logMessage,
                                 instanceEnvironment);
    char *resources;
    int gil, ok, runtime;
    (void)earlyReturnAllowed, (void)requiredIntermediateVariables, (void)intermediateUpdate;
    if (c == NULL) return NULL;
    if (nRequiredIntermediateVariables > 0) {
        LOGF(c, ST_ERROR, "%s: %zu required intermediate variables: this FMU provides none "
             "(canReturnEarlyAfterIntermediateUpdate is false)", call,
             nRequiredIntermediateVariables);
        discard_component(c, call);
        return NULL;
    }
    resources = resources_path(resourcePath);
    if (resources == NULL) {
        LOGF(c, ST_ERROR, "%s: resourcePath is NULL: the FMU needs its resources", call);
        discard_component(c, call);
        return NULL;
    }
    runtime = resources_complete(c, resources, resourcePath, BRIDGE, call)
              ? ensure_runtime(resources) : -1;
    if (runtime == 2) log_message(c, ST_WARNING, "logStatusWarning", runtime_problem());
    if (runtime <= 0) {
        if (runtime == 0) log_message(c, ST_ERROR, "logStatusError", runtime_problem());
        free(resources);
        discard_component(c, call);
        return NULL;
    }
    gil = py.GILEnsure();
    ok = make_adapter(c, resources, BRIDGE, 3, instantiationToken, visible, call);
    if (ok) done(c, py.CallMethod(c->adapter, "status", NULL), call);
    if (ok) ok = done(c, py.CallMethod(c->adapter, "use_event_mode", "i", (int)eventModeUsed),
                      call) < ST_ERROR;
    py.GILRelease(gil);
    free(resources);
    if (!ok || !register_component(c)) {
        if (ok) LOGF(c, ST_ERROR, "%s: too many live instances", call);
        discard_component(c, call);
        return NULL;
    }
    return c;
}

EXPORT fmi3Instance fmi3InstantiateModelExchange(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage)
{
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateModelExchange: this FMU supports co-simulation only");
    (void)instanceName;
    return NULL;
}

EXPORT fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible;
    (void)loggingOn, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: this FMU supports co-simulation only");
    return NULL;
}

EXPORT void fmi3FreeInstance(fmi3Instance instance)
{
    free_instance((Component *)instance, "fmi3FreeInstance");
}

EXPORT fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn,
                                      size_t nCategories, const fmi3String categories[])
{
    ENTER(instance, "fmi3SetDebugLogging");
    size_t n = categories ? nCategories : 0;
    PyObject *list = py.ListNew((Py_ssize_t)n);
    for (size_t i = 0; list && i < n; i++)
        list = put_item(list, i, py.UnicodeFromString(categories[i] ? categories[i] : ""));
    c->loggingOn = loggingOn;
    int status = done(c, list ? py.CallMethod(c->adapter, "set_debug_logging", "iO",
                                              (int)loggingOn, list) : NULL,
                      "fmi3SetDebugLogging");
    if (list) py.DecRef(list);
    LEAVE(status);
}

EXPORT fmi3Status fmi3EnterInitializationMode(fmi3Instance instance,
                                              fmi3Boolean toleranceDefined,
                                              fmi3Float64 tolerance, fmi3Float64 startTime,
                                              fmi3Boolean stopTimeDefined,
                                              fmi3Float64 stopTime)
{
    ENTER(instance, "fmi3EnterInitializationMode");
    LEAVE(done(c, py.CallMethod(c->adapter, "enter_initialization_mode", "iddid",
                                (int)toleranceDefined, tolerance, startTime,
                                (int)stopTimeDefined, stopTime),
               "fmi3EnterInitializationMode"));
}

#define SIMPLE_CALL(fn, method)                                                \
    EXPORT fmi3Status fn(fmi3Instance instance)                                \
    {                                                                          \
        ENTER(instance, #fn);                                                  \
        LEAVE(done(c, py.CallMethod(c->adapter, method, NULL), #fn));         \
    }

SIMPLE_CALL(fmi3ExitInitializationMode, "exit_initialization_mode")
SIMPLE_CALL(fmi3EnterEventMode, "enter_event_mode")
SIMPLE_CALL(fmi3EnterStepMode, "enter_step_mode")
SIMPLE_CALL(fmi3Terminate, "terminate")
/* FMU states stay valid over a reset: the instance keeps its identity */
SIMPLE_CALL(fmi3Reset, "reset")

/* ------------------------------------------------------------------ variables */
/* the values of scalar variables: one value per value reference */
static int scalars(Component *c, const char *call, size_t nvr, size_t nValues)
{
    if (nValues != nvr) {
        LOGF(c, ST_ERROR, "%s: %zu values for %zu value references: every variable of this "
             "FMU is a scalar (nValues = nValueReferences)", call, nValues, nvr);
        return 0;
    }
    return 1;
}

#define GETTER(fn, T, method, kind)                                                        \
    EXPORT fmi3Status fn(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, \
                         T values[], size_t nValues)                                       \
    {                                                                                      \
        ENTER(instance, #fn);                                                              \
        if (!scalars(c, #fn, nvr, nValues)) LEAVE(ST_ERROR);                               \
        LEAVE(get_values(c, #fn, method, vr, nvr, values, kind));                          \
    }
#define SETTER(fn, T, method, kind)                                                        \
    EXPORT fmi3Status fn(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, \
                         const T values[], size_t nValues)                                 \
    {                                                                                      \
        ENTER(instance, #fn);                                                              \
        if (!scalars(c, #fn, nvr, nValues)) LEAVE(ST_ERROR);                               \
        LEAVE(set_values(c, #fn, method, vr, nvr, values, kind));                          \
    }

GETTER(fmi3GetFloat64, fmi3Float64, "get_real", V_DOUBLE)
GETTER(fmi3GetInt32, fmi3Int32, "get_integer", V_INT32)
GETTER(fmi3GetBoolean, fmi3Boolean, "get_boolean", V_CBOOL)
SETTER(fmi3SetFloat64, fmi3Float64, "set_real", V_DOUBLE)
SETTER(fmi3SetInt32, fmi3Int32, "set_integer", V_INT32)
SETTER(fmi3SetBoolean, fmi3Boolean, "set_boolean", V_CBOOL)

EXPORT fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference vr[],
                                size_t nvr, fmi3String values[], size_t nValues)
{
    ENTER(instance, "fmi3GetString");
    if (!scalars(c, "fmi3GetString", nvr, nValues)) LEAVE(ST_ERROR);
    LEAVE(get_strings(c, "fmi3GetString", vr, nvr, values));
}

EXPORT fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference vr[],
                                size_t nvr, const fmi3String values[], size_t nValues)
{
    ENTER(instance, "fmi3SetString");
    if (!scalars(c, "fmi3SetString", nvr, nValues)) LEAVE(ST_ERROR);
    LEAVE(set_strings(c, "fmi3SetString", vr, nvr, values));
}

/* types this FMU has no variable of: any value reference is refused */
static fmi3Status no_variable_of(fmi3Instance instance, const char *call, const char *type,
                                 size_t nvr)
{
    ENTER(instance, call);
    if (nvr == 0) LEAVE(ST_OK);
    LOGF(c, ST_ERROR, "%s: this FMU has no %s variable (its variables are Float64, Int32, "
         "Boolean and String): nothing done", call, type);
    LEAVE(ST_ERROR);
}

#define NO_TYPE(T, type)                                                                   \
    EXPORT fmi3Status fmi3Get##type(fmi3Instance instance, const fmi3ValueReference vr[],  \
                                    size_t nvr, T values[], size_t nValues)                \
    {                                                                                      \
        (void)vr, (void)values, (void)nValues;                                             \
        return no_variable_of(instance, "fmi3Get" #type, #type, nvr);                      \
    }                                                                                      \
    EXPORT fmi3Status fmi3Set##type(fmi3Instance instance, const fmi3ValueReference vr[],  \
                                    size_t nvr, const T values[], size_t nValues)          \
    {                                                                                      \
        (void)vr, (void)values, (void)nValues;                                             \
        return no_variable_of(instance, "fmi3Set" #type, #type, nvr);                      \
    }

NO_TYPE(fmi3Float32, Float32)
NO_TYPE(fmi3Int8, Int8)
NO_TYPE(fmi3UInt8, UInt8)
NO_TYPE(fmi3Int16, Int16)
NO_TYPE(fmi3UInt16, UInt16)
NO_TYPE(fmi3UInt32, UInt32)
NO_TYPE(fmi3Int64, Int64)
NO_TYPE(fmi3UInt64, UInt64)

EXPORT fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[],
                                size_t nvr, size_t valueSizes[], fmi3Binary values[],
                                size_t nValues)
{
    (void)vr, (void)valueSizes, (void)values, (void)nValues;
    return no_variable_of(instance, "fmi3GetBinary", "Binary", nvr);
}

EXPORT fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[],
                                size_t nvr, const size_t valueSizes[],
                                const fmi3Binary values[], size_t nValues)
{
    (void)vr, (void)valueSizes, (void)values, (void)nValues;
    return no_variable_of(instance, "fmi3SetBinary", "Binary", nvr);
}

EXPORT fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[],
                               size_t nvr, fmi3Clock values[])
{
    (void)vr, (void)values;
    return no_variable_of(instance, "fmi3GetClock", "Clock", nvr);
}

EXPORT fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[],
                               size_t nvr, const fmi3Clock values[])
{
    (void)vr, (void)values;
    return no_variable_of(instance, "fmi3SetClock", "Clock", nvr);
}

/* ------------------------------------------------------------------ FMU states */
EXPORT fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    ENTER(instance, "fmi3GetFMUState");
    LEAVE(state_get(c, "fmi3GetFMUState", FMUState));
}

EXPORT fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    ENTER(instance, "fmi3SetFMUState");
    LEAVE(state_set(c, "fmi3SetFMUState", FMUState));
}

EXPORT fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    ENTER(instance, "fmi3FreeFMUState");
    LEAVE(state_free(c, "fmi3FreeFMUState", FMUState));
}

EXPORT fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState,
                                             size_t *size)
{
    ENTER(instance, "fmi3SerializedFMUStateSize");
    LEAVE(state_size(c, "fmi3SerializedFMUStateSize", FMUState, size));
}

EXPORT fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                        fmi3Byte serializedState[], size_t size)
{
    ENTER(instance, "fmi3SerializeFMUState");
    LEAVE(state_serialize(c, "fmi3SerializeFMUState", FMUState, serializedState, size));
}

EXPORT fmi3Status fmi3DeserializeFMUState(fmi3Instance instance,
                                          const fmi3Byte serializedState[], size_t size,
                                          fmi3FMUState *FMUState)
{
    ENTER(instance, "fmi3DeserializeFMUState");
    LEAVE(state_deserialize(c, "fmi3DeserializeFMUState", serializedState, size, FMUState));
}

/* ------------------------------------------------------------------ co-simulation */
EXPORT fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                             fmi3Float64 communicationStepSize,
                             fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                             fmi3Boolean *eventHandlingNeeded,
                             fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                             fmi3Float64 *lastSuccessfulTime)
{
    ENTER(instance, "fmi3DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    PyObject *result = py.CallMethod(c->adapter, "do_step", "dd", currentCommunicationPoint,
                                     communicationStepSize);
    int status = status_of(c, result, "fmi3DoStep");
    PyObject *flags = result ? py.TupleGetItem(result, 1) : NULL;
    PyObject *item;
    if (eventHandlingNeeded) *eventHandlingNeeded = false;
    if (earlyReturn) *earlyReturn = false;
    if (terminateSimulation) *terminateSimulation = status >= ST_ERROR;
    if (lastSuccessfulTime) *lastSuccessfulTime = currentCommunicationPoint;
    if (flags && py.TupleSize(flags) == 4) {
        if (terminateSimulation && (item = py.TupleGetItem(flags, 1)))
            *terminateSimulation = py.LongAsLong(item) != 0;
        if (lastSuccessfulTime && (item = py.TupleGetItem(flags, 3)))
            *lastSuccessfulTime = py.FloatAsDouble(item);
    }
    if (py.ErrOccurred()) py.ErrClear();
    if (result) py.DecRef(result);
    LEAVE(status);
}

/* ------------------------------------------------------------------ not honoured */
static fmi3Status unsupported(fmi3Instance instance, const char *call, const char *why)
{
    Component *c = (Component *)instance;
    if (!enter_component(c)) return fmi3Error;
    LOGF(c, ST_ERROR, "%s: not supported (%s)", call, why);
    leave_component(c);
    return fmi3Error;
}

#define NO_EVENTS "providesEvaluateDiscreteStates is false: the FMU has no discrete states"
#define NO_CLOCKS "the FMU has no clocks"
#define ME_ONLY "a model-exchange call; this FMU supports co-simulation only"

EXPORT fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance i)
{
    return unsupported(i, "fmi3EvaluateDiscreteStates", NO_EVENTS);
}

/* event mode: the FMU has no events of its own; its discrete states never need an update */
EXPORT fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance,
                                           fmi3Boolean *discreteStatesNeedUpdate,
                                           fmi3Boolean *terminateSimulation,
                                           fmi3Boolean *nominalsOfContinuousStatesChanged,
                                           fmi3Boolean *valuesOfContinuousStatesChanged,
                                           fmi3Boolean *nextEventTimeDefined,
                                           fmi3Float64 *nextEventTime)
{
    ENTER(instance, "fmi3UpdateDiscreteStates");
    fmi3Boolean *flags[] = {discreteStatesNeedUpdate, terminateSimulation,
                            nominalsOfContinuousStatesChanged, valuesOfContinuousStatesChanged,
                            nextEventTimeDefined};
    PyObject *result = py.CallMethod(c->adapter, "update_discrete_states", NULL);
    int status = status_of(c, result, "fmi3UpdateDiscreteStates");
    PyObject *values = result ? py.TupleGetItem(result, 1) : NULL;
    for (int k = 0; k < 5; k++) {
        PyObject *item = values && py.TupleSize(values) == 6 ? py.TupleGetItem(values, k) : NULL;
        if (flags[k]) *flags[k] = item ? py.LongAsLong(item) != 0 : false;
    }
    if (nextEventTime) *nextEventTime = 0.0;
    if (py.ErrOccurred()) py.ErrClear();
    if (result) py.DecRef(result);
    LEAVE(status);
}

EXPORT fmi3Status fmi3EnterConfigurationMode(fmi3Instance i)
{
    return unsupported(i, "fmi3EnterConfigurationMode", "the FMU has no structural parameter");
}

EXPORT fmi3Status fmi3ExitConfigurationMode(fmi3Instance i)
{
    return unsupported(i, "fmi3ExitConfigurationMode", "the FMU has no structural parameter");
}

EXPORT fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance i, fmi3ValueReference vr,
                                                      size_t *nDependencies)
{
    (void)vr, (void)nDependencies;
    return unsupported(i, "fmi3GetNumberOfVariableDependencies",
                       "providesPerElementDependencies is false");
}

EXPORT fmi3Status fmi3GetVariableDependencies(fmi3Instance i, fmi3ValueReference dependent,
                                              size_t elementIndicesOfDependent[],
                                              fmi3ValueReference independents[],
                                              size_t elementIndicesOfIndependents[],
                                              fmi3DependencyKind dependencyKinds[],
                                              size_t nDependencies)
{
    (void)dependent, (void)elementIndicesOfDependent, (void)independents;
    (void)elementIndicesOfIndependents, (void)dependencyKinds, (void)nDependencies;
    return unsupported(i, "fmi3GetVariableDependencies",
                       "providesPerElementDependencies is false");
}

EXPORT fmi3Status fmi3GetDirectionalDerivative(fmi3Instance i, const fmi3ValueReference u[],
                                               size_t nu, const fmi3ValueReference k[],
                                               size_t nk, const fmi3Float64 seed[],
                                               size_t ns, fmi3Float64 sensitivity[],
                                               size_t nsens)
{
    (void)u, (void)nu, (void)k, (void)nk, (void)seed, (void)ns, (void)sensitivity, (void)nsens;
    return unsupported(i, "fmi3GetDirectionalDerivative",
                       "providesDirectionalDerivatives is false");
}

EXPORT fmi3Status fmi3GetAdjointDerivative(fmi3Instance i, const fmi3ValueReference u[],
                                           size_t nu, const fmi3ValueReference k[], size_t nk,
                                           const fmi3Float64 seed[], size_t ns,
                                           fmi3Float64 sensitivity[], size_t nsens)
{
    (void)u, (void)nu, (void)k, (void)nk, (void)seed, (void)ns, (void)sensitivity, (void)nsens;
    return unsupported(i, "fmi3GetAdjointDerivative", "providesAdjointDerivatives is false");
}

EXPORT fmi3Status fmi3GetOutputDerivatives(fmi3Instance i, const fmi3ValueReference vr[],
                                           size_t nvr, const fmi3Int32 orders[],
                                           fmi3Float64 values[], size_t nValues)
{
    (void)vr, (void)nvr, (void)orders, (void)values, (void)nValues;
    return unsupported(i, "fmi3GetOutputDerivatives", "maxOutputDerivativeOrder is 0");
}

EXPORT fmi3Status fmi3GetIntervalDecimal(fmi3Instance i, const fmi3ValueReference vr[],
                                         size_t nvr, fmi3Float64 intervals[],
                                         fmi3IntervalQualifier qualifiers[])
{
    (void)vr, (void)nvr, (void)intervals, (void)qualifiers;
    return unsupported(i, "fmi3GetIntervalDecimal", NO_CLOCKS);
}

EXPORT fmi3Status fmi3GetIntervalFraction(fmi3Instance i, const fmi3ValueReference vr[],
                                          size_t nvr, fmi3UInt64 counters[],
                                          fmi3UInt64 resolutions[],
                                          fmi3IntervalQualifier qualifiers[])
{
    (void)vr, (void)nvr, (void)counters, (void)resolutions, (void)qualifiers;
    return unsupported(i, "fmi3GetIntervalFraction", NO_CLOCKS);
}

EXPORT fmi3Status fmi3GetShiftDecimal(fmi3Instance i, const fmi3ValueReference vr[],
                                      size_t nvr, fmi3Float64 shifts[])
{
    (void)vr, (void)nvr, (void)shifts;
    return unsupported(i, "fmi3GetShiftDecimal", NO_CLOCKS);
}

EXPORT fmi3Status fmi3GetShiftFraction(fmi3Instance i, const fmi3ValueReference vr[],
                                       size_t nvr, fmi3UInt64 counters[],
                                       fmi3UInt64 resolutions[])
{
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    return unsupported(i, "fmi3GetShiftFraction", NO_CLOCKS);
}

EXPORT fmi3Status fmi3SetIntervalDecimal(fmi3Instance i, const fmi3ValueReference vr[],
                                         size_t nvr, const fmi3Float64 intervals[])
{
    (void)vr, (void)nvr, (void)intervals;
    return unsupported(i, "fmi3SetIntervalDecimal", NO_CLOCKS);
}

EXPORT fmi3Status fmi3SetIntervalFraction(fmi3Instance i, const fmi3ValueReference vr[],
                                          size_t nvr, const fmi3UInt64 counters[],
                                          const fmi3UInt64 resolutions[])
{
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    return unsupported(i, "fmi3SetIntervalFraction", NO_CLOCKS);
}

EXPORT fmi3Status fmi3SetShiftDecimal(fmi3Instance i, const fmi3ValueReference vr[],
                                      size_t nvr, const fmi3Float64 shifts[])
{
    (void)vr, (void)nvr, (void)shifts;
    return unsupported(i, "fmi3SetShiftDecimal", NO_CLOCKS);
}

EXPORT fmi3Status fmi3SetShiftFraction(fmi3Instance i, const fmi3ValueReference vr[],
                                       size_t nvr, const fmi3UInt64 counters[],
                                       const fmi3UInt64 resolutions[])
{
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    return unsupported(i, "fmi3SetShiftFraction", NO_CLOCKS);
}

EXPORT fmi3Status fmi3ActivateModelPartition(fmi3Instance i, fmi3ValueReference clockReference,
                                             fmi3Float64 activationTime)
{
    (void)clockReference, (void)activationTime;
    return unsupported(i, "fmi3ActivateModelPartition", "scheduled execution; " ME_ONLY);
}

/* model exchange */
EXPORT fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance i)
{
    return unsupported(i, "fmi3EnterContinuousTimeMode", ME_ONLY);
}

EXPORT fmi3Status fmi3CompletedIntegratorStep(fmi3Instance i, fmi3Boolean noSetPrior,
                                              fmi3Boolean *enterEventMode,
                                              fmi3Boolean *terminateSimulation)
{
    (void)noSetPrior, (void)enterEventMode, (void)terminateSimulation;
    return unsupported(i, "fmi3CompletedIntegratorStep", ME_ONLY);
}

EXPORT fmi3Status fmi3SetTime(fmi3Instance i, fmi3Float64 time)
{
    (void)time;
    return unsupported(i, "fmi3SetTime", ME_ONLY);
}

EXPORT fmi3Status fmi3SetContinuousStates(fmi3Instance i, const fmi3Float64 x[], size_t n)
{
    (void)x, (void)n;
    return unsupported(i, "fmi3SetContinuousStates", ME_ONLY);
}

#define ME_ARRAY(fn)                                                           \
    EXPORT fmi3Status fn(fmi3Instance i, fmi3Float64 values[], size_t n)       \
    {                                                                          \
        (void)values, (void)n;                                                 \
        return unsupported(i, #fn, ME_ONLY);                                   \
    }

ME_ARRAY(fmi3GetContinuousStateDerivatives)
ME_ARRAY(fmi3GetEventIndicators)
ME_ARRAY(fmi3GetContinuousStates)
ME_ARRAY(fmi3GetNominalsOfContinuousStates)

EXPORT fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance i, size_t *n)
{
    (void)n;
    return unsupported(i, "fmi3GetNumberOfEventIndicators", ME_ONLY);
}

EXPORT fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance i, size_t *n)
{
    (void)n;
    return unsupported(i, "fmi3GetNumberOfContinuousStates", ME_ONLY);
}
