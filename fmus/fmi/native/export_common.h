/*
 * The part of pantocosim's FMI export libraries that does not depend on the FMI version
 * (export_common.c): the Python C API resolved with dlsym and the runtime that provides it,
 * the registries of live instances and of their FMU states, logging to the host, and calling
 * the FMU's bridge module. fmi2_export.c and fmi3_export.c are the FMI 2.0 and 3.0 APIs over
 * it. Statuses are FMI's numbers, the same in both versions: OK 0, Warning 1, Discard 2,
 * Error 3, Fatal 4.
 */
#ifndef PANTOCOSIM_EXPORT_COMMON_H
#define PANTOCOSIM_EXPORT_COMMON_H

#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>
#include <wchar.h>

#define EXPORT __attribute__((visibility("default")))

enum { ST_OK = 0, ST_WARNING = 1, ST_DISCARD = 2, ST_ERROR = 3, ST_FATAL = 4 };

/* ------------------------------------------------------------------ Python C API by dlsym */
typedef struct _object PyObject;
typedef ssize_t Py_ssize_t;

typedef struct {
    int (*IsInitialized)(void);
    void (*InitializeEx)(int);
    void (*SetProgramName)(const wchar_t *);
    wchar_t *(*DecodeLocale)(const char *, size_t *);
    void *(*SaveThread)(void);
    int (*GILEnsure)(void);
    void (*GILRelease)(int);
    PyObject *(*ImportModule)(const char *);
    PyObject *(*GetAttrString)(PyObject *, const char *);
    PyObject *(*CallMethod)(PyObject *, const char *, const char *, ...);
    PyObject *(*CallObject)(PyObject *, PyObject *);
    PyObject *(*ListNew)(Py_ssize_t);
    int (*ListSetItem)(PyObject *, Py_ssize_t, PyObject *);
    PyObject *(*ListGetItem)(PyObject *, Py_ssize_t);
    Py_ssize_t (*ListSize)(PyObject *);
    int (*ListCheck)(PyObject *);
    PyObject *(*TupleGetItem)(PyObject *, Py_ssize_t);
    Py_ssize_t (*TupleSize)(PyObject *);
    PyObject *(*LongFromLong)(long);
    long (*LongAsLong)(PyObject *);
    PyObject *(*FloatFromDouble)(double);
    double (*FloatAsDouble)(PyObject *);
    PyObject *(*UnicodeFromString)(const char *);
    const char *(*UnicodeAsUTF8)(PyObject *);
    PyObject *(*BytesFromStringAndSize)(const char *, Py_ssize_t);
    int (*BytesAsStringAndSize)(PyObject *, char **, Py_ssize_t *);
    PyObject *(*ObjectStr)(PyObject *);
    PyObject *(*ErrOccurred)(void);
    void (*ErrFetch)(PyObject **, PyObject **, PyObject **);
    void (*ErrClear)(void);
    void (*DecRef)(PyObject *);
    void (*IncRef)(PyObject *);
} PythonApi;

extern PythonApi py;

/* 1 when a Python runtime is ready (the host's, or one started from a candidate); else 0 and
   runtime_problem() says why, naming every candidate */
int ensure_runtime(const char *resources);
const char *runtime_problem(void);

/* ------------------------------------------------------------------ instances and states */
typedef struct State {
    uint64_t magic;
    PyObject *object;
    PyObject *bytes; /* serialised form, made at the first size or serialise call */
    struct State *next;
} State;

struct Component;
/* forwards one message to the host's logger (the version's callback) */
typedef void (*LogSink)(const struct Component *c, int status, const char *category,
                        const char *message);

typedef struct Component {
    uint64_t magic;
    char *instanceName;
    int loggingOn;
    PyObject *adapter; /* the bridge's Adapter over the slave */
    State *states;
    LogSink sink;
    void *hostLogger;      /* the version's logger callback */
    void *hostEnvironment; /* its first argument */
} Component;

Component *new_component(const char *instanceName, int loggingOn, LogSink sink,
                         void *hostLogger, void *hostEnvironment);
int register_component(Component *c);
int registered(const Component *c);
/* unregister, drop the states and the adapter, free (the GIL is taken here) */
void free_component(Component *c, const char *call);

void log_message(const Component *c, int status, const char *category, const char *message);
void logf_message(const Component *c, int status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
const char *category_of(int status);

/* ------------------------------------------------------------------ calling the bridge */
/* the file path of a resource location (file: URI or plain path), percent-decoded, no
   trailing slash; malloc'ed */
char *resources_path(const char *location);
/* import the bridge module from the resources and make the adapter of FMI `fmi`; 0 with a
   log (naming `call`) on failure */
int make_adapter(Component *c, const char *resources, const char *bridge_module, int fmi,
                 const char *token, int visible, const char *call);
void take_exception(char *out, size_t size);
/* the status of a bridge result (status, value), log messages forwarded; kept / released */
int status_of(Component *c, PyObject *result, const char *call);
int done(Component *c, PyObject *result, const char *call);

PyObject *vr_list(const unsigned int vr[], size_t n);
int arrays_given(Component *c, const char *call, const void *vr, size_t n, const void *values);

/* typed values of get/set: how a C array element is read or written */
typedef enum { V_DOUBLE, V_INT, V_INT32, V_CBOOL, V_INTBOOL } ValueKind;
int get_values(Component *c, const char *call, const char *method, const unsigned int vr[],
               size_t n, void *out, ValueKind kind);
int set_values(Component *c, const char *call, const char *method, const unsigned int vr[],
               size_t n, const void *in, ValueKind kind);
int get_strings(Component *c, const char *call, const unsigned int vr[], size_t n,
                const char *out[]);
int set_strings(Component *c, const char *call, const unsigned int vr[], size_t n,
                const char *const in[]);

/* FMU states: C records checked before their Python object is touched */
int state_get(Component *c, const char *call, void **state);
int state_set(Component *c, const char *call, void *state);
int state_free(Component *c, const char *call, void **state);
int state_size(Component *c, const char *call, void *state, size_t *size);
int state_serialize(Component *c, const char *call, void *state, unsigned char *buffer,
                    size_t size);
int state_deserialize(Component *c, const char *call, const unsigned char *data, size_t size,
                      void **state);

/* the entry check of every call on an instance: a pointer that is not a live instance gives
   Error; the GIL is held between ENTER and LEAVE */
#define ENTER(c_in, call)                                                      \
    Component *c = (Component *)(c_in);                                       \
    int gil;                                                                   \
    if (!registered(c)) {                                                      \
        fprintf(stderr, "[logStatusError] %s: not a live pantocosim FMU "      \
                        "instance (%p)\n", call, (void *)c);                   \
        return ST_ERROR;                                                       \
    }                                                                          \
    gil = py.GILEnsure()

#define LEAVE(status)                                                          \
    do {                                                                       \
        int leave_status_ = (status);                                          \
        py.GILRelease(gil);                                                    \
        return leave_status_;                                                  \
    } while (0)

#define LOGF(c, status, ...) logf_message(c, status, __VA_ARGS__)

#endif
