/*
 * The version-neutral part of pantocosim's FMI export libraries (export_common.h):
 *
 * - it finds a Python runtime itself: the host's interpreter when the host is a Python
 *   process, else the executable named by $PANTOCOSIM_PYTHON, else the interpreter that
 *   built the FMU (resources/pantocosim_runtime.txt), else python3 on PATH, each probed for
 *   its shared libpython and for numpy, scipy and numba; libpython is opened at
 *   run time, so the library links no Python and needs no LD_PRELOAD or PYTHONPATH;
 * - instances and FMU states are checked before use: a freed, foreign or forged pointer gives
 *   an Error status, never a crash;
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

#include "export_common.h"

PythonApi py;

/* ------------------------------------------------------------------ components */
#define COMPONENT_MAGIC 0x70616e746f636f6dULL
#define STATE_MAGIC 0x70616e746f737461ULL
#define MAX_COMPONENTS 1024
#define STATUS_LOG_FLAG 16 /* the bridge's "messages are waiting" bit */

static pthread_mutex_t registry_lock = PTHREAD_MUTEX_INITIALIZER;
static Component *live[MAX_COMPONENTS];

int registered(const Component *c)
{
    int found = 0;
    if (c == NULL) return 0;
    pthread_mutex_lock(&registry_lock);
    for (int i = 0; i < MAX_COMPONENTS && !found; i++) found = live[i] == c;
    pthread_mutex_unlock(&registry_lock);
    return found && c->magic == COMPONENT_MAGIC;
}

int register_component(Component *c)
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

Component *new_component(const char *instanceName, int loggingOn, LogSink sink,
                         void *hostLogger, void *hostEnvironment)
{
    Component *c = calloc(1, sizeof *c);
    if (c == NULL) return NULL;
    c->magic = COMPONENT_MAGIC;
    c->instanceName = strdup(instanceName ? instanceName : "");
    c->loggingOn = loggingOn;
    c->sink = sink;
    c->hostLogger = hostLogger;
    c->hostEnvironment = hostEnvironment;
    return c;
}

static void drop_state(State *s)
{
    if (s->object) py.DecRef(s->object);
    if (s->bytes) py.DecRef(s->bytes);
    s->magic = 0;
    free(s);
}

void free_component(Component *c, const char *call)
{
    int gil;
    unregister_component(c);
    if (c->adapter) {
        gil = py.GILEnsure();
        while (c->states) {
            State *next = c->states->next;
            drop_state(c->states);
            c->states = next;
        }
        done(c, py.CallMethod(c->adapter, "free", NULL), call);
        py.DecRef(c->adapter);
        py.GILRelease(gil);
    }
    free(c->instanceName);
    c->magic = 0;
    free(c);
}

/* ------------------------------------------------------------------ logging */
const char *category_of(int status)
{
    switch (status) {
    case ST_OK: return "logAll";
    case ST_WARNING: return "logStatusWarning";
    case ST_DISCARD: return "logStatusDiscard";
    case ST_ERROR: return "logStatusError";
    default: return "logStatusFatal";
    }
}

void log_message(const Component *c, int status, const char *category, const char *message)
{
    if (category == NULL) category = category_of(status);
    if (message == NULL) message = "";
    if (c == NULL || c->sink == NULL || c->hostLogger == NULL) {
        if (status >= ST_ERROR)
            fprintf(stderr, "[%s] %s: %s\n", category, c ? c->instanceName : "", message);
        return;
    }
    c->sink(c, status, category, message);
}

void logf_message(const Component *c, int status, const char *fmt, ...)
{
    char buffer[4096];
    va_list args;
    va_start(args, fmt);
    vsnprintf(buffer, sizeof buffer, fmt, args);
    va_end(args);
    log_message(c, status, category_of(status), buffer);
}

/* ------------------------------------------------------------------ finding Python */
static pthread_mutex_t runtime_lock = PTHREAD_MUTEX_INITIALIZER;
static int runtime_ready = 0;
static char problem[8192];

const char *runtime_problem(void) { return problem; }

