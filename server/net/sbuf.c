/* sbuf.c — reference-counted byte buffers (see sbuf.h). */
#include "server/net/sbuf.h"

#include <pthread.h>
#include <stdlib.h>

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/asan_interface.h>
/* a kept block is poisoned: a use after the last unref still fails under `make asan` */
#define KEPT_POISON(b) ASAN_POISON_MEMORY_REGION((b), sizeof *(b) + (b)->cap)
#define KEPT_UNPOISON(b, n) ASAN_UNPOISON_MEMORY_REGION((b), (n))
#else
#define KEPT_POISON(b) ((void)(b))
#define KEPT_UNPOISON(b, n) ((void)(b), (void)(n))
#endif

/* Large buffers (stream frames of big meshes: 12 MB a version for 1M vertices) are kept for
 * reuse after their last unref instead of freed: a fresh block of that size comes from mmap and
 * page-faults on every first write (~3.8 ms per 12 MB), a kept one does not. At most CACHE_N
 * blocks and CACHE_MAX bytes are kept (the oldest freed first); a block serves a request it
 * exceeds by at most a quarter. */
#define CACHE_MIN ((size_t)1 << 20)
#define CACHE_N 6
#define CACHE_MAX ((size_t)96 << 20)

static pthread_mutex_t cache_mu = PTHREAD_MUTEX_INITIALIZER;
static df_sbuf *cache[CACHE_N];
static size_t cache_bytes, cache_cap[CACHE_N]; /* cache_cap: each kept block's capacity */
static uint64_t cache_age[CACHE_N], cache_clock; /* put order: the oldest is dropped first */

static df_sbuf *cache_take(size_t cap)
{
    df_sbuf *b = NULL;
    pthread_mutex_lock(&cache_mu);
    int best = -1;
    for (int i = 0; i < CACHE_N; i++)
        if (cache[i] && cache_cap[i] >= cap && cache_cap[i] - cap <= cap / 4 &&
            (best < 0 || cache_cap[i] < cache_cap[best]))
            best = i;
    if (best >= 0) {
        b = cache[best];
        cache[best] = NULL;
        cache_bytes -= cache_cap[best];
        KEPT_UNPOISON(b, sizeof *b + cache_cap[best]);
    }
    pthread_mutex_unlock(&cache_mu);
    return b;
}

/* Keeps b, freeing the oldest kept blocks while the count or the bytes would exceed the bounds
 * (blocks of a mesh no longer streamed age out). */
static void cache_put(df_sbuf *b)
{
    df_sbuf *drop[CACHE_N];
    size_t drop_cap[CACHE_N];
    int nd = 0;
    pthread_mutex_lock(&cache_mu);
    for (;;) {
        int n = 0, oldest = -1;
        for (int i = 0; i < CACHE_N; i++)
            if (cache[i]) {
                n++;
                if (oldest < 0 || cache_age[i] < cache_age[oldest]) oldest = i;
            }
        if (n < CACHE_N && cache_bytes + b->cap <= CACHE_MAX) break;
        if (oldest < 0) break;
        drop_cap[nd] = cache_cap[oldest];
        drop[nd++] = cache[oldest];
        cache_bytes -= cache_cap[oldest];
        cache[oldest] = NULL;
    }
    int kept = 0;
    if (cache_bytes + b->cap <= CACHE_MAX)
        for (int i = 0; i < CACHE_N && !kept; i++)
            if (!cache[i]) {
                cache[i] = b;
                cache_cap[i] = b->cap;
                cache_age[i] = ++cache_clock;
                cache_bytes += b->cap;
                KEPT_POISON(b);
                kept = 1;
            }
    pthread_mutex_unlock(&cache_mu);
    for (int i = 0; i < nd; i++) {
        KEPT_UNPOISON(drop[i], sizeof *drop[i] + drop_cap[i]);
        free(drop[i]);
    }
    if (!kept) free(b);
}

df_sbuf *df_sbuf_new(size_t cap)
{
    if (cap > SIZE_MAX - sizeof(df_sbuf)) return NULL;
    df_sbuf *b = cap >= CACHE_MIN ? cache_take(cap) : NULL;
    if (!b) b = malloc(sizeof *b + (cap ? cap : 1));
    else cap = b->cap; /* a kept block: its whole capacity */
    if (!b) return NULL;
    atomic_init(&b->refs, 1);
    b->len = 0;
    b->cap = cap;
    b->data = (uint8_t *)(b + 1);
    b->owned = 0;
    return b;
}

df_sbuf *df_sbuf_adopt(uint8_t *data, size_t len)
{
    df_sbuf *b = malloc(sizeof *b);
    if (!b) return NULL;
    atomic_init(&b->refs, 1);
    b->len = b->cap = len;
    b->data = data;
    b->owned = 1;
    return b;
}

df_sbuf *df_sbuf_ref(df_sbuf *b)
{
    if (b) atomic_fetch_add(&b->refs, 1);
    return b;
}

void df_sbuf_unref(df_sbuf *b)
{
    if (b && atomic_fetch_sub(&b->refs, 1) == 1) {
        if (!b->owned && b->cap >= CACHE_MIN) {
            cache_put(b); /* kept, or freed there */
            return;
        }
        if (b->owned) free(b->data);
        free(b);
    }
}
