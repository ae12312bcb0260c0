/*
 * The rigid DSA-380 pantograph (thesis 2.1.1, annexes A-B) in C: the residual pieces and exact
 * tangents of pantocosim.pantograph.dsa380 (its kernels in dsa380_kinematics.py), with
 * q = (theta, x10, y10, theta7) (2.1), or (theta, x10, y10) with the collector pitch locked
 * (A.37). Its evaluation is an HhtModelFn (hht_dense.h); inputs[0] is the contact force F.
 *
 * Constants (one float64 array, written at export by pantocosim.master.native.export, which
 * places each value by the names below): the parameter vector P of the kernels, then the
 * options and the actuation torques.
 */
#ifndef DSA380_RIGID_H
#define DSA380_RIGID_H

#include "actuation.h"
#include "hht_dense.h"

/* parameter vector P: fixed points (point 2 at the roof height), bars 1..7, links, springs,
   damper, gravity (the names of dsa380_kinematics.py) */
#define DSA_P_X1 0
#define DSA_P_Y1 1
#define DSA_P_X2 2
#define DSA_P_Y2 3
#define DSA_P_X13 4
#define DSA_P_Y13 5
#define DSA_P_L1 6
#define DSA_P_TH34 13
#define DSA_P_R6 14
#define DSA_P_THR 15
#define DSA_P_L1P 16
#define DSA_P_TH1P 17
#define DSA_P_SIG_LO 18
#define DSA_P_SIG_UP 19
#define DSA_P_M_ 20
#define DSA_P_I_ 27
#define DSA_P_LG_ 34
#define DSA_P_THG_ 41
#define DSA_P_KR 48
#define DSA_P_THR0 49
#define DSA_P_KL 50
#define DSA_P_LL0 51
#define DSA_P_CDAMP 52
#define DSA_P_GRAV 53
#define DSA_P_NPAR 54

/* the constants after P */
#define DSA_K_PITCH_LOCK 54         /* 1: theta7 locked (A.37), 3 coordinates */
#define DSA_K_TORQUE 55             /* actuation torque M0 of the static start (2.14) */
#define DSA_K_RAMP 56               /* 1: ramp raising (3.3.1) */
#define DSA_K_TORQUE_LOWERED 57     /* its torque at the lowered height */
#define DSA_K_RAMP_START 58
#define DSA_K_RAMP_DURATION 59
#define DSA_K_AERO_FORCE 60         /* aerodynamic uplift at the train speed [N] */
#define DSA_K_FRICTION_FORCE 61     /* f_r (2.16) */
#define DSA_K_FRICTION_SMOOTHING 62 /* k_t (2.16) */
#define DSA_K_ONE_WAY_DAMPER 63
#define DSA_K_COUNT 64


typedef struct {
    double P[DSA_P_NPAR];
    int n_dofs;
    int one_way;
    Actuation act;
    double aero_force, friction_force, friction_smoothing;
    /* work of an evaluation (4 coordinates; the locked pitch is 0) */
    double q4[4], v4[4], a4[4], vec[2][4], mat[4][4][4];
} Dsa380;

/* Fill m from the constants k (count DSA_K_COUNT); 0, or -1 with the reason in msg
   (HHT_MSG bytes). */
int dsa380_setup(Dsa380 *m, const double *k, long count, char *msg);
/* The residual pieces and tangents at (t, q, v, a) under inputs[0] = F (an HhtModelFn). */
int dsa380_evaluate(void *model, double t, const double *q, const double *v, const double *a,
                    const double *inputs, int tangent, HhtEval *out, char *msg);

#endif
