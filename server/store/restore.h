/* restore.h — the store's place in the daemon's start and stop: open (store.h), restore every
 * session, install the journal (journal.h).
 *
 * Restore, per session row (ascending id): the mesh from its topology and exact base positions,
 * then the change log replayed onto the last snapshot (journal.h; the base when none) in commit
 * order (replay.h: each delta sets the changed vertices' exact doubles, a recipe record is
 * recomputed from the state of its base version and verified by its checksum, REST_FROM_CUR copies
 * the positions into the rest shape): positions and rest shape are bit-identical to those of the
 * last acknowledged change. A recipe record that does not reproduce its checksum stops that
 * session's replay at the last verified version (replay.h): the session gets those positions as a
 * new version (stored version + 1), the log is folded into a snapshot of them, an error names the
 * session, versions and rows lost, and STATS store_replay_mismatches counts it; other sessions
 * restore normally. STATS store_recipes_replayed / _skipped count the recipe records recomputed /
 * superseded at this start. The session keeps its id, name and version, its brush (and brush seq)
 * and its handle set (the ADMM solver and the Kelvinlet pin factorization are rebuilt lazily on
 * first use). Published displacements are recomputed as fl32(cur - base) (stream.h). The undo/redo
 * history is rebuilt from the rows' history steps since the last snapshot (earlier steps are not
 * kept: undo stops at the snapshot). A log that ends inside a stroke or handle move (the daemon
 * died before its end) ends it at restore, as a disconnect would: the positions become one more
 * undo step (a history-only row is appended first). Not restored: open strokes, subscribers. New
 * sessions get ids above every id the store ever gave (meta.next_session_id). Loop thread. */
#ifndef DF_SERVER_STORE_RESTORE_H
#define DF_SERVER_STORE_RESTORE_H

#include "core/common/df_error.h"
#include "server/server.h"

/* Opens srv->cfg's store (store = none: does nothing), restores its sessions into srv, then
 * sets srv->store and srv->store_ops. Call before the listeners open. Errors: df_store_open's
 * (the store file refused: message names it), DF_EFORMAT (a row that cannot be restored:
 * names the session), DF_ELIMIT / DF_ENOMEM (df_session_create's); on error every restored
 * session is destroyed and the store closed. */
int df_store_start(df_server *srv, df_error *err);

/* Restores session id from the rows of `st` into srv, as df_store_start restores each
 * session (cluster mode's failover: the rows loaded from Redis, server/cluster/rebuild.h);
 * srv->next_session_id is left at max(its value, id). A change the restore appends (a stroke
 * left open) goes through srv->store_ops when set. Errors: DF_ENOTFOUND (no such row), and
 * as df_store_start's restore (DF_EFORMAT, DF_EIO, DF_ELIMIT, DF_ENOMEM; the session is not
 * created). Loop thread. */
struct df_store;
int df_store_restore_session(df_server *srv, struct df_store *st, uint64_t id, df_error *err);

/* Closes the store (after the sessions are freed). NULL-safe on srv->store. */
void df_store_stop(df_server *srv);

#endif
