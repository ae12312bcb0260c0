/*
 * What an FMI front (fmi2_front.c, fmi3_front.c) needs of a native model: one model per
 * FMU binary (catenary.c, lumped.c). Statuses: PCS_OK; PCS_DISCARD (the call is refused, the
 * state is unchanged, the message says why); PCS_ERROR (the instance cannot go on).
 */
#ifndef PCS_MODEL_H
#define PCS_MODEL_H

#include <stddef.h>

#include "pcs_data.h"

#define PCS_OK 0
#define PCS_DISCARD 1
#define PCS_ERROR 2

#define PCS_MSG 2048

/* FMI 3.0 value references are unique across types: the model's Integer, Boolean and String
   references are offset by these in the FMI 3.0 model description (fmi3_front.c) */
#define PCS_FMI3_INT32_BASE 10000u
#define PCS_FMI3_BOOLEAN_BASE 20000u
#define PCS_FMI3_STRING_BASE 30000u

typedef struct PcsModel PcsModel;

/* the data kind this model reads (PCS_KIND_...) */
unsigned pcs_model_kind(void);
/* everything a run needs is allocated here (a step allocates nothing) */
PcsModel *pcs_model_new(const PcsData *d, const PcsMemory *mem, char *err);
void pcs_model_free(PcsModel *m, const PcsMemory *mem);
/* the variables, by value reference (the same numbers as the modelDescription.xml written
   by pantocosim.master.native.export, which reads them from the model's header) */
int pcs_get_real(PcsModel *m, unsigned vr, double *value, char *err);
int pcs_set_real(PcsModel *m, unsigned vr, double value, int initialised, char *err);
int pcs_get_integer(PcsModel *m, unsigned vr, int *value, char *err);
int pcs_set_integer(PcsModel *m, unsigned vr, int value, int initialised, char *err);
int pcs_get_boolean(PcsModel *m, unsigned vr, int *value, char *err);
int pcs_set_boolean(PcsModel *m, unsigned vr, int value, int initialised, char *err);
int pcs_get_string(PcsModel *m, unsigned vr, const char **value, char *err);
int pcs_set_string(PcsModel *m, unsigned vr, const char *value, int initialised, char *err);
/* the start state (at fmi2ExitInitializationMode) */
int pcs_initialize(PcsModel *m, char *err);
/* one communication step of size h from the model time t */
int pcs_do_step(PcsModel *m, double t, double h, char *err);
double pcs_time(const PcsModel *m);
/* the FMU state: its size in bytes, a copy into / from a buffer of that size */
size_t pcs_state_bytes(const PcsModel *m);
void pcs_state_save(const PcsModel *m, void *buffer);
void pcs_state_restore(PcsModel *m, const void *buffer);

#endif
