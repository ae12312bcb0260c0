/*
 * The FMI 2.0 front of the host: HostApi's calls as FMI 2.0 calls of the FMU's library
 * (the function types of ../fmi2), resolved once at load; a call the library does not
 * export stops the host naming it (exit 2). Resources: a file:// URI of the FMU's folder.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../fmi2/fmi2FunctionTypes.h"
#include "host.h"

#define FMI2_CALLS(X) X(Instantiate) X(SetupExperiment) X(EnterInitializationMode) \
    X(ExitInitializationMode) X(Terminate) X(Reset) X(FreeInstance) X(DoStep) X(GetReal) \
    X(GetInteger) X(GetBoolean) X(GetString) X(SetReal) X(SetInteger) X(SetBoolean) \
    X(SetString) X(GetFMUstate) X(SetFMUstate) X(FreeFMUstate) X(SerializedFMUstateSize) \
    X(SerializeFMUstate) X(DeSerializeFMUstate) X(GetBooleanStatus) X(GetRealStatus) \
    X(GetIntegerStatus) X(SetRealInputDerivatives)

typedef struct {
#define FIELD(name) fmi2##name##TYPE *name;
    FMI2_CALLS(FIELD)
#undef FIELD
} Fmi2Calls;

static Fmi2Calls *need(HostFmu *f, int present, const char *name)
{
    if (!present) {
        fprintf(stderr, "%s: no symbol fmi2%s\n", f->dir, name);
        exit(2);
    }
    return (Fmi2Calls *)f->calls;
}

/* the FMU's fmi2NAME, stopping the host if its library has none */
#define CALL(f, name) (need(f, ((Fmi2Calls *)(f)->calls)->name != NULL, #name)->name)

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    char text[8192];
    va_list args;
    (void)env;
    va_start(args, message);
    vsnprintf(text, sizeof text, message ? message : "(null)", args);
    va_end(args);
    host_log(instance, (int)status, category, text);
}

static const fmi2CallbackFunctions CALLBACKS = {logger, host_counted_calloc, host_counted_free,
                                                NULL, NULL};

static int instantiate(HostFmu *f, const char *name, int logging, int event_mode)
{
    char uri[8300];
    size_t i;
    (void)event_mode;
    snprintf(f->name, sizeof f->name, "%s", name);
    snprintf(uri, sizeof uri, "file://%s%s/resources", f->dir[0] == '/' ? "" : "/", f->dir);
    for (i = 0; uri[i]; i++)
        if (uri[i] == '\\') uri[i] = '/';
    f->instance = CALL(f, Instantiate)(name, fmi2CoSimulation, f->token, uri, &CALLBACKS,
                                       fmi2False, logging ? fmi2True : fmi2False);
    return f->instance ? fmi2OK : fmi2Error;
}

static int setup(HostFmu *f, double start_time)
{
    return CALL(f, SetupExperiment)(f->instance, fmi2False, 0.0, start_time, fmi2False, 0.0);
}

static int enter(HostFmu *f) { return CALL(f, EnterInitializationMode)(f->instance); }
static int exit_init(HostFmu *f) { return CALL(f, ExitInitializationMode)(f->instance); }
static int terminate(HostFmu *f) { return CALL(f, Terminate)(f->instance); }
static int reset(HostFmu *f) { return CALL(f, Reset)(f->instance); }
static void free_instance(HostFmu *f) { CALL(f, FreeInstance)(f->instance); }

static int step(HostFmu *f, double t, double h, int no_set_state_prior)
{
    return CALL(f, DoStep)(f->instance, t, h, no_set_state_prior ? fmi2True : fmi2False);
}

static int get_real(HostFmu *f, const unsigned *vr, size_t n, double *v)
{
    return CALL(f, GetReal)(f->instance, vr, n, v);
}

static int get_int(HostFmu *f, const unsigned *vr, size_t n, int *v)
{
    return CALL(f, GetInteger)(f->instance, vr, n, v);
}

static int get_bool(HostFmu *f, const unsigned *vr, size_t n, int *v)
{
    return CALL(f, GetBoolean)(f->instance, vr, n, v);
}

static int get_string(HostFmu *f, const unsigned *vr, size_t n, const char **v)
{
    return CALL(f, GetString)(f->instance, vr, n, v);
}

static int set_real(HostFmu *f, const unsigned *vr, size_t n, const double *v)
{
    return CALL(f, SetReal)(f->instance, vr, n, v);
}

static int set_int(HostFmu *f, const unsigned *vr, size_t n, const int *v)
{
    return CALL(f, SetInteger)(f->instance, vr, n, v);
}

static int set_bool(HostFmu *f, const unsigned *vr, size_t n, const int *v)
{
    return CALL(f, SetBoolean)(f->instance, vr, n, v);
}

static int set_string(HostFmu *f, const unsigned *vr, size_t n, const char *const *v)
{
    return CALL(f, SetString)(f->instance, vr, n, (const fmi2String *)v);
}

static int get_state(HostFmu *f, void **state)
{
    return CALL(f, GetFMUstate)(f->instance, state);
}

static int set_state(HostFmu *f, void *state)
{
    return CALL(f, SetFMUstate)(f->instance, state);
}

static int free_state(HostFmu *f, void **state)
{
    return CALL(f, FreeFMUstate)(f->instance, state);
}

static int state_size(HostFmu *f, void *state, size_t *size)
{
    return CALL(f, SerializedFMUstateSize)(f->instance, state, size);
}

static int serialize(HostFmu *f, void *state, unsigned char *blob, size_t size)
{
    return CALL(f, SerializeFMUstate)(f->instance, state, (fmi2Byte *)blob, size);
}

static int deserialize(HostFmu *f, const unsigned char *blob, size_t size, void **state)
{
    return CALL(f, DeSerializeFMUstate)(f->instance, (const fmi2Byte *)blob, size, state);
}

static int terminated(HostFmu *f, int *value)
{
    return CALL(f, GetBooleanStatus)(f->instance, fmi2Terminated, value);
}

static int last_time(HostFmu *f, double *value)
{
    return CALL(f, GetRealStatus)(f->instance, fmi2LastSuccessfulTime, value);
}

static int integer_status(HostFmu *f, int kind, int *value)
{
    return CALL(f, GetIntegerStatus)(f->instance, (fmi2StatusKind)kind, value);
}

static int unsupported(HostFmu *f)
{
    fmi2ValueReference vr = 0;
    fmi2Integer order = 1;
    fmi2Real value = 0.0;
    return CALL(f, SetRealInputDerivatives)(f->instance, &vr, 1, &order, &value);
}

static const HostApi FMI2 = {
    instantiate, setup, enter, exit_init, terminate, reset, free_instance, step,
    get_real, get_int, get_bool, get_string, set_real, set_int, set_bool, set_string,
    get_state, set_state, free_state, state_size, serialize, deserialize,
    terminated, last_time, unsupported, integer_status, NULL, NULL, NULL};

void host_fmi2_bind(HostFmu *f)
{
    Fmi2Calls *calls = (Fmi2Calls *)calloc(1, sizeof *calls);
    if (!calls) exit(2);
#define BIND(name) calls->name = (fmi2##name##TYPE *)host_symbol(f, "fmi2" #name);
    FMI2_CALLS(BIND)
#undef BIND
    f->calls = calls;
    f->api = &FMI2;
}
