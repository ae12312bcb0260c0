/* The data file of a native FMU: reading and checking (pcs_data.h). */
#include "pcs_data.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "pcs_limits.h"

#define HEADER_BYTES 40u
#define SECTION_HEADER_BYTES 40u

unsigned long long pcs_fnv1a(const unsigned char *p, size_t n)
{
    unsigned long long h = 14695981039346656037ULL;
    size_t i;
    for (i = 0; i < n; i++) {
        h ^= (unsigned long long)p[i];
        h *= 1099511628211ULL;
    }
    return h;
}

unsigned pcs_read_u32(const unsigned char *p)
{
    unsigned v;
    memcpy(&v, p, 4);
    return v;
}

unsigned long long pcs_read_u64(const unsigned char *p)
{
    unsigned long long v;
    memcpy(&v, p, 8);
    return v;
}

/* the section at pos: its name, type, count and bytes (padded) within the file; -1 when it
   does not fit */
static int section_at(const PcsData *d, size_t pos, char name[25], unsigned *type,
                      unsigned long long *count, size_t *bytes)
{
    unsigned long long n, width;
    if (d->size - pos < SECTION_HEADER_BYTES) return -1;
    memcpy(name, d->bytes + pos, 24);
    name[24] = '\0';
    *type = pcs_read_u32(d->bytes + pos + 24);
    n = pcs_read_u64(d->bytes + pos + 32);
    if (*type != PCS_TYPE_F64 && *type != PCS_TYPE_I32) return -1;
    width = *type == PCS_TYPE_F64 ? 8u : 4u;
    if (n > (unsigned long long)(d->size - pos - SECTION_HEADER_BYTES) / width) return -1;
    *count = n;
    *bytes = (size_t)((n * width + 7u) / 8u * 8u);
    return *bytes <= d->size - pos - SECTION_HEADER_BYTES ? 0 : -1;
}

/* every section inside the file, every float64 value finite */
static int check_sections(const PcsData *d, char *err, size_t n_err)
{
    size_t pos = HEADER_BYTES, bytes, i;
    unsigned s, type;
    unsigned long long count;
    char name[25];
    for (s = 0; s < d->n_sections; s++) {
        if (section_at(d, pos, name, &type, &count, &bytes) != 0) {
            snprintf(err, n_err, "data file %s: section %u does not fit the file (damaged)",
                     d->path, s + 1);
            return -1;
        }
        for (i = 0; type == PCS_TYPE_F64 && i < (size_t)count; i++) {
            double v;
            memcpy(&v, d->bytes + pos + SECTION_HEADER_BYTES + 8 * i, 8);
            if (!isfinite(v)) {
                snprintf(err, n_err, "data file %s: section %s: value %lu is %g (every value "
                         "must be finite)", d->path, name, (unsigned long)i, v);
                return -1;
            }
        }
        pos += SECTION_HEADER_BYTES + bytes;
    }
    return 0;
}

