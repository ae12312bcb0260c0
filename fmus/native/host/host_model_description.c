/*
 * What the host reads of modelDescription.xml: an attribute of an element (fmiVersion,
 * modelIdentifier, guid, instantiationToken) and a variable's value reference by its name,
 * in the text as the FMU's exporter writes it (attributes in double quotes, no entities in
 * names), FMI 2.0's <ScalarVariable> and FMI 3.0's <Float64>, <Int32>, ... alike.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host.h"

/* the attribute's value within the tag [start, end) into out; 1 if found */
static int tag_attribute(const char *start, const char *end, const char *attribute,
                         char *out, size_t size)
{
    size_t n = strlen(attribute);
    const char *p;
    for (p = start; p + n + 2 < end; p++) {
        if ((p[-1] == ' ' || p[-1] == '\t' || p[-1] == '\n' || p[-1] == '\r')
            && strncmp(p, attribute, n) == 0 && p[n] == '=' && p[n + 1] == '"') {
            const char *value = p + n + 2, *close = strchr(value, '"');
            if (!close || close > end || (size_t)(close - value) >= size) return 0;
            memcpy(out, value, (size_t)(close - value));
            out[close - value] = '\0';
            return 1;
        }
    }
    return 0;
}

int host_attribute(const char *text, const char *element, const char *attribute, char *out,
                   size_t size)
{
    size_t n = strlen(element);
    const char *p;
    for (p = strchr(text, '<'); p; p = strchr(p + 1, '<')) {
        if (strncmp(p + 1, element, n) == 0 && strchr(" \t\r\n", p[n + 1]) && p[n + 1]) {
            const char *end = strchr(p, '>');
            return end && tag_attribute(p + 1 + n, end, attribute, out, size);
        }
    }
    return 0;
}

unsigned host_value_reference(const HostFmu *f, const char *name)
{
    char quoted[300], number[32];
    const char *p;
    snprintf(quoted, sizeof quoted, "name=\"%s\"", name);
    for (p = f->description ? strstr(f->description, quoted) : NULL; p;
         p = strstr(p + 1, quoted)) {
        const char *start = p, *end = strchr(p, '>');
        while (start > f->description && *start != '<') start--;
        if (strchr(" \t\r\n", p[-1]) && end
            && tag_attribute(start + 1, end, "valueReference", number, sizeof number))
            return (unsigned)strtoul(number, NULL, 10);
    }
    fprintf(stderr, "%s/modelDescription.xml: no variable %s\n", f->dir, name);
    exit(2);
}
