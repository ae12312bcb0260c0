/*
 * The allocations counted while a doStep runs (host_in_step set) and outside it: on Linux
 * the host interposes malloc, calloc, realloc and free (over glibc's __libc_ functions), so
 * every allocation of the FMU's library counts, whichever FMI version; elsewhere only the
 * FMI 2.0 allocateMemory / freeMemory callbacks count (FMI 3.0 has none: there the host
 * counts nothing and says so).
 */
#include <stdlib.h>

#include "host.h"

volatile int host_in_step;
long host_step_allocations, host_other_allocations;
#define COUNT() (host_in_step ? host_step_allocations++ : host_other_allocations++)

#if defined(__linux__)
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
void *malloc(size_t n) { COUNT(); return __libc_malloc(n); }
void *calloc(size_t n, size_t s) { COUNT(); return __libc_calloc(n, s); }
void *realloc(void *p, size_t n) { COUNT(); return __libc_realloc(p, n); }
void free(void *p) { if (p) COUNT(); __libc_free(p); }

void *host_counted_calloc(size_t n, size_t size) { return calloc(n, size); }  /* counted there */
void host_counted_free(void *p) { free(p); }

int host_allocations_counted(const HostFmu *f)
{
    (void)f;
    return 1;
}
#else
void *host_counted_calloc(size_t n, size_t size)
{
    COUNT();
    return calloc(n, size);
}

void host_counted_free(void *p)
{
    if (p) COUNT();
    free(p);
}

int host_allocations_counted(const HostFmu *f)
{
    return f->version == 2;
}
#endif
