/* replicate.c — the store ops of cluster mode: the SQLite journal's write (journal.h), then
 * the same rows to Redis under the lease's fencing token, both before the ack (cluster.h). */
#include <inttypes.h>
#include <stdlib.h>

#include "server/cluster/cluster_int.h"
#include "server/cluster/rows.h"
#include "server/cluster/rlog.h"
#include "server/log.h"
#include "server/session/commit.h"
#include "server/session/session.h"
#include "server/store/journal.h"

/* A failed replication: the change is refused (the caller applies nothing) and the session
 * leaves this daemon (its local rows are ahead of what was acknowledged: Redis keeps the
 * truth, the next request rebuilds from it). */
static int failed(df_cluster *cl, uint64_t id, int rc, df_error *err)
{
    df_cluster_schedule_drop(cl, id, err ? err->msg : "replication failed");
    cl->srv->stats.store_errors++;
    return rc;
}

/* After the local journal wrote session s's change: its new changes rows to the Redis
 * stream, or, when the store took a snapshot (or `whole`: a change outside the changes row),
 * every row as the Redis snapshot. `version`: the session's after the change. */
static int replicate(df_server *srv, const df_session *s, uint64_t version, int whole,
                     df_error *err)
{
    df_cluster *cl = srv->cluster;
    df_owned *o = df_cluster_owned(cl, s->id);
    if (!o || o->dropping)
        return df_error_set(err, DF_ESTATE, "cluster: session %" PRIu64 " is no longer owned "
                            "by this daemon", s->id);
    int64_t sv, lr;
    int rc = df_cluster_row_state(srv, s->id, &sv, &lr, err);
    if (rc != DF_OK) return failed(cl, s->id, rc, err);
    if (whole || sv != o->snap_version || lr < o->last_row) {
        rc = df_cluster_snapshot(cl, o, s, version, err);
        return rc == DF_OK ? DF_OK : failed(cl, s->id, rc, err);
    }
    if (lr == o->last_row) return DF_OK; /* nothing journaled */
    uint8_t *rows = NULL;
    size_t len = 0;
    int n = 0;
    int64_t last = 0;
    rc = df_rows_dump_changes(srv->store, s->id, o->last_row, &rows, &len, &n, &last, err);
    if (rc == DF_OK) rc = df_rlog_append(cl->r, s->id, o->token, version, rows, len, err);
    free(rows);
    if (rc != DF_OK) return failed(cl, s->id, rc, err);
    o->last_row = last;
    return DF_OK;
}

static int session_created(df_server *srv, const df_session *s, df_error *err)
{
    df_cluster *cl = srv->cluster;
    int rc = df_store_journal_ops.session_created(srv, s, err);
    if (rc != DF_OK) return rc;
    char token[DF_LEASE_VALUE_MAX];
    int got = df_lease_acquire(cl->r, s->id, cl->advertise, cl->ttl_ms, token, err);
    if (got == 0)
        rc = df_error_set(err, DF_EINTERNAL, "cluster: new session %" PRIu64 " already leased "
                          "(%s)", s->id, token);
    else if (got < 0) rc = got;
    if (rc == DF_OK) rc = df_cluster_own(cl, s->id, token, err);
    df_owned *o = rc == DF_OK ? df_cluster_owned(cl, s->id) : NULL;
    if (o) rc = df_cluster_snapshot(cl, o, s, atomic_load(&s->version), err);
    if (rc != DF_OK) {
        df_error e;
        df_cluster_disown(cl, s->id);
        df_rows_delete_session(srv->store, s->id, &e);
    }
    return rc;
}

static int session_closing(df_server *srv, const df_session *s, df_error *err)
{
    df_cluster *cl = srv->cluster;
    df_owned *o = df_cluster_owned(cl, s->id);
    if (!o || o->dropping)
        return df_error_set(err, DF_ESTATE, "cluster: session %" PRIu64 " is no longer owned "
                            "by this daemon", s->id);
    int rc = df_rlog_close(cl->r, s->id, o->token, err);
    if (rc == DF_ESTATE) return failed(cl, s->id, rc, err);
    if (rc != DF_OK) return rc;
    df_cluster_disown(cl, s->id);
    return df_store_journal_ops.session_closing(srv, s, err);
}

static int change(df_server *srv, const df_session *s, const df_change *c, df_error *err)
{
    int rc = df_store_journal_ops.change(srv, s, c, err);
    return rc != DF_OK ? rc : replicate(srv, s, c->version ? c->version : atomic_load(&s->version), c->hs != NULL,
                                        err);
}

static int brush(df_server *srv, const df_session *s, const df_brush_state *next, uint64_t who,
                 df_error *err)
{
    int rc = df_store_journal_ops.brush(srv, s, next, who, err);
    return rc != DF_OK ? rc : replicate(srv, s, atomic_load(&s->version), 1, err); /* the row's brush column */
}

static int access_saved(df_server *srv, const df_session *s, const df_membership *next,
                        df_error *err)
{
    int rc = df_store_journal_ops.access(srv, s, next, err);
    return rc != DF_OK ? rc : replicate(srv, s, atomic_load(&s->version), 1, err); /* the access row */
}

const df_store_ops df_cluster_store_ops = {.session_created = session_created,
                                           .session_closing = session_closing,
                                           .change = change,
                                           .brush = brush,
                                           .access = access_saved};
