/* cluster.c — cluster mode's start, stop, owned sessions, lease renewal and drops (see
 * cluster.h). */
#include "server/cluster/cluster.h"

#include <hiredis/hiredis.h>
#include <inttypes.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>

#include "server/cluster/cluster_int.h"
#include "server/cluster/rows.h"
#include "server/cluster/rlog.h"
#include "server/exec/job.h"
#include "server/log.h"
#include "server/session/session.h"
#include "server/store/journal.h"
#include "server/store/store.h"

/* KEYS lease; ARGV token: deletes the lease when it is still ours. */
static const char k_release[] =
    "if redis.call('GET', KEYS[1]) == ARGV[1] then return redis.call('DEL', KEYS[1]) end\n"
    "return 0\n";

df_owned *df_cluster_owned(df_cluster *cl, uint64_t id)
{
    for (size_t i = 0; cl && i < cl->n_owned; i++)
        if (cl->owned[i].id == id) return &cl->owned[i];
    return NULL;
}

int df_cluster_own(df_cluster *cl, uint64_t id, const char *token, df_error *err)
{
    df_owned *o = df_cluster_owned(cl, id);
    if (!o) {
        if (cl->n_owned == cl->cap_owned) {
            size_t nc = cl->cap_owned ? 2 * cl->cap_owned : 16;
            df_owned *n = realloc(cl->owned, nc * sizeof *n);
            if (!n) return df_error_set(err, DF_ENOMEM, "out of memory");
            cl->owned = n;
            cl->cap_owned = nc;
        }
        o = &cl->owned[cl->n_owned++];
    }
    memset(o, 0, sizeof *o);
    o->id = id;
    snprintf(o->token, sizeof o->token, "%s", token);
    return DF_OK;
}

void df_cluster_disown(df_cluster *cl, uint64_t id)
{
    df_owned *o = df_cluster_owned(cl, id);
    if (o) *o = cl->owned[--cl->n_owned];
}

