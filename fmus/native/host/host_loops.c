/*
 * The loops of the host, as a HIL rig runs the native FMUs (modes in host_main.c): the
 * catenary forced, the pantograph forced, and the two coupled (the contact inside the
 * catenary, or the penalty law in the host), optionally paced to the wall clock; each
 * doStep timed (p50 / p99 / max in microseconds) and the allocations made in it counted
 * (host_memory.c). Variables are found by name in each FMU's modelDescription.xml.
 */
#if !defined(_WIN32) && !defined(_POSIX_C_SOURCE) && !defined(_XOPEN_SOURCE)
#define _POSIX_C_SOURCE 200809L   /* clock_gettime */
#endif
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
#else
#include <time.h>
#endif

#include "host.h"

#define MAX_PANTOGRAPHS 4
#define MAX_OUTPUTS (2 * MAX_PANTOGRAPHS + 64)

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

static void check(int status, const char *what, double t)
{
    if (status != 0) {
        fprintf(stderr, "%s returned %d at t = %.6g\n", what, status, t);
        exit(5);
    }
}

static double timed_step(HostFmu *f, double t, double h)
{
    double t0 = now_us(), t1;
    host_in_step = 1;
    check(f->api->step(f, t, h, 1), "doStep", t);
    host_in_step = 0;
    t1 = now_us();
    if (f->step_event || f->step_early || f->step_terminated) {
        fprintf(stderr, "doStep of %s at t = %.6g asks for an event, returned early or "
                "terminated\n", f->name, t);
        exit(5);
    }
    return t1 - t0;
}

/* the FMU in dir loaded and instantiated */
static void open_fmu(HostFmu *f, const char *dir, const char *name)
{
    host_load(f, dir, NULL, NULL);
    if (f->api->instantiate(f, name, 0, 0) != 0) {
        fprintf(stderr, "instantiating %s failed\n", f->dir);
        exit(4);
    }
}

/* the instance in initialization mode from t = 0 */
static void enter(HostFmu *f)
{
    check(f->api->setup(f, 0.0), "setupExperiment", 0.0);
    check(f->api->enter(f), "enterInitializationMode", 0.0);
}

/* the value reference of NAME_k (k = 1, 2, ...; or 0, 1, ... for the supports) */
static unsigned numbered(const HostFmu *f, const char *name, int k)
{
    char full[128];
    snprintf(full, sizeof full, "%s_%d", name, k);
    return host_value_reference(f, full);
}

static double *times(int steps)
{
    double *t = (double *)calloc((size_t)(steps > 0 ? steps : 1), sizeof(double));
    if (!t) {
        fprintf(stderr, "no memory for %d step times\n", steps);
        exit(2);
    }
    return t;
}

static void print_allocations(const HostFmu *a, const HostFmu *b)
{
    if (host_allocations_counted(a) && (!b || host_allocations_counted(b))) {
        printf("allocations in doStep: %ld\n", host_step_allocations);
        printf("allocations outside doStep: %ld\n", host_other_allocations);
    } else {
        printf("allocations in doStep: not counted (FMI 3.0 has no memory callbacks, and "
               "the host interposes malloc on Linux only)\n");
    }
}

