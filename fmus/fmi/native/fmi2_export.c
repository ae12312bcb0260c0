/*
 * pantocosim's FMI 2.0 co-simulation export library.
 *
 * Every pantocosim FMU carries this library as binaries/linux64/<modelIdentifier>.so. It
 * implements the FMI 2.0 C API over the FMU's Python slave (a pythonfmu ``Fmi2Slave``
 * subclass) through the bridge module ``pantocosim_fmi2_bridge`` in the FMU's resources:
 *
 * - it finds a Python runtime itself: the host's interpreter when the host is a Python
 *   process, else the executable named by $PANTOCOSIM_PYTHON, else the interpreter that
 *   built the FMU (resources/pantocosim_runtime.txt), else python3 on PATH, each probed for
 *   its shared libpython and for numpy, scipy and numba; libpython is opened at
 *   run time, so the library links no Python and needs no LD_PRELOAD or PYTHONPATH;
 * - statuses are FMI's: a call that is not honoured returns fmi2Error (fmi2Discard from
 *   fmi2DoStep) with a categorised log message, and the instance stays usable;
 * - components and FMU states are checked before use: a freed, foreign or forged pointer gives
 *   fmi2Error, never a crash;
 * - an interpreter it started is never finalised (the process exit reclaims it).
 *
 * Only the C library and the POSIX dl/pthread API are used; Python is called through the
 * stable C API functions resolved with dlsym.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#include <wchar.h>

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

#define EXPORT __attribute__((visibility("default")))

/* ------------------------------------------------------------------ Python C API by dlsym */
typedef struct _object PyObject;
typedef ssize_t Py_ssize_t;

static struct {
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
} py;

/* ------------------------------------------------------------------ components and states */
#define COMPONENT_MAGIC 0x70616e746f636f6dULL
#define STATE_MAGIC 0x70616e746f737461ULL
#define MAX_COMPONENTS 1024
#define STATUS_LOG_FLAG 16 /* the bridge's "messages are waiting" bit */

typedef struct State {
    uint64_t magic;
    PyObject *object;
    PyObject *bytes; /* serialised form, made by fmi2SerializedFMUstateSize */
    struct State *next;
} State;

typedef struct Component {
    uint64_t magic;
    char *instanceName;
    fmi2CallbackFunctions callbacks;
    int loggingOn;
    PyObject *adapter; /* the bridge's Adapter over the slave */
    State *states;
} Component;

static pthread_mutex_t registry_lock = PTHREAD_MUTEX_INITIALIZER;
static Component *live[MAX_COMPONENTS];

static int registered(const Component *c)
{
    int found = 0;
    if (c == NULL) return 0;
    pthread_mutex_lock(&registry_lock);
    for (int i = 0; i < MAX_COMPONENTS && !found; i++) found = live[i] == c;
    pthread_mutex_unlock(&registry_lock);
    return found && c->magic == COMPONENT_MAGIC;
}

static int register_component(Component *c)
{
    int slot = -1;
    pthread_mutex_lock(&registry_lock);
    for (int i = 0; i < MAX_COMPONENTS && slot < 0; i++)
        if (live[i] == NULL) slot = i;
    if (slot >= 0) live[slot] = c;
    pthread_mutex_unlock(&registry_lock);
    return slot >= 0;
}

static void unregister_component(Component *c)
{
    pthread_mutex_lock(&registry_lock);
    for (int i = 0; i < MAX_COMPONENTS; i++)
        if (live[i] == c) live[i] = NULL;
    pthread_mutex_unlock(&registry_lock);
}

/* ------------------------------------------------------------------ logging */
static const char *category_of(fmi2Status status)
{
    switch (status) {
    case fmi2OK: return "logAll";
    case fmi2Warning: return "logStatusWarning";
    case fmi2Discard: return "logStatusDiscard";
    case fmi2Error: return "logStatusError";
    default: return "logStatusFatal";
    }
}

static void log_to(const fmi2CallbackFunctions *cb, const char *instance, fmi2Status status,
                   const char *category, const char *message)
{
    if (cb == NULL || cb->logger == NULL) {
        if (status >= fmi2Error) fprintf(stderr, "[%s] %s: %s\n", category, instance, message);
        return;
    }
    cb->logger(cb->componentEnvironment, instance ? instance : "", status,
               category ? category : category_of(status), "%s", message ? message : "");
}

static void logf_to(const fmi2CallbackFunctions *cb, const char *instance, fmi2Status status,
                    const char *fmt, ...)
{
    char buffer[4096];
    va_list args;
    va_start(args, fmt);
    vsnprintf(buffer, sizeof buffer, fmt, args);
    va_end(args);
    log_to(cb, instance, status, category_of(status), buffer);
}

