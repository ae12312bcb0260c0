/*
 * A C host for the native FMUs (pantocosim export-native), as a HIL loop runs them: no
 * Python, one process, the FMUs' own binaries loaded with dlopen / LoadLibrary.
 *
 *   realtime_host forced CATENARY_DIR STEPS DT [SUBSTEPS]
 *       the catenary alone under F_k(t) = F0_k (1 + 0.1 sin(2 pi 7 t)) + 20 [t > 0.3 s]
 *       (contact_mode 0); prints "t wire_height_k wire_velocity_k ... support_uplift_j"
 *       per step with 17 digits, then the p50 / p99 / max of doStep in microseconds
 *   realtime_host coupled CATENARY_DIR PANTOGRAPH_DIR STEPS DT [paced]
 *       the catenary in contact_mode 1 (penalty contact inside) and a pantograph FMU: each
 *       step the pantograph's height and velocity go into the catenary, its contact force
 *       into the pantograph (zero-order hold); prints "t F z_pantograph z_wire" per step,
 *       then the p50 / p99 / max of each FMU's doStep in microseconds; "paced" waits for
 *       the wall clock at every step (busy-waiting) and counts the steps that end after
 *       their deadline t0 + (k + 1) DT
 *   realtime_host coupled-forces CATENARY_DIR PANTOGRAPH_DIR STEPS DT [paced]
 *       the same loop with the catenary in contact_mode 0: the host applies the penalty
 *       law F = max(0, k_H (z_pantograph - z_wire)) (k_H: the catenary's contact_stiffness)
 *       and gives F to both FMUs, as an explicit co-simulation master does
 *   realtime_host pantograph PANTOGRAPH_DIR STEPS DT
 *       the pantograph alone under F(t) = F0 (1 + 0.1 sin(2 pi 7 t)); prints "t z v"
 *
 * Every mode prints "allocations in doStep: N": on Linux the host interposes malloc,
 * calloc, realloc and free (over glibc's __libc_ functions) and counts the calls made
 * while a doStep runs (and, to show the count works, those outside it); elsewhere it
 * counts the FMI allocateMemory / freeMemory callbacks.
 */
#if !defined(_WIN32) && !defined(_XOPEN_SOURCE)
#define _XOPEN_SOURCE 700   /* realpath, clock_gettime */
#endif
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
#else
#include <dlfcn.h>
#include <time.h>
#endif

typedef void *fmi2Component;
typedef unsigned int fmi2ValueReference;
typedef int fmi2Status;
typedef struct {
    void (*logger)(void *, const char *, int, const char *, const char *, ...);
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, int);
    void *componentEnvironment;
} Callbacks;

static volatile int in_step;
static long step_allocations, other_allocations;
#define COUNT() (in_step ? step_allocations++ : other_allocations++)

#if defined(__linux__)
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
void *malloc(size_t n) { COUNT(); return __libc_malloc(n); }
void *calloc(size_t n, size_t s) { COUNT(); return __libc_calloc(n, s); }
void *realloc(void *p, size_t n) { COUNT(); return __libc_realloc(p, n); }
void free(void *p) { if (p) COUNT(); __libc_free(p); }
#endif

#if defined(__linux__)
static void *cb_alloc(size_t n, size_t s) { return calloc(n, s); }   /* counted there */
static void cb_free(void *p) { free(p); }
#else
static void *cb_alloc(size_t n, size_t s) { COUNT(); return calloc(n, s); }
static void cb_free(void *p) { if (p) COUNT(); free(p); }
#endif

static void logger(void *env, const char *name, int status, const char *category,
                   const char *message, ...)
{
    char text[4096];
    va_list args;
    (void)env;
    (void)category;
    va_start(args, message);
    vsnprintf(text, sizeof text, message ? message : "", args);
    va_end(args);
    fprintf(stderr, "LOG %s %d %s\n", name, status, text);
}