/* F_k(t) = F0_k (1 + 0.1 sin(2 pi 7 t)) + 20 [t > 0.3 s] on the catenary (contact_mode 0) */
static int forced(const char *dir, int steps, double h, int sub)
{
    static HostFmu cat;   /* zeroed */
    unsigned vr_np, vr_ns, vr_F0[MAX_PANTOGRAPHS], vr_F[MAX_PANTOGRAPHS], vr_out[MAX_OUTPUTS];
    double F0[MAX_PANTOGRAPHS], F[MAX_PANTOGRAPHS], out[MAX_OUTPUTS], nsup, *tc = times(steps);
    int np, nout, i, k;
    open_fmu(&cat, dir, "catenary");
    enter(&cat);
    check(cat.api->exit_init(&cat), "exitInitializationMode", 0.0);
    vr_np = host_value_reference(&cat, "n_pantographs");
    vr_ns = host_value_reference(&cat, "n_supports");
    check(cat.api->get_int(&cat, &vr_np, 1, &np), "getInteger", 0.0);
    check(cat.api->get_real(&cat, &vr_ns, 1, &nsup), "getReal", 0.0);
    if (np < 1 || np > MAX_PANTOGRAPHS || nsup < 0.0 || nsup > 64.0) {
        fprintf(stderr, "%s: n_pantographs %d, n_supports %g (1..4 and 0..64 accepted)\n",
                cat.dir, np, nsup);
        return 2;
    }
    for (k = 0; k < np; k++) {
        vr_F0[k] = numbered(&cat, "static_force", k + 1);
        vr_F[k] = numbered(&cat, "contact_force", k + 1);
        vr_out[2 * k] = numbered(&cat, "wire_height", k + 1);
        vr_out[2 * k + 1] = numbered(&cat, "wire_velocity", k + 1);
    }
    nout = 2 * np;
    for (k = 0; k < (int)nsup; k++) vr_out[nout++] = numbered(&cat, "support_uplift", k);
    check(cat.api->get_real(&cat, vr_F0, (size_t)np, F0), "getReal", 0.0);
    for (i = 0; i < steps; i++) {
        double t = i * h * sub, t1 = t + h * sub;
        for (k = 0; k < np; k++)
            F[k] = F0[k] * (1.0 + 0.1 * sin(2.0 * 3.141592653589793 * 7.0 * t1))
                   + (t1 > 0.3 ? 20.0 : 0.0);
        check(cat.api->set_real(&cat, vr_F, (size_t)np, F), "setReal", t);
        tc[i] = timed_step(&cat, t, h * sub);
        check(cat.api->get_real(&cat, vr_out, (size_t)nout, out), "getReal", t);
        printf("%.17g", t1);
        for (k = 0; k < nout; k++) printf(" %.17g", out[k]);
        printf("\n");
    }
    percentiles("catenary", tc, steps);
    cat.api->free_instance(&cat);
    print_allocations(&cat, NULL);
    return 0;
}

/* F(t) = F0 (1 + 0.1 sin(2 pi 7 t)) on the pantograph */
static int pantograph(const char *dir, int steps, double h)
{
    static HostFmu pan;   /* zeroed */
    unsigned vr_F, vr_out[2];
    double F0, F, out[2];
    int i;
    open_fmu(&pan, dir, "pantograph");
    enter(&pan);
    check(pan.api->exit_init(&pan), "exitInitializationMode", 0.0);
    vr_F = host_value_reference(&pan, "contact_force");
    vr_out[0] = host_value_reference(&pan, "contact_height");
    vr_out[1] = host_value_reference(&pan, "contact_velocity");
    check(pan.api->get_real(&pan, &vr_F, 1, &F0), "getReal", 0.0);
    for (i = 0; i < steps; i++) {
        double t = i * h, t1 = t + h;
        F = F0 * (1.0 + 0.1 * sin(2.0 * 3.141592653589793 * 7.0 * t1));
        check(pan.api->set_real(&pan, &vr_F, 1, &F), "setReal", t);
        timed_step(&pan, t, h);
        check(pan.api->get_real(&pan, vr_out, 2, out), "getReal", t);
        printf("%.17g %.17g %.17g\n", t1, out[0], out[1]);
    }
    pan.api->free_instance(&pan);
    print_allocations(&pan, NULL);
    return 0;
}

/* the catenary's and the pantograph's value references in the coupled loop */
typedef struct {
    unsigned mode, k_h, z_in[2], F_out, z_wire, F_in, pan_F, pan_z[2];
} Coupling;

static Coupling coupling(const HostFmu *cat, const HostFmu *pan)
{
    Coupling c;
    c.mode = host_value_reference(cat, "contact_mode");
    c.k_h = host_value_reference(cat, "contact_stiffness");
    c.z_in[0] = host_value_reference(cat, "pantograph_height_1");
    c.z_in[1] = host_value_reference(cat, "pantograph_velocity_1");
    c.F_out = host_value_reference(cat, "contact_force_out_1");
    c.z_wire = host_value_reference(cat, "wire_height_1");
    c.F_in = host_value_reference(cat, "contact_force_1");
    c.pan_F = host_value_reference(pan, "contact_force");
    c.pan_z[0] = host_value_reference(pan, "contact_height");
    c.pan_z[1] = host_value_reference(pan, "contact_velocity");
    return c;
}