#define LOGF(c, status, ...) logf_to(&(c)->callbacks, (c)->instanceName, status, __VA_ARGS__)

/* ------------------------------------------------------------------ finding Python */
static pthread_mutex_t runtime_lock = PTHREAD_MUTEX_INITIALIZER;
static int runtime_ready = 0;
static char runtime_problem[8192];

#define RESOLVE(field, name)                                                   \
    do {                                                                       \
        *(void **)(&py.field) = dlsym(lib, name);                              \
        if (py.field == NULL) {                                                \
            snprintf(runtime_problem, sizeof runtime_problem,                  \
                     "the Python runtime has no symbol %s", name);             \
            return 0;                                                          \
        }                                                                      \
    } while (0)

static int resolve_api(void *lib)
{
    RESOLVE(IsInitialized, "Py_IsInitialized");
    RESOLVE(InitializeEx, "Py_InitializeEx");
    RESOLVE(SaveThread, "PyEval_SaveThread");
    RESOLVE(GILEnsure, "PyGILState_Ensure");
    RESOLVE(GILRelease, "PyGILState_Release");
    RESOLVE(ImportModule, "PyImport_ImportModule");
    RESOLVE(GetAttrString, "PyObject_GetAttrString");
    RESOLVE(CallMethod, "PyObject_CallMethod");
    RESOLVE(CallObject, "PyObject_CallObject");
    RESOLVE(ListNew, "PyList_New");
    RESOLVE(ListSetItem, "PyList_SetItem");
    RESOLVE(ListGetItem, "PyList_GetItem");
    RESOLVE(ListSize, "PyList_Size");
    RESOLVE(TupleGetItem, "PyTuple_GetItem");
    RESOLVE(TupleSize, "PyTuple_Size");
    RESOLVE(LongFromLong, "PyLong_FromLong");
    RESOLVE(LongAsLong, "PyLong_AsLong");
    RESOLVE(FloatFromDouble, "PyFloat_FromDouble");
    RESOLVE(FloatAsDouble, "PyFloat_AsDouble");
    RESOLVE(UnicodeFromString, "PyUnicode_FromString");
    RESOLVE(UnicodeAsUTF8, "PyUnicode_AsUTF8");
    RESOLVE(BytesFromStringAndSize, "PyBytes_FromStringAndSize");
    RESOLVE(BytesAsStringAndSize, "PyBytes_AsStringAndSize");
    RESOLVE(ObjectStr, "PyObject_Str");
    RESOLVE(ErrOccurred, "PyErr_Occurred");
    RESOLVE(ErrFetch, "PyErr_Fetch");
    RESOLVE(ErrClear, "PyErr_Clear");
    RESOLVE(DecRef, "Py_DecRef");
    RESOLVE(IncRef, "Py_IncRef");
    *(void **)(&py.SetProgramName) = dlsym(lib, "Py_SetProgramName");
    *(void **)(&py.DecodeLocale) = dlsym(lib, "Py_DecodeLocale");
    return 1;
}

/* value of "key=" in a key=value file (first line that has it), or "" */
static void read_key(const char *file, const char *key, char *out, size_t size)
{
    char line[PATH_MAX + 64];
    size_t n = strlen(key);
    FILE *f = fopen(file, "r");
    out[0] = '\0';
    if (f == NULL) return;
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, key, n) == 0 && line[n] == '=') {
            size_t len = strnlen(line + n + 1, size - 1);
            memcpy(out, line + n + 1, len);
            out[len] = '\0';
            out[strcspn(out, "\r\n")] = '\0';
            break;
        }
    }
    fclose(f);
}

/* Python code run by a candidate interpreter: prints its libpython, its executable and the
   modules it lacks (one line each). */
static const char PROBE[] =
    "import importlib.util as u, os, sys, sysconfig\n"
    "v = lambda k: sysconfig.get_config_var(k) or ''\n"
    "names = [v('INSTSONAME'), v('LDLIBRARY')]\n"
    "dirs = [v('LIBDIR'), os.path.join(v('LIBDIR'), v('MULTIARCH')),"
    " '/usr/lib/' + v('MULTIARCH'), '/usr/lib64', '/usr/lib']\n"
    "libs = [os.path.join(d, n) for n in names for d in dirs if n and d]\n"
    "print(next((p for p in libs if os.path.isfile(p) and '.so' in os.path.basename(p)), ''))\n"
    "print(sys.executable)\n"
    "old = sys.version_info < (3, 11)\n"
    "print(','.join(['python>=3.11'] * old + [m for m in ('numpy', 'scipy', 'numba',"
    ") if u.find_spec(m) is None]))\n";

