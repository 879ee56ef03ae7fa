/* rebuild.h — failover: a session of the cluster rebuilt on this daemon from its Redis
 * snapshot and stream (cluster.h).
 *
 * The snapshot's rows and every stream entry's changes rows are loaded into the local store
 * (rows.h) in one transaction, the session row's version set to the last entry's, and the
 * store's own restore (server/store/restore.h df_store_restore_session) rebuilds the session
 * exactly as a restart of a single daemon would: positions and rest shape bit-identical to
 * the last acknowledged change, brush, handles, access, undo history since the snapshot. The
 * rebuilt row set is then written back as the session's Redis snapshot under the new lease
 * (compacting the stream, and replicating the history row a restore appends for a stroke left
 * open). Loop thread. */
#ifndef DF_SERVER_CLUSTER_REBUILD_H
#define DF_SERVER_CLUSTER_REBUILD_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "server/cluster/cluster_int.h"

/* Rebuilds session id, whose lease this daemon just took under `token`, into cl->srv (*out).
 * Errors: DF_ENOTFOUND (no snapshot: the session does not exist), DF_EFORMAT (malformed rows:
 * message names the session), DF_EIO (Redis or the local store), DF_ESTATE (fenced while
 * writing the snapshot back), DF_ENOMEM; on error nothing of the session stays here. */
int df_cluster_rebuild(df_cluster *cl, uint64_t id, const char *token, struct df_session **out,
                       df_error *err);

#endif
