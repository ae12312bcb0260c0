/*
 * The script interpreter of the host (mode "script", host_main.c): FMI calls read from
 * standard input, one a line, for FMI 2.0 and 3.0 FMUs alike (tests/fmi_script.py writes
 * them):
 *
 *   load A DIR MODEL_IDENTIFIER TOKEN    instantiate A NAME [events]       free A
 *   setup A T0      enter A      exit A      terminate A      reset A
 *   set A r|i|b|s VR VALUE       get A r|i|b|s VR...       step A T H
 *   copy A VR B VR          (get Real of A into set Real of B)
 *   getstate A K   setstate A K [B]   freestate A K   serialize A K   deserialize A K [B]
 *   garbage A K    (deserialize 16 bytes of garbage into slot K)
 *   terminated A   lasttime A   (of the last step)   unsupported A   (input derivatives)
 *   intstatus A KIND   (FMI 2.0: fmi2GetIntegerStatus, which FMI 2.0 defines for no kind)
 *   eventmode A    update A (prints fmi3UpdateDiscreteStates' five flags)    stepmode A
 *                  (FMI 3.0 only)
 *
 * r, i, b, s are Real, Integer, Boolean, String (FMI 3.0: Float64, Int32, Boolean,
 * String); "instantiate A NAME events" instantiates with eventModeUsed (FMI 3.0). Each call
 * prints "= LINE CALL STATUS [values]"; the FMUs' log messages print "LOG INSTANCE STATUS
 * CATEGORY MESSAGE". Values are printed with 17 digits. An FMI 3.0 step that asks for an
 * event or returns early stops the script (exit 5).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host.h"

#define MAX_FMUS 8
#define MAX_WORDS 72

static HostFmu fmus[MAX_FMUS];
static int n_fmus;
static char extra[8192]; /* values printed after the status */

static HostFmu *find(const char *alias)
{
    int i;
    for (i = 0; alias && i < n_fmus; i++)
        if (strcmp(fmus[i].alias, alias) == 0) return &fmus[i];
    fprintf(stderr, "unknown FMU alias %s\n", alias ? alias : "(none)");
    exit(2);
}

static void append(const char *format, const void *value, char kind)
{
    size_t used = strlen(extra);
    if (kind == 'r') snprintf(extra + used, sizeof extra - used, format, *(const double *)value);
    else if (kind == 's') snprintf(extra + used, sizeof extra - used, format,
                                   *(const char *const *)value);
    else snprintf(extra + used, sizeof extra - used, format, *(const int *)value);
}

static int kind_of(const char *word, int line)
{
    const char *k = word ? strchr("ribs", word[0]) : NULL;
    if (!k || !word[0]) {
        fprintf(stderr, "line %d: type %s (r, i, b or s accepted)\n", line,
                word ? word : "(none)");
        exit(2);
    }
    return (int)(k - "ribs");
}

static int set(HostFmu *f, char **a, int line)
{
    unsigned vr = (unsigned)strtoul(a[3], NULL, 10);
    double r = atof(a[4]);
    int i = atoi(a[4]);
    const char *str = a[4];
    switch (kind_of(a[2], line)) {
    case 0: return f->api->set_real(f, &vr, 1, &r);
    case 1: return f->api->set_int(f, &vr, 1, &i);
    case 2: return f->api->set_bool(f, &vr, 1, &i);
    default: return f->api->set_string(f, &vr, 1, &str);
    }
}

static int get(HostFmu *f, char **a, int n, int line)
{
    unsigned vr[HOST_MAX_VALUES];
    double r[HOST_MAX_VALUES];
    int i[HOST_MAX_VALUES], s, j, m = n - 3 < HOST_MAX_VALUES ? n - 3 : HOST_MAX_VALUES;
    const char *str[HOST_MAX_VALUES];
    int k = kind_of(a[2], line);
    for (j = 0; j < m; j++) vr[j] = (unsigned)strtoul(a[3 + j], NULL, 10);
    s = k == 0 ? f->api->get_real(f, vr, (size_t)m, r)
        : k == 1 ? f->api->get_int(f, vr, (size_t)m, i)
        : k == 2 ? f->api->get_bool(f, vr, (size_t)m, i)
                 : f->api->get_string(f, vr, (size_t)m, str);
    for (j = 0; s < 2 && j < m; j++) {
        if (k == 0) append(" %.17g", &r[j], 'r');
        else if (k == 3) append(" %s", &str[j], 's');
        else append(" %d", &i[j], 'i');
    }
    return s;
}

