/*
 * A minimal native FMI 3.0 co-simulation host for the tests (tests/test_fmi3.py): the FMI 3.0
 * counterpart of fmi2_host.c. It dlopens the FMUs' x86_64-linux binaries, as a C or C++
 * master does, and runs a script of FMI calls read from standard input, one call per line,
 * in the script language of fmi2_host.c (tests/fmi_script.py writes it):
 *
 *   load A DIR MODEL_IDENTIFIER TOKEN    instantiate A NAME [events]       free A
 *   setup A T0 (kept for enter)  enter A      exit A      terminate A      reset A
 *   set A r|i|b|s VR VALUE       get A r|i|b|s VR...       step A T H
 *   copy A VR B VR          (fmi3GetFloat64 of A into fmi3SetFloat64 of B)
 *   getstate A K   setstate A K [B]   freestate A K   serialize A K   deserialize A K [B]
 *   garbage A K    (fmi3DeserializeFMUState of 16 bytes of garbage into slot K)
 *   terminated A   (terminateSimulation of the last fmi3DoStep)
 *   lasttime A     (lastSuccessfulTime of the last fmi3DoStep)    unsupported A
 *   eventmode A    update A (fmi3UpdateDiscreteStates: prints its five flags)    stepmode A
 *
 * "instantiate A NAME events" instantiates with eventModeUsed = true.
 *
 * r, i, b, s are Float64, Int32, Boolean and String. Each call prints
 * "= LINE CALL STATUS [values]"; the FMU's log messages print
 * "LOG INSTANCE STATUS CATEGORY MESSAGE". Values are printed with 17 digits.
 */
#include <dlfcn.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void *fmi3Instance;
typedef void *fmi3FMUState;
typedef uint32_t fmi3ValueReference;
typedef int fmi3Status;
typedef void (*LogMessage)(void *, int, const char *, const char *);

typedef struct {
    char alias[32];
    void *lib;
    char resources[4096];
    char token[128];
    char name[64];
    double t0;
    bool terminate;
    double last_time;
    fmi3Instance c;
    fmi3FMUState states[16];
    unsigned char *blobs[16];
    size_t blob_sizes[16];
} Fmu;

static Fmu fmus[8];
static int n_fmus;

static void log_message(void *env, int status, const char *category, const char *message)
{
    char text[8192];
    Fmu *f = (Fmu *)env;
    snprintf(text, sizeof text, "%s", message ? message : "(null)");
    for (char *p = text; *p; p++)
        if (*p == '\n') *p = ' ';
    printf("LOG %s %d %s %s\n", f ? f->name : "(null)", status,
           category ? category : "(null)", text);
}

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
typedef fmi3Status (*F0)(fmi3Instance);
typedef fmi3Status (*FVr)(fmi3Instance, const fmi3ValueReference *, size_t, void *, size_t);

