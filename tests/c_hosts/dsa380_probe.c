/*
 * A probe of the native rigid DSA-380 and the dense HHT engine for tests/test_native_dsa380.py
 * (built there as a shared library, called through ctypes): one model and one engine in static
 * memory, the engine's work arrays in a caller buffer as an FMU instance gives them.
 */
#include <string.h>

#include "dsa380_rigid.h"
#include "hht_dense.h"

static Dsa380 model;
static HhtDense engine;
static double memory[8192];

int probe_setup(const double *k, long count, char *msg)
{
    return dsa380_setup(&model, k, count, msg);
}

int probe_n(void) { return model.n_dofs; }

/* f_inertia, f_rest (n) and mass, inertia_q, damping, stiffness (4 n^2) */
int probe_evaluate(double t, const double *q, const double *v, const double *a, double F,
                   double *f, double *mats, char *msg)
{
    int n = model.n_dofs;
    HhtEval ev;
    ev.f_inertia = f;
    ev.f_rest = f + n;
    ev.mass = mats;
    ev.inertia_q = mats + n * n;
    ev.damping = mats + 2 * n * n;
    ev.stiffness = mats + 3 * n * n;
    return dsa380_evaluate(&model, t, q, v, a, &F, 1, &ev, msg);
}

double probe_mechanism(double theta, double *A, double *V, double *p5)
{
    return dsa380_mechanism(model.P, theta, A, V, p5);
}

int probe_start(double alpha, double rtol, double etol, int max_iterations, int linear,
                double t0, const double *q0, double F0, char *msg)
{
    HhtSettings s;
    s.alpha = alpha;
    s.rtol = rtol;
    s.etol = etol;
    s.max_iterations = max_iterations;
    s.linear_predictor = linear;
    if (hht_dense_init(&engine, model.n_dofs, &s, dsa380_evaluate, &model, memory,
                       sizeof memory, msg))
        return -1;
    return hht_dense_start(&engine, t0, q0, NULL, &F0, msg);
}

/* one step; the state (t, steps, has a_prev, q, v, a, a_prev, f_rest) after it in out */
int probe_step(double h, double F, double *out, int *iterations, char *msg)
{
    int status = hht_dense_step(&engine, h, &F, msg);
    memcpy(out, engine.state.block, (3 + 5 * (size_t)engine.n) * sizeof(double));
    *iterations = engine.iterations;
    return status;
}
