/*
 * Memory of a native FMU instance: the host's allocator, kept per instance (a context
 * pointer, no global state), and one arena per model for its work memory, measured in a
 * first pass and allocated once.
 *
 *   PcsArena a = {0};
 *   carve(m, &a);                          measures: every pcs_arena_take returns NULL
 *   if (pcs_arena_open(&a, mem) != 0) ...  one zeroed block of the measured total
 *   carve(m, &a);                          the same takes, now inside the block
 *   if (pcs_arena_full(&a) != 0) ...       every byte measured was taken, none beyond
 */
#ifndef PCS_MEMORY_H
#define PCS_MEMORY_H

#include <stddef.h>

typedef struct {
    void *(*alloc)(void *ctx, size_t count, size_t size);   /* zeroed memory, as calloc */
    void (*release)(void *ctx, void *p);
    void *ctx;                                               /* the host's, per instance */
} PcsMemory;

/* a * b and a + b, (size_t)-1 when they do not fit (a size no file or arena can hold) */
size_t pcs_mul(size_t a, size_t b);
size_t pcs_add(size_t a, size_t b);

/* count * size zeroed bytes; NULL when the product overflows or the host has no memory */
void *pcs_alloc(const PcsMemory *mem, size_t count, size_t size);
/* give p back to the allocator it came from (NULL: nothing) */
void pcs_free(const PcsMemory *mem, void *p);

typedef struct {
    unsigned char *base;     /* NULL while measuring */
    size_t size;             /* the measured total (bytes) */
    size_t used;
    int overflow;            /* a size did not fit in size_t, or a take went beyond size */
} PcsArena;

/* count items of size bytes, aligned to 16 bytes; NULL while measuring or on overflow */
void *pcs_arena_take(PcsArena *a, size_t count, size_t size);
/* allocate the measured total and start taking from it; -1 on overflow or no memory */
int pcs_arena_open(PcsArena *a, const PcsMemory *mem);
/* 0 when the takes used exactly the measured total */
int pcs_arena_full(const PcsArena *a);
void pcs_arena_close(PcsArena *a, const PcsMemory *mem);

#endif
