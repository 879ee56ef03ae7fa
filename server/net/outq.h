/* outq.h — a client's bounded output queue (pure accounting, no I/O).
 *
 * Items are shared frame buffers (df_sbuf). Each item is either pending (not yet handed to the
 * socket) or in flight (given to uv_write, not completed). `bytes` counts both; a push that would
 * take `bytes` over `limit` fails with DF_ELIMIT and the caller drops the client — except that an
 * empty queue always accepts one item, so a single frame larger than the limit (a big snapshot
 * chunk) can still be delivered to a client that keeps up. */
#ifndef DF_SERVER_OUTQ_H
#define DF_SERVER_OUTQ_H

#include <stddef.h>
#include <stdint.h>

#include "server/net/sbuf.h"

#define DF_OUTQ_MAX_BATCH 64 /* items handed to one uv_write */

typedef struct df_outq {
    df_sbuf **items;     /* ring buffer of `cap` slots */
    size_t head, count, cap;
    size_t inflight;     /* the first `inflight` items of the ring are in flight */
    size_t bytes;        /* bytes of all items (pending + in flight) */
    size_t limit;
    uint64_t total_bytes; /* bytes completed since init (for stats) */
    uint64_t total_items;
} df_outq;

/* Initializes an empty queue with a byte limit (> 0). */
void df_outq_init(df_outq *q, size_t limit);

/* Appends `b` (takes a new reference on success). Errors: DF_ELIMIT when the queue is non-empty and
 * bytes + b->len > limit; DF_ENOMEM when the ring cannot grow. On error nothing changes. */
int df_outq_push(df_outq *q, df_sbuf *b);

/* Moves up to `max` (<= DF_OUTQ_MAX_BATCH) pending items to in flight and stores them in out[]
 * in order. Returns how many (0 when nothing is pending). */
size_t df_outq_take(df_outq *q, df_sbuf **out, size_t max);

/* Completes the oldest `n` in-flight items (n <= inflight): drops their references and bytes. */
void df_outq_complete(df_outq *q, size_t n);

/* Number of pending (not in flight) items. */
size_t df_outq_pending(const df_outq *q);

/* Drops every item (pending and in flight) and frees the ring; the queue is empty afterwards. */
void df_outq_clear(df_outq *q);

#endif