typedef struct {
    void *lib;
    fmi2Component c;
    fmi2Component (*instantiate)(const char *, int, const char *, const char *,
                                 const Callbacks *, int, int);
    fmi2Status (*setup)(fmi2Component, int, double, double, int, double);
    fmi2Status (*enter)(fmi2Component);
    fmi2Status (*exit_)(fmi2Component);
    fmi2Status (*get)(fmi2Component, const fmi2ValueReference *, size_t, double *);
    fmi2Status (*set)(fmi2Component, const fmi2ValueReference *, size_t, const double *);
    fmi2Status (*seti)(fmi2Component, const fmi2ValueReference *, size_t, const int *);
    fmi2Status (*step)(fmi2Component, double, double, int);
    void (*free_)(fmi2Component);
    double *times;
} Fmu;

static Callbacks callbacks = {logger, cb_alloc, cb_free, NULL, NULL};

static void *symbol(void *lib, const char *name)
{
#ifdef _WIN32
    FARPROC fp = GetProcAddress((HMODULE)lib, name);
    void *p;
    memcpy(&p, &fp, sizeof p);
#else
    void *p = dlsym(lib, name);
#endif
    if (!p) {
        fprintf(stderr, "missing symbol %s\n", name);
        exit(3);
    }
    return p;
}

