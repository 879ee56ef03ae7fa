/* resync.c — the per-session ring of recently broadcast versions (see resync.h). */
#include "server/session/resync.h"

#include <stdlib.h>
#include <string.h>

void df_resync_init(df_resync *r) { memset(r, 0, sizeof *r); }

static df_resync_ver *at(const df_resync *r, size_t i) { return &r->v[(r->head + i) % r->cap]; }

static void drop_oldest(df_resync *r)
{
    df_resync_ver *e = at(r, 0);
    for (size_t i = 0; i < e->n; i++) df_sbuf_unref(e->frames[i]);
    free(e->frames);
    r->bytes -= e->bytes <= r->bytes ? e->bytes : r->bytes;
    memset(e, 0, sizeof *e);
    r->head = (r->head + 1) % r->cap;
    r->count--;
    r->dropped++;
    if (r->count == 0) r->head = 0;
}

static void clear(df_resync *r)
{
    while (r->count) drop_oldest(r);
    r->bytes = 0;
}

void df_resync_free(df_resync *r)
{
    uint64_t dropped = r->dropped;
    if (r->cap) clear(r);
    free(r->v);
    df_resync_init(r);
    r->dropped = dropped;
}

uint64_t df_resync_version_bytes(df_sbuf *const *frames, size_t n)
{
    uint64_t b = sizeof(df_resync_ver) + (uint64_t)n * sizeof(df_sbuf *);
    for (size_t i = 0; i < n; i++) b += sizeof(df_sbuf) + frames[i]->cap;
    return b;
}

uint64_t df_resync_trim(df_resync *r, uint64_t max_bytes)
{
    uint64_t before = r->bytes;
    while (r->count && r->bytes > max_bytes) drop_oldest(r);
    return before - r->bytes;
}

uint64_t df_resync_first(const df_resync *r) { return r->count ? at(r, 0)->version : 0; }

uint64_t df_resync_last(const df_resync *r)
{
    return r->count ? at(r, r->count - 1)->version : 0;
}

/* Room for one more entry (the ring doubles; entries keep their order). */
static int grow(df_resync *r)
{
    if (r->count < r->cap) return DF_OK;
    size_t nc = r->cap ? 2 * r->cap : 16;
    df_resync_ver *n = calloc(nc, sizeof *n);
    if (!n) return DF_ENOMEM;
    for (size_t i = 0; i < r->count; i++) n[i] = *at(r, i);
    free(r->v);
    r->v = n;
    r->cap = nc;
    r->head = 0;
    return DF_OK;
}

int df_resync_push(df_resync *r, uint64_t version, df_sbuf *const *frames, size_t n,
                   uint64_t max_bytes, df_error *err)
{
    if (r->count && (version == 0 || version - 1 != df_resync_last(r)))
        clear(r); /* a gap: the kept versions no longer lead to this one */
    uint64_t bytes = df_resync_version_bytes(frames, n);
    if (bytes > max_bytes) { /* it cannot be kept, and older versions would leave a hole */
        clear(r);
        return DF_OK;
    }
    df_sbuf **refs = n ? malloc(n * sizeof *refs) : NULL;
    if ((n && !refs) || grow(r) != DF_OK) {
        free(refs);
        clear(r);
        return df_error_set(err, DF_ENOMEM, "resync ring: out of memory for version %llu",
                            (unsigned long long)version);
    }
    for (size_t i = 0; i < n; i++) refs[i] = df_sbuf_ref(frames[i]);
    df_resync_ver *e = at(r, r->count);
    e->version = version;
    e->frames = refs;
    e->n = n;
    e->bytes = bytes;
    r->count++;
    r->bytes += bytes;
    df_resync_trim(r, max_bytes);
    return DF_OK;
}

int df_resync_covers(const df_resync *r, uint64_t from, uint64_t current)
{
    return r->count && from < current && df_resync_last(r) == current &&
           df_resync_first(r) <= from + 1;
}

const df_resync_ver *df_resync_find(const df_resync *r, uint64_t version)
{
    uint64_t first = df_resync_first(r);
    if (!r->count || version < first || version - first >= r->count) return NULL;
    return at(r, (size_t)(version - first));
}
