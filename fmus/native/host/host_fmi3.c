/*
 * The FMI 3.0 front of the host: HostApi's calls as FMI 3.0 co-simulation calls of the
 * FMU's library (the function types of ../fmi3), resolved once at load; a call the library
 * does not export stops the host naming it (exit 2). FMI 2.0's words map as: setup keeps
 * the start time for fmi3EnterInitializationMode; Real, Integer are Float64, Int32;
 * terminated and last time are those fmi3DoStep returned. Resources: the folder's native
 * path with a trailing separator.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../fmi3/fmi3FunctionTypes.h"
#include "host.h"

#define FMI3_CALLS(X) X(InstantiateCoSimulation) X(EnterInitializationMode) \
    X(ExitInitializationMode) X(Terminate) X(Reset) X(FreeInstance) X(DoStep) X(GetFloat64) \
    X(GetInt32) X(GetBoolean) X(GetString) X(SetFloat64) X(SetInt32) X(SetBoolean) \
    X(SetString) X(GetFMUState) X(SetFMUState) X(FreeFMUState) X(SerializedFMUStateSize) \
    X(SerializeFMUState) X(DeserializeFMUState) X(EnterEventMode) X(EnterStepMode) \
    X(UpdateDiscreteStates) X(GetOutputDerivatives)

typedef struct {
#define FIELD(name) fmi3##name##TYPE *name;
    FMI3_CALLS(FIELD)
#undef FIELD
} Fmi3Calls;

static Fmi3Calls *need(HostFmu *f, int present, const char *name)
{
    if (!present) {
        fprintf(stderr, "%s: no symbol fmi3%s\n", f->dir, name);
        exit(2);
    }
    return (Fmi3Calls *)f->calls;
}

/* the FMU's fmi3NAME, stopping the host if its library has none */
#define CALL(f, name) (need(f, ((Fmi3Calls *)(f)->calls)->name != NULL, #name)->name)

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                        fmi3String message)
{
    host_log(env ? ((HostFmu *)env)->name : NULL, (int)status, category, message);
}

static int instantiate(HostFmu *f, const char *name, int logging, int event_mode)
{
    char resources[4200];
    snprintf(f->name, sizeof f->name, "%s", name);
#ifdef _WIN32
    snprintf(resources, sizeof resources, "%s\\resources\\", f->dir);
#else
    snprintf(resources, sizeof resources, "%s/resources/", f->dir);
#endif
    f->instance = CALL(f, InstantiateCoSimulation)(name, f->token, resources, fmi3False,
                                                   logging != 0, event_mode != 0, fmi3False,
                                                   NULL, 0, f, log_message, NULL);
    return f->instance ? fmi3OK : fmi3Error;
}

static int setup(HostFmu *f, double start_time)
{
    f->start_time = start_time;
    return fmi3OK;
}

static int enter(HostFmu *f)
{
    return CALL(f, EnterInitializationMode)(f->instance, fmi3False, 0.0, f->start_time,
                                            fmi3False, 0.0);
}

static int exit_init(HostFmu *f) { return CALL(f, ExitInitializationMode)(f->instance); }
static int terminate(HostFmu *f) { return CALL(f, Terminate)(f->instance); }
static int reset(HostFmu *f) { return CALL(f, Reset)(f->instance); }
static void free_instance(HostFmu *f) { CALL(f, FreeInstance)(f->instance); }
static int event_mode(HostFmu *f) { return CALL(f, EnterEventMode)(f->instance); }
static int step_mode(HostFmu *f) { return CALL(f, EnterStepMode)(f->instance); }

static int step(HostFmu *f, double t, double h, int no_set_state_prior)
{
    fmi3Boolean event = fmi3True, terminate_now = fmi3True, early = fmi3True;
    int s;
    f->step_last_time = -1.0;
    s = CALL(f, DoStep)(f->instance, t, h, no_set_state_prior != 0, &event, &terminate_now,
                        &early, &f->step_last_time);
    f->step_event = event;
    f->step_terminated = terminate_now;
    f->step_early = early;
    return s;
}

static int get_real(HostFmu *f, const unsigned *vr, size_t n, double *v)
{
    return CALL(f, GetFloat64)(f->instance, vr, n, v, n);
}

static int set_real(HostFmu *f, const unsigned *vr, size_t n, const double *v)
{
    return CALL(f, SetFloat64)(f->instance, vr, n, v, n);
}

