/* rlog.h — a session's replicated log in Redis: a snapshot plus a Stream of the changes
 * after it (cluster.h, rows.h), every write fenced by the lease (lease.h).
 *
 * Keys of session ID (hash tag {ID}: one slot):
 *   deformd:{ID}:snap   the snapshot: every store row of the session (rows.h dump)
 *   deformd:{ID}:log    the Stream: one entry per acknowledged change after the snapshot,
 *                       fields v (the session version) and r (the changes row, rows.h)
 *   deformd:sessions    hash ID -> "KIND PLANAR NV NE VERSION OBSERVERS NAME" of each of the
 *                       cluster, as of its last snapshot (LIST_SESSIONS, list.c)
 *   deformd:next_id     INCR: the cluster's session ids (never reused)
 * The two global keys are each read and written by single-key commands only, so in a Redis
 * Cluster each simply lives on the master of its own slot (no shared hash tag is needed). There
 * the index entry, in another slot than the session's keys, is written by its own HSET / HDEL
 * right after the session's fenced script (one Redis: inside it, atomically).
 * Each write is one Lua script that first compares deformd:{ID}:lease with the writer's token
 * and fails with "FENCED" when it differs (the lease expired or another daemon took it): an
 * XADD for a change; SET snap + DEL log (the snapshot holds every change so far) for a
 * snapshot; DEL of every key for a close. Durability is Redis's (AOF, appendfsync).
 * Loop thread. */
#ifndef DF_SERVER_CLUSTER_RLOG_H
#define DF_SERVER_CLUSTER_RLOG_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "server/cluster/redis.h"

/* One replicated change as read back. */
typedef struct df_rlog_entry {
    uint64_t version;
    uint8_t *row;   /* rows.h changes dump (malloc'd) */
    size_t len;
} df_rlog_entry;

/* Fenced XADD of a change (`row`, len bytes; `version` the session's after it) to session id's
 * log under lease token `token`. Errors: DF_ESTATE (fenced: the lease is not ours any more),
 * DF_EIO (Redis unreachable), DF_EINTERNAL. */
int df_rlog_append(df_redis *r, uint64_t id, const char *token, uint64_t version,
                     const uint8_t *row, size_t len, df_error *err);

/* Fenced snapshot: `snap` (len bytes, rows.h session dump) becomes session id's snapshot, its
 * log is emptied and its index entry becomes `info` (list.c). Errors: as df_rlog_append. */
int df_rlog_snapshot(df_redis *r, uint64_t id, const char *token, const char *info,
                       const uint8_t *snap, size_t len, df_error *err);

/* Fenced removal of every key of session id (a close). Errors: as df_rlog_append. */
int df_rlog_close(df_redis *r, uint64_t id, const char *token, df_error *err);

/* Session id's snapshot (*snap, *snap_len: malloc'd; *snap = NULL when the session does not
 * exist) and its log entries in order (*entries, *n: free with df_rlog_entries_free).
 * Errors: DF_EIO, DF_EINTERNAL, DF_ENOMEM. */
int df_rlog_read(df_redis *r, uint64_t id, uint8_t **snap, size_t *snap_len,
                   df_rlog_entry **entries, size_t *n, df_error *err);
void df_rlog_entries_free(df_rlog_entry *e, size_t n);

/* A new cluster-wide session id (INCR deformd:next_id) into *id. Errors: DF_EIO,
 * DF_EINTERNAL. */
int df_rlog_new_id(df_redis *r, uint64_t *id, df_error *err);

#endif
