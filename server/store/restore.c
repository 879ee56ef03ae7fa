/* restore.c — opening the store at start-up and restoring its sessions (see restore.h). */
#include "server/store/restore.h"

#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>
#include <uv.h>

#include "core/mesh/mesh_io.h"
#include "server/log.h"
#include "server/session/commit.h"
#include "server/session/session.h"
#include "server/store/codec.h"
#include "server/store/journal.h"
#include "server/store/replay.h"
#include "server/store/store.h"

/* Below this many vertices a replayed field is evaluated by one thread (as h_brush.c). */
#define REPLAY_PARALLEL_MIN_VERTICES 32768

/* A copy of session id's large value `name` (store.h: blobs) into *out (malloc'd; NULL when
 * absent), *len its bytes (0 when absent). Errors: DF_EIO (reading), DF_ENOMEM. */
static int blob_read(df_store *st, uint64_t id, const char *name, void **out, size_t *len,
                     df_error *err)
{
    *out = NULL;
    *len = 0;
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(df_store_db(st), "SELECT data FROM blobs WHERE session = ? AND"
                           " name = ?", -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, "reading a session's mesh", err);
    sqlite3_bind_int64(q, 1, (sqlite3_int64)id);
    sqlite3_bind_text(q, 2, name, -1, SQLITE_STATIC);
    int rc = DF_OK, step = sqlite3_step(q);
    if (step == SQLITE_ROW && (*len = (size_t)sqlite3_column_bytes(q, 0)) > 0) {
        if (!(*out = malloc(*len))) rc = df_error_set(err, DF_ENOMEM, "out of memory");
        else memcpy(*out, sqlite3_column_blob(q, 0), *len);
    } else if (step != SQLITE_ROW && step != SQLITE_DONE) {
        rc = df_store_fail(st, DF_EIO, "reading a session's mesh", err);
    }
    sqlite3_finalize(q);
    return rc;
}

/* blob_read of exactly `want` bytes (absent counts as 0): DF_EFORMAT otherwise. */
static int blob_exact(df_store *st, uint64_t id, const char *name, size_t want, void **out,
                      df_error *err)
{
    size_t len;
    int rc = blob_read(st, id, name, out, &len, err);
    if (rc == DF_OK && len != want) {
        free(*out);
        *out = NULL;
        rc = df_error_set(err, DF_EFORMAT, "%s of %zu bytes, %zu expected", name, len, want);
    }
    return rc;
}

/* The access columns 11..15 of restore_all's query (NULL: no access row, a session of a
 * schema 1 store: the configured mode, no owner) into s. */
static int restore_access(df_server *srv, df_session *s, sqlite3_stmt *q, df_error *err)
{
    if (sqlite3_column_type(q, 11) == SQLITE_NULL) return DF_OK; /* as df_session_create */
    snprintf(s->owner, sizeof s->owner, "%s", (const char *)sqlite3_column_text(q, 11));
    int mode = sqlite3_column_int(q, 12), obs = sqlite3_column_int(q, 13);
    if (mode < DF_ACCESS_MODE_OPEN || mode > DF_ACCESS_MODE_OWNER || obs < 0 || obs > 1)
        return df_error_set(err, DF_EFORMAT, "access row: mode %d observers %d", mode, obs);
    df_membership_free(&s->acc);
    df_membership_init(&s->acc, mode, obs);
    if (sqlite3_column_type(q, 14) != SQLITE_NULL) {
        if (sqlite3_column_bytes(q, 14) != DF_JOIN_HASH_BYTES)
            return df_error_set(err, DF_EFORMAT, "access row: join key hash of %d bytes",
                                sqlite3_column_bytes(q, 14));
        memcpy(s->acc.key_hash, sqlite3_column_blob(q, 14), DF_JOIN_HASH_BYTES);
        s->acc.has_key = 1;
    }
    const char *members = (const char *)sqlite3_column_text(q, 15);
    (void)srv;
    return members ? df_membership_members_parse(&s->acc, members,
                                                 (size_t)sqlite3_column_bytes(q, 15), err)
                   : DF_OK;
}

