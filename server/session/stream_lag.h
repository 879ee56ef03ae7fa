/* stream_lag.h — coalescing of the stream for subscribers that cannot keep up (issue 16,
 * PROTOCOL.md 6.3 "Bandwidth"): an extension of the output-queue backpressure of server/net/
 * (outq.h: a client over output_queue_limit is dropped) for connections whose hello carried the
 * stream-encoding trailer (any encoding, exact included; df_conn.stream_neg), when they are not
 * on the shared-memory ring.
 *
 * When such a subscriber's output queue holds the start threshold (config
 * stream_coalesce_start, default DF_LAG_HI(limit)) or more as the first chunk of a version is
 * broadcast, it starts lagging: from that version on its stream frames are not queued but
 * folded into a per-subscription accumulator (exact: the newest float32 displacement of every
 * row the skipped versions listed; quantized: the sum of the group's dq of every row), so
 * nothing grows with the number of versions. Once its queue is down to the resume threshold
 * (stream_coalesce_resume, default DF_LAG_LO(limit); checked at every stream frame of the
 * session and once per loop iteration), it gets one coalesced version: version = the last one skipped, base_version = the version it
 * held (so `version > base_version + 1`), the rows that changed since (exact: their newest u,
 * DISPLACEMENT events, sparse or dense; quantized: QDISP events with the summed dq, exactly the
 * delta against the K it holds), compressed like its other frames (ZSTD). A version's chunks are
 * never split: lagging starts and ends at version boundaries, so no client applies half a
 * version. Each version skipped counts in the connection's `coalesced` (stats
 * client.<id>.coalesced) and the daemon's stream_coalesced_versions.
 * Loop thread only. */
#ifndef DF_SERVER_STREAM_LAG_H
#define DF_SERVER_STREAM_LAG_H

#include <stdint.h>

#include "server/net/sbuf.h"
#include "server/session/session.h"
#include "server/session/stream_enc.h"

#define DF_LAG_HI(limit) ((limit) / 8)  /* default queued bytes at which a subscriber starts
                                         * lagging (config stream_coalesce_start = 0) */
#define DF_LAG_LO(limit) ((limit) / 16) /* ... and at which it gets its coalesced version
                                         * (stream_coalesce_resume = 0) */

/* The thresholds in effect for a connection with output queue limit `limit` under config
 * `start`, `resume` (bytes, 0 = the defaults above): *hi = start capped at limit, *lo = resume
 * capped at *hi. Pure. */
void df_stream_lag_thresholds(size_t limit, int start, int resume, size_t *hi, size_t *lo);

/* The coalescing state of one subscription (session.h sub_lag[i], parallel to subs[i]). */
typedef struct df_sublag {
    uint8_t mid;              /* the last frame sent to it had MORE: the version continues */
    uint8_t lagging;          /* versions are folded into the accumulator */
    uint8_t kind;             /* kind of the last version folded */
    uint64_t held;            /* the version the client holds (base_version of the catch-up) */
    uint64_t last;            /* the last version folded (version of the catch-up) */
    uint8_t *touched;         /* nv flags: rows the folded versions listed */
    float *u;                 /* exact: nv x 3 newest displacements of touched rows */
    int64_t *dq;              /* quantized: nv x 3 summed dq of touched rows */
    uint64_t charged;         /* bytes of the above charged to memory_max_mb (DF_MEM_STREAM) */
} df_sublag;

/* Sends stream frame `frame` (a DISPLACEMENT or PROGRESS event chunk of session s) to subscriber
 * i: its variant from `vs` (stream_enc.h), or folded into its accumulator when it lags (and its
 * coalesced version when its queue has drained). Returns df_conn_send's result, or DF_OK when
 * folded. The accumulator (13 bytes a vertex exact, 25 quantized) is charged to memory_max_mb
 * (membudget.h DF_MEM_STREAM) while the subscriber lags. Errors: DF_ENOMEM when the
 * accumulator cannot be made or the memory budget refuses it (logged once per lag attempt with
 * the ELIMIT message; the frame is then queued as usual: the queue limit still applies, so such
 * a subscriber is dropped like any slow reader and resyncs). */
int df_stream_lag_send(df_session *s, int i, df_sbuf *frame, df_enc_variants *vs);

/* Sends the coalesced version to every lagging subscriber of every session whose queue has
 * drained to DF_LAG_LO (the server's per-iteration check). */
void df_stream_lag_poll(df_server *srv);

/* Frees subscription i's accumulator (unsubscribe, session destroy); `c` leaves its lagging
 * count. */
void df_stream_lag_release(df_session *s, int i);

#endif