int pcs_data_load(PcsData *d, const char *path, const PcsMemory *mem, char *err, size_t n_err)
{
    FILE *f;
    long size;
    unsigned long long payload, sum;
    memset(d, 0, sizeof *d);
    strncpy(d->path, path, sizeof d->path - 1);
    f = fopen(path, "rb");
    if (!f) {
        snprintf(err, n_err, "data file %s: cannot be opened", path);
        return -1;
    }
    if (fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        snprintf(err, n_err, "data file %s: cannot be read", path);
        return -1;
    }
    if ((double)size > PCS_MAX_BYTES) {
        fclose(f);
        snprintf(err, n_err, "data file %s: %ld bytes, more than a native FMU takes (%.0f)",
                 path, size, PCS_MAX_BYTES);
        return -1;
    }
    if ((unsigned long)size < HEADER_BYTES) {
        fclose(f);
        snprintf(err, n_err, "data file %s: %ld bytes, shorter than its %u-byte header "
                 "(truncated or not a pantocosim data file)", path, size, HEADER_BYTES);
        return -1;
    }
    d->bytes = (unsigned char *)pcs_alloc(mem, (size_t)size, 1);
    if (!d->bytes) {
        fclose(f);
        snprintf(err, n_err, "data file %s: no memory for %ld bytes", path, size);
        return -1;
    }
    d->size = (size_t)size;
    if (fread(d->bytes, 1, d->size, f) != d->size) {
        fclose(f);
        pcs_data_free(d, mem);
        snprintf(err, n_err, "data file %s: cannot be read", path);
        return -1;
    }
    fclose(f);
    if (memcmp(d->bytes, "PCSDATA", 8) != 0) {
        pcs_data_free(d, mem);
        snprintf(err, n_err, "data file %s: not a pantocosim data file (no PCSDATA magic)", path);
        return -1;
    }
    if (pcs_read_u32(d->bytes + 12) != 0x01020304u) {
        unsigned mark = pcs_read_u32(d->bytes + 12);
        pcs_data_free(d, mem);
        snprintf(err, n_err, "data file %s: its byte-order mark reads 0x%08x: pantocosim "
                 "writes data files little-endian, and this FMU runs on a big-endian machine "
                 "(native FMUs take little-endian hosts only) or the file is damaged", path,
                 mark);
        return -1;
    }
    if (pcs_read_u32(d->bytes + 8) != PCS_DATA_VERSION) {
        unsigned v = pcs_read_u32(d->bytes + 8);
        pcs_data_free(d, mem);
        snprintf(err, n_err, "data file %s: format version %u, this FMU reads version %u",
                 path, v, PCS_DATA_VERSION);
        return -1;
    }
    d->kind = pcs_read_u32(d->bytes + 16);
    d->n_sections = pcs_read_u32(d->bytes + 20);
    payload = pcs_read_u64(d->bytes + 24);
    if (payload != (unsigned long long)(d->size - HEADER_BYTES)) {
        pcs_data_free(d, mem);
        snprintf(err, n_err, "data file %s: the header announces %llu payload bytes, the "
                 "file holds %lu (truncated or damaged)", path, payload,
                 (unsigned long)(size - (long)HEADER_BYTES));
        return -1;
    }
    sum = pcs_fnv1a(d->bytes + HEADER_BYTES, d->size - HEADER_BYTES);
    if (sum != pcs_read_u64(d->bytes + 32)) {
        pcs_data_free(d, mem);
        snprintf(err, n_err, "data file %s: checksum mismatch (damaged)", path);
        return -1;
    }
    d->checksum = sum;
    if (check_sections(d, err, n_err) != 0) {
        pcs_data_free(d, mem);
        return -1;
    }
    return 0;
}

void pcs_data_free(PcsData *d, const PcsMemory *mem)
{
    pcs_free(mem, d->bytes);
    d->bytes = NULL;
    d->size = 0;
}

const void *pcs_data_section(const PcsData *d, const char *name, unsigned type, size_t count,
                             size_t *found, char *err, size_t n_err)
{
    size_t pos = HEADER_BYTES, bytes;
    unsigned s, t;
    unsigned long long n;
    char sname[25];
    for (s = 0; s < d->n_sections; s++) {
        if (section_at(d, pos, sname, &t, &n, &bytes) != 0) break;
        if (strcmp(sname, name) == 0) {
            if (t != type) {
                snprintf(err, n_err, "data file %s: section %s holds %s values, expected %s",
                         d->path, name, t == PCS_TYPE_F64 ? "float64" : "int32",
                         type == PCS_TYPE_F64 ? "float64" : "int32");
                return NULL;
            }
            if (!found && n != (unsigned long long)count) {
                snprintf(err, n_err, "data file %s: section %s holds %llu values, expected %lu "
                         "(from section sizes)", d->path, name, n, (unsigned long)count);
                return NULL;
            }
            if (found) *found = (size_t)n;
            return d->bytes + pos + SECTION_HEADER_BYTES;
        }
        pos += SECTION_HEADER_BYTES + bytes;
    }
    snprintf(err, n_err, "data file %s: section %s is missing", d->path, name);
    return NULL;
}

const char *pcs_data_text(const PcsData *d, const char *name, char *err, size_t n_err)
{
    size_t words = 0;
    const char *text = (const char *)pcs_data_section(d, name, PCS_TYPE_I32, 0, &words, err,
                                                      n_err);
    if (!text) return NULL;
    if (words == 0 || text[4 * words - 1] != '\0') {
        snprintf(err, n_err, "data file %s: section %s is not a string", d->path, name);
        return NULL;
    }
    return text;
}

static int hex(int c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

int pcs_uri_to_path(const char *uri, char *out, size_t n_out)
{
    const char *p = uri;
    size_t k = 0;
    if (!uri) return -1;
    if (strncmp(p, "file://", 7) == 0) {
        p += 7;
        if (strncmp(p, "localhost/", 10) == 0) p += 9;
    } else if (strncmp(p, "file:", 5) == 0) {
        p += 5;
    }
    /* file:///C:/dir -> C:/dir on Windows */
    if (p[0] == '/' && p[1] && p[2] == ':') p++;
    for (; *p; p++) {
        int c = (unsigned char)*p;
        if (c == '%' && hex(p[1]) >= 0 && hex(p[2]) >= 0) {
            c = hex(p[1]) * 16 + hex(p[2]);
            p += 2;
        }
        if (k + 1 >= n_out) return -1;
        out[k++] = (char)c;
    }
    out[k] = '\0';
    return 0;
}
