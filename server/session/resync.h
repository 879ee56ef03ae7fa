/* resync.h — a session's resync ring: the frames of the versions most recently broadcast, kept
 * so that a client that holds version v can catch up with exactly the frames of versions
 * v+1 .. current (PROTOCOL.md 6.2, SUBSCRIBE flag FROM_VERSION) instead of a dense snapshot.
 *
 * The ring holds, per version, the references of its frames exactly as df_session_broadcast sent
 * them (DISPLACEMENT or PROGRESS chunks, request ids and flags as sent): df_sbuf references,
 * never copies. Versions are consecutive: the ring keeps versions first .. last, each whole (all
 * its chunks), and is bounded by bytes: pushing a version drops the oldest versions, whole,
 * until the ring fits its budget again; a version larger than the budget on its own leaves the
 * ring empty. A version that does not follow the last one kept (a gap: a failed push, a restore)
 * clears the ring first, so it never serves a version log with a hole.
 *
 * Pure bookkeeping (no I/O, no server): the session glue (budget, memory charge, stats) is
 * session.c df_session_resync_record, the reader is the subscribe handler (h_basic.c). Loop
 * thread only (like the subscribers). */
#ifndef DF_SERVER_RESYNC_H
#define DF_SERVER_RESYNC_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "server/net/sbuf.h"

/* The frames of one version. */
typedef struct df_resync_ver {
    uint64_t version;
    df_sbuf **frames;            /* n references, in broadcast order */
    size_t n;
    uint64_t bytes;              /* what this version costs (df_resync_version_bytes) */
} df_resync_ver;

typedef struct df_resync {
    df_resync_ver *v;            /* circular: v[(head + i) % cap], i < count, oldest first */
    size_t head, count, cap;
    uint64_t bytes;              /* sum of the kept versions' bytes */
    uint64_t dropped;            /* versions dropped to the budget (or by a gap) so far */
} df_resync;

/* An empty ring (no allocation). Never fails. */
void df_resync_init(df_resync *r);

/* Releases every frame reference and the ring's storage; the ring is empty and reusable. */
void df_resync_free(df_resync *r);

/* Bytes charged for a version of `n` frames: each frame's allocation (sizeof(df_sbuf) + its
 * capacity), the reference array and the entry. Frames shared with output queues count whole:
 * the ring keeps them alive. */
uint64_t df_resync_version_bytes(df_sbuf *const *frames, size_t n);

/* Appends version `version` made of frames[0 .. n) (a reference is taken on each; n may be 0
 * for a version without frames, which is still recorded), then drops the oldest versions,
 * whole, while the ring holds more than `max_bytes`. When `version` does not follow the last
 * kept version, the ring is cleared first. max_bytes 0 keeps nothing. Returns DF_OK, or
 * DF_ENOMEM (the ring is then cleared: the next push starts over; no reference taken). */
int df_resync_push(df_resync *r, uint64_t version, df_sbuf *const *frames, size_t n,
                   uint64_t max_bytes, df_error *err);

/* Drops the oldest versions, whole, while the ring holds more than `max_bytes`; returns the
 * bytes freed. */
uint64_t df_resync_trim(df_resync *r, uint64_t max_bytes);

/* Oldest / newest version kept; 0 when the ring is empty. */
uint64_t df_resync_first(const df_resync *r);
uint64_t df_resync_last(const df_resync *r);

/* 1 when the ring can bring a client from version `from` to `current` (from < current): it
 * keeps every version from+1 .. current; else 0. (from == current needs nothing: 0 here.) */
int df_resync_covers(const df_resync *r, uint64_t from, uint64_t current);

/* The kept entry of `version`, or NULL when the ring does not hold it. The pointer is valid
 * until the next push, trim or free. */
const df_resync_ver *df_resync_find(const df_resync *r, uint64_t version);

#endif
