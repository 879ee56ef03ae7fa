/* rebuild.c — a session rebuilt from Redis through the store's restore (see rebuild.h). */
#include "server/cluster/rebuild.h"

#include <inttypes.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <uv.h>

#include "server/cluster/rows.h"
#include "server/cluster/rlog.h"
#include "server/log.h"
#include "server/session/session.h"
#include "server/store/restore.h"
#include "server/store/store.h"

/* The rows of snapshot + entries into the local store, in one transaction. */
static int load_rows(df_store *st, uint64_t id, const uint8_t *snap, size_t snap_len,
                     const df_rlog_entry *e, size_t n, df_error *err)
{
    int rc = df_store_exec(st, "BEGIN IMMEDIATE", "loading a replicated session", err);
    if (rc != DF_OK) return rc;
    rc = df_rows_load(st, id, snap, snap_len, err);
    for (size_t i = 0; rc == DF_OK && i < n; i++) rc = df_rows_load(st, id, e[i].row, e[i].len, err);
    if (rc == DF_OK && n) {
        char sql[128];
        snprintf(sql, sizeof sql, "UPDATE sessions SET version = %" PRIu64 " WHERE id = %" PRIu64,
                 e[n - 1].version, id);
        rc = df_store_exec(st, sql, "loading a replicated session", err);
    }
    if (rc == DF_OK) rc = df_store_exec(st, "COMMIT", "loading a replicated session", err);
    if (rc != DF_OK) sqlite3_exec(df_store_db(st), "ROLLBACK", NULL, NULL, NULL);
    return rc;
}

int df_cluster_rebuild(df_cluster *cl, uint64_t id, const char *token, df_session **out,
                       df_error *err)
{
    df_server *srv = cl->srv;
    uint64_t t0 = uv_hrtime();
    uint8_t *snap = NULL;
    size_t snap_len = 0, n = 0;
    df_rlog_entry *e = NULL;
    int rc = df_rlog_read(cl->r, id, &snap, &snap_len, &e, &n, err);
    if (rc == DF_OK && !snap)
        rc = df_error_set(err, DF_ENOTFOUND, "no session %" PRIu64 " in the cluster", id);
    df_error ignore;
    if (rc == DF_OK) rc = df_rows_delete_session(srv->store, id, err); /* a stale copy */
    if (rc == DF_OK) rc = load_rows(srv->store, id, snap, snap_len, e, n, err);
    free(snap);
    df_rlog_entries_free(e, n);
    if (rc == DF_OK) {
        const df_store_ops *ops = srv->store_ops;
        srv->store_ops = NULL; /* the restore re-creates the session: not a new one */
        rc = df_store_restore_session(srv, srv->store, id, err);
        srv->store_ops = ops;
    }
    df_session *s = rc == DF_OK ? df_session_find(srv, id) : NULL;
    if (rc == DF_OK && !s) rc = df_error_set(err, DF_EINTERNAL, "session %" PRIu64 " not "
                                             "restored", id);
    if (rc == DF_OK) rc = df_cluster_own(cl, id, token, err);
    df_owned *o = rc == DF_OK ? df_cluster_owned(cl, id) : NULL;
    if (o) rc = df_cluster_snapshot(cl, o, s, atomic_load(&s->version), err);
    if (rc != DF_OK) {
        df_cluster_disown(cl, id);
        if (s) df_session_destroy(s);
        df_rows_delete_session(srv->store, id, &ignore);
        return rc;
    }
    df_log(DF_LOG_INFO, "cluster: session %" PRIu64 " '%s' taken over (lease %s) at version "
           "%llu from snapshot + %zu stream entries in %.1f ms", id, s->name, token,
           (unsigned long long)atomic_load(&s->version), n, (double)(uv_hrtime() - t0) / 1e6);
    *out = s;
    return DF_OK;
}
