/* cluster_int.h — cluster mode's state shared by its files (cluster.h). Loop thread. */
#ifndef DF_SERVER_CLUSTER_INT_H
#define DF_SERVER_CLUSTER_INT_H

#include <stdint.h>
#include <uv.h>

#include "server/cluster/lease.h"
#include "server/cluster/redis.h"
#include "server/server.h"

/* A session this daemon owns. */
typedef struct df_owned {
    uint64_t id;
    char token[DF_LEASE_VALUE_MAX]; /* the lease value: the fencing token */
    int64_t snap_version;           /* the store row's snap_version last replicated */
    int64_t last_row;               /* the highest changes rowid replicated (0: none) */
    int dropping;                   /* fenced or failed: dropped at the next drop pass */
} df_owned;

typedef struct df_cluster {
    df_server *srv;
    df_redis *r;
    char advertise[DF_CONFIG_PATH_MAX];
    int ttl_ms;
    df_owned *owned;
    size_t n_owned, cap_owned;
    uv_timer_t renew;   /* every ttl / 3 */
    uv_idle_t drop;     /* drops sessions marked dropping, outside of their commit */
    int drop_active;
} df_cluster;

/* The replicating store ops (replicate.c). */
extern const df_store_ops df_cluster_store_ops;

/* The owned entry of session id, or NULL. */
df_owned *df_cluster_owned(df_cluster *cl, uint64_t id);

/* Adds an owned session (token copied). Errors: DF_ENOMEM. */
int df_cluster_own(df_cluster *cl, uint64_t id, const char *token, df_error *err);

/* Forgets an owned entry (no Redis call). */
void df_cluster_disown(df_cluster *cl, uint64_t id);

/* Marks session id to be dropped from this daemon at the next loop iteration (not owned any
 * more: fenced, or a replication write failed), logging `why`. */
void df_cluster_schedule_drop(df_cluster *cl, uint64_t id, const char *why);

/* The session's store row state: snap_version and the highest changes rowid. Errors: DF_EIO. */
int df_cluster_row_state(df_server *srv, uint64_t id, int64_t *snap_version, int64_t *last_row,
                         df_error *err);

/* Writes session s's whole row set as its Redis snapshot (fenced by o's token), its index
 * entry (list.c: "KIND PLANAR NV NE VERSION OBSERVERS NAME", `version` the session's after the change
 * being written) and records the replicated state in o. Errors: DF_ESTATE (fenced), DF_EIO,
 * DF_EINTERNAL, DF_ENOMEM. */
struct df_session;
int df_cluster_snapshot(df_cluster *cl, df_owned *o, const struct df_session *s,
                        uint64_t version, df_error *err);

#endif
