/*
 * The C host of the native FMUs and of the Python FMUs' embedding library: one program
 * (host_main.c) over a loader (host_loader.c, host_model_description.c) that hides FMI 2.0
 * and FMI 3.0 behind one table of calls (HostApi), filled by one thin front per version
 * (host_fmi2.c, host_fmi3.c). The loops (host_loops.c) and the script interpreter
 * (host_script.c) call the table only, never an FMI function.
 *
 * An FMU is a folder (the unpacked .fmu): its FMI version is the fmiVersion attribute of
 * its modelDescription.xml; its library is binaries/<platform>/<modelIdentifier> with the
 * platform folder of the host's own platform (host_platform_folder).
 */
#ifndef HOST_H
#define HOST_H

#include <stddef.h>
#include <stdio.h>

#define HOST_STATES 16        /* FMU state slots of a script's FMU */
#define HOST_MAX_VALUES 64    /* values of one get or set call */

typedef struct HostFmu HostFmu;

/* what every FMI version offers, in FMI 2.0's words; statuses are the FMI status numbers
   (0 OK, 1 Warning, 2 Discard, 3 Error, 4 Fatal); a version's own calls are NULL in the
   other version's table */
typedef struct {
    int (*instantiate)(HostFmu *f, const char *name, int logging, int event_mode);
    int (*setup)(HostFmu *f, double start_time);   /* FMI 3.0: kept for enter */
    int (*enter)(HostFmu *f);
    int (*exit_init)(HostFmu *f);
    int (*terminate)(HostFmu *f);
    int (*reset)(HostFmu *f);
    void (*free_instance)(HostFmu *f);
    int (*step)(HostFmu *f, double t, double h, int no_set_state_prior);
    int (*get_real)(HostFmu *f, const unsigned *vr, size_t n, double *v);
    int (*get_int)(HostFmu *f, const unsigned *vr, size_t n, int *v);
    int (*get_bool)(HostFmu *f, const unsigned *vr, size_t n, int *v);
    int (*get_string)(HostFmu *f, const unsigned *vr, size_t n, const char **v);
    int (*set_real)(HostFmu *f, const unsigned *vr, size_t n, const double *v);
    int (*set_int)(HostFmu *f, const unsigned *vr, size_t n, const int *v);
    int (*set_bool)(HostFmu *f, const unsigned *vr, size_t n, const int *v);
    int (*set_string)(HostFmu *f, const unsigned *vr, size_t n, const char *const *v);
    int (*get_state)(HostFmu *f, void **state);
    int (*set_state)(HostFmu *f, void *state);
    int (*free_state)(HostFmu *f, void **state);
    int (*state_size)(HostFmu *f, void *state, size_t *size);
    int (*serialize)(HostFmu *f, void *state, unsigned char *blob, size_t size);
    int (*deserialize)(HostFmu *f, const unsigned char *blob, size_t size, void **state);
    int (*terminated)(HostFmu *f, int *value);     /* of the last step */
    int (*last_time)(HostFmu *f, double *value);   /* last successful time of the last step */
    int (*unsupported)(HostFmu *f);   /* a call the FMUs do not offer (input derivatives) */
    int (*integer_status)(HostFmu *f, int kind, int *value);   /* FMI 2.0 only */
    int (*event_mode)(HostFmu *f);                             /* FMI 3.0 only */
    int (*step_mode)(HostFmu *f);                              /* FMI 3.0 only */
    int (*update)(HostFmu *f, int flags[5]);                   /* FMI 3.0 only */
} HostApi;

struct HostFmu {
    char alias[32];             /* the script's name of the FMU */
    char name[64];              /* the instance name */
    char dir[4096];             /* the unpacked FMU, an absolute path */
    char identifier[256];       /* modelIdentifier */
    char token[256];            /* guid or instantiationToken */
    int version;                /* 2 or 3 */
    char *description;          /* modelDescription.xml's text, NULL if it has none */
    void *library;
    const HostApi *api;
    void *calls;                /* the version front's resolved FMI functions */
    void *instance;
    double start_time;          /* FMI 3.0: setup's start time, given to enter */
    int step_terminated, step_event, step_early;   /* FMI 3.0: the last doStep's flags */
    double step_last_time;
    void *states[HOST_STATES];
    unsigned char *blobs[HOST_STATES];
    size_t blob_sizes[HOST_STATES];
};

/* host_loader.c: the FMU in dir loaded (identifier and token NULL: modelDescription.xml's);
   exits 3 naming what is missing */
void host_load(HostFmu *f, const char *dir, const char *identifier, const char *token);
void (*host_symbol(HostFmu *f, const char *name))(void);   /* NULL if absent */
const char *host_platform_folder(int version);
const char *host_library_suffix(void);
void host_log(const char *instance, int status, const char *category, const char *text);
extern FILE *host_log_stream;   /* where the FMUs' messages go (stderr unless set) */

/* host_model_description.c: an attribute of modelDescription.xml's text */
int host_attribute(const char *text, const char *element, const char *attribute, char *out,
                   size_t size);
unsigned host_value_reference(const HostFmu *f, const char *name);   /* exits 3 if absent */

/* host_fmi2.c, host_fmi3.c: the fronts */
void host_fmi2_bind(HostFmu *f);
void host_fmi3_bind(HostFmu *f);

/* host_memory.c: the allocations counted while a doStep runs and outside */
extern volatile int host_in_step;
extern long host_step_allocations, host_other_allocations;
void *host_counted_calloc(size_t n, size_t size);
void host_counted_free(void *p);
int host_allocations_counted(const HostFmu *f);   /* 0 where nothing counts them */

/* host_loops.c and host_script.c: the two ways of running FMUs */
int host_loop(int argc, char **argv);
int host_script(FILE *in);

#endif
