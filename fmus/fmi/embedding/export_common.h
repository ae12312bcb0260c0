/*
 * The part of pantocosim's FMI embedding libraries that does not depend on the FMI version
 * (export_common.c): the Python C API resolved with dlsym and the runtime that provides it,
 * the registries of live instances and of their FMU states, logging to the host, and calling
 * the FMU's bridge module. fmi2_export.c and fmi3_export.c are the FMI 2.0 and 3.0 APIs over
 * it. Statuses are FMI's numbers, the same in both versions: OK 0, Warning 1, Discard 2,
 * Error 3, Fatal 4.
 */
#ifndef PANTOCOSIM_EXPORT_COMMON_H
#define PANTOCOSIM_EXPORT_COMMON_H

#include <pthread.h>
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

/* 1 when a Python runtime is ready (the host's, or one started from a candidate); 2 when this
   call started it on a candidate after skipping others (runtime_problem() says which
   Python runs and why the others were skipped, for a warning); else 0 and
   runtime_problem() says why, naming every candidate and what it lacked */
int ensure_runtime(const char *resources);
const char *runtime_problem(void);
/* the Python the FMUs run in, for messages ("PANTOCOSIM_PYTHON = /x/python (libpython...)",
   "the host process's own Python (...)") */
const char *runtime_used(void);

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
    /* one call at a time on an instance: a call, or the freeing of the instance or of one of
       its states, waits for the call under way on another thread (taken before the GIL) */
    pthread_mutex_t call_lock;
    int users;  /* calls holding or waiting for call_lock (under the registry's lock) */
    int freed;  /* set by the instance's free call: the last user releases the memory */
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
/* the start of a call on c: 1 with c held for this thread (c is a live instance: registered
   and not freed; calls of other threads on it wait), else 0 */
int enter_component(Component *c);
/* the end of a call begun by enter_component (the memory of an instance freed meanwhile is
   released by its last user) */
void leave_component(Component *c);
/* the instance's free call (fmi2FreeInstance, fmi3FreeInstance): unregistered, its states
   and adapter dropped (the GIL is taken here), its memory released once no call uses it;
   nothing for a pointer that is not a live instance */
void free_instance(Component *c, const char *call);
/* an instance that was never registered (a failed instantiation) released at once */
void discard_component(Component *c, const char *call);

void log_message(const Component *c, int status, const char *category, const char *message);
void logf_message(const Component *c, int status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
const char *category_of(int status);

/* ------------------------------------------------------------------ calling the bridge */
/* the file path of a resource location (file: URI or plain path), percent-decoded, no
   trailing slash; malloc'ed */
char *resources_path(const char *location);
/* 1 when the resources folder holds the bridge module; else 0 with a log naming what is
   missing (the folder, or the module in it) and the location the host gave */
int resources_complete(Component *c, const char *resources, const char *location,
                       const char *bridge_module, const char *call);
/* import the bridge module from the resources and make the adapter of FMI `fmi`; 0 with a
   log (naming `call`) on failure */
int make_adapter(Component *c, const char *resources, const char *bridge_module, int fmi,
                 const char *token, int visible, const char *call);
void take_exception(char *out, size_t size);
/* the status of a bridge result (status, value), log messages forwarded; kept / released */
int status_of(Component *c, PyObject *result, const char *call);
int done(Component *c, PyObject *result, const char *call);

/* list[i] = item (the reference stolen), the list; NULL (the list released, the Python
   error left for the caller's status) when the list or the item is NULL */
PyObject *put_item(PyObject *list, size_t i, PyObject *item);
/* the value references as a Python list; NULL (a Python error set) when it cannot be made */
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
    const char *enter_call_ = (call);                                          \
    int gil;                                                                   \
    if (!enter_component(c)) {                                                 \
        fprintf(stderr, "[logStatusError] %s: not a live pantocosim FMU "      \
                        "instance (%p)\n", enter_call_, (void *)c);            \
        return (int)ST_ERROR;                                                  \
    }                                                                          \
    gil = py.GILEnsure()

/* the call's status; a Python error still set is logged and cleared (the next call on this
   thread starts clean), then the GIL and the instance are released */
#define LEAVE(status)                                                          \
    do {                                                                       \
        int leave_status_ = leave_clean(c, enter_call_, (status));             \
        py.GILRelease(gil);                                                    \
        leave_component(c);                                                    \
        return leave_status_;                                                  \
    } while (0)

int leave_clean(Component *c, const char *call, int status);

#define LOGF(c, status, ...) logf_message(c, status, __VA_ARGS__)

#endif