/* Run `exe -c PROBE` and read its three lines; 1 if it ran. */
static int probe_python(const char *exe, char *lib, char *resolved, char *missing, size_t size)
{
    int fds[2];
    pid_t pid;
    FILE *f;
    int status = 0;
    char *lines[3] = {lib, resolved, missing};
    if (pipe(fds) != 0) return 0;
    pid = fork();
    if (pid < 0) {
        close(fds[0]);
        close(fds[1]);
        return 0;
    }
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);
        dup2(fds[1], 1);
        if (null >= 0) dup2(null, 2);
        close(fds[0]);
        close(fds[1]);
        execlp(exe, exe, "-I", "-c", PROBE, (char *)NULL);
        _exit(127);
    }
    close(fds[1]);
    f = fdopen(fds[0], "r");
    for (int i = 0; i < 3; i++) {
        lines[i][0] = '\0';
        if (f && fgets(lines[i], (int)size, f)) lines[i][strcspn(lines[i], "\r\n")] = '\0';
    }
    if (f) fclose(f);
    else close(fds[0]);
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

static void append_problem(const char *fmt, ...)
{
    size_t used = strlen(runtime_problem);
    va_list args;
    if (used >= sizeof runtime_problem - 1) return;
    va_start(args, fmt);
    vsnprintf(runtime_problem + used, sizeof runtime_problem - used, fmt, args);
    va_end(args);
}

/* Open libpython `lib` and start its interpreter as if run as `exe` (its venv, its
   site-packages). The GIL is released afterwards; the interpreter is never finalised. */
static int start_interpreter(const char *lib_path, const char *exe)
{
    void *lib = dlopen(lib_path, RTLD_NOW | RTLD_GLOBAL);
    if (lib == NULL) {
        append_problem("; %s: %s", lib_path, dlerror());
        return 0;
    }
    if (!resolve_api(lib)) return 0;
    if (!py.IsInitialized()) {
        if (py.SetProgramName && py.DecodeLocale) {
            wchar_t *name = py.DecodeLocale(exe, NULL);
            if (name) py.SetProgramName(name); /* kept: Python keeps the pointer */
        }
        py.InitializeEx(0); /* no signal handlers: the host owns them */
        py.SaveThread();
    }
    return 1;
}

static int try_candidate(const char *exe, const char *origin)
{
    char lib[PATH_MAX], resolved[PATH_MAX], missing[1024];
    if (exe == NULL || *exe == '\0') return 0;
    if (!probe_python(exe, lib, resolved, missing, sizeof lib)) {
        append_problem("; %s %s: does not run", origin, exe);
        return 0;
    }
    if (*missing) {
        append_problem("; %s %s: lacks %s", origin, resolved, missing);
        return 0;
    }
    if (*lib == '\0') {
        append_problem("; %s %s: has no shared libpython (a Python built with "
                       "--enable-shared, or Debian's libpython3.X package, is needed)",
                       origin, resolved);
        return 0;
    }
    return start_interpreter(lib, resolved);
}

/* The host's interpreter if the process has one, else the first candidate that fits. */
static int ensure_runtime(const char *resources)
{
    char runtime_file[PATH_MAX], exe[PATH_MAX];
    int ok = 0;
    pthread_mutex_lock(&runtime_lock);
    if (runtime_ready) {
        pthread_mutex_unlock(&runtime_lock);
        return 1;
    }
    runtime_problem[0] = '\0';
    if (dlsym(RTLD_DEFAULT, "Py_IsInitialized") != NULL) {
        ok = resolve_api(RTLD_DEFAULT);
        if (ok && !py.IsInitialized()) {
            py.InitializeEx(0);
            py.SaveThread();
        }
    } else {
        snprintf(runtime_file, sizeof runtime_file, "%s/pantocosim_runtime.txt", resources);
        read_key(runtime_file, "executable", exe, sizeof exe);
        snprintf(runtime_problem, sizeof runtime_problem, "no usable Python runtime");
        ok = try_candidate(getenv("PANTOCOSIM_PYTHON"), "PANTOCOSIM_PYTHON =")
             || try_candidate(exe, "the build's Python")
             || try_candidate("python3", "python3 on PATH:");
        if (!ok)
            append_problem(". Set PANTOCOSIM_PYTHON to a Python >= 3.11 executable with numpy, "
                           "scipy, numba and pythonfmu, built with a shared libpython");
    }
    runtime_ready = ok;
    pthread_mutex_unlock(&runtime_lock);
    return ok;
}

