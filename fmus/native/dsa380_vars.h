/*
 * Value references and data-file layout of the native rigid DSA-380 pantograph FMU
 * (dsa380_pantograph.c): the variable names of the Python pantograph FMU
 * (fmus/fmi/pantograph_ports.py). pantocosim.master.native reads the DSA_VR_ lines to write
 * modelDescription.xml and the DSA_S_ lines to write the section "scalars".
 */
#ifndef DSA380_VARS_H
#define DSA380_VARS_H

/* Real */
#define DSA_VR_CONTACT_FORCE 1
#define DSA_VR_CONTACT_HEIGHT 2
#define DSA_VR_CONTACT_VELOCITY 3
#define DSA_VR_STATIC_FORCE 4
#define DSA_VR_AERO_C1 5
#define DSA_VR_AERO_C2 6
#define DSA_VR_SPEED_KMH 7
#define DSA_VR_FRICTION_FORCE 8
#define DSA_VR_FRICTION_SMOOTHING 9
#define DSA_VR_HHT_ALPHA 10
#define DSA_VR_INITIAL_HEIGHT 11
#define DSA_VR_INITIAL_CONTACT_FORCE 12
#define DSA_VR_NEWTON_ITERATIONS 13
#define DSA_VR_INTERNAL_STEP 14
#define DSA_VR_RAMP_START_TIME 15
#define DSA_VR_RAMP_DURATION 16
#define DSA_VR_LOWERED_HEIGHT 17
/* Integer */
#define DSA_VR_START_MODE 1
/* Boolean */
#define DSA_VR_ONE_WAY_DAMPER 1
#define DSA_VR_FORCE_EXTRAPOLATION 2

/* section "scalars": the stepping, the start and the parameters fixed at export */
#define DSA_S_STEP 0                /* internal step h [s] */
#define DSA_S_ALPHA 1               /* HHT alpha */
#define DSA_S_RTOL 2                /* Newton tolerances and limit (core/hht.py) */
#define DSA_S_ETOL 3
#define DSA_S_MAX_ITERATIONS 4
#define DSA_S_LINEAR_PREDICTOR 5
#define DSA_S_HEIGHT_MIN 6          /* the heights the model represents [m] */
#define DSA_S_HEIGHT_MAX 7
#define DSA_S_STATIC_FORCE 8
#define DSA_S_AERO_C1 9
#define DSA_S_AERO_C2 10
#define DSA_S_SPEED_KMH 11
#define DSA_S_FRICTION_FORCE 12
#define DSA_S_FRICTION_SMOOTHING 13
#define DSA_S_ONE_WAY_DAMPER 14
#define DSA_S_INITIAL_HEIGHT 15
#define DSA_S_INITIAL_CONTACT_FORCE 16
#define DSA_S_START_MODE 17         /* 0 static in contact, 1 ramp raising */
#define DSA_S_RAMP_START_TIME 18
#define DSA_S_RAMP_DURATION 19
#define DSA_S_LOWERED_HEIGHT 20
#define DSA_S_START_FORCE 21        /* the contact force at t0 */
#define DSA_S_COUNT 22

#endif
