/*
 * The flexible-bar DSA-380 (thesis 2.2) in C: the residual pieces and exact tangents of
 * pantocosim.pantograph.dsa380_flexible (planar ANCF beams of beam_ancf.py, collector springs
 * (A.11), torsional spring and actuation torque on the slope of bar 1 at joint 1 (2.14),
 * damper 13-1p (A.13), collector friction (2.15)-(2.17)). q is the displacement of the free
 * node positions and slopes from the reference configuration q_ref; the mass matrix is
 * constant. Its evaluation is an HhtModelFn (hht_dense.h); inputs[0] is the contact force.
 *
 * The topology (elements' coordinate pairs and their 2x2 maps, welded slopes, grounded
 * points) is built in Python and exported as arrays; the scalars below are placed by name.
 */
#ifndef DSA380_FLEXIBLE_H
#define DSA380_FLEXIBLE_H

#include <stddef.h>

#include "actuation.h"
#include "hht_dense.h"

/* the constants (section "constants") */
#define DSF_K_N 0                  /* unknowns */
#define DSF_K_NE 1                 /* beam elements */
#define DSF_K_NG 2                 /* Gauss points per element */
#define DSF_K_P5 3                 /* first index of point 5's pair, 11, 12, 1p */
#define DSF_K_P11 4
#define DSF_K_P12 5
#define DSF_K_P1P 6
#define DSF_K_S1 7                 /* the slope of bar 1 at joint 1 */
#define DSF_K_Y10 8                /* the contact point's height, point 5's */
#define DSF_K_Y5 9
#define DSF_K_KL 10
#define DSF_K_L0 11
#define DSF_K_C 12
#define DSF_K_X13 13
#define DSF_K_Y13 14
#define DSF_K_KR 15
#define DSF_K_TH0 16
#define DSF_K_ONE_WAY_DAMPER 17
#define DSF_K_FRICTION_FORCE 18
#define DSF_K_FRICTION_SMOOTHING 19
#define DSF_K_AERO_FORCE 20
#define DSF_K_TORQUE 21
#define DSF_K_RAMP 22
#define DSF_K_TORQUE_LOWERED 23
#define DSF_K_RAMP_START 24
#define DSF_K_RAMP_DURATION 25
#define DSF_K_COUNT 26

#define DSF_MAX_N 1024
#define DSF_MAX_NE 1024
#define DSF_MAX_NG 16

/* the arrays: q_ref (n), M (n x n), Qg (n), E0 (ne x 8), length, EA, EI (ne), pg (ne x 4:
   the first unknown of each coordinate pair of an element, -1 grounded), pR (ne x 4 x 2 x 2),
   xi_g, w_g (ng) */
typedef struct {
    const double *q_ref, *M, *Qg, *E0, *length, *EA, *EI, *pR, *xi_g, *w_g;
    const int *pg;
} DsfArrays;

typedef struct {
    int n, ne, ng;
    int p5, p11, p12, p1p, s1, y10, y5, one_way;
    double kl, l0, c, x13, y13, kr, th0, friction_force, friction_smoothing, aero_force;
    Actuation act;
    DsfArrays a;
    /* work (caller memory): q (n), dE, Fe (ne x 8), Ke (ne x 64) */
    double *q, *dE, *Fe, *Ke;
} Dsa380Flex;

/* Bytes of work memory for n unknowns and ne elements (0: out of bounds). */
size_t dsf_work_bytes(int n, int ne);
/* Check the constants k (count DSF_K_COUNT) and the arrays, lay out the work memory; 0, or -1
   with the reason in msg (HHT_MSG bytes). The arrays are the caller's, kept alive. */
int dsf_setup(Dsa380Flex *m, const double *k, long count, const DsfArrays *arrays, void *work,
              size_t work_bytes, char *msg);
/* The residual pieces and tangents at (t, q, v, a) under inputs[0] = F (an HhtModelFn). */
int dsf_evaluate(void *model, double t, const double *q, const double *v, const double *a,
                 const double *inputs, int tangent, HhtEval *out, char *msg);

#endif
