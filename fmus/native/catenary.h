/*
 * The native catenaries: the shared part (catenary.c: contact points, the communication
 * step as internal steps, the FMU state, the variables) under the linear model
 * (catenary_linear.c) and the modal model (catenary_modal.c), each with its own model table
 * and its own internal step and outputs (CatenaryStep). The models call the shared part,
 * never each other.
 */
#ifndef CATENARY_H
#define CATENARY_H

#include "catenary_vars.h"
#include "pcs_layout.h"
#include "pcs_limits.h"
#include "pcs_model.h"

typedef struct Catenary Catenary;

/* what a catenary model adds to the shared part */
typedef struct {
    /* one internal step of h with forces F (contact_mode 0) or pantograph heights zp and
       velocities vp (contact_mode 1, F written); the contact points at t + h are in m->pts */
    int (*step)(Catenary *m, double *F, const double *zp, const double *vp, char *err);
    /* wire heights, velocities and support uplifts from the state */
    void (*outputs)(Catenary *m);
} CatenaryStep;

typedef struct {
    int dof[4];          /* free DOF (modal model: index among the wire's DOFs), -1 fixed */
    double w[4], dw[4];  /* Hermite weights (3.13) and d/dx */
    double zfix[4];      /* reference z of the fixed DOFs (modal model: of all four) */
} Point;

struct Catenary {
    const CatenaryStep *own;      /* the model's step and outputs */
    PcsArena arena;               /* its state and work memory */
    /* sizes */
    int n, bw_m, bw_k, bw, nd, np, ne, ns;
    /* constants */
    double h, alpha, beta, gamma, ar, br, speed, wave, k_h, c_h, x_min, x_max;
    double c_a, c_v, c_f, cutoff;
    int spans, model_code;
    const double *M, *K, *q_ref, *r0, *q0, *F0, *x0;
    const int *d_idx, *d_tension;
    const double *d_val, *d_ka, *d_N0;
    const double *w_xs, *w_xe, *w_Ex, *w_Le, *w_zfix;
    const int *w_dof, *s_dof;
    const double *s_z;
    const char *definition;
    /* kept factor (column j: L[j..j+bw, j]) and columns A^-1 b_d */
    double *L, *LR, *Z, *inv_diag;
    /* the band diagonals of M and K that hold a nonzero */
    unsigned char *used_m, *used_k;
    /* state (contiguous: t, n_steps, failed, steps at the last forming of the products,
       inputs at t, q, v, a, f, the kept products P, committed slack set) */
    double *state;
    size_t state_len;
    double *t, *n_steps, *prev, *q, *v, *a, *f, *committed, *failed, *synced;
    double *Kd, *Kv, *Ka, *Mv, *Ma;
    /* work */
    double *qp, *vp, *dp, *rhs, *R, *x, *tmp, *tmp2, *W, *Np, *bx, *bW, *sl, *sl_new, *s, *y,
        *small, *zs;
    int *rows;
    Point pts[CAT_MAX_PANTOGRAPHS];
    /* variables */
    int mode, extrapolate, initialised;
    double rtol, iterations;
    double u_force[CAT_MAX_PANTOGRAPHS], u_z[CAT_MAX_PANTOGRAPHS], u_v[CAT_MAX_PANTOGRAPHS];
    double out_z[CAT_MAX_PANTOGRAPHS], out_v[CAT_MAX_PANTOGRAPHS], out_F[CAT_MAX_PANTOGRAPHS];
    double uplift[CAT_MAX_SUPPORTS];
    /* the start's pantograph heights (contact_mode 1) */
    double z_start[CAT_MAX_PANTOGRAPHS];
    /* the modal model's tables and work (catenary_modal.c) */
    struct Modal *modal;
};


/* the shared part (catenary.c) */
int pcs_locate(const Catenary *m, double x, Point *p, char *err);
int pcs_dense_solve(double *A, double *y, int n);
/* the penalty forces F with the wire affine in them: z_w = z0 + G F, v_w = v0 + H F (the
   pantographs at z0 + dz, v0 + dv; penalty_contact.condensed_forces); -1 when the system is
   singular or the active set does not settle in 2 np + 2 passes */
int pcs_penalty_forces(const Catenary *m, const double *dz, const double *dv,
                        const double *G, const double *H, double *F);
/* reading: the sizes both models share within the limits (pcs_limits.h); the CAT_SCALAR_
   fields of the scalars (pcs_layout.h) and the sections both read (F0, x0, drop_ka, drop_N0, drop_tension, wire_*,
   definition; master/native/export.py), the wire's DOFs below dofs, the inputs' start
   (contact forces F0, extrapolated heights); the work memory of
   carve (measured, bounded by PCS_MAX_BYTES, allocated, taken). 0, or -1 with err */
int cat_check_sizes(const Catenary *m, const PcsData *d, char *err);
int cat_read_common(Catenary *m, const PcsData *d, const double *sc, int dofs, char *err);
int cat_arena(Catenary *m, const PcsData *d, const PcsMemory *mem,
              void (*carve)(Catenary *m, PcsArena *a), char *err);
/* the end of a model's initialisation, its outputs at the start computed: the inputs and
   the contact forces of the static start (contact_mode 1: the pantographs F0 / k_H above
   the wire) */
void cat_start(Catenary *m);
/* the model table's entries both models share */
int cat_step(void *model, double t, double h, char *err);
void cat_outputs(void *model);
size_t cat_state_bytes(const void *model);
void cat_state_save(const void *model, void *buffer);
void cat_state_restore(void *model, const void *buffer);
int cat_get_real(void *model, unsigned vr, double *value, char *err);
int cat_set_real(void *model, unsigned vr, double value, int initialised, char *err);
int cat_get_integer(void *model, unsigned vr, int *value, char *err);
int cat_set_integer(void *model, unsigned vr, int value, int initialised, char *err);
int cat_get_boolean(void *model, unsigned vr, int *value, char *err);
int cat_set_boolean(void *model, unsigned vr, int value, int initialised, char *err);
int cat_get_string(void *model, unsigned vr, const char **value, char *err);
int cat_set_string(void *model, unsigned vr, const char *value, int initialised, char *err);

/* a catenary model's table: its name, kind, new, free and initialise over the shared rest */
#define CATENARY_TABLE(NAME, KIND, NEW, FREE, INIT)                                        \
    {NAME, KIND, NEW, FREE, INIT, cat_step, cat_outputs, cat_state_bytes, cat_state_save,  \
     cat_state_restore, cat_get_real, cat_set_real, cat_get_integer, cat_set_integer,      \
     cat_get_boolean, cat_set_boolean, cat_get_string, cat_set_string}

#endif