static void load(char **a)
{
    Fmu *f = &fmus[n_fmus++];
    char lib[4200];
    snprintf(f->alias, sizeof f->alias, "%s", a[1]);
    snprintf(lib, sizeof lib, "%s/binaries/x86_64-linux/%s.so", a[2], a[3]);
    snprintf(f->resources, sizeof f->resources, "%s/resources/", a[2]);
    snprintf(f->token, sizeof f->token, "%s", a[4]);
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
        typedef fmi3Instance (*I)(const char *, const char *, const char *, bool, bool, bool,
                                  bool, const fmi3ValueReference *, size_t, void *,
                                  LogMessage, void *);
        snprintf(f->name, sizeof f->name, "%s", a[2]);
        bool events = n > 3 && !strcmp(a[3], "events");
        f->c = CALL(f, "fmi3InstantiateCoSimulation", I, a[2], f->token, f->resources, false,
                    true, events, false, NULL, 0, f, log_message, NULL);
        s = f->c ? 0 : 3;
    } else if (!strcmp(cmd, "setup")) {
        f->t0 = atof(a[2]);
    } else if (!strcmp(cmd, "enter")) {
        typedef fmi3Status (*E)(fmi3Instance, bool, double, double, bool, double);
        s = CALL(f, "fmi3EnterInitializationMode", E, f->c, false, 0.0, f->t0, false, 0.0);
    } else if (!strcmp(cmd, "exit")) {
        s = CALL(f, "fmi3ExitInitializationMode", F0, f->c);
    } else if (!strcmp(cmd, "terminate")) {
        s = CALL(f, "fmi3Terminate", F0, f->c);
    } else if (!strcmp(cmd, "reset")) {
        s = CALL(f, "fmi3Reset", F0, f->c);
    } else if (!strcmp(cmd, "free")) {
        CALL(f, "fmi3FreeInstance", void (*)(fmi3Instance), f->c);
    } else if (!strcmp(cmd, "step")) {
        typedef fmi3Status (*D)(fmi3Instance, double, double, bool, bool *, bool *, bool *,
                                double *);
        bool event = true, early = true;
        f->terminate = true;
        f->last_time = -1.0;
        s = CALL(f, "fmi3DoStep", D, f->c, atof(a[2]), atof(a[3]), false, &event,
                 &f->terminate, &early, &f->last_time);
        if (event || early) {
            printf("= %d step: eventHandlingNeeded %d earlyReturn %d\n", line, event, early);
            exit(5);
        }
    } else if (!strcmp(cmd, "set")) {
        fmi3ValueReference vr = (fmi3ValueReference)strtoul(a[3], NULL, 10);
        double r = atof(a[4]);
        int32_t i = atoi(a[4]);
        bool b = atoi(a[4]) != 0;
        const char *str = a[4];
        const char *names[] = {"fmi3SetFloat64", "fmi3SetInt32", "fmi3SetBoolean",
                               "fmi3SetString"};
        int k = strchr("ribs", a[2][0]) - "ribs";
        void *value = k == 0 ? (void *)&r : k == 1 ? (void *)&i : k == 2 ? (void *)&b
                                                                         : (void *)&str;
        s = CALL(f, names[k], FVr, f->c, &vr, 1, value, 1);
    } else if (!strcmp(cmd, "get")) {
        fmi3ValueReference vr[64];
        double r[64];
        int32_t i[64];
        bool b[64];
        const char *str[64];
        int m = n - 3, k = strchr("ribs", a[2][0]) - "ribs";
        const char *names[] = {"fmi3GetFloat64", "fmi3GetInt32", "fmi3GetBoolean",
                               "fmi3GetString"};
        void *out = k == 0 ? (void *)r : k == 1 ? (void *)i : k == 2 ? (void *)b : (void *)str;
        for (int j = 0; j < m; j++) vr[j] = (fmi3ValueReference)strtoul(a[3 + j], NULL, 10);
        s = CALL(f, names[k], FVr, f->c, vr, (size_t)m, out, (size_t)m);
        for (int j = 0; s < 2 && j < m; j++) {
            size_t used = strlen(extra);
            if (k == 0) snprintf(extra + used, sizeof extra - used, " %.17g", r[j]);
            else if (k == 1) snprintf(extra + used, sizeof extra - used, " %d", i[j]);
            else if (k == 2) snprintf(extra + used, sizeof extra - used, " %d", (int)b[j]);
            else snprintf(extra + used, sizeof extra - used, " %s", str[j]);
        }
    } else if (!strcmp(cmd, "copy")) {
        Fmu *g = find(a[3]);
        fmi3ValueReference from = (fmi3ValueReference)strtoul(a[2], NULL, 10);
        fmi3ValueReference to = (fmi3ValueReference)strtoul(a[4], NULL, 10);
        double r = 0.0;
        s = CALL(f, "fmi3GetFloat64", FVr, f->c, &from, 1, &r, 1);
        if (s < 2) s = CALL(g, "fmi3SetFloat64", FVr, g->c, &to, 1, &r, 1);
    } else if (!strcmp(cmd, "getstate") || !strcmp(cmd, "setstate")
               || !strcmp(cmd, "freestate")) {
        int k = atoi(a[2]);
        typedef fmi3Status (*G)(fmi3Instance, fmi3FMUState *);
        typedef fmi3Status (*St)(fmi3Instance, fmi3FMUState);
        if (cmd[0] == 'g') s = CALL(f, "fmi3GetFMUState", G, f->c, &f->states[k]);
        else if (cmd[0] == 's') /* optionally another FMU's slot: a foreign pointer */
            s = CALL(f, "fmi3SetFMUState", St, f->c, (a[3] ? find(a[3]) : f)->states[k]);
        else {
            fmi3FMUState copy = f->states[k]; /* the slot keeps the freed pointer */
            s = CALL(f, "fmi3FreeFMUState", G, f->c, &copy);
        }
    } else if (!strcmp(cmd, "serialize")) {
        int k = atoi(a[2]);
        size_t size = 0;
        typedef fmi3Status (*Z)(fmi3Instance, fmi3FMUState, size_t *);
        typedef fmi3Status (*W)(fmi3Instance, fmi3FMUState, unsigned char *, size_t);
        s = CALL(f, "fmi3SerializedFMUStateSize", Z, f->c, f->states[k], &size);
        if (s < 2) {
            free(f->blobs[k]);
            f->blobs[k] = malloc(size);
            f->blob_sizes[k] = size;
            s = CALL(f, "fmi3SerializeFMUState", W, f->c, f->states[k], f->blobs[k], size);
        }
    } else if (!strcmp(cmd, "deserialize") || !strcmp(cmd, "garbage")) {
        int k = atoi(a[2]);
        static unsigned char junk[16] = "garbage bytes!!";
        typedef fmi3Status (*R)(fmi3Instance, const unsigned char *, size_t, fmi3FMUState *);
        f->states[k] = NULL;
        if (cmd[0] == 'g') s = CALL(f, "fmi3DeserializeFMUState", R, f->c, junk, 16,
                                    &f->states[k]);
        else {
            Fmu *from = a[3] ? find(a[3]) : f; /* blob of another FMU's slot */
            s = CALL(f, "fmi3DeserializeFMUState", R, f->c, from->blobs[k],
                     from->blob_sizes[k], &f->states[k]);
        }
    } else if (!strcmp(cmd, "eventmode")) {
        s = CALL(f, "fmi3EnterEventMode", F0, f->c);
    } else if (!strcmp(cmd, "stepmode")) {
        s = CALL(f, "fmi3EnterStepMode", F0, f->c);
    } else if (!strcmp(cmd, "update")) {
        typedef fmi3Status (*U)(fmi3Instance, bool *, bool *, bool *, bool *, bool *, double *);
        bool flags[5] = {true, true, true, true, true};
        double next = -1.0;
        s = CALL(f, "fmi3UpdateDiscreteStates", U, f->c, &flags[0], &flags[1], &flags[2],
                 &flags[3], &flags[4], &next);
        snprintf(extra, sizeof extra, " %d %d %d %d %d", flags[0], flags[1], flags[2],
                 flags[3], flags[4]);
    } else if (!strcmp(cmd, "terminated")) {
        snprintf(extra, sizeof extra, " %d", (int)f->terminate);
    } else if (!strcmp(cmd, "lasttime")) {
        snprintf(extra, sizeof extra, " %.17g", f->last_time);
    } else if (!strcmp(cmd, "unsupported")) {
        fmi3ValueReference vr = 0;
        int32_t order = 1;
        double value = 0.0;
        typedef fmi3Status (*U)(fmi3Instance, const fmi3ValueReference *, size_t,
                                const int32_t *, double *, size_t);
        s = CALL(f, "fmi3GetOutputDerivatives", U, f->c, &vr, 1, &order, &value, 1);
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