#define RESOLVE(field, name)                                                   \
    do {                                                                       \
        *(void **)(&py.field) = dlsym(lib, name);                              \
        if (py.field == NULL) {                                                \
            snprintf(problem, sizeof problem,                                  \
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
    size_t used = strlen(problem);
    va_list args;
    if (used >= sizeof problem - 1) return;
    va_start(args, fmt);
    vsnprintf(problem + used, sizeof problem - used, fmt, args);
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
int ensure_runtime(const char *resources)
{
    char runtime_file[PATH_MAX], exe[PATH_MAX];
    int ok = 0;
    pthread_mutex_lock(&runtime_lock);
    if (runtime_ready) {
        pthread_mutex_unlock(&runtime_lock);
        return 1;
    }
    problem[0] = '\0';
    if (dlsym(RTLD_DEFAULT, "Py_IsInitialized") != NULL) {
        ok = resolve_api(RTLD_DEFAULT);
        if (ok && !py.IsInitialized()) {
            py.InitializeEx(0);
            py.SaveThread();
        }
    } else {
        snprintf(runtime_file, sizeof runtime_file, "%s/pantocosim_runtime.txt", resources);
        read_key(runtime_file, "executable", exe, sizeof exe);
        snprintf(problem, sizeof problem, "no usable Python runtime");
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
void take_exception(char *out, size_t size)
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
        int status = s ? (int)py.LongAsLong(s) : ST_ERROR;
        if (py.ErrOccurred()) py.ErrClear();
        if (status == ST_OK && !c->loggingOn) continue;
        log_message(c, status, category, text ? text : "(no text)");
    }
    if (py.ErrOccurred()) py.ErrClear();
    py.DecRef(messages);
}

int status_of(Component *c, PyObject *result, const char *call)
{
    PyObject *item;
    long code;
    if (result == NULL) {
        char message[2048];
        take_exception(message, sizeof message);
        LOGF(c, ST_ERROR, "%s: %s", call, message);
        return ST_ERROR;
    }
    item = py.TupleGetItem(result, 0);
    code = item ? py.LongAsLong(item) : -1;
    if (code < 0 || py.ErrOccurred()) {
        py.ErrClear();
        LOGF(c, ST_ERROR, "%s: the FMU's bridge returned no status", call);
        return ST_ERROR;
    }
    if (code & STATUS_LOG_FLAG) forward_log(c);
    code &= ~STATUS_LOG_FLAG;
    return code > ST_ERROR ? ST_ERROR : (int)code;
}

int done(Component *c, PyObject *result, const char *call)
{
    int status = status_of(c, result, call);
    if (result) py.DecRef(result);
    return status;
}

PyObject *vr_list(const unsigned int vr[], size_t n)
{
    PyObject *list = py.ListNew((Py_ssize_t)n);
    for (size_t i = 0; list && i < n; i++)
        py.ListSetItem(list, (Py_ssize_t)i, py.LongFromLong((long)vr[i]));
    return list;
}

int arrays_given(Component *c, const char *call, const void *vr, size_t n, const void *values)
{
    if (n > 0 && (vr == NULL || values == NULL)) {
        LOGF(c, ST_ERROR, "%s: NULL value reference or value array for %zu values", call, n);
        return 0;
    }
    return 1;
}

char *resources_path(const char *location)
{
    const char *path = location;
    char *out, *r, *w;
    int uri = 0;
    if (location == NULL) return NULL;
    if (strncmp(path, "file://", 7) == 0) {
        path += 7;
        if (strncmp(path, "localhost/", 10) == 0) path += 9;
        uri = 1;
    } else if (strncmp(path, "file:", 5) == 0) {
        path += 5;
        uri = 1;
    }
    out = strdup(path);
    if (out == NULL) return NULL;
    for (r = w = out; *r; r++, w++) { /* percent-decoding of a URI */
        if (uri && r[0] == '%' && r[1] && r[2]) {
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

int make_adapter(Component *c, const char *resources, const char *bridge_module, int fmi,
                 const char *token, int visible, const char *call)
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
    bridge = py.ImportModule(bridge_module);
    if (bridge == NULL) goto fail;
    c->adapter = py.CallMethod(bridge, "instantiate", "sssini", resources, c->instanceName,
                               token ? token : "", visible, (Py_ssize_t)(intptr_t)c, fmi);
    py.DecRef(bridge);
    if (c->adapter == NULL) goto fail;
    return 1;
fail:
    take_exception(message, sizeof message);
    LOGF(c, ST_ERROR, "%s: %s", call, message);
    return 0;
}

/* ------------------------------------------------------------------ typed get/set */
int get_values(Component *c, const char *call, const char *method, const unsigned int vr[],
               size_t n, void *out, ValueKind kind)
{
    if (!arrays_given(c, call, vr, n, out)) return ST_ERROR;
    PyObject *refs = vr_list(vr, n);
    PyObject *result = py.CallMethod(c->adapter, method, "O", refs);
    py.DecRef(refs);
    int status = status_of(c, result, call);
    if (result != NULL) {
        PyObject *values = py.TupleGetItem(result, 1);
        for (size_t i = 0; values && status < ST_DISCARD && i < n; i++) {
            PyObject *item = py.ListGetItem(values, (Py_ssize_t)i);
            if (item == NULL) break;
            switch (kind) {
            case V_DOUBLE: ((double *)out)[i] = py.FloatAsDouble(item); break;
            case V_INT: ((int *)out)[i] = (int)py.LongAsLong(item); break;
            case V_INT32: ((int32_t *)out)[i] = (int32_t)py.LongAsLong(item); break;
            case V_CBOOL: ((_Bool *)out)[i] = py.LongAsLong(item) != 0; break;
            case V_INTBOOL: ((int *)out)[i] = py.LongAsLong(item) != 0; break;
            }
        }
        if (py.ErrOccurred()) {
            py.ErrClear();
            status = ST_ERROR;
            LOGF(c, ST_ERROR, "%s: the slave returned values of the wrong type", call);
        }
        py.DecRef(result);
    }
    return status;
}

int set_values(Component *c, const char *call, const char *method, const unsigned int vr[],
               size_t n, const void *in, ValueKind kind)
{
    if (!arrays_given(c, call, vr, n, in)) return ST_ERROR;
    PyObject *refs = vr_list(vr, n), *values = py.ListNew((Py_ssize_t)n);
    for (size_t i = 0; values && i < n; i++) {
        PyObject *item = NULL;
        switch (kind) {
        case V_DOUBLE: item = py.FloatFromDouble(((const double *)in)[i]); break;
        case V_INT: item = py.LongFromLong(((const int *)in)[i]); break;
        case V_INT32: item = py.LongFromLong(((const int32_t *)in)[i]); break;
        case V_CBOOL: item = py.LongFromLong(((const _Bool *)in)[i] ? 1 : 0); break;
        case V_INTBOOL: item = py.LongFromLong(((const int *)in)[i] ? 1 : 0); break;
        }
        py.ListSetItem(values, (Py_ssize_t)i, item);
    }
    int status = done(c, py.CallMethod(c->adapter, method, "OO", refs, values), call);
    py.DecRef(refs);
    py.DecRef(values);
    return status;
}

int get_strings(Component *c, const char *call, const unsigned int vr[], size_t n,
                const char *out[])
{
    if (!arrays_given(c, call, vr, n, out)) return ST_ERROR;
    PyObject *refs = vr_list(vr, n);
    /* the strings stay valid until the next call: the adapter keeps the list it returns */
    PyObject *result = py.CallMethod(c->adapter, "get_string", "O", refs);
    py.DecRef(refs);
    int status = status_of(c, result, call);
    if (result != NULL) {
        PyObject *values = py.TupleGetItem(result, 1);
        for (size_t i = 0; values && status < ST_DISCARD && i < n; i++) {
            PyObject *item = py.ListGetItem(values, (Py_ssize_t)i);
            out[i] = item ? py.UnicodeAsUTF8(item) : NULL;
            if (out[i] == NULL) {
                py.ErrClear();
                out[i] = "";
                status = ST_ERROR;
                LOGF(c, ST_ERROR, "%s: the slave returned no string for vr %u", call, vr[i]);
            }
        }
        py.DecRef(result);
    }
    return status;
}

int set_strings(Component *c, const char *call, const unsigned int vr[], size_t n,
                const char *const in[])
{
    if (!arrays_given(c, call, vr, n, in)) return ST_ERROR;
    PyObject *refs = vr_list(vr, n), *values = py.ListNew((Py_ssize_t)n);
    for (size_t i = 0; values && i < n; i++)
        py.ListSetItem(values, (Py_ssize_t)i, py.UnicodeFromString(in[i] ? in[i] : ""));
    int status = done(c, py.CallMethod(c->adapter, "set_string", "OO", refs, values), call);
    py.DecRef(refs);
    py.DecRef(values);
    return status;
}

/* ------------------------------------------------------------------ FMU states */
static State *find_state(Component *c, const void *s)
{
    for (State *x = c->states; x; x = x->next)
        if (x == s && x->magic == STATE_MAGIC) return x;
    return NULL;
}

static int state_refused(Component *c, const char *call, const void *s)
{
    LOGF(c, ST_ERROR, "%s: %p is not an FMU state of instance '%s' (freed, of another "
         "instance, or never made by this instance): nothing done", call, s, c->instanceName);
    return ST_ERROR;
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
static int keep_state(Component *c, PyObject *result, void **out, State *reuse,
                      const char *call)
{
    int status = status_of(c, result, call);
    PyObject *object = result ? py.TupleGetItem(result, 1) : NULL;
    if (status < ST_DISCARD && object) {
        py.IncRef(object);
        if (reuse) {
            py.DecRef(reuse->object);
            if (reuse->bytes) py.DecRef(reuse->bytes);
            reuse->bytes = NULL;
            reuse->object = object;
        } else if ((*out = new_state(c, object)) == NULL) {
            py.DecRef(object);
            status = ST_ERROR;
        }
    }
    if (result) py.DecRef(result);
    return status;
}

int state_get(Component *c, const char *call, void **state)
{
    State *reuse = NULL;
    if (state == NULL) {
        LOGF(c, ST_ERROR, "%s: the FMU state argument is NULL", call);
        return ST_ERROR;
    }
    if (*state != NULL && (reuse = find_state(c, *state)) == NULL)
        return state_refused(c, call, *state);
    return keep_state(c, py.CallMethod(c->adapter, "get_state", NULL), state, reuse, call);
}

int state_set(Component *c, const char *call, void *state)
{
    State *s = find_state(c, state);
    if (s == NULL) return state_refused(c, call, state);
    return done(c, py.CallMethod(c->adapter, "set_state", "O", s->object), call);
}

int state_free(Component *c, const char *call, void **state)
{
    if (state == NULL || *state == NULL) return ST_OK;
    State *s = find_state(c, *state);
    if (s == NULL) return state_refused(c, call, *state);
    for (State **p = &c->states; *p; p = &(*p)->next) {
        if (*p == s) {
            *p = s->next;
            break;
        }
    }
    drop_state(s);
    *state = NULL;
    return ST_OK;
}

static int serialised(Component *c, State *s, const char *call)
{
    if (s->bytes) return ST_OK;
    PyObject *result = py.CallMethod(c->adapter, "serialize", "O", s->object);
    int status = status_of(c, result, call);
    if (result && status < ST_DISCARD) {
        s->bytes = py.TupleGetItem(result, 1);
        py.IncRef(s->bytes);
    }
    if (result) py.DecRef(result);
    return s->bytes ? status : ST_ERROR;
}

int state_size(Component *c, const char *call, void *state, size_t *size)
{
    char *data;
    Py_ssize_t n;
    State *s = find_state(c, state);
    if (s == NULL) return state_refused(c, call, state);
    int status = serialised(c, s, call);
    if (status >= ST_DISCARD || size == NULL) return size ? status : ST_ERROR;
    py.BytesAsStringAndSize(s->bytes, &data, &n);
    *size = (size_t)n;
    return status;
}

int state_serialize(Component *c, const char *call, void *state, unsigned char *buffer,
                    size_t size)
{
    char *data;
    Py_ssize_t n;
    State *s = find_state(c, state);
    if (s == NULL) return state_refused(c, call, state);
    int status = serialised(c, s, call);
    if (status >= ST_DISCARD) return status;
    py.BytesAsStringAndSize(s->bytes, &data, &n);
    if (buffer == NULL || size < (size_t)n) {
        LOGF(c, ST_ERROR, "%s: the buffer holds %zu bytes; the state needs %zd", call, size,
             n);
        return ST_ERROR;
    }
    memcpy(buffer, data, (size_t)n);
    return status;
}

int state_deserialize(Component *c, const char *call, const unsigned char *data, size_t size,
                      void **state)
{
    if (state == NULL || (data == NULL && size > 0)) {
        LOGF(c, ST_ERROR, "%s: NULL argument", call);
        return ST_ERROR;
    }
    PyObject *bytes = py.BytesFromStringAndSize((const char *)data, (Py_ssize_t)size);
    PyObject *result = py.CallMethod(c->adapter, "deserialize", "O", bytes);
    py.DecRef(bytes);
    return keep_state(c, result, state, NULL, call);
}
