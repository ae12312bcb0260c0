/*
 * A probe of the native rigid and flexible DSA-380 and the dense HHT engine for tests/test_native_dsa380.py
 * (built there as a shared library, called through ctypes): the models and one engine in static
 * memory, the engine's work arrays in a caller buffer as an FMU instance gives them.
 */
#include <string.h>

#include "dsa380_flexible.h"
#include "dsa380_rigid.h"
#include "hht_dense.h"

static Dsa380 model;
static HhtDense engine;
static double memory[60000];

/* the residual pieces (f: f_inertia, f_rest) and tangents (mats: mass, inertia_q, damping,
   stiffness) of a model of n unknowns at (t, q, v, a) under F */
static int evaluate_into(HhtModelFn fn, void *data, int n, double t, const double *q,
                         const double *v, const double *a, double F, double *f, double *mats,
                         char *msg)
{
    HhtEval ev;
    ev.f_inertia = f;
    ev.f_rest = f + n;
    ev.mass = mats;
    ev.inertia_q = mats + n * n;
    ev.damping = mats + 2 * n * n;
    ev.stiffness = mats + 3 * n * n;
    return fn(data, t, q, v, a, &F, 1, &ev, msg);
}

/* the engine on a model of n unknowns, started at (t0, q0) under F0 */
static int start(HhtModelFn fn, void *data, int n, double alpha, double rtol, double etol,
                 int max_iterations, int linear, double t0, const double *q0, double F0,
                 char *msg)
{
    HhtSettings s;
    s.alpha = alpha;
    s.rtol = rtol;
    s.etol = etol;
    s.max_iterations = max_iterations;
    s.linear_predictor = linear;
    if (hht_dense_init(&engine, n, &s, fn, data, memory, sizeof memory, msg)) return -1;
    return hht_dense_start(&engine, t0, q0, NULL, &F0, msg);
}

int probe_setup(const double *k, long count, char *msg)
{
    return dsa380_setup(&model, k, count, msg);
}

int probe_n(void) { return model.n_dofs; }

int probe_evaluate(double t, const double *q, const double *v, const double *a, double F,
                   double *f, double *mats, char *msg)
{
    return evaluate_into(dsa380_evaluate, &model, model.n_dofs, t, q, v, a, F, f, mats, msg);
}

int probe_start(double alpha, double rtol, double etol, int max_iterations, int linear,
                double t0, const double *q0, double F0, char *msg)
{
    return start(dsa380_evaluate, &model, model.n_dofs, alpha, rtol, etol, max_iterations,
                 linear, t0, q0, F0, msg);
}

/* one step; the state (t, steps, has a_prev, q, v, a, a_prev, f_rest) after it in out */
int probe_step(double h, double F, double *out, int *iterations, char *msg)
{
    int status = hht_dense_step(&engine, h, &F, msg);
    memcpy(out, engine.state.block, (3 + 5 * (size_t)engine.n) * sizeof(double));
    *iterations = engine.iterations;
    return status;
}

/* ---- the flexible DSA-380 */
static Dsa380Flex flex;
static double flex_work[200000];

int probe_flex_setup(const double *k, long count, const double *q_ref, const double *M,
                     const double *Qg, const double *E0, const double *length,
                     const double *EA, const double *EI, const int *pg, const double *pR,
                     const double *xi_g, const double *w_g, char *msg)
{
    DsfArrays a;
    a.q_ref = q_ref; a.M = M; a.Qg = Qg; a.E0 = E0; a.length = length; a.EA = EA; a.EI = EI;
    a.pg = pg; a.pR = pR; a.xi_g = xi_g; a.w_g = w_g;
    return dsf_setup(&flex, k, count, &a, flex_work, sizeof flex_work, msg);
}

int probe_flex_evaluate(double t, const double *q, const double *v, const double *a,
                        double F, double *f, double *mats, char *msg)
{
    return evaluate_into(dsf_evaluate, &flex, flex.n, t, q, v, a, F, f, mats, msg);
}

int probe_flex_start(double alpha, double rtol, double etol, int max_iterations, int linear,
                     double t0, const double *q0, double F0, char *msg)
{
    return start(dsf_evaluate, &flex, flex.n, alpha, rtol, etol, max_iterations, linear, t0,
                 q0, F0, msg);
}