static int copy(HostFmu *f, char **a)
{
    HostFmu *g = find(a[3]);
    unsigned from = (unsigned)strtoul(a[2], NULL, 10), to = (unsigned)strtoul(a[4], NULL, 10);
    double r = 0.0;
    int s = f->api->get_real(f, &from, 1, &r);
    return s < 2 ? g->api->set_real(g, &to, 1, &r) : s;
}

/* getstate, setstate (optionally another FMU's slot: a foreign pointer), freestate (the
   slot keeps the freed pointer) */
static int state(HostFmu *f, const char *cmd, char **a)
{
    int k = atoi(a[2]) & (HOST_STATES - 1);
    void *kept;
    if (cmd[0] == 'g') return f->api->get_state(f, &f->states[k]);
    if (cmd[0] == 's') return f->api->set_state(f, (a[3] ? find(a[3]) : f)->states[k]);
    kept = f->states[k];
    return f->api->free_state(f, &kept);
}

static int serialize(HostFmu *f, char **a)
{
    int k = atoi(a[2]) & (HOST_STATES - 1), s;
    size_t size = 0;
    s = f->api->state_size(f, f->states[k], &size);
    if (s < 2) {
        free(f->blobs[k]);
        f->blobs[k] = (unsigned char *)malloc(size ? size : 1);
        f->blob_sizes[k] = size;
        s = f->api->serialize(f, f->states[k], f->blobs[k], size);
    }
    return s;
}

/* deserialize a slot's blob (optionally another FMU's), or 16 bytes of garbage */
static int deserialize(HostFmu *f, const char *cmd, char **a)
{
    static const unsigned char junk[16] = "garbage bytes!!";
    int k = atoi(a[2]) & (HOST_STATES - 1);
    HostFmu *from = a[3] ? find(a[3]) : f;
    f->states[k] = NULL;
    if (cmd[0] == 'g') return f->api->deserialize(f, junk, 16, &f->states[k]);
    return f->api->deserialize(f, from->blobs[k], from->blob_sizes[k], &f->states[k]);
}

static int step(HostFmu *f, char **a, int line)
{
    int s = f->api->step(f, atof(a[2]), atof(a[3]), 0);
    if (f->step_event || f->step_early) {
        printf("= %d step: eventHandlingNeeded %d earlyReturn %d\n", line, f->step_event,
               f->step_early);
        exit(5);
    }
    return s;
}

static int status_call(HostFmu *f, const char *cmd, char **a)
{
    int v = -1, s, flags[5];
    double r = -1.0;
    if (!strcmp(cmd, "terminated")) {
        s = f->api->terminated(f, &v);
        append(" %d", &v, 'i');
    } else if (!strcmp(cmd, "lasttime")) {
        s = f->api->last_time(f, &r);
        append(" %.17g", &r, 'r');
    } else if (!strcmp(cmd, "intstatus")) {
        s = f->api->integer_status(f, atoi(a[2]), &v);
        append(" %d", &v, 'i');
    } else {
        s = f->api->update(f, flags);
        snprintf(extra, sizeof extra, " %d %d %d %d %d", flags[0], flags[1], flags[2],
                 flags[3], flags[4]);
    }
    return s;
}

/* a call the FMU's version has (its HostApi entry), else the script stops naming it */
static void offered(const HostFmu *f, int present, const char *cmd, int line)
{
    if (!present) {
        fprintf(stderr, "line %d: %s is no FMI %d.0 call\n", line, cmd, f->version);
        exit(2);
    }
}

