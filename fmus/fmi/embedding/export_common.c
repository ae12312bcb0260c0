/*
 * The version-neutral part of pantocosim's FMI embedding libraries (export_common.h):
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
#include <ctype.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <wchar.h>

extern char **environ;

#include "export_common.h"

PythonApi py;

/* ------------------------------------------------------------------ components */
#define COMPONENT_MAGIC 0x70616e746f636f6dULL
#define STATE_MAGIC 0x70616e746f737461ULL
#define MAX_COMPONENTS 1024
#define STATUS_LOG_FLAG 16 /* the bridge's "messages are waiting" bit */

static pthread_mutex_t registry_lock = PTHREAD_MUTEX_INITIALIZER;
static Component *live[MAX_COMPONENTS];

/* c is in the registry (under registry_lock: only then is c->magic safe to read) */
static int is_live(const Component *c)
{
    for (int i = 0; i < MAX_COMPONENTS; i++)
        if (live[i] == c) return c->magic == COMPONENT_MAGIC;
    return 0;
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
    pthread_mutexattr_t recursive; /* a host's logger may call the instance back */
    Component *c = calloc(1, sizeof *c);
    if (c == NULL) return NULL;
    c->instanceName = strdup(instanceName ? instanceName : "");
    if (c->instanceName == NULL || pthread_mutexattr_init(&recursive) != 0) {
        free(c->instanceName);
        free(c);
        return NULL;
    }
    pthread_mutexattr_settype(&recursive, PTHREAD_MUTEX_RECURSIVE);
    int made = pthread_mutex_init(&c->call_lock, &recursive);
    pthread_mutexattr_destroy(&recursive);
    if (made != 0) {
        free(c->instanceName);
        free(c);
        return NULL;
    }
    c->magic = COMPONENT_MAGIC;
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

/* the states and the adapter released (the GIL is taken here) */
static void drop_python(Component *c, const char *call)
{
    int gil;
    if (c->adapter == NULL) return;
    gil = py.GILEnsure();
    while (c->states) {
        State *next = c->states->next;
        drop_state(c->states);
        c->states = next;
    }
    done(c, py.CallMethod(c->adapter, "free", NULL), call);
    py.DecRef(c->adapter);
    c->adapter = NULL;
    if (py.ErrOccurred()) py.ErrClear();
    py.GILRelease(gil);
}

static void release_memory(Component *c)
{
    pthread_mutex_destroy(&c->call_lock);
    free(c->instanceName);
    c->magic = 0;
    free(c);
}

int enter_component(Component *c)
{
    int ok;
    if (c == NULL) return 0;
    pthread_mutex_lock(&registry_lock);
    ok = is_live(c);
    if (ok) c->users++; /* pinned: its memory stays until leave_component */
    pthread_mutex_unlock(&registry_lock);
    if (!ok) return 0;
    pthread_mutex_lock(&c->call_lock);
    if (c->freed) { /* freed by the call it waited for */
        leave_component(c);
        return 0;
    }
    return 1;
}

void leave_component(Component *c)
{
    int last;
    pthread_mutex_unlock(&c->call_lock);
    pthread_mutex_lock(&registry_lock);
    last = --c->users == 0 && c->freed;
    pthread_mutex_unlock(&registry_lock);
    if (last) release_memory(c);
}

void free_instance(Component *c, const char *call)
{
    if (!enter_component(c)) return;
    c->freed = 1;
    unregister_component(c); /* from now on, new calls are refused */
    drop_python(c, call);
    leave_component(c);
}

void discard_component(Component *c, const char *call)
{
    drop_python(c, call);
    release_memory(c);
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

static void append_problem(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static void append_problem(const char *fmt, ...)
{
    size_t used = strlen(problem);
    va_list args;
    if (used >= sizeof problem - 1) return;
    va_start(args, fmt);
    vsnprintf(problem + used, sizeof problem - used, fmt, args);
    va_end(args);
}

/* the time bound of one probe [s]: $PANTOCOSIM_PROBE_TIMEOUT_S (unset or blank:
   PROBE_TIMEOUT_S), or -1 when it is not a number of seconds > 0 and below
   PROBE_TIMEOUT_MAX_S (the poll's milliseconds stay an int) */
#define PROBE_TIMEOUT_S 30.0
#define PROBE_TIMEOUT_MAX_S 1e6
static double probe_timeout(void)
{
    const char *text = getenv("PANTOCOSIM_PROBE_TIMEOUT_S");
    char *end = NULL;
    double value;
    while (text && isspace((unsigned char)*text)) text++;
    if (text == NULL || *text == '\0') return PROBE_TIMEOUT_S;
    value = strtod(text, &end);
    while (end != text && isspace((unsigned char)*end)) end++;
    return end != text && *end == '\0' && value > 0.0 && value < PROBE_TIMEOUT_MAX_S ? value
                                                                                     : -1.0;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Start `exe -I -c PROBE` (posix_spawnp: no fork of a possibly threaded host) in a process
   group of its own, its standard output into *out_fd; its pid, or -1 with errno's text in
   why. */
static pid_t spawn_probe(const char *exe, int *out_fd, char *why, size_t why_size)
{
    int fds[2], err;
    pid_t pid = -1;
    posix_spawn_file_actions_t actions;
    posix_spawnattr_t attr;
    sigset_t none, defaults;
    char *argv[] = {(char *)exe, "-I", "-c", (char *)PROBE, NULL};
    if (pipe2(fds, O_CLOEXEC) != 0) {
        snprintf(why, why_size, "cannot be started (pipe: %s)", strerror(errno));
        return -1;
    }
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
    posix_spawnattr_init(&attr);
    sigemptyset(&none);
    sigemptyset(&defaults); /* the host's handlers and mask are not the probe's */
    sigaddset(&defaults, SIGPIPE);
    sigaddset(&defaults, SIGINT);
    sigaddset(&defaults, SIGTERM);
    posix_spawnattr_setsigmask(&attr, &none);
    posix_spawnattr_setsigdefault(&attr, &defaults);
    posix_spawnattr_setpgroup(&attr, 0);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK
                                        | POSIX_SPAWN_SETSIGDEF);
    err = posix_spawnp(&pid, exe, &actions, &attr, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attr);
    close(fds[1]);
    if (err != 0) {
        close(fds[0]);
        snprintf(why, why_size, "does not run (%s)", strerror(err));
        return -1;
    }
    *out_fd = fds[0];
    return pid;
}

/* What the probe prints, into out (at most size - 1 bytes, the rest read and dropped, so
   the probe never blocks on a full pipe), until it closes its output or `limit` seconds
   have passed; 1 if it closed its output in time. */
static int read_probe(int fd, char *out, size_t size, double limit)
{
    size_t used = 0;
    double deadline = now_s() + limit;
    char scratch[4096];
    for (;;) {
        double left = deadline - now_s();
        struct pollfd p = {fd, POLLIN, 0};
        ssize_t n;
        int ready;
        if (left <= 0.0) break;
        ready = poll(&p, 1, (int)(left * 1000.0) + 1);
        if (ready < 0 && errno == EINTR) continue;
        if (ready <= 0) break;
        if (used + 1 < size) n = read(fd, out + used, size - 1 - used);
        else n = read(fd, scratch, sizeof scratch);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            out[used] = '\0';
            return n == 0;
        }
        if (used + 1 < size) used += (size_t)n;
    }
    out[used] = '\0';
    return 0;
}

/* The next line of *text into out (size bytes, without its newline); 0 when it does not fit */
static int next_line(const char **text, char *out, size_t size)
{
    size_t n = strcspn(*text, "\n");
    int fits = n < size;
    snprintf(out, size, "%.*s", (int)(fits ? n : size - 1), *text);
    out[strcspn(out, "\r")] = '\0';
    *text += n + ((*text)[n] == '\n');
    return fits;
}

/* Run the probe in `exe` within the time bound and read its three lines (libpython,
   executable, modules it lacks); 1 if it answered, else 0 with the reason in why. */
static int probe_python(const char *exe, char *lib, char *resolved, char *missing,
                        size_t size, char *why, size_t why_size)
{
    char output[3 * PATH_MAX + 256];
    const char *text = output;
    double limit = probe_timeout();
    int fd = -1, status = 0, closed, waited, fits;
    pid_t pid = spawn_probe(exe, &fd, why, why_size);
    if (pid < 0) return 0;
    closed = read_probe(fd, output, sizeof output, limit);
    close(fd);
    if (!closed) kill(-pid, SIGKILL); /* the probe and whatever it started */
    while ((waited = (int)waitpid(pid, &status, 0)) < 0 && errno == EINTR) {
    }
    if (!closed) {
        snprintf(why, why_size, "did not answer within %g s (stopped; "
                 "PANTOCOSIM_PROBE_TIMEOUT_S sets this time bound)", limit);
        return 0;
    }
    if (waited == pid && !(WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
        if (WIFSIGNALED(status))
            snprintf(why, why_size, "does not run (killed by signal %d)", WTERMSIG(status));
        else
            snprintf(why, why_size, "does not run (exit status %d)", WEXITSTATUS(status));
        return 0;
    } /* waited < 0 (the host reaps its children itself): its answer decides */
    fits = next_line(&text, lib, size);
    fits &= next_line(&text, resolved, size);
    fits &= next_line(&text, missing, size);
    if (!fits || *resolved == '\0') {
        snprintf(why, why_size, "is not a Python that answers the probe (it printed %.200s%s)",
                 output, strlen(output) > 200 ? "..." : "");
        return 0;
    }
    return 1;
}

/* the Python the FMUs run in, for messages: "the host process's own Python" or the
   candidate that was started */
static char runtime_origin[2 * PATH_MAX + 256];

const char *runtime_used(void) { return runtime_origin; }

/* Open libpython `lib` and start its interpreter as if run as `exe` (its venv, its
   site-packages). The GIL is released afterwards; the interpreter is never finalised. */
static int start_interpreter(const char *lib_path, const char *exe, const char *origin)
{
    void *lib = dlopen(lib_path, RTLD_NOW | RTLD_GLOBAL);
    if (lib == NULL) {
        append_problem("; %s %s: %s", origin, exe, dlerror());
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
    snprintf(runtime_origin, sizeof runtime_origin, "%.200s %.4095s (%.4095s)", origin, exe,
             lib_path);
    return 1;
}

static int try_candidate(const char *exe, const char *origin)
{
    char lib[PATH_MAX], resolved[PATH_MAX], missing[PATH_MAX], why[512];
    if (exe == NULL || *exe == '\0') return 0;
    if (!probe_python(exe, lib, resolved, missing, sizeof lib, why, sizeof why)) {
        append_problem("; %s %s: %s", origin, exe, why);
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
    return start_interpreter(lib, resolved, origin);
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
        Dl_info where;
        void *symbol = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
        ok = resolve_api(RTLD_DEFAULT);
        if (ok && !py.IsInitialized()) {
            py.InitializeEx(0);
            py.SaveThread();
        }
        snprintf(runtime_origin, sizeof runtime_origin, "the host process's own Python (%s, "
                 "already loaded in the process: the FMU runs in it, so it needs numpy, "
                 "scipy and numba)",
                 dladdr(symbol, &where) && where.dli_fname ? where.dli_fname : "linked in");
    } else if (probe_timeout() < 0.0) {
        snprintf(problem, sizeof problem, "environment variable: PANTOCOSIM_PROBE_TIMEOUT_S = "
                 "'%.200s': not a time bound: give seconds, a number > 0 and below %g "
                 "(default %g)", getenv("PANTOCOSIM_PROBE_TIMEOUT_S"), PROBE_TIMEOUT_MAX_S,
                 PROBE_TIMEOUT_S);
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
    if (ok && strchr(problem, ';')) { /* started on a later candidate: say which, and why */
        char skipped[sizeof problem];
        snprintf(skipped, sizeof skipped, "%s", strchr(problem, ';') + 2);
        snprintf(problem, sizeof problem, "the FMUs run in %.2000s; skipped: %.6000s",
                 runtime_origin, skipped);
        ok = 2;
    }
    runtime_ready = ok != 0;
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

int leave_clean(Component *c, const char *call, int status)
{
    char message[2048];
    if (!py.ErrOccurred()) return status;
    take_exception(message, sizeof message);
    LOGF(c, ST_ERROR, "%s: a Python error was left pending (cleared): %s", call, message);
    return status > ST_ERROR ? status : ST_ERROR;
}

PyObject *put_item(PyObject *list, size_t i, PyObject *item)
{
    if (list == NULL) {
        if (item) py.DecRef(item);
        return NULL;
    }
    if (item == NULL || py.ListSetItem(list, (Py_ssize_t)i, item) != 0) { /* item stolen */
        py.DecRef(list);
        return NULL;
    }
    return list;
}

PyObject *vr_list(const unsigned int vr[], size_t n)
{
    PyObject *list = py.ListNew((Py_ssize_t)n);
    for (size_t i = 0; list && i < n; i++)
        list = put_item(list, i, py.LongFromLong((long)vr[i]));
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

int resources_complete(Component *c, const char *resources, const char *location,
                       const char *bridge_module, const char *call)
{
    char bridge[PATH_MAX];
    struct stat info;
    if (stat(resources, &info) != 0 || !S_ISDIR(info.st_mode)) {
        LOGF(c, ST_ERROR, "%s: the FMU's resources folder %s is missing (%s; the resource "
             "location given is '%s'): it holds the FMU's Python model and its bridge "
             "%s.py; extract the whole FMU", call, resources,
             stat(resources, &info) != 0 ? strerror(errno) : "not a folder", location,
             bridge_module);
        return 0;
    }
    snprintf(bridge, sizeof bridge, "%s/%s.py", resources, bridge_module);
    if (access(bridge, R_OK) != 0) {
        LOGF(c, ST_ERROR, "%s: the FMU's resources folder %s has no readable %s.py (%s): the "
             "FMU is incomplete; build it again with pantocosim build-fmus", call, resources,
             bridge_module, strerror(errno));
        return 0;
    }
    return 1;
}

/* "Python 3.11.2 (/usr/bin/python3, prefix /usr)" of the running interpreter, into out */
static void python_identity(char *out, size_t size)
{
    const char *names[] = {"version", "executable", "prefix"};
    char text[3][512] = {"?", "?", "?"};
    PyObject *sys = py.ImportModule("sys");
    for (int i = 0; sys && i < 3; i++) {
        PyObject *value = py.GetAttrString(sys, names[i]);
        PyObject *str = value ? py.ObjectStr(value) : NULL;
        const char *utf8 = str ? py.UnicodeAsUTF8(str) : NULL;
        if (utf8) snprintf(text[i], sizeof text[i], "%s", utf8);
        if (str) py.DecRef(str);
        if (value) py.DecRef(value);
    }
    if (sys) py.DecRef(sys);
    if (py.ErrOccurred()) py.ErrClear();
    text[0][strcspn(text[0], " ")] = '\0';
    snprintf(out, size, "Python %s (sys.executable '%s', prefix %s)", text[0], text[1],
             text[2]);
}

int make_adapter(Component *c, const char *resources, const char *bridge_module, int fmi,
                 const char *token, int visible, const char *call)
{
    char message[4096], identity[1600];
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
    python_identity(identity, sizeof identity);
    LOGF(c, ST_ERROR, "%s: %s [in %s: %s]", call, message, identity, runtime_used());
    return 0;
}

/* ------------------------------------------------------------------ typed get/set */
int get_values(Component *c, const char *call, const char *method, const unsigned int vr[],
               size_t n, void *out, ValueKind kind)
{
    if (!arrays_given(c, call, vr, n, out)) return ST_ERROR;
    PyObject *refs = vr_list(vr, n);
    PyObject *result = refs ? py.CallMethod(c->adapter, method, "O", refs) : NULL;
    if (refs) py.DecRef(refs);
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
    PyObject *refs = vr_list(vr, n), *values = refs ? py.ListNew((Py_ssize_t)n) : NULL;
    for (size_t i = 0; values && i < n; i++) {
        PyObject *item = NULL;
        switch (kind) {
        case V_DOUBLE: item = py.FloatFromDouble(((const double *)in)[i]); break;
        case V_INT: item = py.LongFromLong(((const int *)in)[i]); break;
        case V_INT32: item = py.LongFromLong(((const int32_t *)in)[i]); break;
        case V_CBOOL: item = py.LongFromLong(((const _Bool *)in)[i] ? 1 : 0); break;
        case V_INTBOOL: item = py.LongFromLong(((const int *)in)[i] ? 1 : 0); break;
        }
        values = put_item(values, i, item);
    }
    int status = done(c, values ? py.CallMethod(c->adapter, method, "OO", refs, values) : NULL,
                      call);
    if (refs) py.DecRef(refs);
    if (values) py.DecRef(values);
    return status;
}

int get_strings(Component *c, const char *call, const unsigned int vr[], size_t n,
                const char *out[])
{
    if (!arrays_given(c, call, vr, n, out)) return ST_ERROR;
    PyObject *refs = vr_list(vr, n);
    /* the strings stay valid until the next call: the adapter keeps the list it returns */
    PyObject *result = refs ? py.CallMethod(c->adapter, "get_string", "O", refs) : NULL;
    if (refs) py.DecRef(refs);
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
    PyObject *refs = vr_list(vr, n), *values = refs ? py.ListNew((Py_ssize_t)n) : NULL;
    for (size_t i = 0; values && i < n; i++)
        values = put_item(values, i, py.UnicodeFromString(in[i] ? in[i] : ""));
    int status = done(c, values ? py.CallMethod(c->adapter, "set_string", "OO", refs, values)
                                : NULL, call);
    if (refs) py.DecRef(refs);
    if (values) py.DecRef(values);
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

/* the state's bytes (made at the first call, then kept) into data and n */
static int serialised(Component *c, State *s, const char *call, char **data, Py_ssize_t *n)
{
    int status = ST_OK;
    if (s->bytes == NULL) {
        PyObject *result = py.CallMethod(c->adapter, "serialize", "O", s->object);
        PyObject *bytes = NULL;
        status = status_of(c, result, call);
        if (result && status < ST_DISCARD) bytes = py.TupleGetItem(result, 1);
        if (bytes) py.IncRef(bytes);
        if (result) py.DecRef(result);
        if (status >= ST_DISCARD) {
            if (bytes) py.DecRef(bytes);
            return status;
        }
        s->bytes = bytes;
    }
    if (s->bytes == NULL || py.BytesAsStringAndSize(s->bytes, data, n) != 0 || *n < 0) {
        char message[1024];
        take_exception(message, sizeof message);
        if (s->bytes) py.DecRef(s->bytes);
        s->bytes = NULL;
        LOGF(c, ST_ERROR, "%s: the FMU's bridge gave no bytes for the state (%s)", call,
             message);
        return ST_ERROR;
    }
    return status;
}

int state_size(Component *c, const char *call, void *state, size_t *size)
{
    char *data = NULL;
    Py_ssize_t n = 0;
    State *s = find_state(c, state);
    if (s == NULL) return state_refused(c, call, state);
    if (size == NULL) {
        LOGF(c, ST_ERROR, "%s: the size argument is NULL", call);
        return ST_ERROR;
    }
    int status = serialised(c, s, call, &data, &n);
    if (status < ST_DISCARD) *size = (size_t)n;
    return status;
}

int state_serialize(Component *c, const char *call, void *state, unsigned char *buffer,
                    size_t size)
{
    char *data = NULL;
    Py_ssize_t n = 0;
    State *s = find_state(c, state);
    if (s == NULL) return state_refused(c, call, state);
    int status = serialised(c, s, call, &data, &n);
    if (status >= ST_DISCARD) return status;
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
    PyObject *result = bytes ? py.CallMethod(c->adapter, "deserialize", "O", bytes) : NULL;
    if (bytes) py.DecRef(bytes);
    return keep_state(c, result, state, NULL, call);
}
