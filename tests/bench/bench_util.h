/* bench_util.h — small helpers shared by the C benches (header-only). */
#ifndef DF_BENCH_UTIL_H
#define DF_BENCH_UTIL_H

#include <stdint.h>
#include <time.h>

/* Monotonic time, seconds. */
static inline double bench_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A reproducible uniform number in [0, 1) from state *s (64-bit LCG, the top 53 bits). */
static inline double bench_rnd(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) / 9007199254740992.0;
}

#endif
