/*
 * Value references and data-file layout of the native nonlinear pantograph FMUs (the rigid and
 * the flexible DSA-380, nonlinear_pantograph.c): the variable names of the Python pantograph FMU
 * (fmus/fmi/pantograph_ports.py). pantocosim.master.native reads the NLP_VR_ lines to write
 * modelDescription.xml and the NLP_S_ lines to write the section "scalars".
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

/* section "scalars": the stepping, the start and the parameters fixed at export */
#define NLP_S_STEP 0                /* internal step h [s] */
#define NLP_S_ALPHA 1               /* HHT alpha */
#define NLP_S_RTOL 2                /* Newton tolerances and limit (core/hht.py) */
#define NLP_S_ETOL 3
#define NLP_S_MAX_ITERATIONS 4
#define NLP_S_LINEAR_PREDICTOR 5
#define NLP_S_HEIGHT_MIN 6          /* the heights the model represents [m] */
#define NLP_S_HEIGHT_MAX 7
#define NLP_S_STATIC_FORCE 8
#define NLP_S_AERO_C1 9
#define NLP_S_AERO_C2 10
#define NLP_S_SPEED_KMH 11
#define NLP_S_FRICTION_FORCE 12
#define NLP_S_FRICTION_SMOOTHING 13
#define NLP_S_ONE_WAY_DAMPER 14
#define NLP_S_INITIAL_HEIGHT 15
#define NLP_S_INITIAL_CONTACT_FORCE 16
#define NLP_S_START_MODE 17         /* 0 static in contact, 1 ramp raising */
#define NLP_S_RAMP_START_TIME 18
#define NLP_S_RAMP_DURATION 19
#define NLP_S_LOWERED_HEIGHT 20
#define NLP_S_START_FORCE 21        /* the contact force at t0 */
#define NLP_S_COUNT 22

#endif
