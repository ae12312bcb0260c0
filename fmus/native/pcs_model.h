/*
 * The model table: what the instance layer (pcs_instance.c) needs of a native model. Each
 * model fills one PcsModelType in its own file (catenary_linear.c, catenary_modal.c,
 * lumped.c); the FMU's binary lists the models it holds in pcs_model_table (model_table.c,
 * written by pantocosim.master.native.build), and an instance takes the one whose kind is
 * its data file's. Statuses: PCS_OK; PCS_DISCARD (the call is refused, the state is
 * unchanged, the message says why); PCS_ERROR (the instance cannot go on). Messages go into
 * err (PCS_MSG bytes). A model knows nothing of FMI.
 */
#ifndef PCS_MODEL_H
#define PCS_MODEL_H

#include <stddef.h>

#include "pcs_data.h"
#include "pcs_float.h"

#define PCS_OK 0
#define PCS_DISCARD 1
#define PCS_ERROR 2

#define PCS_MSG 2048

/* FMI 3.0 value references are unique across types: the model's Integer, Boolean and String
   references are offset by these in the FMI 3.0 model description (fmi3_front.c) */
#define PCS_FMI3_INT32_BASE 10000u
#define PCS_FMI3_BOOLEAN_BASE 20000u
#define PCS_FMI3_STRING_BASE 30000u

typedef struct {
    const char *name;          /* "linear catenary", for messages */
    unsigned kind;             /* the data files it reads (PCS_KIND_..., pcs_data.h) */
    /* new: everything a run needs is allocated here (a step allocates nothing); NULL with
       the reason in err */
    void *(*create)(const PcsData *d, const PcsMemory *mem, char *err);
    void (*destroy)(void *model, const PcsMemory *mem);
    /* the start state (at ExitInitializationMode) */
    int (*initialize)(void *model, char *err);
    /* one communication step of size h from the model time t */
    int (*step)(void *model, double t, double h, char *err);
    /* the outputs from the state (after a state is restored) */
    void (*outputs)(void *model);
    /* the FMU state: its size in bytes, a copy into / from a buffer of that size */
    size_t (*state_bytes)(const void *model);
    void (*state_save)(const void *model, void *buffer);
    void (*state_restore)(void *model, const void *buffer);
    /* the variables, by value reference (the numbers of the model's <model>_vars.h, which
       pantocosim.master.native.build reads to write modelDescription.xml); a setter is
       told whether the model was initialised (parameters are set before only) */
    int (*get_real)(void *model, unsigned vr, double *value, char *err);
    int (*set_real)(void *model, unsigned vr, double value, int initialised, char *err);
    int (*get_integer)(void *model, unsigned vr, int *value, char *err);
    int (*set_integer)(void *model, unsigned vr, int value, int initialised, char *err);
    int (*get_boolean)(void *model, unsigned vr, int *value, char *err);
    int (*set_boolean)(void *model, unsigned vr, int value, int initialised, char *err);
    int (*get_string)(void *model, unsigned vr, const char **value, char *err);
    int (*set_string)(void *model, unsigned vr, const char *value, int initialised,
                      char *err);
} PcsModelType;

/* the models of this binary, NULL-terminated (model_table.c) */
extern const PcsModelType *const pcs_model_table[];
/* the guid (FMI 2.0) or instantiationToken (FMI 3.0) of the modelDescription.xml this binary
   was built with (model_table.c): instantiation with another token is refused */
extern const char pcs_instantiation_token[];

#endif
