/* outq.c — bounded output queue accounting (see outq.h). */
#include "server/net/outq.h"

#include <stdlib.h>
#include <string.h>

#include "core/common/df_error.h"

void df_outq_init(df_outq *q, size_t limit)
{
    memset(q, 0, sizeof *q);
    q->limit = limit ? limit : 1;
}

static int grow(df_outq *q)
{
    size_t ncap = q->cap ? q->cap * 2 : 16;
    df_sbuf **n = malloc(ncap * sizeof *n);
    if (!n) return DF_ENOMEM;
    for (size_t i = 0; i < q->count; i++) n[i] = q->items[(q->head + i) % q->cap];
    free(q->items);
    q->items = n;
    q->cap = ncap;
    q->head = 0;
    return DF_OK;
}

int df_outq_push(df_outq *q, df_sbuf *b)
{
    if (!q || !b) return DF_EINVAL;
    if (q->count > 0 && (b->len > q->limit || q->bytes > q->limit - b->len)) return DF_ELIMIT;
    if (q->count == q->cap && grow(q) != DF_OK) return DF_ENOMEM;
    q->items[(q->head + q->count) % q->cap] = df_sbuf_ref(b);
    q->count++;
    q->bytes += b->len;
    return DF_OK;
}

size_t df_outq_pending(const df_outq *q) { return q->count - q->inflight; }

size_t df_outq_take(df_outq *q, df_sbuf **out, size_t max)
{
    if (max > DF_OUTQ_MAX_BATCH) max = DF_OUTQ_MAX_BATCH;
    size_t n = 0;
    while (n < max && q->inflight < q->count) {
        out[n++] = q->items[(q->head + q->inflight) % q->cap];
        q->inflight++;
    }
    return n;
}

void df_outq_complete(df_outq *q, size_t n)
{
    if (n > q->inflight) n = q->inflight;
    for (size_t i = 0; i < n; i++) {
        df_sbuf *b = q->items[q->head];
        q->bytes -= b->len;
        q->total_bytes += b->len;
        q->total_items++;
        df_sbuf_unref(b);
        q->head = (q->head + 1) % q->cap;
        q->count--;
        q->inflight--;
    }
}

void df_outq_clear(df_outq *q)
{
    for (size_t i = 0; i < q->count; i++) df_sbuf_unref(q->items[(q->head + i) % q->cap]);
    free(q->items);
    q->items = NULL;
    q->head = q->count = q->cap = q->inflight = 0;
    q->bytes = 0;
}
