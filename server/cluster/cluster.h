/* cluster.h — cluster mode (issue 15): many deformd daemons serve one studio's sessions
 * through one Redis, and a session survives the loss of its daemon.
 *
 * Config (config.h): cluster = redis://HOST:PORT turns it on (or a comma-separated list of
 * Redis Cluster seed nodes: redis.h routes each command to its key's slot master); advertise = HOST:PORT is the
 * address other daemons redirect clients to (default: the TCP listener's); cluster_lease_ms the
 * lease ttl. Without `cluster` nothing here runs and deformd is the single daemon it was.
 *
 * Ownership (lease.h): each session has one owning daemon, holding its lease (SET NX PX,
 * renewed every ttl/3; the value "EPOCH HOST:PORT" is the fencing token). Compute for a
 * session runs only on its owner, so its versions stay totally ordered.
 * Replication (replicate.c, rlog.h, rows.h): the daemon keeps its SQLite store (`store`,
 * required) as the working copy of its own sessions; every change the store journals before
 * the ack (server/store/journal.h) is then appended, as the same changes row, to the session's
 * Redis Stream by a Lua script that checks the token, still before the ack, apply and
 * broadcast. When the store folds a session's log into a snapshot (journal.h policy), and for
 * a brush state, handle set or access change (kept in the session row and blobs, not in the
 * changes row), the whole row set becomes the Redis snapshot and the stream is emptied.
 * A failed Redis write (Redis unreachable, or fenced) fails the change (nothing applied,
 * acked or broadcast) and the daemon drops the session (SESSION_CLOSED to its subscribers,
 * local rows deleted): the truth is Redis's, and the next request for the session rebuilds it
 * there. Writes use a synchronous hiredis context on the loop thread, as the SQLite store
 * writes synchronously: simplest and correct (the ack waits for the write anyway).
 * Routing (route.c): a request for a session this daemon does not hold is looked up in Redis:
 * leased by another daemon -> error DF_EMOVED "MOVED <id> <HOST:PORT>" (PROTOCOL.md), which
 * the clients follow (reconnect to that address, retry once); not leased (its owner died and
 * the lease expired, or was released) -> this daemon takes the lease with a new epoch,
 * rebuilds the session from snapshot + stream through the store's own restore (rebuild.c) and
 * serves it. LIST_SESSIONS lists every session of the cluster with its owner's address.
 * A stale owner (paused past its lease) finds out at its next renew or write: fenced, it
 * drops the session and never writes again.
 * Loop thread. */
#ifndef DF_SERVER_CLUSTER_CLUSTER_H
#define DF_SERVER_CLUSTER_CLUSTER_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "server/server.h"

/* Starts cluster mode when srv->cfg.cluster is set (else does nothing): connects to Redis
 * (refusing the start when it does not answer), drops the sessions the local store restored
 * (the cluster's copy is Redis's), installs the replicating store ops and the lease renewal.
 * Call after the store opened. Errors: DF_EINVAL (no store, no advertise address), DF_EIO
 * (Redis unreachable: message names it), DF_ENOMEM. */
int df_cluster_start(df_server *srv, df_error *err);

/* Releases every lease this daemon holds (other daemons take over at once) and frees the
 * cluster state. NULL-safe on srv->cluster. */
void df_cluster_stop(df_server *srv);

/* Cluster routing of a request for session `id` that this daemon does not hold: DF_OK with
 * *out the session (taken over and rebuilt here), DF_EMOVED (message "MOVED <id> <addr>": owned
 * by the daemon at addr), DF_ENOTFOUND (no such session in the cluster), DF_EIO (Redis). */
int df_cluster_route(df_server *srv, uint64_t id, struct df_session **out, df_error *err);

/* Before a new session is created: a cluster-wide id (Redis INCR), srv->next_session_id set so
 * that df_session_create gives it. No-op outside cluster mode. Errors: DF_EIO. */
int df_cluster_next_id(df_server *srv, df_error *err);

/* LIST_SESSIONS in cluster mode: `local` (this daemon's listed sessions, oldest first; owned by
 * the caller) plus every session of the cluster held elsewhere or nowhere (from the Redis index:
 * its sizes, the version of its last replicated change; subscribers and undo depths 0; those
 * that admit no observers only for admins), answered on r. When the requester's HELLO set
 * DF_HELLO_WANT_OWNERS, the owners trailer follows (PROTOCOL.md 4.10): each listed session's
 * owner address ("" while unleased). Errors: DF_EIO (Redis), DF_ENOMEM; r is then not
 * answered. */
struct df_req;
struct df_msg_session_list;
int df_cluster_list_sessions(struct df_req *r, const struct df_msg_session_list *local,
                             df_error *err);

/* This daemon's advertised address ("" outside cluster mode). */
const char *df_cluster_advertise(const df_server *srv);

#endif