static int lifecycle(HostFmu *f, const char *cmd, char **a, int n)
{
    if (!strcmp(cmd, "instantiate"))
        return f->api->instantiate(f, a[2] ? a[2] : f->alias, 1,
                                   n > 3 && !strcmp(a[3], "events"));
    if (!strcmp(cmd, "setup")) return f->api->setup(f, atof(a[2]));
    if (!strcmp(cmd, "enter")) return f->api->enter(f);
    if (!strcmp(cmd, "exit")) return f->api->exit_init(f);
    if (!strcmp(cmd, "terminate")) return f->api->terminate(f);
    if (!strcmp(cmd, "reset")) return f->api->reset(f);
    if (!strcmp(cmd, "eventmode")) return f->api->event_mode(f);
    if (!strcmp(cmd, "stepmode")) return f->api->step_mode(f);
    f->api->free_instance(f);
    return 0;
}

static int run(int line, char **a, int n)
{
    static const char *const LIFECYCLE[] = {"instantiate", "setup", "enter", "exit",
                                            "terminate", "reset", "free", "eventmode",
                                            "stepmode", NULL};
    const char *cmd = a[0];
    HostFmu *f;
    int s, i;
    if (!strcmp(cmd, "load") && n >= 5 && n_fmus < MAX_FMUS) {
        f = &fmus[n_fmus++];
        snprintf(f->alias, sizeof f->alias, "%s", a[1]);
        host_load(f, a[2], a[3], a[4]);
        printf("= %d load 0\n", line);
        return 0;
    }
    f = find(a[1]);
    extra[0] = '\0';
    offered(f, strcmp(cmd, "intstatus") || f->api->integer_status, cmd, line);
    offered(f, strcmp(cmd, "eventmode") || f->api->event_mode, cmd, line);
    offered(f, strcmp(cmd, "stepmode") || f->api->step_mode, cmd, line);
    offered(f, strcmp(cmd, "update") || f->api->update, cmd, line);
    for (i = 0; LIFECYCLE[i] && strcmp(cmd, LIFECYCLE[i]); i++) {
    }
    if (LIFECYCLE[i]) s = lifecycle(f, cmd, a, n);
    else if (!strcmp(cmd, "step") && n >= 4) s = step(f, a, line);
    else if (!strcmp(cmd, "set") && n >= 5) s = set(f, a, line);
    else if (!strcmp(cmd, "get") && n >= 4) s = get(f, a, n, line);
    else if (!strcmp(cmd, "copy") && n >= 5) s = copy(f, a);
    else if ((!strcmp(cmd, "getstate") || !strcmp(cmd, "setstate")
              || !strcmp(cmd, "freestate")) && n >= 3) s = state(f, cmd, a);
    else if (!strcmp(cmd, "serialize") && n >= 3) s = serialize(f, a);
    else if ((!strcmp(cmd, "deserialize") || !strcmp(cmd, "garbage")) && n >= 3)
        s = deserialize(f, cmd, a);
    else if (!strcmp(cmd, "terminated") || !strcmp(cmd, "lasttime") || !strcmp(cmd, "update")
             || (!strcmp(cmd, "intstatus") && n >= 3)) s = status_call(f, cmd, a);
    else if (!strcmp(cmd, "unsupported")) s = f->api->unsupported(f);
    else {
        fprintf(stderr, "line %d: unknown call %s with %d words\n", line, cmd, n);
        exit(2);
    }
    printf("= %d %s %d%s\n", line, cmd, s, extra);
    return s;
}

int host_script(FILE *in)
{
    char buffer[8192];
    int line = 0, i, k;
    host_log_stream = stdout;
#ifdef _WIN32
    setvbuf(stdout, NULL, _IONBF, 0);   /* the C runtime has no line buffering */
#else
    setvbuf(stdout, NULL, _IOLBF, 0);
#endif
    while (fgets(buffer, sizeof buffer, in)) {
        char *a[MAX_WORDS] = {0};
        char *word;
        int n = 0;
        line++;
        for (word = strtok(buffer, " \t\r\n"); word && n < MAX_WORDS - 1;
             word = strtok(NULL, " \t\r\n"))
            a[n++] = word;
        if (n == 0 || a[0][0] == '#') continue;
        run(line, a, n);
    }
    for (i = 0; i < n_fmus; i++) /* the libraries stay loaded, as in most hosts */
        for (k = 0; k < HOST_STATES; k++) free(fmus[i].blobs[k]);
    return 0;
}
