/*
 * The instance of a native FMU, shared by the FMI 2.0 and 3.0 fronts (fmi2_front.c,
 * fmi3_front.c, which only translate types): its phase, the host's allocator and logger,
 * the data file and the model read from it (pcs_model.h), load and reset, the variables,
 * the step and the FMU states. Every function takes a possibly NULL instance and checks the
 * phase and the model before it touches either; a refusal is logged with the reason.
 */
#ifndef PCS_INSTANCE_H
#define PCS_INSTANCE_H

#include <stddef.h>

#include "pcs_model.h"

typedef enum {
    PCS_INSTANTIATED, PCS_INITIALISATION, PCS_STEPPING, PCS_TERMINATED, PCS_FAILED
} PcsPhase;

/* the front's logger: status PCS_OK, PCS_DISCARD or PCS_ERROR */
typedef void (*PcsLogger)(void *host, const char *instance, int status, const char *category,
                          const char *text);

typedef enum { PCS_REAL, PCS_INTEGER, PCS_BOOLEAN, PCS_STRING } PcsType;

typedef union {
    double real;
    int integer;               /* Integer and Boolean (0 or 1) */
    const char *string;
} PcsValue;

typedef struct {
    PcsMemory mem;             /* the host's allocator (ctx: the front's host data) */
    PcsLogger log;
    void *host;                /* the front's data: callbacks, environment */
    const PcsModelType *type;  /* NULL until a data file was read */
    void *model;               /* NULL after a failed load */
    PcsData data;
    PcsPhase phase;
    int initialised;           /* the model was initialised since it was read */
    double time;
    char name[128];
    char data_path[512];
    char msg[PCS_MSG];
} PcsInstance;

/* the instance of the data file model.pcsdata in the folder resources (a native path);
   NULL (the reason logged) when token is not pcs_instantiation_token (the host read another
   modelDescription.xml) or the data file cannot be read */
PcsInstance *pcs_instance_new(const char *name, const char *token, const char *resources,
                              const PcsMemory *mem, PcsLogger log, void *host);
void pcs_instance_free(PcsInstance *c);
int pcs_reset(PcsInstance *c, const char *call);
/* phase changes: the start time (FMI 2.0 SetupExperiment, FMI 3.0 EnterInitializationMode),
   initialisation, termination */
int pcs_set_start(PcsInstance *c, const char *call, double start);
int pcs_enter_initialisation(PcsInstance *c, const char *call);
int pcs_exit_initialisation(PcsInstance *c, const char *call);
int pcs_terminate(PcsInstance *c, const char *call);
int pcs_step(PcsInstance *c, const char *call, double t, double h);
/* log text with status (PCS_...) and return it; PCS_ERROR also fails the instance */
int pcs_report(PcsInstance *c, int status, const char *text);
/* log "call: text" as an Error and return PCS_ERROR; the phase is kept (the call was wrong,
   not the instance) */
int pcs_refuse(PcsInstance *c, const char *call, const char *text);

/* how values are accessed: written (up to step mode), read in any phase (FMI 2.0, whose
   hosts may read start values when instantiated) or read from initialisation mode on (FMI
   3.0, whose standard makes a read when instantiated an Error) */
typedef enum { PCS_READ_ANY, PCS_READ_INITIALISED, PCS_WRITE } PcsAccess;

/* before n values are accessed: the phase, the model and the arrays */
int pcs_values(PcsInstance *c, const char *call, PcsAccess access, size_t n, const void *vr,
               const void *values);
/* one value; a value reference the model does not have, or a value it refuses, is an Error
   that keeps the phase */
int pcs_get(PcsInstance *c, const char *call, PcsType type, unsigned vr,
            PcsValue *value);
int pcs_set(PcsInstance *c, const char *call, PcsType type, unsigned vr,
            const PcsValue *value);

/* FMU states: taken with the host's allocator, checked on the way back (this instance,
   this export, the size, a finite time) */
int pcs_state_get(PcsInstance *c, const char *call, void **state);
int pcs_state_set(PcsInstance *c, const char *call, const void *state);
int pcs_state_free(PcsInstance *c, const char *call, void **state);
int pcs_state_size(PcsInstance *c, const char *call, const void *state, size_t *size);
int pcs_state_serialize(PcsInstance *c, const char *call, const void *state,
                        unsigned char *out, size_t size);
int pcs_state_deserialize(PcsInstance *c, const char *call, const unsigned char *in,
                          size_t size, void **state);

#endif
