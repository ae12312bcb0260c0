/*
 * The data file of a pantocosim native FMU (resources/model.pcsdata), written at export by
 * pantocosim.master.native.export and documented in docs/tutorials/hil.md:
 *
 *   header (40 bytes)  magic "PCSDATA\0", uint32 version, uint32 byte-order mark 0x01020304,
 *                      uint32 model kind, uint32 number of sections, uint64 payload bytes,
 *                      uint64 FNV-1a 64 checksum of the payload
 *   payload            sections, each: char name[24] (NUL padded), uint32 type (1 = float64,
 *                      2 = int32), uint32 0, uint64 count, then count values padded to 8 bytes
 *
 * The file is read once, at instantiation; a damaged, truncated or foreign file, one larger
 * than PCS_MAX_BYTES (pcs_limits.h), a section that does not fit the file or a float64 value
 * that is not finite is refused with a message naming it and what is wrong.
 */
#ifndef PCS_DATA_H
#define PCS_DATA_H

#include <stddef.h>

#include "pcs_memory.h"

#define PCS_DATA_VERSION 1u
#define PCS_KIND_LINEAR_CATENARY 1u
#define PCS_KIND_MODAL_CATENARY 2u
#define PCS_KIND_LUMPED_PANTOGRAPH 3u
#define PCS_KIND_DSA380_RIGID 4u
#define PCS_KIND_DSA380_FLEXIBLE 5u
#define PCS_TYPE_F64 1u
#define PCS_TYPE_I32 2u

typedef struct {
    unsigned char *bytes;      /* the whole file */
    size_t size;
    unsigned kind;
    unsigned n_sections;
    unsigned long long checksum;   /* the payload's (tells one export from another) */
    char path[512];
} PcsData;

/* Read and check path; 0 on success, else -1 with the reason in err. */
int pcs_data_load(PcsData *d, const char *path, const PcsMemory *mem, char *err, size_t n_err);
void pcs_data_free(PcsData *d, const PcsMemory *mem);
/* The values of section name of the type and count (found not NULL: any count, written
   to *found); NULL with the reason in err when it is missing or of another type or size. */
const void *pcs_data_section(const PcsData *d, const char *name, unsigned type, size_t count,
                             size_t *found, char *err, size_t n_err);
/* The NUL-terminated string of section name (int32 words); NULL with the reason in err. */
const char *pcs_data_text(const PcsData *d, const char *name, char *err, size_t n_err);
/* A little-endian uint32 / uint64 at p (the data file's and the FMU states' integers). */
unsigned pcs_read_u32(const unsigned char *p);
unsigned long long pcs_read_u64(const unsigned char *p);
/* The 64-bit FNV-1a hash of n bytes (the payload checksum; also used by FMU states). */
unsigned long long pcs_fnv1a(const unsigned char *p, size_t n);
/* file:// URI (FMI resource location) to a path; 0 on success */
int pcs_uri_to_path(const char *uri, char *out, size_t n_out);

#endif
