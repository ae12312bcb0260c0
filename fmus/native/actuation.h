/*
 * The actuation torque on the lower arm of a torque-raised pantograph (the rigid and the
 * flexible DSA-380): M0 of the static start (2.14), or with ramp raising (3.3.1)
 * M_low + r(t) (M0 - M_low), r rising linearly from 0 to 1 over the ramp's duration.
 */
#ifndef ACTUATION_H
#define ACTUATION_H

typedef struct {
    int ramp;                  /* 1: ramp raising */
    double torque;             /* M0 [N m] */
    double torque_lowered;     /* M_low: the lowered start's torque */
    double ramp_start, ramp_duration;   /* [s] */
} Actuation;

double actuation_torque(const Actuation *a, double t);

#endif
