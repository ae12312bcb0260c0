/*
 * Value references of the native nonlinear pantograph FMUs (the rigid and
 * the flexible DSA-380, nonlinear_pantograph.c): the variable names of the Python pantograph FMU
 * (fmus/fmi/pantograph_ports.py). pantocosim.master.native reads the NLP_VR_ lines to write
 * modelDescription.xml.
 */
#ifndef NONLINEAR_PANTOGRAPH_VARS_H
#define NONLINEAR_PANTOGRAPH_VARS_H

/* Real */
#define NLP_VR_CONTACT_FORCE 1
#define NLP_VR_CONTACT_HEIGHT 2
#define NLP_VR_CONTACT_VELOCITY 3
#define NLP_VR_STATIC_FORCE 4
#define NLP_VR_AERO_C1 5
#define NLP_VR_AERO_C2 6
#define NLP_VR_SPEED_KMH 7
#define NLP_VR_FRICTION_FORCE 8
#define NLP_VR_FRICTION_SMOOTHING 9
#define NLP_VR_HHT_ALPHA 10
#define NLP_VR_INITIAL_HEIGHT 11
#define NLP_VR_INITIAL_CONTACT_FORCE 12
#define NLP_VR_NEWTON_ITERATIONS 13
#define NLP_VR_INTERNAL_STEP 14
#define NLP_VR_RAMP_START_TIME 15
#define NLP_VR_RAMP_DURATION 16
#define NLP_VR_LOWERED_HEIGHT 17
/* Integer */
#define NLP_VR_START_MODE 1
/* Boolean */
#define NLP_VR_ONE_WAY_DAMPER 1
#define NLP_VR_FORCE_EXTRAPOLATION 2

#endif