/* the FMU unpacked in dir: its only binary of this platform, its resources */
static void load(Fmu *f, const char *given, const char *identifier, const char *name)
{
    char path[8192], uri[8192], dir[4096];
    size_t i;
#ifdef _WIN32
    if (!_fullpath(dir, given, sizeof dir)) {
#else
    if (!realpath(given, dir)) {
#endif
        fprintf(stderr, "no folder %s\n", given);
        exit(3);
    }
#ifdef _WIN32
    snprintf(path, sizeof path, "%s\\binaries\\win64\\%s.dll", dir, identifier);
    f->lib = (void *)LoadLibraryA(path);
#else
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", dir, identifier);
    f->lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
#endif
    if (!f->lib) {
        fprintf(stderr, "cannot load %s\n", path);
        exit(3);
    }
    *(void **)&f->instantiate = symbol(f->lib, "fmi2Instantiate");
    *(void **)&f->setup = symbol(f->lib, "fmi2SetupExperiment");
    *(void **)&f->enter = symbol(f->lib, "fmi2EnterInitializationMode");
    *(void **)&f->exit_ = symbol(f->lib, "fmi2ExitInitializationMode");
    *(void **)&f->get = symbol(f->lib, "fmi2GetReal");
    *(void **)&f->set = symbol(f->lib, "fmi2SetReal");
    *(void **)&f->seti = symbol(f->lib, "fmi2SetInteger");
    *(void **)&f->step = symbol(f->lib, "fmi2DoStep");
    *(void **)&f->free_ = symbol(f->lib, "fmi2FreeInstance");
    snprintf(uri, sizeof uri, "file://%s%s/resources", dir[0] == '/' ? "" : "/", dir);
    for (i = 0; uri[i]; i++)
        if (uri[i] == '\\') uri[i] = '/';
    f->c = f->instantiate(name, 1, "", uri, &callbacks, 0, 0);
    if (!f->c) {
        fprintf(stderr, "fmi2Instantiate of %s failed\n", dir);
        exit(4);
    }
}

static void check(fmi2Status s, const char *what, double t)
{
    if (s != 0) {
        fprintf(stderr, "%s returned %d at t = %.6g\n", what, s, t);
        exit(5);
    }
}

static double now_us(void)
{
#ifdef _WIN32
    LARGE_INTEGER c, f;
    QueryPerformanceCounter(&c);
    QueryPerformanceFrequency(&f);
    return 1e6 * (double)c.QuadPart / (double)f.QuadPart;
#else
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e6 * (double)ts.tv_sec + 1e-3 * (double)ts.tv_nsec;
#endif
}

/* busy-wait until the deadline (a thread that sleeps gives its core and caches away and
   wakes when the scheduler lets it) */
static void wait_until_us(double deadline)
{
    while (now_us() < deadline) {
    }
}

/* sort t[0..n) in place (Shell sort: no allocation and no system call, unlike a library
   sort of a large array, so that a system-call count over the run is the FMUs' own) */
static void sort(double *t, int n)
{
    int gap, i, j;
    for (gap = n / 2; gap > 0; gap /= 2)
        for (i = gap; i < n; i++) {
            double x = t[i];
            for (j = i; j >= gap && t[j - gap] > x; j -= gap) t[j] = t[j - gap];
            t[j] = x;
        }
}

static void percentiles(const char *what, double *t, int n)
{
    sort(t, n);
    printf("%s doStep us: p50 %.2f p99 %.2f max %.2f\n", what, t[n / 2],
           t[(int)(0.99 * (n - 1))], t[n - 1]);
}

static double timed_step(Fmu *f, double t, double h)
{
    double t0 = now_us(), t1;
    in_step = 1;
    check(f->step(f->c, t, h, 1), "fmi2DoStep", t);
    in_step = 0;
    t1 = now_us();
    return t1 - t0;
}

static void start(Fmu *f)
{
    check(f->setup(f->c, 0, 0.0, 0.0, 0, 0.0), "fmi2SetupExperiment", 0.0);
    check(f->enter(f->c), "fmi2EnterInitializationMode", 0.0);
}

int main(int argc, char **argv)
{
    int steps, i, k;
    double h;
    if (argc < 5) {
        fprintf(stderr, "usage: see the comment at the top of realtime_host.c\n");
        return 2;
    }
    if (strcmp(argv[1], "forced") == 0) {
        Fmu cat;
        fmi2ValueReference vr_np = 1, vr_F0[4], vr_F[4], vr_out[8 + 64];
        double F0[4], F[4], out[8 + 64], nsup;
        fmi2ValueReference vr_ns = 7;
        int np, nout, sub = argc > 5 ? atoi(argv[5]) : 1;
        double *tc;
        steps = atoi(argv[3]);
        tc = (double *)calloc((size_t)steps, sizeof(double));
        h = atof(argv[4]);
        load(&cat, argv[2], "pantocosim_catenary_native", "catenary");
        start(&cat);
        check(cat.exit_(cat.c), "fmi2ExitInitializationMode", 0.0);
        {
            int (*geti)(fmi2Component, const fmi2ValueReference *, size_t, int *);
            *(void **)&geti = symbol(cat.lib, "fmi2GetInteger");
            check(geti(cat.c, &vr_np, 1, &np), "fmi2GetInteger", 0.0);
        }
        check(cat.get(cat.c, &vr_ns, 1, &nsup), "fmi2GetReal", 0.0);
        for (k = 0; k < np; k++) {
            vr_F0[k] = 110 + (unsigned)k;
            vr_F[k] = 120 + (unsigned)k;
            vr_out[2 * k] = 150 + (unsigned)k;
            vr_out[2 * k + 1] = 160 + (unsigned)k;
        }
        nout = 2 * np;
        for (k = 0; k < (int)nsup; k++) vr_out[nout++] = 200 + (unsigned)k;
        check(cat.get(cat.c, vr_F0, (size_t)np, F0), "fmi2GetReal", 0.0);
        for (i = 0; i < steps; i++) {
            double t = i * h * sub, t1 = t + h * sub;
            for (k = 0; k < np; k++)
                F[k] = F0[k] * (1.0 + 0.1 * sin(2.0 * 3.141592653589793 * 7.0 * t1))
                       + (t1 > 0.3 ? 20.0 : 0.0);
            check(cat.set(cat.c, vr_F, (size_t)np, F), "fmi2SetReal", t);
            tc[i] = timed_step(&cat, t, h * sub);
            check(cat.get(cat.c, vr_out, (size_t)nout, out), "fmi2GetReal", t);
            printf("%.17g", t1);
            for (k = 0; k < nout; k++) printf(" %.17g", out[k]);
            printf("\n");
        }
        percentiles("catenary", tc, steps);
        cat.free_(cat.c);
    } else if (strcmp(argv[1], "pantograph") == 0) {
        Fmu pan;
        fmi2ValueReference vr_F = 1, vr_out[2] = {2, 3};
        double F0, F, out[2];
        steps = atoi(argv[3]);
        h = atof(argv[4]);
        load(&pan, argv[2], "pantocosim_pantograph_native", "pantograph");
        start(&pan);
        check(pan.exit_(pan.c), "fmi2ExitInitializationMode", 0.0);
        check(pan.get(pan.c, &vr_F, 1, &F0), "fmi2GetReal", 0.0);
        for (i = 0; i < steps; i++) {
            double t = i * h, t1 = t + h;
            F = F0 * (1.0 + 0.1 * sin(2.0 * 3.141592653589793 * 7.0 * t1));
            check(pan.set(pan.c, &vr_F, 1, &F), "fmi2SetReal", t);
            timed_step(&pan, t, h);
            check(pan.get(pan.c, vr_out, 2, out), "fmi2GetReal", t);
            printf("%.17g %.17g %.17g\n", t1, out[0], out[1]);
        }
        pan.free_(pan.c);
    } else if ((strcmp(argv[1], "coupled") == 0 || strcmp(argv[1], "coupled-forces") == 0)
               && argc >= 6) {
        Fmu cat, pan;
        fmi2ValueReference vr_mode = 4, vr_zin[2] = {130, 140}, vr_Fout = 170, vr_zw = 150;
        fmi2ValueReference vr_pF = 1, vr_pz[2] = {2, 3};
        int one = 1, paced = argc > 6 && strcmp(argv[6], "paced") == 0, misses = 0;
        int inside = strcmp(argv[1], "coupled") == 0;
        fmi2ValueReference vr_kh = 3, vr_Fin = 120;
        double zv[2], F, zw, *tc, *tp, t_next = 0.0, k_h = 0.0;
        steps = atoi(argv[4]);
        h = atof(argv[5]);
        tc = (double *)calloc((size_t)steps, sizeof(double));
        tp = (double *)calloc((size_t)steps, sizeof(double));
        load(&cat, argv[2], "pantocosim_catenary_native", "catenary");
        load(&pan, argv[3], "pantocosim_pantograph_native", "pantograph");
        start(&cat);
        if (inside) check(cat.seti(cat.c, &vr_mode, 1, &one), "fmi2SetInteger", 0.0);
        check(cat.exit_(cat.c), "fmi2ExitInitializationMode", 0.0);
        check(cat.get(cat.c, &vr_kh, 1, &k_h), "fmi2GetReal", 0.0);
        start(&pan);
        check(pan.exit_(pan.c), "fmi2ExitInitializationMode", 0.0);
        if (paced) t_next = now_us();
        for (i = 0; i < steps; i++) {
            double t = i * h;
            check(pan.get(pan.c, vr_pz, 2, zv), "fmi2GetReal", t);
            if (inside) {
                check(cat.set(cat.c, vr_zin, 2, zv), "fmi2SetReal", t);
                tc[i] = timed_step(&cat, t, h);
                check(cat.get(cat.c, &vr_Fout, 1, &F), "fmi2GetReal", t);
                check(cat.get(cat.c, &vr_zw, 1, &zw), "fmi2GetReal", t);
            } else {
                check(cat.get(cat.c, &vr_zw, 1, &zw), "fmi2GetReal", t);
                F = zv[0] > zw ? k_h * (zv[0] - zw) : 0.0;
                check(cat.set(cat.c, &vr_Fin, 1, &F), "fmi2SetReal", t);
                tc[i] = timed_step(&cat, t, h);
            }
            check(pan.set(pan.c, &vr_pF, 1, &F), "fmi2SetReal", t);
            tp[i] = timed_step(&pan, t, h);
            if (!paced) printf("%.17g %.17g %.17g %.17g\n", t + h, F, zv[0], zw);
            if (paced) {
                t_next += h * 1e6;
                if (now_us() > t_next) misses++;
                else wait_until_us(t_next);
            }
        }
        percentiles("catenary", tc, steps);
        percentiles("pantograph", tp, steps);
        if (paced) printf("deadline misses: %d of %d steps\n", misses, steps);
        cat.free_(cat.c);
        pan.free_(pan.c);
    } else {
        fprintf(stderr, "unknown mode %s\n", argv[1]);
        return 2;
    }
    printf("allocations in doStep: %ld\n", step_allocations);
    printf("allocations outside doStep: %ld\n", other_allocations);
    return 0;
}
