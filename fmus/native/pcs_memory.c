/* The host's allocator per instance and the work-memory arena (pcs_memory.h). */
#include "pcs_memory.h"

#define ALIGN 16u

size_t pcs_mul(size_t a, size_t b)
{
    return b && a > (size_t)-1 / b ? (size_t)-1 : a * b;
}

size_t pcs_add(size_t a, size_t b)
{
    return a > (size_t)-1 - b ? (size_t)-1 : a + b;
}

void *pcs_alloc(const PcsMemory *mem, size_t count, size_t size)
{
    if (count == 0 || size == 0) count = size = 1;
    if (count > (size_t)-1 / size) return NULL;
    return mem->alloc(mem->ctx, count, size);
}

void pcs_free(const PcsMemory *mem, void *p)
{
    if (p) mem->release(mem->ctx, p);
}

void *pcs_arena_take(PcsArena *a, size_t count, size_t size)
{
    size_t bytes, start;
    if (a->overflow) return NULL;
    if (size && count > ((size_t)-1 - ALIGN) / size) {
        a->overflow = 1;
        return NULL;
    }
    bytes = (count * size + ALIGN - 1) / ALIGN * ALIGN;
    start = a->used;
    if (bytes > (size_t)-1 - start || (a->base && start + bytes > a->size)) {
        a->overflow = 1;
        return NULL;
    }
    a->used = start + bytes;
    return a->base ? a->base + start : NULL;
}

int pcs_arena_open(PcsArena *a, const PcsMemory *mem)
{
    if (a->overflow) return -1;
    a->size = a->used;
    a->used = 0;
    a->base = (unsigned char *)pcs_alloc(mem, a->size ? a->size : 1, 1);
    return a->base ? 0 : -1;
}

int pcs_arena_full(const PcsArena *a)
{
    return a->base && !a->overflow && a->used == a->size ? 0 : -1;
}

void pcs_arena_close(PcsArena *a, const PcsMemory *mem)
{
    pcs_free(mem, a->base);
    a->base = NULL;
    a->size = a->used = 0;
}