/* ------------------------------------------------------------------ calling the bridge */
/* The message of the pending Python exception (cleared), into out. */
static void take_exception(char *out, size_t size)
{
    PyObject *type = NULL, *value = NULL, *trace = NULL, *text;
    snprintf(out, size, "unknown Python error");
    if (!py.ErrOccurred()) return;
    py.ErrFetch(&type, &value, &trace);
    text = value ? py.ObjectStr(value) : (type ? py.ObjectStr(type) : NULL);
    if (text) {
        const char *s = py.UnicodeAsUTF8(text);
        if (s) snprintf(out, size, "%s", s);
        py.DecRef(text);
    }
    py.ErrClear();
    if (type) py.DecRef(type);
    if (value) py.DecRef(value);
    if (trace) py.DecRef(trace);
}

/* Forward the adapter's waiting log messages to the host's logger. */
static void forward_log(Component *c)
{
    PyObject *messages = py.CallMethod(c->adapter, "take_log", NULL);
    if (messages == NULL) {
        py.ErrClear();
        return;
    }
    for (Py_ssize_t i = 0; i < py.ListSize(messages); i++) {
        PyObject *m = py.ListGetItem(messages, i); /* (status, category, text) */
        PyObject *s = m ? py.TupleGetItem(m, 0) : NULL, *k = m ? py.TupleGetItem(m, 1) : NULL;
        PyObject *t = m ? py.TupleGetItem(m, 2) : NULL;
        const char *category = k ? py.UnicodeAsUTF8(k) : NULL, *text = t ? py.UnicodeAsUTF8(t) : NULL;
        fmi2Status status = s ? (fmi2Status)py.LongAsLong(s) : fmi2Error;
        if (py.ErrOccurred()) py.ErrClear();
        if (status == fmi2OK && !c->loggingOn) continue;
        log_to(&c->callbacks, c->instanceName, status, category, text ? text : "(no text)");
    }
    if (py.ErrOccurred()) py.ErrClear();
    py.DecRef(messages);
}

/* The status of a bridge result, a tuple (status, value), with the log messages forwarded;
   the result is kept. A NULL result (a Python exception escaping the bridge) is an error. */
static fmi2Status status_of(Component *c, PyObject *result, const char *call)
{
    PyObject *item;
    long code;
    if (result == NULL) {
        char message[2048];
        take_exception(message, sizeof message);
        LOGF(c, fmi2Error, "%s: %s", call, message);
        return fmi2Error;
    }
    item = py.TupleGetItem(result, 0);
    code = item ? py.LongAsLong(item) : -1;
    if (code < 0 || py.ErrOccurred()) {
        py.ErrClear();
        LOGF(c, fmi2Error, "%s: the FMU's bridge returned no status", call);
        return fmi2Error;
    }
    if (code & STATUS_LOG_FLAG) forward_log(c);
    code &= ~STATUS_LOG_FLAG;
    return code > fmi2Error ? fmi2Error : (fmi2Status)code;
}

/* status_of, releasing the result */
static fmi2Status done(Component *c, PyObject *result, const char *call)
{
    fmi2Status status = status_of(c, result, call);
    if (result) py.DecRef(result);
    return status;
}

/* ------------------------------------------------------------------ entry checks */
#define ENTER(c_in, call)                                                      \
    Component *c = (Component *)(c_in);                                       \
    int gil;                                                                   \
    if (!registered(c)) {                                                      \
        fprintf(stderr, "[logStatusError] %s: not a live pantocosim FMU "      \
                        "instance (%p)\n", call, (void *)c);                   \
        return fmi2Error;                                                      \
    }                                                                          \
    gil = py.GILEnsure()

#define LEAVE(status)                                                          \
    do {                                                                       \
        fmi2Status leave_status_ = (status);                                   \
        py.GILRelease(gil);                                                    \
        return leave_status_;                                                  \
    } while (0)

static PyObject *vr_list(const fmi2ValueReference vr[], size_t n)
{
    PyObject *list = py.ListNew((Py_ssize_t)n);
    for (size_t i = 0; list && i < n; i++)
        py.ListSetItem(list, (Py_ssize_t)i, py.LongFromLong((long)vr[i]));
    return list;
}

