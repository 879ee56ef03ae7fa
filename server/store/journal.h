/* journal.h — what the daemon writes to the durable store (store.h), and when.
 *
 * df_store_journal_ops are the srv->store_ops (server.h) the session layer calls:
 *   session_created  df_session_create, before the load is acknowledged: the session row
 *                    (id, name, mesh topology, exact double base positions, version 0, brush)
 *                    and meta.next_session_id, in one transaction;
 *   session_closing  the close request, before the session is closed: its row and its log;
 *   change           df_session_commit, BEFORE step 1 (commit.h): one change-log row (version,
 *                    kind = the request's message type, who = the request's origin: connection
 *                    or device id, flags, the position delta from s->cur to c->pos (codec.h),
 *                    the handle set it installs) and, for a new handle set, the session
 *                    row's handles, in one transaction. The session row is NOT updated
 *                    otherwise: SQLite rewrites the whole row (its mesh blobs too) on any
 *                    UPDATE, which cost ~25 pages a change on a 1k-vertex mesh (bench_load);
 *                    the current version is the last row's (store.h) and the log's size since
 *                    the snapshot is kept in memory (df_store_session_log);
 *   brush            df_brush_state_apply, before the state changes: a change-log row (kind
 *                    DF_MSG_BRUSH_STATE_SET, aux = the new brush, flag DF_JOURNAL_BRUSH); the
 *                    session row's brush and brush_seq are written with the next snapshot, and
 *                    the restore takes the last brush row and counts the brush rows since.
 * A change with only an undo-history step (a stroke's end, a move's final commit) is a row
 * without delta: its DF_JOURNAL_HIST lets the restore rebuild the undo/redo history.
 * Rest shape: flag DF_JOURNAL_REST_FROM_CUR (the rest shape becomes the positions after this
 * change); a change that installs a handle set has DF_JOURNAL_HANDLES and its blob in aux.
 *
 * Write first, then apply: the in-memory state never moves ahead of the store. A failed write
 * is rolled back in SQLite (nothing of it stays on disk) and returns the error: the commit then
 * applies nothing, broadcasts nothing and answers the error, so the session stays at its last
 * acknowledged state in memory and on disk (the next change's delta is taken from that same
 * state). Writing first needs no undo of swapped buffers, history steps or caches, which a
 * rollback of the applied state would. Durability: the transaction's COMMIT returns once the
 * WAL holds it (and, with durability = full, fsynced), before the ack and the broadcast.
 * Snapshots: once a session's log since its last snapshot exceeds max(DF_STORE_SNAPSHOT_MIN,
 * 2 x 24 x nv bytes) (the blobs' stored, i.e. packed, sizes), the change's transaction also
 * writes the positions and rest shape after it, its version and the session brush into the
 * session row (cur, rest, version, brush, brush_seq) and deletes the session's log rows: a session holds at
 * most its mesh, one snapshot and about twice its position bytes of log, and a restart replays
 * at most that (restore.h). The deleted rows' kind / who are not kept.
 * Cost: a Kelvinlet stroke moves every vertex slightly (the field is never exactly zero), so a
 * brush version's raw delta is dense: 24 bytes per vertex + 8. The codec writes it packed
 * (codec.h: XOR against the previous state, byte planes, zstd) when smaller: measured by
 * tests/bench/bench_store_delta.c on a 1M-vertex grid, 200 local grab strokes, ~1.3 bytes per
 * vertex per change for a tri-scale brush (~17x less than raw) and ~5.9 for the single-scale
 * default (~4x; its 1/r far field moves every vertex by more than float32 resolution). That is
 * still above the target (200 strokes within 2 x the position bytes, 0.24 bytes per
 * vertex per stroke): the low mantissa bits of the far-field motion are incompressible, and
 * only recording a stroke as its request plus checkpoints would reach it. The snapshot rule
 * below bounds the log either way. srv->store counts the bytes written (df_store_log_bytes).
 *
 * Loop thread. */
#ifndef DF_SERVER_STORE_JOURNAL_H
#define DF_SERVER_STORE_JOURNAL_H

#include "server/server.h"

enum { DF_JOURNAL_REST_FROM_CUR = 1, DF_JOURNAL_HANDLES = 2, DF_JOURNAL_BRUSH = 4 };
/* flags bits 4..6: the change's undo-history step (commit.h DF_HIST_*), replayed at restore */
#define DF_JOURNAL_HIST_SHIFT 4
#define DF_JOURNAL_HIST(flags) (((flags) >> DF_JOURNAL_HIST_SHIFT) & 7)

extern const df_store_ops df_store_journal_ops;

#endif
