/*
 * A minimal native FMI 2.0 co-simulation host for the tests (tests/test_native_host.py):
 * it dlopens the FMUs' linux64 binaries, as a C or C++ master does, and runs a script of FMI
 * calls read from standard input, one call per line:
 *
 *   load A DIR MODEL_IDENTIFIER GUID     instantiate A NAME       free A
 *   setup A T0      enter A      exit A      terminate A      reset A
 *   set A r|i|b|s VR VALUE       get A r|i|b|s VR...       step A T H
 *   copy A VR B VR          (fmi2GetReal of A into fmi2SetReal of B)
 *   getstate A K   setstate A K [B]   freestate A K   serialize A K   deserialize A K [B]
 *   garbage A K    (fmi2DeSerializeFMUstate of 16 bytes of garbage into slot K)
 *   terminated A   lasttime A     unsupported A
 *   intstatus A KIND   (fmi2GetIntegerStatus: FMI 2.0 defines none, so Error)
 *
 * Each call prints "= LINE CALL STATUS [values]"; the FMU's log messages print
 * "LOG INSTANCE STATUS CATEGORY MESSAGE". Values are printed with 17 digits.
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void *fmi2Component;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef int fmi2Status;
typedef void (*Logger)(void *, const char *, int, const char *, const char *, ...);
typedef struct {
    Logger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, int);
    void *componentEnvironment;
} Callbacks;

typedef struct {
    char alias[32];
    void *lib;
    char resources[4096];
    char guid[128];
    fmi2Component c;
    fmi2FMUstate states[16];
    char *blobs[16];
    size_t blob_sizes[16];
} Fmu;

static Fmu fmus[8];
static int n_fmus;

static void logger(void *env, const char *instance, int status, const char *category,
                   const char *message, ...)
{
    char text[8192];
    va_list args;
    (void)env;
    va_start(args, message);
    vsnprintf(text, sizeof text, message ? message : "(null)", args);
    va_end(args);
    for (char *p = text; *p; p++)
        if (*p == '\n') *p = ' ';
    printf("LOG %s %d %s %s\n", instance ? instance : "(null)", status,
           category ? category : "(null)", text);
}

static Callbacks callbacks = {logger, calloc, free, NULL, NULL};

static Fmu *find(const char *alias)
{
    for (int i = 0; i < n_fmus; i++)
        if (strcmp(fmus[i].alias, alias) == 0) return &fmus[i];
    fprintf(stderr, "unknown FMU alias %s\n", alias);
    exit(3);
}

static void *sym(Fmu *f, const char *name)
{
    void *p = dlsym(f->lib, name);
    if (p == NULL) {
        fprintf(stderr, "%s: no symbol %s\n", f->alias, name);
        exit(3);
    }
    return p;
}

#define CALL(f, name, type, ...) ((type)sym(f, name))(__VA_ARGS__)
typedef fmi2Status (*F0)(fmi2Component);
typedef fmi2Status (*FVr)(fmi2Component, const fmi2ValueReference *, size_t, void *);

static void load(char **a)
{
    Fmu *f = &fmus[n_fmus++];
    char lib[4200];
    snprintf(f->alias, sizeof f->alias, "%s", a[1]);
    snprintf(lib, sizeof lib, "%s/binaries/linux64/%s.so", a[2], a[3]);
    snprintf(f->resources, sizeof f->resources, "file://%s/resources", a[2]);
    snprintf(f->guid, sizeof f->guid, "%s", a[4]);
    f->lib = dlopen(lib, RTLD_NOW | RTLD_LOCAL);
    if (f->lib == NULL) {
        printf("= load %s failed: %s\n", a[1], dlerror());
        exit(4);
    }
}

static char extra[8192]; /* values printed after the status */

