/*
 * The limits of the native FMUs, the one place they are defined (docs/tutorials/hil.md
 * lists them): a data file whose sizes exceed them is refused before anything is allocated,
 * an input or a step beyond them is refused with a Discard.
 */
#ifndef PCS_LIMITS_H
#define PCS_LIMITS_H

/* coordinates of a model, contact-wire elements and DOFs (the Python size guard's MAX_DOFS,
   pantocosim.catenary.size_guard) */
#define PCS_MAX_DOFS 200000
/* half-bandwidth of a banded matrix (catenary: M, K; modal: the contact wire's residual) */
#define PCS_MAX_BAND 2000
/* droppers of a catenary */
#define PCS_MAX_DROPPERS 10000
/* bytes a model may hold: its data file and everything it allocates (1 GiB) */
#define PCS_MAX_BYTES 1073741824.0
/* internal steps in one communication step */
#define PCS_MAX_SUBSTEPS 100000
/* the inputs no pantograph can go beyond: |contact force| in N, |height| above the rail in
   m, |vertical velocity| in m/s */
#define PCS_MAX_CONTACT_FORCE 1e5
#define PCS_MAX_HEIGHT 100.0
#define PCS_MAX_VELOCITY 100.0

/* the internal steps of h in a communication step H (1..PCS_MAX_SUBSTEPS), or -1 with the
   reason in err (PCS_MSG bytes): H not finite and > 0, not a whole number of h, too many */
long pcs_substeps(double H, double h, char *err);
/* 0 when |value| <= limit (finite), else -1 with "name = value: ..." in err */
/* a parameter fixed at export: its own value (to 1e-12 relative) is PCS_OK, another
   PCS_ERROR with the message */
int pcs_fixed_real(const char *name, double exported, double value, char *err);

int pcs_within(const char *name, double value, double lo, double hi, const char *unit,
               char *err);

#endif