static int get_int(HostFmu *f, const unsigned *vr, size_t n, int *v)
{
    fmi3Int32 values[HOST_MAX_VALUES];
    size_t i;
    int s;
    if (n > HOST_MAX_VALUES) return fmi3Error;
    s = CALL(f, GetInt32)(f->instance, vr, n, values, n);
    for (i = 0; i < n; i++) v[i] = (int)values[i];
    return s;
}

static int set_int(HostFmu *f, const unsigned *vr, size_t n, const int *v)
{
    fmi3Int32 values[HOST_MAX_VALUES];
    size_t i;
    if (n > HOST_MAX_VALUES) return fmi3Error;
    for (i = 0; i < n; i++) values[i] = (fmi3Int32)v[i];
    return CALL(f, SetInt32)(f->instance, vr, n, values, n);
}

static int get_bool(HostFmu *f, const unsigned *vr, size_t n, int *v)
{
    fmi3Boolean values[HOST_MAX_VALUES];
    size_t i;
    int s;
    if (n > HOST_MAX_VALUES) return fmi3Error;
    s = CALL(f, GetBoolean)(f->instance, vr, n, values, n);
    for (i = 0; i < n; i++) v[i] = values[i] ? 1 : 0;
    return s;
}

static int set_bool(HostFmu *f, const unsigned *vr, size_t n, const int *v)
{
    fmi3Boolean values[HOST_MAX_VALUES];
    size_t i;
    if (n > HOST_MAX_VALUES) return fmi3Error;
    for (i = 0; i < n; i++) values[i] = v[i] != 0;
    return CALL(f, SetBoolean)(f->instance, vr, n, values, n);
}

static int get_string(HostFmu *f, const unsigned *vr, size_t n, const char **v)
{
    return CALL(f, GetString)(f->instance, vr, n, v, n);
}

static int set_string(HostFmu *f, const unsigned *vr, size_t n, const char *const *v)
{
    return CALL(f, SetString)(f->instance, vr, n, v, n);
}

static int get_state(HostFmu *f, void **state)
{
    return CALL(f, GetFMUState)(f->instance, state);
}

static int set_state(HostFmu *f, void *state)
{
    return CALL(f, SetFMUState)(f->instance, state);
}

static int free_state(HostFmu *f, void **state)
{
    return CALL(f, FreeFMUState)(f->instance, state);
}

static int state_size(HostFmu *f, void *state, size_t *size)
{
    return CALL(f, SerializedFMUStateSize)(f->instance, state, size);
}

static int serialize(HostFmu *f, void *state, unsigned char *blob, size_t size)
{
    return CALL(f, SerializeFMUState)(f->instance, state, blob, size);
}

static int deserialize(HostFmu *f, const unsigned char *blob, size_t size, void **state)
{
    return CALL(f, DeserializeFMUState)(f->instance, blob, size, state);
}

static int terminated(HostFmu *f, int *value)
{
    *value = f->step_terminated;
    return fmi3OK;
}

static int last_time(HostFmu *f, double *value)
{
    *value = f->step_last_time;
    return fmi3OK;
}

static int update(HostFmu *f, int flags[5])
{
    fmi3Boolean b[5] = {fmi3True, fmi3True, fmi3True, fmi3True, fmi3True};
    fmi3Float64 next = -1.0;
    int i, s = CALL(f, UpdateDiscreteStates)(f->instance, &b[0], &b[1], &b[2], &b[3], &b[4],
                                             &next);
    for (i = 0; i < 5; i++) flags[i] = b[i];
    return s;
}

static int unsupported(HostFmu *f)
{
    fmi3ValueReference vr = 0;
    fmi3Int32 order = 1;
    fmi3Float64 value = 0.0;
    return CALL(f, GetOutputDerivatives)(f->instance, &vr, 1, &order, &value, 1);
}

static const HostApi FMI3 = {
    instantiate, setup, enter, exit_init, terminate, reset, free_instance, step,
    get_real, get_int, get_bool, get_string, set_real, set_int, set_bool, set_string,
    get_state, set_state, free_state, state_size, serialize, deserialize,
    terminated, last_time, unsupported, NULL, event_mode, step_mode, update};

void host_fmi3_bind(HostFmu *f)
{
    Fmi3Calls *calls = (Fmi3Calls *)calloc(1, sizeof *calls);
    if (!calls) exit(2);
#define BIND(name) calls->name = (fmi3##name##TYPE *)host_symbol(f, "fmi3" #name);
    FMI3_CALLS(BIND)
#undef BIND
    f->calls = calls;
    f->api = &FMI3;
}