static int run(int line, char **a, int n)
{
    const char *cmd = a[0];
    Fmu *f = n > 1 && strcmp(cmd, "load") ? find(a[1]) : NULL;
    int s = 0;
    if (!strcmp(cmd, "load")) {
        load(a);
        printf("= %d load 0\n", line);
        return 0;
    }
    extra[0] = '\0';
    if (!strcmp(cmd, "instantiate")) {
        typedef fmi2Component (*I)(const char *, int, const char *, const char *,
                                   const Callbacks *, int, int);
        f->c = CALL(f, "fmi2Instantiate", I, a[2], 1, f->guid, f->resources, &callbacks, 0, 1);
        s = f->c ? 0 : 3;
    } else if (!strcmp(cmd, "setup")) {
        typedef fmi2Status (*S)(fmi2Component, int, double, double, int, double);
        s = CALL(f, "fmi2SetupExperiment", S, f->c, 0, 0.0, atof(a[2]), 0, 0.0);
    } else if (!strcmp(cmd, "enter")) {
        s = CALL(f, "fmi2EnterInitializationMode", F0, f->c);
    } else if (!strcmp(cmd, "exit")) {
        s = CALL(f, "fmi2ExitInitializationMode", F0, f->c);
    } else if (!strcmp(cmd, "terminate")) {
        s = CALL(f, "fmi2Terminate", F0, f->c);
    } else if (!strcmp(cmd, "reset")) {
        s = CALL(f, "fmi2Reset", F0, f->c);
    } else if (!strcmp(cmd, "free")) {
        CALL(f, "fmi2FreeInstance", void (*)(fmi2Component), f->c);
    } else if (!strcmp(cmd, "step")) {
        typedef fmi2Status (*D)(fmi2Component, double, double, int);
        s = CALL(f, "fmi2DoStep", D, f->c, atof(a[2]), atof(a[3]), 0);
    } else if (!strcmp(cmd, "set")) {
        fmi2ValueReference vr = (fmi2ValueReference)strtoul(a[3], NULL, 10);
        double r = atof(a[4]);
        int i = atoi(a[4]);
        const char *str = a[4];
        const char *names[] = {"fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean",
                               "fmi2SetString"};
        int k = strchr("ribs", a[2][0]) - "ribs";
        void *value = k == 0 ? (void *)&r : k == 3 ? (void *)&str : (void *)&i;
        s = CALL(f, names[k], FVr, f->c, &vr, 1, value);
    } else if (!strcmp(cmd, "get")) {
        fmi2ValueReference vr[64];
        double r[64];
        int i[64];
        const char *str[64];
        int m = n - 3, k = strchr("ribs", a[2][0]) - "ribs";
        const char *names[] = {"fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean",
                               "fmi2GetString"};
        for (int j = 0; j < m; j++) vr[j] = (fmi2ValueReference)strtoul(a[3 + j], NULL, 10);
        s = CALL(f, names[k], FVr, f->c, vr, (size_t)m,
                 k == 0 ? (void *)r : k == 3 ? (void *)str : (void *)i);
        for (int j = 0; s < 2 && j < m; j++) {
            size_t used = strlen(extra);
            if (k == 0) snprintf(extra + used, sizeof extra - used, " %.17g", r[j]);
            else if (k == 3) snprintf(extra + used, sizeof extra - used, " %s", str[j]);
            else snprintf(extra + used, sizeof extra - used, " %d", i[j]);
        }
    } else if (!strcmp(cmd, "copy")) {
        Fmu *g = find(a[3]);
        fmi2ValueReference from = (fmi2ValueReference)strtoul(a[2], NULL, 10);
        fmi2ValueReference to = (fmi2ValueReference)strtoul(a[4], NULL, 10);
        double r = 0.0;
        s = CALL(f, "fmi2GetReal", FVr, f->c, &from, 1, &r);
        if (s < 2) s = CALL(g, "fmi2SetReal", FVr, g->c, &to, 1, &r);
    } else if (!strcmp(cmd, "getstate") || !strcmp(cmd, "setstate")
               || !strcmp(cmd, "freestate")) {
        int k = atoi(a[2]);
        typedef fmi2Status (*G)(fmi2Component, fmi2FMUstate *);
        typedef fmi2Status (*St)(fmi2Component, fmi2FMUstate);
        if (cmd[0] == 'g') s = CALL(f, "fmi2GetFMUstate", G, f->c, &f->states[k]);
        else if (cmd[0] == 's') /* optionally another FMU's slot: a foreign pointer */
            s = CALL(f, "fmi2SetFMUstate", St, f->c, (a[3] ? find(a[3]) : f)->states[k]);
        else {
            fmi2FMUstate copy = f->states[k]; /* the slot keeps the freed pointer */
            s = CALL(f, "fmi2FreeFMUstate", G, f->c, &copy);
        }
    } else if (!strcmp(cmd, "serialize")) {
        int k = atoi(a[2]);
        size_t size = 0;
        typedef fmi2Status (*Z)(fmi2Component, fmi2FMUstate, size_t *);
        typedef fmi2Status (*W)(fmi2Component, fmi2FMUstate, char *, size_t);
        s = CALL(f, "fmi2SerializedFMUstateSize", Z, f->c, f->states[k], &size);
        if (s < 2) {
            free(f->blobs[k]);
            f->blobs[k] = malloc(size);
            f->blob_sizes[k] = size;
            s = CALL(f, "fmi2SerializeFMUstate", W, f->c, f->states[k], f->blobs[k], size);
        }
    } else if (!strcmp(cmd, "deserialize") || !strcmp(cmd, "garbage")) {
        int k = atoi(a[2]);
        static char junk[16] = "garbage bytes!!";
        typedef fmi2Status (*R)(fmi2Component, const char *, size_t, fmi2FMUstate *);
        f->states[k] = NULL;
        if (cmd[0] == 'g') s = CALL(f, "fmi2DeSerializeFMUstate", R, f->c, junk, 16,
                                    &f->states[k]);
        else {
            Fmu *from = a[3] ? find(a[3]) : f; /* blob of another FMU's slot */
            s = CALL(f, "fmi2DeSerializeFMUstate", R, f->c, from->blobs[k],
                     from->blob_sizes[k], &f->states[k]);
        }
    } else if (!strcmp(cmd, "terminated")) {
        int v = -1;
        typedef fmi2Status (*B)(fmi2Component, int, int *);
        s = CALL(f, "fmi2GetBooleanStatus", B, f->c, 3, &v);
        snprintf(extra, sizeof extra, " %d", v);
    } else if (!strcmp(cmd, "lasttime")) {
        double v = -1;
        typedef fmi2Status (*Rs)(fmi2Component, int, double *);
        s = CALL(f, "fmi2GetRealStatus", Rs, f->c, 2, &v);
        snprintf(extra, sizeof extra, " %.17g", v);
    } else if (!strcmp(cmd, "intstatus")) {
        int v = -1;
        typedef fmi2Status (*Is)(fmi2Component, int, int *);
        s = CALL(f, "fmi2GetIntegerStatus", Is, f->c, atoi(a[2]), &v);
        snprintf(extra, sizeof extra, " %d", v);
    } else if (!strcmp(cmd, "unsupported")) {
        fmi2ValueReference vr = 0;
        int order = 1;
        double value = 0.0;
        typedef fmi2Status (*U)(fmi2Component, const fmi2ValueReference *, size_t,
                                const int *, const double *);
        s = CALL(f, "fmi2SetRealInputDerivatives", U, f->c, &vr, 1, &order, &value);
    } else {
        fprintf(stderr, "line %d: unknown call %s\n", line, cmd);
        exit(3);
    }
    printf("= %d %s %d%s\n", line, cmd, s, extra);
    return s;
}

int main(void)
{
    char buffer[8192];
    int line = 0;
    setvbuf(stdout, NULL, _IOLBF, 0);
    while (fgets(buffer, sizeof buffer, stdin)) {
        char *a[72] = {0};
        int n = 0;
        line++;
        for (char *t = strtok(buffer, " \t\r\n"); t && n < 71; t = strtok(NULL, " \t\r\n"))
            a[n++] = t;
        if (n == 0 || a[0][0] == '#') continue;
        run(line, a, n);
    }
    for (int i = 0; i < n_fmus; i++) /* the libraries stay loaded, as in most hosts */
        for (int k = 0; k < 16; k++) free(fmus[i].blobs[k]);
    return 0;
}