int df_cluster_row_state(df_server *srv, uint64_t id, int64_t *snap_version, int64_t *last_row,
                         df_error *err)
{
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(df_store_db(srv->store), "SELECT snap_version FROM sessions WHERE"
                           " id = ?", -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(srv->store, DF_EIO, "reading the session row", err);
    sqlite3_bind_int64(q, 1, (sqlite3_int64)id);
    *snap_version = sqlite3_step(q) == SQLITE_ROW ? sqlite3_column_int64(q, 0) : -1;
    sqlite3_finalize(q);
    return df_rows_last_change(srv->store, id, last_row, err);
}

int df_cluster_snapshot(df_cluster *cl, df_owned *o, const df_session *s, uint64_t version,
                        df_error *err)
{
    char info[DF_SESSION_NAME_MAX + 96];
    snprintf(info, sizeof info, "%d %d %d %d %" PRIu64 " %d %s", (int)s->mesh.kind,
             s->mesh.planar, s->mesh.nv, s->mesh.ne, version, s->acc.observers, s->name);
    df_store *st = cl->srv->store;
    int64_t sv, lr;
    uint8_t *snap = NULL;
    size_t len = 0;
    int rc = df_cluster_row_state(cl->srv, o->id, &sv, &lr, err);
    if (rc == DF_OK) rc = df_rows_dump_session(st, o->id, &snap, &len, err);
    if (rc == DF_OK) rc = df_rlog_snapshot(cl->r, o->id, o->token, info, snap, len, err);
    free(snap);
    if (rc == DF_OK) {
        o->snap_version = sv;
        o->last_row = lr;
    }
    return rc;
}

/* Drops one session from this daemon: its queued jobs answered, SESSION_CLOSED to its
 * subscribers, its local rows deleted. Its Redis keys stay (the cluster's copy). */
static void drop_session(df_cluster *cl, uint64_t id)
{
    df_server *srv = cl->srv;
    df_cluster_disown(cl, id);
    df_session *s = df_session_find(srv, id);
    if (s) {
        df_job_drop_queued(s, df_job_pred_all, NULL, "session moved to another daemon");
        df_session_close(s);
        df_job_pump(s); /* frees it once its FIFO is empty */
    }
    df_error e;
    if (srv->store && df_rows_delete_session(srv->store, id, &e) != DF_OK)
        df_log(DF_LOG_WARN, "cluster: session %" PRIu64 ": %s", id, e.msg);
}

static void on_drop(uv_idle_t *h)
{
    df_cluster *cl = h->data;
    for (size_t i = 0; i < cl->n_owned;) {
        if (cl->owned[i].dropping) drop_session(cl, cl->owned[i].id); /* swaps in the last */
        else i++;
    }
    uv_idle_stop(h);
    cl->drop_active = 0;
}

void df_cluster_schedule_drop(df_cluster *cl, uint64_t id, const char *why)
{
    df_owned *o = df_cluster_owned(cl, id);
    if (!o || o->dropping) return;
    o->dropping = 1;
    df_log(DF_LOG_WARN, "cluster: session %" PRIu64 " dropped from this daemon: %s", id, why);
    if (!cl->drop_active) {
        cl->drop_active = 1;
        uv_idle_start(&cl->drop, on_drop);
    }
}

/* Every owned lease renewed in one pipelined round trip (one fsync of the AOF for all). */
static void on_renew(uv_timer_t *h)
{
    df_cluster *cl = h->data;
    size_t n = cl->n_owned;
    if (!n) return;
    uint64_t *ids = malloc(n * sizeof *ids);
    const char **tokens = malloc(n * sizeof *tokens);
    int *ok = malloc(n * sizeof *ok);
    df_error e;
    int rc = ids && tokens && ok ? DF_OK : df_error_set(&e, DF_ENOMEM, "out of memory");
    for (size_t i = 0; rc == DF_OK && i < n; i++) {
        ids[i] = cl->owned[i].id;
        tokens[i] = cl->owned[i].token;
    }
    if (rc == DF_OK) rc = df_lease_renew_many(cl->r, n, ids, tokens, cl->ttl_ms, ok, &e);
    if (rc != DF_OK) /* Redis unreachable: retried at the next tick */
        df_log(DF_LOG_WARN, "cluster: renewing %zu lease(s): %s", n, e.msg);
    for (size_t i = 0; rc == DF_OK && i < n; i++)
        if (!ok[i]) df_cluster_schedule_drop(cl, ids[i], "its lease was lost (fenced)");
    free(ids);
    free(tokens);
    free(ok);
}

const char *df_cluster_advertise(const df_server *srv)
{
    return srv->cluster ? srv->cluster->advertise : "";
}

int df_cluster_next_id(df_server *srv, df_error *err)
{
    if (!srv->cluster) return DF_OK;
    uint64_t id;
    int rc = df_rlog_new_id(srv->cluster->r, &id, err);
    if (rc == DF_OK) srv->next_session_id = id - 1;
    return rc;
}

/* Logs the Redis server's persistence: the cluster's durability (cluster.h). A Redis without
 * AOF loses every session at its restart; appendfsync everysec up to a second of acknowledged
 * changes at a crash of its machine. CONFIG may be renamed or refused: then nothing is said. */
static void log_persistence(df_redis *r)
{
    const char *keys[2] = {"appendonly", "appendfsync"};
    char val[2][32] = {"", ""};
    for (int k = 0; k < 2; k++) {
        redisReply *rep = NULL;
        df_error e;
        if (df_redis_cmdv(r, &rep, &e, 3, "CONFIG", "GET", keys[k]) != DF_OK) return;
        if (rep->type == REDIS_REPLY_ARRAY && rep->elements == 2 &&
            rep->element[1]->type == REDIS_REPLY_STRING)
            snprintf(val[k], sizeof val[k], "%s", rep->element[1]->str);
        df_redis_reply_free(rep);
    }
    if (!val[0][0]) return;
    if (strcmp(val[0], "yes") != 0)
        df_log(DF_LOG_WARN, "cluster: redis %s has appendonly %s: a restart of Redis loses the "
               "sessions (set appendonly yes, appendfsync always)", df_redis_addr(r), val[0]);
    else if (strcmp(val[1], "always") != 0)
        df_log(DF_LOG_WARN, "cluster: redis %s has appendfsync %s: a crash of its machine may "
               "lose acknowledged changes (appendfsync always keeps every one)",
               df_redis_addr(r), val[1]);
}

int df_cluster_start(df_server *srv, df_error *err)
{
    const df_server_config *cfg = &srv->cfg;
    if (!cfg->cluster[0]) return DF_OK;
    if (!srv->store)
        return df_error_set(err, DF_EINVAL, "cluster: needs a local store (store = PATH, not "
                            "none): the working copy of the sessions this daemon owns");
    df_cluster *cl = calloc(1, sizeof *cl);
    if (!cl) return df_error_set(err, DF_ENOMEM, "out of memory");
    cl->srv = srv;
    cl->ttl_ms = cfg->cluster_lease_ms;
    if (cfg->advertise[0]) snprintf(cl->advertise, sizeof cl->advertise, "%s", cfg->advertise);
    else if (srv->have_tcp)
        snprintf(cl->advertise, sizeof cl->advertise, "%s:%d", cfg->tcp_host,
                 srv->tcp_port_bound);
    int rc = DF_OK;
    if (!cl->advertise[0])
        rc = df_error_set(err, DF_EINVAL, "cluster: needs advertise = HOST:PORT (or a tcp "
                          "listener): the address other daemons redirect clients to");
    if (rc == DF_OK) rc = df_redis_new(cfg->cluster, &cl->r, err);
    redisReply *rep = NULL;
    if (rc == DF_OK) rc = df_redis_cmdv(cl->r, &rep, err, 1, "PING");
    if (rc == DF_OK && rep->type == REDIS_REPLY_ERROR)
        rc = df_error_set(err, DF_EIO, "cluster redis %s: PING: %s", df_redis_addr(cl->r),
                          rep->str);
    df_redis_reply_free(rep);
    if (rc != DF_OK) {
        df_redis_free(cl->r);
        free(cl);
        return rc;
    }
    /* the local store's sessions are a previous run's working copies: Redis holds them */
    while (srv->sessions) {
        uint64_t id = srv->sessions->id;
        df_session_destroy(srv->sessions);
        df_error e;
        if (df_rows_delete_session(srv->store, id, &e) != DF_OK)
            df_log(DF_LOG_WARN, "cluster: %s", e.msg);
    }
    srv->cluster = cl;
    srv->store_ops = &df_cluster_store_ops;
    srv->session_route = df_cluster_route;
    uv_timer_init(srv->loop, &cl->renew);
    cl->renew.data = cl;
    int period = cl->ttl_ms / 3 > 0 ? cl->ttl_ms / 3 : 1;
    uv_timer_start(&cl->renew, on_renew, (uint64_t)period, (uint64_t)period);
    uv_unref((uv_handle_t *)&cl->renew);
    uv_idle_init(srv->loop, &cl->drop);
    cl->drop.data = cl;
    log_persistence(cl->r);
    df_log(DF_LOG_INFO, "cluster: redis %s, advertised as %s, lease %d ms",
           df_redis_addr(cl->r), cl->advertise, cl->ttl_ms);
    return DF_OK;
}

static void free_cluster(uv_handle_t *h)
{
    free(h->data);
}

void df_cluster_stop(df_server *srv)
{
    df_cluster *cl = srv->cluster;
    if (!cl) return;
    for (size_t i = 0; i < cl->n_owned; i++) { /* others take over at once */
        char kl[64];
        df_lease_key(cl->owned[i].id, "lease", kl, sizeof kl);
        redisReply *rep = NULL;
        df_error e;
        if (df_redis_cmdv(cl->r, &rep, &e, 5, "EVAL", k_release, "1", kl,
                          cl->owned[i].token) != DF_OK)
            break;
        df_redis_reply_free(rep);
    }
    uv_timer_stop(&cl->renew);
    uv_idle_stop(&cl->drop);
    srv->cluster = NULL;
    srv->session_route = NULL;
    srv->store_ops = srv->store ? &df_store_journal_ops : NULL;
    df_redis_free(cl->r);
    free(cl->owned);
    /* the handles close with the loop's other handles; the last one frees cl */
    uv_close((uv_handle_t *)&cl->renew, NULL);
    uv_close((uv_handle_t *)&cl->drop, free_cluster);
}
