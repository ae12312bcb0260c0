/* The actuation torque (actuation.h): pantocosim.pantograph.base.TorqueActuatedPantograph. */
#include "actuation.h"
#include "pcs_float.h"

double actuation_torque(const Actuation *a, double t)
{
    double f;
    if (!a->ramp) return a->torque;
    if (a->ramp_duration <= 0.0) f = t >= a->ramp_start ? 1.0 : 0.0;
    else {
        f = (t - a->ramp_start) / a->ramp_duration;
        f = f < 0.0 ? 0.0 : f;
        f = f > 1.0 ? 1.0 : f;
    }
    return a->torque_lowered + f * (a->torque - a->torque_lowered);
}
