/*
 * Value references of the native lumped pantograph FMU: the same variable names as the
 * Python pantograph FMU (fmus/fmi/pantograph_ports.py). pantocosim.master.native.export
 * reads the PAN_VR_ lines of this file to write modelDescription.xml.
 */
#ifndef LUMPED_VARS_H
#define LUMPED_VARS_H

/* Real */
#define PAN_VR_CONTACT_FORCE 1
#define PAN_VR_CONTACT_HEIGHT 2
#define PAN_VR_CONTACT_VELOCITY 3
#define PAN_VR_STATIC_FORCE 4
#define PAN_VR_AERO_C1 5
#define PAN_VR_AERO_C2 6
#define PAN_VR_SPEED_KMH 7
#define PAN_VR_FRICTION_FORCE 8
#define PAN_VR_FRICTION_SMOOTHING 9
#define PAN_VR_HHT_ALPHA 10
#define PAN_VR_INITIAL_HEIGHT 11
#define PAN_VR_INITIAL_CONTACT_FORCE 12
#define PAN_VR_NEWTON_ITERATIONS 13
#define PAN_VR_INTERNAL_STEP 14
/* Integer */
#define PAN_VR_START_MODE 1
/* Boolean */
#define PAN_VR_ONE_WAY_DAMPER 1
#define PAN_VR_FORCE_EXTRAPOLATION 2
/* String */
#define PAN_VR_PRESET 1

#define PAN_MAX_DOFS 16

#endif