/* One session row (the columns of restore_all's query) restored into srv. */
static int restore_one(df_server *srv, df_store *st, sqlite3_stmt *q, df_error *err)
{
    uint64_t id = (uint64_t)sqlite3_column_int64(q, 0);
    char name[DF_SESSION_NAME_MAX];
    snprintf(name, sizeof name, "%s", (const char *)sqlite3_column_text(q, 1));
    df_mesh m;
    df_mesh_init(&m);
    m.kind = (df_mesh_kind)sqlite3_column_int(q, 2);
    m.planar = sqlite3_column_int(q, 3);
    int64_t nv = sqlite3_column_int64(q, 4), ne = sqlite3_column_int64(q, 5),
            nf = sqlite3_column_int64(q, 6);
    int es = df_mesh_elem_size(m.kind);
    int rc = DF_EFORMAT;
    df_error e;
    df_error_set(&e, DF_EFORMAT, "sizes: kind %d, %lld vertices, %lld elements, %lld faces",
                 (int)m.kind, (long long)nv, (long long)ne, (long long)nf);
    if (es && nv >= 1 && nv <= INT32_MAX / 3 && ne >= 0 && ne <= INT32_MAX / 4 && nf >= 0 &&
        nf <= INT32_MAX / 3) {
        m.nv = (int32_t)nv;
        m.ne = (int32_t)ne;
        m.nf = (int32_t)nf;
        void *V = NULL, *E = NULL, *F = NULL;
        rc = blob_exact(st, id, "base", 24 * (size_t)nv, &V, &e);
        m.V = V;
        if (rc == DF_OK) rc = blob_exact(st, id, "elems", 4 * (size_t)es * (size_t)ne, &E, &e);
        m.E = E;
        if (rc == DF_OK) rc = blob_exact(st, id, "faces", 12 * (size_t)nf, &F, &e);
        m.F = F;
        for (size_t i = 0; rc == DF_OK && i < (size_t)es * (size_t)ne; i++)
            if (m.E[i] < 0 || m.E[i] >= m.nv) rc = df_error_set(&e, DF_EFORMAT, "elems: index");
        for (size_t i = 0; rc == DF_OK && i < 3 * (size_t)nf; i++)
            if (m.F[i] < 0 || m.F[i] >= m.nv) rc = df_error_set(&e, DF_EFORMAT, "faces: index");
    }
    if (rc != DF_OK) {
        df_mesh_free(&m);
        return df_error_set(err, rc, "store %s: session %llu '%s': malformed mesh row (%s)",
                            df_store_path(st), (unsigned long long)id, name, e.msg);
    }
    df_session *s;
    srv->next_session_id = id - 1; /* df_session_create gives it back its id */
    /* a name held by another session here (cluster mode's takeover: names are per daemon,
     * server/cluster/cluster.h) does not refuse it: the session keeps its name */
    int dup = df_session_find_name(srv, name) != NULL;
    if ((rc = df_session_create(srv, &m, dup ? "" : name, &s, &e)) != DF_OK)
        return df_error_set(err, rc, "store %s: session %llu '%s': %s", df_store_path(st),
                            (unsigned long long)id, name, e.msg);
    if (dup) snprintf(s->name, sizeof s->name, "%s", name);
    atomic_store(&s->version, (uint64_t)sqlite3_column_int64(q, 7)); /* before any write */
    uint64_t n_changes = 0;
    size_t pb = 24 * (size_t)s->nv;
    for (int k = 0; k < 2 && rc == DF_OK; k++) { /* the last snapshot (absent: the base) */
        void *snap = NULL;
        size_t len;
        rc = blob_read(st, id, k ? "rest" : "cur", &snap, &len, &e);
        if (rc == DF_OK && snap && len != pb)
            rc = df_error_set(&e, DF_EFORMAT, "snapshot of %zu bytes, %zu expected", len, pb);
        if (rc == DF_OK && snap) memcpy(k ? s->rest : s->cur, snap, pb);
        free(snap);
    }
    if (rc == DF_OK && s->mesh.ne > 0) { /* of the rest shape, as a load counts them */
        df_mesh rm = s->mesh;
        rm.V = s->rest;
        rc = df_admm_find_degenerate(&rm, NULL, &s->degen, &e);
    }
    if (rc == DF_OK) rc = restore_access(srv, s, q, &e);
    if (rc == DF_OK) rc = df_session_history_reset(s, &e); /* undo starts at the snapshot */
    df_replay_result rr;
    memset(&rr, 0, sizeof rr);
    if (rc == DF_OK)
        rc = df_store_replay(st, s, (uint64_t)sqlite3_column_int64(q, 10),
                             s->nv < REPLAY_PARALLEL_MIN_VERTICES ? 1 : srv->cfg.threads, &rr,
                             &e);
    n_changes = rr.rows;
    srv->stats.store_recipes_replayed += rr.recipes_replayed;
    srv->stats.store_recipes_skipped += rr.recipes_skipped;
    if (rc == DF_OK && rr.mismatch) {
        /* never a wrong mesh: the session stays at the last verified version's positions,
         * published as a new version (no version number names two meshes), folded into a
         * snapshot so that the next start does not replay the dropped rows onto them */
        uint64_t stored = atomic_load(&s->version), next = stored + 1;
        srv->stats.store_replay_mismatches++;
        df_log(DF_LOG_ERROR, "store %s: session %llu '%s': the change of version %llu does not "
               "replay to what was recorded (%s): restored at version %llu's positions, the "
               "last verified, as version %llu; %llu logged change(s) from version %llu on are "
               "lost", df_store_path(st), (unsigned long long)id, name,
               (unsigned long long)rr.bad_version, rr.why,
               (unsigned long long)rr.verified_version, (unsigned long long)next,
               (unsigned long long)rr.rows_dropped, (unsigned long long)rr.bad_version);
        atomic_store(&s->version, next);
        rc = df_session_history_reset(s, &e);
        if (rc == DF_OK) rc = df_store_replay_cut(st, s, next, &e);
    }
    if (rc == DF_OK && memcmp(s->hist.state, s->cur, 3 * (size_t)s->nv * sizeof(double)) != 0) {
        /* the log ends inside a stroke or move (the daemon died before its end): it ends now,
         * as a disconnect ends a stroke: the positions become an undo step, logged first so
         * that the next restart replays the same history */
        df_change c;
        df_change_init(&c, NULL, NULL);
        c.hist = DF_HIST_COMMIT;
        rc = (srv->store_ops ? srv->store_ops : &df_store_journal_ops)->change(srv, s, &c, &e);
        if (rc == DF_OK) rc = df_session_history_commit(s, &e);
        df_change_clear(srv, &c);
        df_log(DF_LOG_INFO, "session %llu: the stroke or move open when the daemon stopped "
               "ends here (one undo step)", (unsigned long long)id);
    }
    const uint8_t *b = sqlite3_column_blob(q, 8);
    if (rc == DF_OK && b)
        rc = df_codec_brush_unpack(b, (size_t)sqlite3_column_bytes(q, 8), &s->brush, &e);
    s->brush_seq = (uint64_t)sqlite3_column_int64(q, 9);
    void *h = NULL;
    size_t hlen = 0;
    if (rc == DF_OK) rc = blob_read(st, id, "handles", &h, &hlen, &e);
    if (rc == DF_OK && h) rc = df_codec_handles_decode(h, hlen, s->nv, &s->hs, &e);
    free(h);
    if (rc != DF_OK) {
        df_session_destroy(s);
        return df_error_set(err, rc, "store %s: session %llu '%s': %s", df_store_path(st),
                            (unsigned long long)id, name, e.msg);
    }
    for (size_t i = 0; i < 3 * (size_t)s->nv; i++)
        s->uf[i] = (float)(s->cur[i] - s->mesh.V[i]);
    df_log(DF_LOG_INFO, "session %llu '%s' restored at version %llu (%llu logged changes; "
           "%llu stroke recipe(s) replayed and verified, %llu superseded)",
           (unsigned long long)id, s->name, (unsigned long long)atomic_load(&s->version),
           (unsigned long long)n_changes, (unsigned long long)rr.recipes_replayed,
           (unsigned long long)rr.recipes_skipped);
    return DF_OK;
}

