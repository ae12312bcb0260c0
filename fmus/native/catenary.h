/*
 * The native catenary's instance (catenary.c: the linear model, the variables and the
 * stepping loop; catenary_modal.c: the modal model's tables and step).
 */
#ifndef CATENARY_H
#define CATENARY_H

#include "catenary_vars.h"
#include "pcs_model.h"

typedef struct {
    int dof[4];          /* free DOF (modal model: index among the wire's DOFs), -1 fixed */
    double w[4], dw[4];  /* Hermite weights (3.13) and d/dx */
    double zfix[4];      /* reference z of the fixed DOFs (modal model: of all four) */
} Point;

struct PcsModel {
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
    /* the modal model's tables and work (catenary_modal.c); NULL: the linear model */
    struct Modal *modal;
};


/* shared by both models (catenary.c) */
int pcs_locate(const PcsModel *m, double x, Point *p, char *err);
int pcs_dense_solve(double *A, double *y, int n);
/* the penalty forces F with the wire affine in them: z_w = z0 + G F, v_w = v0 + H F (the
   pantographs at z0 + dz, v0 + dv; penalty_contact.condensed_forces) */
void pcs_penalty_forces(const PcsModel *m, const double *dz, const double *dv,
                        const double *G, const double *H, double *F);

/* the modal model (catenary_modal.c) */
PcsModel *modal_new(const PcsData *d, const PcsMemory *mem, char *err);
void modal_free(PcsModel *m, const PcsMemory *mem);
int modal_initialize(PcsModel *m, char *err);
int modal_step(PcsModel *m, double *F, const double *zp, const double *vp, char *err);
void modal_outputs(PcsModel *m);

#endif
