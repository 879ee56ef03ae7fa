/* rows.h — a session's rows of the durable store (server/store/store.h schema 3) as bytes:
 * what cluster mode replicates to Redis (cluster.h). The store's change log IS the replicated
 * log: a stream entry is one `changes` row exactly as journal.c wrote it (version, kind, who,
 * flags, packed delta / handle set / brush in aux, recipe record), and a snapshot is every row
 * of the session (sessions, blobs, access, and the changes rows not yet folded into its
 * snapshot blobs). Loading them back into a store and running the store's restore
 * (restore.h df_store_restore_session) rebuilds the session exactly as a restart would.
 *
 * Encoding (native-endian, like the store's blobs: the daemons of one cluster share a byte
 * order): u32 magic DF_ROWS_MAGIC, u32 row count, then per row: u8 table (DF_ROWS_*), u8 column
 * count (the table's, below), then per column: u8 SQLite type (1 integer: i64; 3 text, 4
 * blob: u32 length + bytes; 5 null).
 * Columns: sessions(id, name, kind, planar, nv, ne, nf, version, brush, brush_seq, log_bytes,
 * snap_version, replay_ns), blobs(session, name, data), access(session, owner, mode, observers,
 * key_hash, members), changes(session, version, kind, who, flags, delta, aux, recipe): the
 * session column first in each. Loop thread (the store's connection). */
#ifndef DF_SERVER_CLUSTER_ROWS_H
#define DF_SERVER_CLUSTER_ROWS_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "server/store/store.h"

#define DF_ROWS_MAGIC 0x31525344u /* "DSR1" */
enum { DF_ROWS_SESSIONS = 0, DF_ROWS_BLOBS = 1, DF_ROWS_ACCESS = 2, DF_ROWS_CHANGES = 3 };

/* Every row of session id in `st` into a new malloc'd buffer (*out, *len). Errors: DF_EIO
 * (reading the store), DF_ENOMEM. */
int df_rows_dump_session(df_store *st, uint64_t id, uint8_t **out, size_t *len, df_error *err);

/* The changes rows of session id whose rowid is above `after`, in commit order, into a new
 * buffer (*out, *len; *n rows) and *last = the highest rowid read (after when none). Errors:
 * DF_EIO, DF_ENOMEM. */
int df_rows_dump_changes(df_store *st, uint64_t id, int64_t after, uint8_t **out, size_t *len,
                         int *n, int64_t *last, df_error *err);

/* The highest changes rowid of session id (0: none). Errors: DF_EIO. */
int df_rows_last_change(df_store *st, uint64_t id, int64_t *last, df_error *err);

/* Inserts the rows of buffer b (len bytes, either dump) into `st`, in the caller's
 * transaction; every row must be of session id. Errors: DF_EFORMAT (malformed, or a row of
 * another session: message says which), DF_EIO (the store's). */
int df_rows_load(df_store *st, uint64_t id, const uint8_t *b, size_t len, df_error *err);

/* Deletes every row of session id from `st` (its local copy), in one transaction. Errors:
 * DF_EIO. */
int df_rows_delete_session(df_store *st, uint64_t id, df_error *err);

#endif