#define SESSIONS_QUERY                                                                     \
    "SELECT id, name, kind, planar, nv, ne, nf, version, brush, brush_seq, snap_version,"  \
    " a.owner, a.mode, a.observers, a.key_hash, a.members FROM sessions LEFT JOIN access a" \
    " ON a.session = sessions.id"

int df_store_restore_session(df_server *srv, df_store *st, uint64_t id, df_error *err)
{
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(df_store_db(st), SESSIONS_QUERY " WHERE id = ?", -1, &q, NULL) !=
        SQLITE_OK)
        return df_store_fail(st, DF_EIO, "reading the session", err);
    sqlite3_bind_int64(q, 1, (sqlite3_int64)id);
    uint64_t next = srv->next_session_id;
    int rc = sqlite3_step(q) == SQLITE_ROW
                 ? restore_one(srv, st, q, err)
                 : df_error_set(err, DF_ENOTFOUND, "store %s: no session %llu",
                                df_store_path(st), (unsigned long long)id);
    sqlite3_finalize(q);
    srv->next_session_id = next > id ? next : id;
    return rc;
}

static int restore_all(df_server *srv, df_store *st, int *count, df_error *err)
{
    sqlite3 *db = df_store_db(st);
    sqlite3_stmt *q = NULL;
    uint64_t next = 0;
    *count = 0;
    if (sqlite3_prepare_v2(db, "SELECT value FROM meta WHERE key = 'next_session_id'", -1, &q,
                           NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, "reading meta", err);
    if (sqlite3_step(q) == SQLITE_ROW) next = (uint64_t)sqlite3_column_int64(q, 0);
    sqlite3_finalize(q);
    if (sqlite3_prepare_v2(db, SESSIONS_QUERY " ORDER BY id", -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, "reading the sessions", err);
    int rc = DF_OK, step;
    while (rc == DF_OK && (step = sqlite3_step(q)) == SQLITE_ROW) {
        uint64_t id = (uint64_t)sqlite3_column_int64(q, 0);
        if ((rc = restore_one(srv, st, q, err)) == DF_OK) (*count)++;
        if (id > next) next = id;
    }
    if (rc == DF_OK && step != SQLITE_DONE)
        rc = df_store_fail(st, DF_EIO, "reading the sessions", err);
    sqlite3_finalize(q);
    srv->next_session_id = next;
    return rc;
}

int df_store_start(df_server *srv, df_error *err)
{
    char path[4096];
    int def = 0;
    int r = df_store_resolve_path(srv->cfg.store_path, getenv("STATE_DIRECTORY"),
                                  getenv("XDG_STATE_HOME"), getenv("HOME"), path, sizeof path,
                                  &def, err);
    if (r < 0) return r;
    if (r == 1) {
        df_log(DF_LOG_INFO, "store: none (sessions are kept in memory only)");
        return DF_OK;
    }
    uint64_t t0 = uv_hrtime();
    df_store *st;
    const char *checked = "";
    int rc = df_store_open(path, srv->cfg.durability, srv->cfg.store_max_mb, def, &st, &checked,
                           err);
    if (rc != DF_OK) return rc;
    int count = 0;
    srv->store = st; /* store_ops stay NULL until restored (only a stroke left open writes) */
    if ((rc = restore_all(srv, st, &count, err)) != DF_OK) {
        while (srv->sessions) df_session_destroy(srv->sessions);
        df_store_stop(srv);
        return rc;
    }
    srv->store_ops = &df_store_journal_ops;
    static const char *const dur[] = {"full", "normal", "off"};
    df_log(DF_LOG_INFO, "store %s: %d session(s) restored in %.1f ms (%s%s, durability %s)",
           path, count, (double)(uv_hrtime() - t0) / 1e6, checked[0] ? checked : "new file",
           checked[0] ? " ok" : "", dur[srv->cfg.durability]);
    return DF_OK;
}

void df_store_stop(df_server *srv)
{
    if (!srv->store) return;
    df_log(DF_LOG_INFO, "store %s: %llu change(s) logged since start, %llu bytes of blobs",
           df_store_path(srv->store), (unsigned long long)df_store_log_changes(srv->store),
           (unsigned long long)df_store_log_bytes(srv->store));
    df_store_close(srv->store);
    srv->store = NULL;
    srv->store_ops = NULL;
}
