/* journal.h — what the daemon writes to the durable store (store.h), and when.
 *
 * df_store_journal_ops are the srv->store_ops (server.h) the session layer calls:
 *   session_created  df_session_create, before the load is acknowledged: the session row
 *                    (id, name, sizes, version 0, brush), its blobs 'base' (exact double base
 *                    positions), 'elems', 'faces' and meta.next_session_id, in one
 *                    transaction;
 *   session_closing  the close request, before the session is closed: its row, blobs and log;
 *   change           df_session_commit, BEFORE step 1 (commit.h): one change-log row (version,
 *                    kind = the request's message type, who = the request's origin: connection
 *                    or device id, flags, the position delta from s->cur to c->pos (codec.h),
 *                    the handle set it installs; or a recipe record, below), the session row's
 *                    version and log counters and the blob 'handles', in one transaction (the
 *                    session row holds no large value: SQLite rewrites a whole row on UPDATE);
 *   brush            df_brush_state_apply, before the state changes: a change-log row (kind
 *                    DF_MSG_BRUSH_STATE_SET, aux = the new brush) and the session row's brush;
 *   access           SESSION_ACCESS / JOIN, before the policy changes: the session's access
 *                    row (owner, mode, observers, join key hash, members; also written by
 *                    session_created and deleted by session_closing).
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
 * 2 x 24 x nv bytes) (the blobs' stored, i.e. packed, sizes), or its replay cost the threshold
 * below, the change's transaction also writes the positions and rest shape after it as the
 * session's blobs 'cur' and 'rest' (none while the rest shape is the base), snap_version = its
 * version, and deletes the session's log rows: a session holds at
 * most its mesh, one snapshot and about twice its position bytes of log, and a restart replays
 * at most that (restore.h). The deleted rows' kind / who are not kept.
 * Recipe records (schema 3, record.h): a brush version (BRUSH_BEGIN / BRUSH_UPDATE) whose stroke is
 * replayable (the change's recipe_replayable, no rebase) and began at a version the log can rebuild
 * (base_version >= the session's snap_version) is written as its recipe (brush, strength,
 * cumulative load, pins: 272 bytes + 24 per pin, in a 32-byte record), base_version and the
 * checksum of its positions, flag DF_JOURNAL_RECIPE, no delta. A BRUSH_END right after its stroke's
 * last publish (no other version in between) carries the same recipe with the checksum of the state
 * it commits (no flag: its positions are unchanged); when the live undo step was a RECIPE (the
 * END's history plan, history.h) the row also has DF_JOURNAL_HIST_RECIPE and the restore commits it
 * with df_session_history_commit_recipe (replayed, a RECIPE step when it reproduces the state), so
 * the restored undo history holds recipes where the live one did. Everything else (rebased or
 * cancelled strokes, handle moves, undo / redo results, loads, reset-rest) keeps the packed delta
 * (codec.h).
 * Snapshot by replay cost too: sessions.replay_ns sums the estimated restore time of what the
 * restore will replay (per record: the live-measured field time plus DF_STORE_REPLAY_VERTEX_NS per
 * vertex; a brush version immediately superseded by the next one of the same stroke is not
 * replayed, replay.h, and stops counting; a RECIPE end counts once more); past
 * df_store_snapshot_replay_ns (DF_STORE_SNAPSHOT_REPLAY_NS, 1 s) the change's transaction writes a
 * snapshot as above once no stroke stays open after it (a snapshot inside a stroke would leave the
 * stroke's later versions without their base state: deltas), or inside one past
 * DF_STORE_SNAPSHOT_REPLAY_FORCE times the threshold, so a restart replays about that much per
 * session at most.
 * Cost (tests/bench/bench_store_delta.c: a real session and store, 1M-vertex grid, 200 local grab
 * strokes of 4 versions and an end each, durability full): the journal holds 304,000 bytes (1000
 * recipe records, 0.013 x the position bytes; the target is 2 x) for either falloff, where
 * packed deltas of each stroke's net change alone would be 49 x (single-scale) or 11 x (tri-scale):
 * a Kelvinlet stroke moves every vertex by a little, and the low mantissa bits of that motion do
 * not compress. A brush version's commit (checksum of the positions and the transaction) takes
 * ~6-12 ms at 1M vertices. srv->store counts the bytes written (df_store_log_bytes).
 *
 * Loop thread. */
#ifndef DF_SERVER_STORE_JOURNAL_H
#define DF_SERVER_STORE_JOURNAL_H

#include "server/server.h"
#include "server/session/session.h"

enum { DF_JOURNAL_REST_FROM_CUR = 1, DF_JOURNAL_HANDLES = 2, DF_JOURNAL_BRUSH = 4,
       DF_JOURNAL_RECIPE = 8, /* the positions after the row are its recipe's replay */
       DF_JOURNAL_HIST_RECIPE = 128 /* a stroke's end whose undo step was a RECIPE (history.h):
                                     * the restore commits it with the row's recipe */ };
/* flags bits 4..6: the change's undo-history step (commit.h DF_HIST_*), replayed at restore */
#define DF_JOURNAL_HIST_SHIFT 4
#define DF_JOURNAL_HIST(flags) (((flags) >> DF_JOURNAL_HIST_SHIFT) & 7)

extern const df_store_ops df_store_journal_ops;

/* Within the caller's transaction: positions `cur` and rest shape `rest` (3 x nv doubles each;
 * a rest shape bitwise the base is kept as none) become session s's snapshot of `version`
 * (store.h: blobs 'cur', 'rest'; sessions.snap_version), its log counters restart at 0 and its
 * log rows are deleted. Errors: DF_EIO, DF_ELIMIT (store full), with the store's message. */
struct df_store;
int df_journal_write_snapshot(struct df_store *st, const df_session *s, const double *cur,
                              const double *rest, uint64_t version, df_error *err);

#endif