static int arrays_given(Component *c, const char *call, const void *vr, size_t n,
                        const void *values)
{
    if (n > 0 && (vr == NULL || values == NULL)) {
        LOGF(c, fmi2Error, "%s: NULL value reference or value array for %zu values", call, n);
        return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------ the FMI 2.0 API */
EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

static char *resources_path(const char *location)
{
    const char *path = location;
    char *out, *r, *w;
    if (location == NULL) return NULL;
    if (strncmp(path, "file://", 7) == 0) {
        path += 7;
        if (strncmp(path, "localhost/", 10) == 0) path += 9;
    } else if (strncmp(path, "file:", 5) == 0) {
        path += 5;
    }
    out = strdup(path);
    if (out == NULL) return NULL;
    for (r = w = out; *r; r++, w++) { /* percent-decoding */
        if (r[0] == '%' && r[1] && r[2]) {
            char hex[3] = {r[1], r[2], 0};
            *w = (char)strtol(hex, NULL, 16);
            r += 2;
        } else {
            *w = *r;
        }
    }
    *w = '\0';
    for (size_t n = strlen(out); n > 1 && out[n - 1] == '/'; n--) out[n - 1] = '\0';
    return out;
}

static void free_component(Component *c)
{
    free(c->instanceName);
    c->magic = 0;
    free(c);
}

/* Import the bridge from the FMU's resources and make the adapter; 0 with a log on failure. */
static int make_adapter(Component *c, const char *resources, const char *guid, int visible)
{
    char message[4096];
    PyObject *sys = py.ImportModule("sys"), *path, *bridge, *added;
    if (sys == NULL) goto fail;
    path = py.GetAttrString(sys, "path");
    py.DecRef(sys);
    if (path == NULL) goto fail;
    added = py.CallMethod(path, "insert", "is", 0, resources);
    py.DecRef(path);
    if (added == NULL) goto fail;
    py.DecRef(added);
    bridge = py.ImportModule("pantocosim_fmi2_bridge");
    if (bridge == NULL) goto fail;
    c->adapter = py.CallMethod(bridge, "instantiate", "sssin", resources, c->instanceName,
                               guid ? guid : "", visible, (Py_ssize_t)(intptr_t)c);
    py.DecRef(bridge);
    if (c->adapter == NULL) goto fail;
    return 1;
fail:
    take_exception(message, sizeof message);
    LOGF(c, fmi2Error, "fmi2Instantiate: %s", message);
    return 0;
}

EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType,
                                     fmi2String fmuGUID, fmi2String fmuResourceLocation,
                                     const fmi2CallbackFunctions *functions,
                                     fmi2Boolean visible, fmi2Boolean loggingOn)
{
    Component *c;
    char *resources;
    int gil, ok;
    const char *name = instanceName ? instanceName : "";
    if (fmuType != fmi2CoSimulation) {
        log_to(functions, name, fmi2Error, "logStatusError",
               "fmi2Instantiate: this FMU supports co-simulation only");
        return NULL;
    }
    resources = resources_path(fmuResourceLocation);
    if (resources == NULL) {
        log_to(functions, name, fmi2Error, "logStatusError",
               "fmi2Instantiate: fmuResourceLocation is NULL: the FMU needs its resources");
        return NULL;
    }
    if (!ensure_runtime(resources)) {
        log_to(functions, name, fmi2Error, "logStatusError", runtime_problem);
        free(resources);
        return NULL;
    }
    c = calloc(1, sizeof *c);
    if (c == NULL) {
        free(resources);
        return NULL;
    }
    c->magic = COMPONENT_MAGIC;
    c->instanceName = strdup(name);
    c->loggingOn = loggingOn;
    if (functions) c->callbacks = *functions;
    gil = py.GILEnsure();
    ok = make_adapter(c, resources, fmuGUID, visible);
    if (ok) done(c, py.CallMethod(c->adapter, "status", NULL), "fmi2Instantiate");
    py.GILRelease(gil);
    free(resources);
    if (!ok || !register_component(c)) {
        if (ok) LOGF(c, fmi2Error, "fmi2Instantiate: more than %d live instances",
                     MAX_COMPONENTS);
        gil = py.GILEnsure();
        if (c->adapter) py.DecRef(c->adapter);
        py.GILRelease(gil);
        free_component(c);
        return NULL;
    }
    return c;
}

static void drop_state(State *s)
{
    if (s->object) py.DecRef(s->object);
    if (s->bytes) py.DecRef(s->bytes);
    s->magic = 0;
    free(s);
}

EXPORT void fmi2FreeInstance(fmi2Component comp)
{
    Component *c = (Component *)comp;
    int gil;
    if (!registered(c)) return;
    unregister_component(c);
    gil = py.GILEnsure();
    while (c->states) {
        State *next = c->states->next;
        drop_state(c->states);
        c->states = next;
    }
    done(c, py.CallMethod(c->adapter, "free", NULL), "fmi2FreeInstance");
    py.DecRef(c->adapter);
    py.GILRelease(gil);
    free_component(c);
}

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean loggingOn,
                                      size_t nCategories, const fmi2String categories[])
{
    ENTER(comp, "fmi2SetDebugLogging");
    PyObject *list = py.ListNew(0);
    for (size_t i = 0; list && categories && i < nCategories; i++) {
        PyObject *s = py.UnicodeFromString(categories[i] ? categories[i] : "");
        py.CallMethod(list, "append", "O", s);
        py.DecRef(s);
    }
    c->loggingOn = loggingOn;
    fmi2Status status = done(c, py.CallMethod(c->adapter, "set_debug_logging", "iO",
                                                loggingOn, list), "fmi2SetDebugLogging");
    py.DecRef(list);
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

/* --- get/set: the bridge takes lists and returns (status, values) or a status */
#define GETTER(fn, T, method, convert)                                                 \
    EXPORT fmi2Status fn(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, \
                         T value[])                                                    \
    {                                                                                  \
        ENTER(comp, #fn);                                                              \
        if (!arrays_given(c, #fn, vr, nvr, value)) LEAVE(fmi2Error);                   \
        PyObject *refs = vr_list(vr, nvr);                                             \
        PyObject *result = py.CallMethod(c->adapter, method, "O", refs);               \
        py.DecRef(refs);                                                               \
        fmi2Status status = status_of(c, result, #fn);                                    \
        if (result != NULL) {                                                          \
            PyObject *values = py.TupleGetItem(result, 1);                             \
            for (size_t i = 0; values && status < fmi2Discard && i < nvr; i++) {       \
                PyObject *item = py.ListGetItem(values, (Py_ssize_t)i);                \
                if (item == NULL) break;                                               \
                value[i] = convert;                                                    \
            }                                                                          \
            if (py.ErrOccurred()) {                                                    \
                py.ErrClear();                                                         \
                status = fmi2Error;                                                    \
                LOGF(c, fmi2Error, "%s: the slave returned values of the wrong type", #fn); \
            }                                                                          \
            py.DecRef(result);                                                         \
        }                                                                              \
        LEAVE(status);                                                                 \
    }

GETTER(fmi2GetReal, fmi2Real, "get_real", py.FloatAsDouble(item))
GETTER(fmi2GetInteger, fmi2Integer, "get_integer", (fmi2Integer)py.LongAsLong(item))
GETTER(fmi2GetBoolean, fmi2Boolean, "get_boolean", (fmi2Boolean)(py.LongAsLong(item) != 0))

EXPORT fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                fmi2String value[])
{
    ENTER(comp, "fmi2GetString");
    if (!arrays_given(c, "fmi2GetString", vr, nvr, value)) LEAVE(fmi2Error);
    PyObject *refs = vr_list(vr, nvr);
    /* the strings stay valid until the next call: the adapter keeps the list it returns */
    PyObject *result = py.CallMethod(c->adapter, "get_string", "O", refs);
    py.DecRef(refs);
    fmi2Status status = status_of(c, result, "fmi2GetString");
    if (result != NULL) {
        PyObject *values = py.TupleGetItem(result, 1);
        for (size_t i = 0; values && status < fmi2Discard && i < nvr; i++) {
            PyObject *item = py.ListGetItem(values, (Py_ssize_t)i);
            value[i] = item ? py.UnicodeAsUTF8(item) : NULL;
            if (value[i] == NULL) {
                py.ErrClear();
                value[i] = "";
                status = fmi2Error;
                LOGF(c, fmi2Error, "fmi2GetString: the slave returned no string for vr %u",
                     vr[i]);
            }
        }
        py.DecRef(result);
    }
    LEAVE(status);
}

#define SETTER(fn, T, method, make)                                                    \
    EXPORT fmi2Status fn(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, \
                         const T value[])                                              \
    {                                                                                  \
        ENTER(comp, #fn);                                                              \
        if (!arrays_given(c, #fn, vr, nvr, value)) LEAVE(fmi2Error);                   \
        PyObject *refs = vr_list(vr, nvr), *values = py.ListNew((Py_ssize_t)nvr);       \
        for (size_t i = 0; values && i < nvr; i++)                                     \
            py.ListSetItem(values, (Py_ssize_t)i, make);                               \
        fmi2Status status = done(c, py.CallMethod(c->adapter, method, "OO", refs,       \
                                                  values), #fn);                       \
        py.DecRef(refs);                                                               \
        py.DecRef(values);                                                             \
        LEAVE(status);                                                                 \
    }

SETTER(fmi2SetReal, fmi2Real, "set_real", py.FloatFromDouble(value[i]))
SETTER(fmi2SetInteger, fmi2Integer, "set_integer", py.LongFromLong(value[i]))
SETTER(fmi2SetBoolean, fmi2Boolean, "set_boolean", py.LongFromLong(value[i] ? 1 : 0))
SETTER(fmi2SetString, fmi2String, "set_string",
       py.UnicodeFromString(value[i] ? value[i] : ""))

/* --- FMU states: C records that are checked before their Python object is touched */
static State *find_state(Component *c, const void *s)
{
    for (State *x = c->states; x; x = x->next)
        if (x == s && x->magic == STATE_MAGIC) return x;
    return NULL;
}

static fmi2Status state_refused(Component *c, const char *call, const void *s)
{
    LOGF(c, fmi2Error, "%s: %p is not an FMU state of instance '%s' (freed, of another "
         "instance, or never made by fmi2GetFMUstate/fmi2DeSerializeFMUstate): nothing done",
         call, s, c->instanceName);
    return fmi2Error;
}

static State *new_state(Component *c, PyObject *object)
{
    State *s = calloc(1, sizeof *s);
    if (s == NULL) return NULL;
    s->magic = STATE_MAGIC;
    s->object = object;
    s->next = c->states;
    c->states = s;
    return s;
}

/* (status, object) from the bridge into a new or the given state */
static fmi2Status keep_state(Component *c, PyObject *result, fmi2FMUstate *out, State *reuse,
                             const char *call)
{
    fmi2Status status = status_of(c, result, call);
    PyObject *object = result ? py.TupleGetItem(result, 1) : NULL;
    if (status < fmi2Discard && object) {
        py.IncRef(object);
        if (reuse) {
            py.DecRef(reuse->object);
            if (reuse->bytes) py.DecRef(reuse->bytes);
            reuse->bytes = NULL;
            reuse->object = object;
        } else if ((*out = new_state(c, object)) == NULL) {
            py.DecRef(object);
            status = fmi2Error;
        }
    }
    if (result) py.DecRef(result);
    return status;
}

EXPORT fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate)
{
    ENTER(comp, "fmi2GetFMUstate");
    State *reuse = NULL;
    if (FMUstate == NULL) {
        LOGF(c, fmi2Error, "fmi2GetFMUstate: FMUstate is NULL");
        LEAVE(fmi2Error);
    }
    if (*FMUstate != NULL && (reuse = find_state(c, *FMUstate)) == NULL)
        LEAVE(state_refused(c, "fmi2GetFMUstate", *FMUstate));
    LEAVE(keep_state(c, py.CallMethod(c->adapter, "get_state", NULL), FMUstate, reuse,
                     "fmi2GetFMUstate"));
}

EXPORT fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate FMUstate)
{
    ENTER(comp, "fmi2SetFMUstate");
    State *s = find_state(c, FMUstate);
    if (s == NULL) LEAVE(state_refused(c, "fmi2SetFMUstate", FMUstate));
    LEAVE(done(c, py.CallMethod(c->adapter, "set_state", "O", s->object),
                 "fmi2SetFMUstate"));
}

EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate)
{
    ENTER(comp, "fmi2FreeFMUstate");
    if (FMUstate == NULL || *FMUstate == NULL) LEAVE(fmi2OK);
    State *s = find_state(c, *FMUstate);
    if (s == NULL) LEAVE(state_refused(c, "fmi2FreeFMUstate", *FMUstate));
    for (State **p = &c->states; *p; p = &(*p)->next) {
        if (*p == s) {
            *p = s->next;
            break;
        }
    }
    drop_state(s);
    *FMUstate = NULL;
    LEAVE(fmi2OK);
}

static fmi2Status serialised(Component *c, State *s, const char *call)
{
    if (s->bytes) return fmi2OK;
    PyObject *result = py.CallMethod(c->adapter, "serialize", "O", s->object);
    fmi2Status status = status_of(c, result, call);
    if (result && status < fmi2Discard) {
        s->bytes = py.TupleGetItem(result, 1);
        py.IncRef(s->bytes);
    }
    if (result) py.DecRef(result);
    return s->bytes ? status : fmi2Error;
}

EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate FMUstate,
                                             size_t *size)
{
    ENTER(comp, "fmi2SerializedFMUstateSize");
    char *data;
    Py_ssize_t n;
    State *s = find_state(c, FMUstate);
    if (s == NULL) LEAVE(state_refused(c, "fmi2SerializedFMUstateSize", FMUstate));
    fmi2Status status = serialised(c, s, "fmi2SerializedFMUstateSize");
    if (status >= fmi2Discard || size == NULL) LEAVE(size ? status : fmi2Error);
    py.BytesAsStringAndSize(s->bytes, &data, &n);
    *size = (size_t)n;
    LEAVE(status);
}

EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate FMUstate,
                                        fmi2Byte serializedState[], size_t size)
{
    ENTER(comp, "fmi2SerializeFMUstate");
    char *data;
    Py_ssize_t n;
    State *s = find_state(c, FMUstate);
    if (s == NULL) LEAVE(state_refused(c, "fmi2SerializeFMUstate", FMUstate));
    fmi2Status status = serialised(c, s, "fmi2SerializeFMUstate");
    if (status >= fmi2Discard) LEAVE(status);
    py.BytesAsStringAndSize(s->bytes, &data, &n);
    if (serializedState == NULL || size < (size_t)n) {
        LOGF(c, fmi2Error, "fmi2SerializeFMUstate: the buffer holds %zu bytes; the state "
             "needs %zd (fmi2SerializedFMUstateSize)", size, n);
        LEAVE(fmi2Error);
    }
    memcpy(serializedState, data, (size_t)n);
    LEAVE(status);
}

EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte serializedState[],
                                          size_t size, fmi2FMUstate *FMUstate)
{
    ENTER(comp, "fmi2DeSerializeFMUstate");
    if (FMUstate == NULL || (serializedState == NULL && size > 0)) {
        LOGF(c, fmi2Error, "fmi2DeSerializeFMUstate: NULL argument");
        LEAVE(fmi2Error);
    }
    PyObject *bytes = py.BytesFromStringAndSize(serializedState, (Py_ssize_t)size);
    PyObject *result = py.CallMethod(c->adapter, "deserialize", "O", bytes);
    py.DecRef(bytes);
    LEAVE(keep_state(c, result, FMUstate, NULL, "fmi2DeSerializeFMUstate"));
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

static fmi2Status status_call(Component *c, const char *call, fmi2StatusKind s, int *integer,
                              double *real)
{
    PyObject *result = py.CallMethod(c->adapter, "status_of", "i", (int)s);
    fmi2Status status = status_of(c, result, call);
    if (result && status < fmi2Discard) {
        PyObject *value = py.TupleGetItem(result, 1);
        if (integer) *integer = (int)py.LongAsLong(value);
        if (real) *real = py.FloatAsDouble(value);
    }
    if (result) py.DecRef(result);
    return status;
}

EXPORT fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value)
{
    ENTER(comp, "fmi2GetStatus");
    int v = 0;
    fmi2Status status = value ? status_call(c, "fmi2GetStatus", s, &v, NULL) : fmi2Error;
    if (value && status < fmi2Discard) *value = (fmi2Status)v;
    LEAVE(status);
}

EXPORT fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s,
                                    fmi2Real *value)
{
    ENTER(comp, "fmi2GetRealStatus");
    LEAVE(value ? status_call(c, "fmi2GetRealStatus", s, NULL, value) : fmi2Error);
}

EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s,
                                       fmi2Integer *value)
{
    ENTER(comp, "fmi2GetIntegerStatus");
    LEAVE(value ? status_call(c, "fmi2GetIntegerStatus", s, value, NULL) : fmi2Error);
}

EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s,
                                       fmi2Boolean *value)
{
    ENTER(comp, "fmi2GetBooleanStatus");
    LEAVE(value ? status_call(c, "fmi2GetBooleanStatus", s, value, NULL) : fmi2Error);
}

EXPORT fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s,
                                      fmi2String *value)
{
    ENTER(comp, "fmi2GetStringStatus");
    (void)s;
    if (value) *value = "";
    LOGF(c, fmi2Discard, "fmi2GetStringStatus: no string status (the FMU never returns "
         "fmi2Pending)");
    LEAVE(fmi2Discard);
}

/* --- calls this FMU does not honour: fmi2Error with the reason */
static fmi2Status unsupported(fmi2Component comp, const char *call, const char *why)
{
    Component *c = (Component *)comp;
    if (!registered(c)) return fmi2Error;
    LOGF(c, fmi2Error, "%s: not supported (%s)", call, why);
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
