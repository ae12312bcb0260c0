/*
 * HHT-alpha with Newton-Raphson for a small dense second-order model (a few dozen unknowns),
 * the native twin of pantocosim.core.hht.HHTIntegrator with full Newton (a tangent and a
 * factorization at every iteration):
 *
 *   f_inertia(q, a) + (1 + alpha) f_rest(t + h) - alpha f_rest(t) = 0,            (3.16)
 *   q = q_p + beta h^2 a,  v = v_p + gamma h a,                                   (3.18)
 *
 * the same predictor (constant a_n, or linear 2 a_n - a_{n-1}), residual test
 * max|R| <= rtol * (largest term of R), energy test |dq_k . R_k| <= etol |dq_0 . R_0| (thesis
 * 3.3.2), round-off test on the correction, and iteration limit. The Newton matrix
 * c_a M + dM/dq a + (1 + alpha) (c_v C + K) is solved by LU with partial pivoting.
 *
 * All memory is the caller's (hht_dense_bytes, then hht_dense_init): a step allocates
 * nothing. A step that fails (a model that cannot be evaluated, a non-finite residual, a
 * singular matrix, no convergence within the limit) returns HHT_FAILED with the reason and
 * leaves the state as it was.
 */
#ifndef HHT_DENSE_H
#define HHT_DENSE_H

#include <stddef.h>

#define HHT_OK 0
#define HHT_FAILED 1

#define HHT_MSG 512

/* What a model writes at (t, q, v, a): the residual pieces and, when asked, their tangents
   (n x n, row-major): mass = d f_inertia/da, inertia_q = d f_inertia/dq, damping =
   d f_rest/dv, stiffness = d f_rest/dq. */
typedef struct {
    double *f_inertia, *f_rest;
    double *mass, *inertia_q, *damping, *stiffness;
} HhtEval;

/* A model: 0 when evaluated, else nonzero with the reason in msg (HHT_MSG bytes). */
typedef int (*HhtModelFn)(void *model, double t, const double *q, const double *v,
                          const double *a, const double *inputs, int tangent, HhtEval *out,
                          char *msg);

typedef struct {
    double alpha, rtol, etol;
    int max_iterations;
    int linear_predictor;      /* 0: a_{n+1} guessed as a_n, 1: as 2 a_n - a_{n-1} */
} HhtSettings;

/* The state a step depends on (one block: copy it to save, copy it back to restore):
   t, steps taken, whether a_prev holds a_{n-1}, then q, v, a, a_prev, f_rest (n each). */
typedef struct {
    int n;
    double *block;             /* 3 + 5 n doubles */
    double *q, *v, *a, *a_prev, *f_rest;
} HhtState;

typedef struct {
    int n;
    HhtSettings s;
    double beta, gamma;
    HhtModelFn model;
    void *model_data;
    HhtState state;
    HhtEval ev;
    /* work arrays */
    double *q_p, *v_p, *q, *v, *a, *hist, *R, *S, *x;
    int *piv;
    /* the last step */
    int iterations;
    double residual;
} HhtDense;

/* Bytes of caller memory an engine of n unknowns needs (aligned for double). */
size_t hht_dense_bytes(int n);
/* Lay the engine out in memory (hht_dense_bytes(n) bytes, zeroed or not); 0 on success,
   else -1 with the reason in msg (bad n or settings). */
int hht_dense_init(HhtDense *e, int n, const HhtSettings *s, HhtModelFn model,
                   void *model_data, void *memory, size_t bytes, char *msg);
/* Start at (t0, q0, v0) with the inputs at t0; a0 solves M(q0) a0 = -f_rest(t0, q0, v0). */
int hht_dense_start(HhtDense *e, double t0, const double *q0, const double *v0,
                    const double *inputs0, char *msg);
/* Advance from t to t + h with the inputs valid at t + h. */
int hht_dense_step(HhtDense *e, double h, const double *inputs, char *msg);

/* Dense LU with partial pivoting of the n x n row-major A, in place; 0, or -1 if singular. */
int hht_lu_factor(double *A, int *piv, int n);
/* Solve with the factors of hht_lu_factor: b is overwritten by the solution. */
void hht_lu_solve(const double *LU, const int *piv, int n, double *b);

#endif
