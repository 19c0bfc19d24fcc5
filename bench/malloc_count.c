/* A malloc that counts its calls, for bench_layered.py --allocations:
 *   gcc -O2 -shared -fPIC -o /tmp/malloc_count.so bench/malloc_count.c
 *   LD_PRELOAD=/tmp/malloc_count.so python bench/bench_layered.py --allocations
 * (operator new calls malloc, so C++ allocations are counted too). */
#define _GNU_SOURCE
#include <stdatomic.h>
#include <stddef.h>
extern void *__libc_malloc(size_t);
static atomic_long count;
void *malloc(size_t n) {
    atomic_fetch_add(&count, 1);
    return __libc_malloc(n);
}
long malloc_count(void) { return atomic_load(&count); }
