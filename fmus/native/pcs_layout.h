/*
 * The fields of the data files' sections "sizes" (int32) and "scalars" (float64), by
 * position: the one place they are named. The models read them with these names;
 * pantocosim.master.native.headers reads these lines to write them (export.py) and to read
 * them back (models.py). A section holds exactly the fields of its prefix, 0..last.
 */
#ifndef PCS_LAYOUT_H
#define PCS_LAYOUT_H

/* linear catenary: sizes */
#define LIN_SIZE_DOFS 0
#define LIN_SIZE_BAND_M 1
#define LIN_SIZE_BAND_K 2
#define LIN_SIZE_DROPPERS 3
#define LIN_SIZE_DROPPER_WIDTH 4
#define LIN_SIZE_PANTOGRAPHS 5
#define LIN_SIZE_WIRE_ELEMENTS 6
#define LIN_SIZE_SUPPORTS 7
#define LIN_SIZE_SPANS 8
#define LIN_SIZE_MODEL_CODE 9
#define LIN_SIZES 10

/* modal catenary: sizes */
#define MOD_SIZE_COORDINATES 0
#define MOD_SIZE_MODES 1
#define MOD_SIZE_DROPPER_COORDINATES 2
#define MOD_SIZE_PANTOGRAPH_COORDINATES 3
#define MOD_SIZE_DROPPERS 4
#define MOD_SIZE_PANTOGRAPHS 5
#define MOD_SIZE_WIRE_ELEMENTS 6
#define MOD_SIZE_SUPPORTS 7
#define MOD_SIZE_WIRE_DOFS 8
#define MOD_SIZE_BAND 9
#define MOD_SIZE_SPANS 10
#define MOD_SIZE_MODEL_CODE 11
#define MOD_SIZES 12

/* both catenaries: scalars (the modal model adds MOD_SCALAR_ fields after them) */
#define CAT_SCALAR_STEP 0
#define CAT_SCALAR_ALPHA 1
#define CAT_SCALAR_BETA 2
#define CAT_SCALAR_GAMMA 3
#define CAT_SCALAR_RAYLEIGH_MASS 4
#define CAT_SCALAR_RAYLEIGH_STIFFNESS 5
#define CAT_SCALAR_SPEED 6
#define CAT_SCALAR_WAVE_SPEED 7
#define CAT_SCALAR_CONTACT_STIFFNESS 8
#define CAT_SCALAR_CONTACT_DAMPING 9
#define CAT_SCALAR_WIRE_START 10
#define CAT_SCALAR_WIRE_END 11
#define CAT_SCALAR_MODAL_CUTOFF 12
#define CAT_SCALAR_NEWTON_RTOL 13
#define LIN_SCALARS 14
#define MOD_SCALAR_DROPPER_STIFFNESS 14
#define MOD_SCALARS 15

/* lumped pantograph: sizes and scalars */
#define PAN_SIZE_MASSES 0
#define PAN_SIZES 1
#define PAN_SCALAR_STEP 0
#define PAN_SCALAR_ALPHA 1
#define PAN_SCALAR_BETA 2
#define PAN_SCALAR_GAMMA 3
#define PAN_SCALAR_HEIGHT_MIN 4
#define PAN_SCALAR_HEIGHT_MAX 5
#define PAN_SCALAR_STATIC_FORCE 6
#define PAN_SCALAR_AERO_C1 7
#define PAN_SCALAR_AERO_C2 8
#define PAN_SCALAR_SPEED_KMH 9
#define PAN_SCALAR_INITIAL_HEIGHT 10
#define PAN_SCALAR_INITIAL_FORCE 11
#define PAN_SCALAR_FRICTION_FORCE 12
#define PAN_SCALAR_FRICTION_SMOOTHING 13
#define PAN_SCALARS 14

/* nonlinear pantographs (rigid, flexible DSA-380): scalars, the stepping, the start and the
   parameters fixed at export */
#define NLP_SCALAR_STEP 0                /* internal step h [s] */
#define NLP_SCALAR_ALPHA 1               /* HHT alpha */
#define NLP_SCALAR_RTOL 2                /* Newton tolerances and limit (core/hht.py) */
#define NLP_SCALAR_ETOL 3
#define NLP_SCALAR_MAX_ITERATIONS 4
#define NLP_SCALAR_LINEAR_PREDICTOR 5
#define NLP_SCALAR_HEIGHT_MIN 6          /* the heights the model represents [m] */
#define NLP_SCALAR_HEIGHT_MAX 7
#define NLP_SCALAR_STATIC_FORCE 8
#define NLP_SCALAR_AERO_C1 9
#define NLP_SCALAR_AERO_C2 10
#define NLP_SCALAR_SPEED_KMH 11
#define NLP_SCALAR_FRICTION_FORCE 12
#define NLP_SCALAR_FRICTION_SMOOTHING 13
#define NLP_SCALAR_ONE_WAY_DAMPER 14
#define NLP_SCALAR_INITIAL_HEIGHT 15
#define NLP_SCALAR_INITIAL_CONTACT_FORCE 16
#define NLP_SCALAR_START_MODE 17         /* 0 static in contact, 1 ramp raising */
#define NLP_SCALAR_RAMP_START_TIME 18
#define NLP_SCALAR_RAMP_DURATION 19
#define NLP_SCALAR_LOWERED_HEIGHT 20
#define NLP_SCALAR_START_FORCE 21        /* the contact force at t0 */
#define NLP_SCALARS 22

#endif
