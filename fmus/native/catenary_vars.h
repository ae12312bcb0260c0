/*
 * Value references of the native catenary FMU: the same variable names as the Python
 * catenary FMU (fmus/fmi/catenary_ports.py). pantocosim.master.native.export reads the
 * CAT_VR_ lines of this file to write modelDescription.xml: this is the one place they
 * are numbered. A per-pantograph variable k (1..n) is BASE + k - 1, a support j is
 * CAT_VR_SUPPORT_UPLIFT + j.
 */
#ifndef CATENARY_VARS_H
#define CATENARY_VARS_H

/* Real */
#define CAT_VR_SPEED_KMH 1
#define CAT_VR_HHT_ALPHA 2
#define CAT_VR_CONTACT_STIFFNESS 3
#define CAT_VR_CONTACT_DAMPING 4
#define CAT_VR_NEWTON_RTOL 5
#define CAT_VR_MODAL_CUTOFF_HZ 6
#define CAT_VR_N_SUPPORTS 7
#define CAT_VR_TRAIN_SPEED_KMH 8
#define CAT_VR_NEWTON_ITERATIONS 9
#define CAT_VR_INTERNAL_STEP 10
#define CAT_VR_POSITION 100
#define CAT_VR_STATIC_FORCE 110
#define CAT_VR_CONTACT_FORCE 120
#define CAT_VR_PANTOGRAPH_HEIGHT 130
#define CAT_VR_PANTOGRAPH_VELOCITY 140
#define CAT_VR_WIRE_HEIGHT 150
#define CAT_VR_WIRE_VELOCITY 160
#define CAT_VR_CONTACT_FORCE_OUT 170
#define CAT_VR_SUPPORT_UPLIFT 200
/* Integer */
#define CAT_VR_N_PANTOGRAPHS 1
#define CAT_VR_SPANS 2
#define CAT_VR_CATENARY_MODEL 3
#define CAT_VR_CONTACT_MODE 4
/* Boolean */
#define CAT_VR_EXTRAPOLATE_HEIGHTS 1
/* String */
#define CAT_VR_CATENARY_DEFINITION 1

#define CAT_MAX_PANTOGRAPHS 4
#define CAT_MAX_SUPPORTS 64

#endif