/* one step of the catenary: the contact inside it (contact_mode 1), or the penalty law
   F = max(0, k_H (z_pantograph - z_wire)) applied here; the contact force and wire height */
static double catenary_step(HostFmu *cat, const Coupling *c, int inside, double k_h,
                            const double zv[2], double t, double h, double *tc, double *zw)
{
    double F;
    if (inside) {
        check(cat->api->set_real(cat, c->z_in, 2, zv), "setReal", t);
        *tc = timed_step(cat, t, h);
        check(cat->api->get_real(cat, &c->F_out, 1, &F), "getReal", t);
        check(cat->api->get_real(cat, &c->z_wire, 1, zw), "getReal", t);
    } else {
        check(cat->api->get_real(cat, &c->z_wire, 1, zw), "getReal", t);
        F = zv[0] > *zw ? k_h * (zv[0] - *zw) : 0.0;
        check(cat->api->set_real(cat, &c->F_in, 1, &F), "setReal", t);
        *tc = timed_step(cat, t, h);
    }
    return F;
}

/* the catenary and a pantograph, coupled each step (zero-order hold), paced or not */
static int coupled(const char *cat_dir, const char *pan_dir, int steps, double h, int inside,
                   int paced)
{
    static HostFmu cat, pan;   /* zeroed */
    Coupling c;
    double zv[2], F, zw, *tc = times(steps), *tp = times(steps), t_next = 0.0, k_h = 0.0;
    int one = 1, misses = 0, i;
    open_fmu(&cat, cat_dir, "catenary");
    open_fmu(&pan, pan_dir, "pantograph");
    c = coupling(&cat, &pan);
    enter(&cat);
    if (inside) check(cat.api->set_int(&cat, &c.mode, 1, &one), "setInteger", 0.0);
    check(cat.api->exit_init(&cat), "exitInitializationMode", 0.0);
    check(cat.api->get_real(&cat, &c.k_h, 1, &k_h), "getReal", 0.0);
    enter(&pan);
    check(pan.api->exit_init(&pan), "exitInitializationMode", 0.0);
    if (paced) t_next = now_us();
    for (i = 0; i < steps; i++) {
        double t = i * h;
        check(pan.api->get_real(&pan, c.pan_z, 2, zv), "getReal", t);
        F = catenary_step(&cat, &c, inside, k_h, zv, t, h, &tc[i], &zw);
        check(pan.api->set_real(&pan, &c.pan_F, 1, &F), "setReal", t);
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
    cat.api->free_instance(&cat);
    pan.api->free_instance(&pan);
    print_allocations(&cat, &pan);
    return 0;
}

static int positive(const char *word, const char *what)
{
    int n = atoi(word);
    if (n < 1) {
        fprintf(stderr, "%s %s: a positive whole number accepted\n", what, word);
        exit(2);
    }
    return n;
}

static double step_size(const char *word)
{
    double h = atof(word);
    if (!(h > 0.0)) {
        fprintf(stderr, "DT %s: a positive number of seconds accepted\n", word);
        exit(2);
    }
    return h;
}

int host_loop(int argc, char **argv)
{
    const char *mode = argv[1];
    if (!strcmp(mode, "forced") && argc >= 5)
        return forced(argv[2], positive(argv[3], "STEPS"), step_size(argv[4]),
                      argc > 5 ? positive(argv[5], "SUBSTEPS") : 1);
    if (!strcmp(mode, "pantograph") && argc >= 5)
        return pantograph(argv[2], positive(argv[3], "STEPS"), step_size(argv[4]));
    if ((!strcmp(mode, "coupled") || !strcmp(mode, "coupled-forces")) && argc >= 6)
        return coupled(argv[2], argv[3], positive(argv[4], "STEPS"), step_size(argv[5]),
                       !strcmp(mode, "coupled"), argc > 6 && !strcmp(argv[6], "paced"));
    fprintf(stderr, "mode %s with %d arguments: see the usage at the top of host_main.c\n",
            mode, argc - 2);
    return 2;
}
