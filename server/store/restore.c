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
#include "server/store/store.h"

/* The highest version in session `id`'s change log, 0 when it has no rows (store.h: the
 * current version is the larger of this and the session row's). */
static int last_logged_version(df_store *st, uint64_t id, uint64_t *out, df_error *err)
{
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(df_store_db(st), "SELECT max(version) FROM changes WHERE session = ?",
                           -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, "reading the change log", err);
    sqlite3_bind_int64(q, 1, (sqlite3_int64)id);
    int step = sqlite3_step(q);
    *out = step == SQLITE_ROW ? (uint64_t)sqlite3_column_int64(q, 0) : 0;
    sqlite3_finalize(q);
    return step == SQLITE_ROW ? DF_OK : df_store_fail(st, DF_EIO, "reading the change log", err);
}

/* The session brush after the log: the last brush row's (DF_JOURNAL_BRUSH, aux) when there is
 * one, else the session row's `row` (row_len bytes; NULL: the defaults stay); brush_seq = the
 * row's `row_seq` + the brush rows since (store.h). */
static int restore_brush(df_store *st, df_session *s, const uint8_t *row, size_t row_len,
                         uint64_t row_seq, df_error *err)
{
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(df_store_db(st), "SELECT aux, (SELECT count(*) FROM changes WHERE"
                           " session = ?1 AND flags & ?2) FROM changes WHERE session = ?1 AND"
                           " flags & ?2 ORDER BY id DESC LIMIT 1", -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, "reading the brush rows", err);
    sqlite3_bind_int64(q, 1, (sqlite3_int64)s->id);
    sqlite3_bind_int(q, 2, DF_JOURNAL_BRUSH);
    int step = sqlite3_step(q), rc = DF_OK;
    if (step == SQLITE_ROW) {
        row = sqlite3_column_blob(q, 0);
        row_len = (size_t)sqlite3_column_bytes(q, 0);
        row_seq += (uint64_t)sqlite3_column_int64(q, 1);
    } else if (step != SQLITE_DONE) {
        rc = df_store_fail(st, DF_EIO, "reading the brush rows", err);
    }
    if (rc == DF_OK && row) rc = df_codec_brush_unpack(row, row_len, &s->brush, err);
    if (rc == DF_OK) s->brush_seq = row_seq;
    sqlite3_finalize(q);
    return rc;
}

/* Replays session s's change log onto its positions and rest shape (the last snapshot or the
 * base), with each row's undo-history step on s->hist, in the commit's order (state, then
 * history), and sets the log's size since the snapshot (df_store_session_log: the delta and
 * aux bytes of the rows other than brush rows, as journal.c counts them). */
static int replay(df_store *st, df_session *s, uint64_t *n_changes, df_error *err)
{
    sqlite3_stmt *q = NULL;
    uint64_t *logged = df_store_session_log(st, s->id);
    if (!logged) return df_error_set(err, DF_ENOMEM, "out of memory");
    *logged = 0;
    if (sqlite3_prepare_v2(df_store_db(st), "SELECT flags, delta, length(aux) FROM changes"
                           " WHERE session = ? ORDER BY id", -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, "reading the change log", err);
    sqlite3_bind_int64(q, 1, (sqlite3_int64)s->id);
    int rc = DF_OK, step;
    *n_changes = 0;
    while (rc == DF_OK && (step = sqlite3_step(q)) == SQLITE_ROW) {
        int flags = sqlite3_column_int(q, 0);
        const uint8_t *d = sqlite3_column_blob(q, 1);
        size_t len = (size_t)sqlite3_column_bytes(q, 1);
        if (!(flags & DF_JOURNAL_BRUSH)) *logged += len + (uint64_t)sqlite3_column_int64(q, 2);
        if (d) rc = df_codec_delta_apply(d, len, s->cur, s->nv, NULL, err);
        if (rc == DF_OK && (flags & DF_JOURNAL_REST_FROM_CUR))
            memcpy(s->rest, s->cur, 3 * (size_t)s->nv * sizeof(double));
        if (rc == DF_OK) {
            switch (DF_JOURNAL_HIST(flags)) { /* as commit.c's apply_history */
            case DF_HIST_COMMIT: rc = df_session_history_commit(s, err); break;
            case DF_HIST_RESET: rc = df_session_history_reset(s, err); break;
            case DF_HIST_UNDO:
            case DF_HIST_REDO: {
                /* The step it moved to may predate the snapshot the history starts at (an undo
                 * of a change the snapshot folded in): the history then restarts at the
                 * positions the row produced, so later undo steps revert to them, as live. */
                const double *at = DF_JOURNAL_HIST(flags) == DF_HIST_UNDO
                                       ? df_history_undo(&s->hist, NULL)
                                       : df_history_redo(&s->hist, NULL);
                if (!at || memcmp(at, s->cur, 3 * (size_t)s->nv * sizeof(double)))
                    rc = df_session_history_reset(s, err);
                break;
            }
            default: break;
            }
        }
        (*n_changes)++;
    }
    if (rc == DF_OK && step != SQLITE_DONE) rc = df_store_fail(st, DF_EIO, "reading the log", err);
    sqlite3_finalize(q);
    return rc;
}

/* A copy of column `col` (exactly `len` bytes, NULL allowed when len is 0). */
static int column_copy(sqlite3_stmt *q, int col, size_t len, void **out)
{
    *out = NULL;
    if ((size_t)sqlite3_column_bytes(q, col) != len) return DF_EFORMAT;
    if (!len) return DF_OK;
    if (!(*out = malloc(len))) return DF_ENOMEM;
    memcpy(*out, sqlite3_column_blob(q, col), len);
    return DF_OK;
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
    if (es && nv >= 1 && nv <= INT32_MAX / 3 && ne >= 0 && ne <= INT32_MAX / 4 && nf >= 0 &&
        nf <= INT32_MAX / 3) {
        m.nv = (int32_t)nv;
        m.ne = (int32_t)ne;
        m.nf = (int32_t)nf;
        void *V = NULL, *E = NULL, *F = NULL;
        rc = column_copy(q, 7, 24 * (size_t)nv, &V);
        m.V = V;
        if (rc == DF_OK) rc = column_copy(q, 8, 4 * (size_t)es * (size_t)ne, &E);
        m.E = E;
        if (rc == DF_OK) rc = column_copy(q, 9, 12 * (size_t)nf, &F);
        m.F = F;
        for (size_t i = 0; rc == DF_OK && i < (size_t)es * (size_t)ne; i++)
            if (m.E[i] < 0 || m.E[i] >= m.nv) rc = DF_EFORMAT;
        for (size_t i = 0; rc == DF_OK && i < 3 * (size_t)nf; i++)
            if (m.F[i] < 0 || m.F[i] >= m.nv) rc = DF_EFORMAT;
    }
    if (rc != DF_OK) {
        df_mesh_free(&m);
        return df_error_set(err, rc, "store %s: session %llu '%s': %s", df_store_path(st),
                            (unsigned long long)id, name,
                            rc == DF_ENOMEM ? "out of memory" : "malformed mesh row");
    }
    df_session *s;
    srv->next_session_id = id - 1; /* df_session_create gives it back its id */
    df_error e;
    if ((rc = df_session_create(srv, &m, name, &s, &e)) != DF_OK)
        return df_error_set(err, rc, "store %s: session %llu '%s': %s", df_store_path(st),
                            (unsigned long long)id, name, e.msg);
    uint64_t version = (uint64_t)sqlite3_column_int64(q, 10), logged_version = 0;
    rc = last_logged_version(st, id, &logged_version, &e);
    if (logged_version > version) version = logged_version;
    atomic_store(&s->version, version); /* before any write */
    if (rc == DF_OK) /* the brush too: a snapshot written below takes it */
        rc = restore_brush(st, s, sqlite3_column_blob(q, 11), (size_t)sqlite3_column_bytes(q, 11),
                           (uint64_t)sqlite3_column_int64(q, 12), &e);
    uint64_t n_changes = 0;
    size_t pb = 24 * (size_t)s->nv;
    for (int col = 14; col <= 15; col++) { /* the last snapshot (NULL: the base) */
        if (sqlite3_column_type(q, col) == SQLITE_NULL) continue;
        if ((size_t)sqlite3_column_bytes(q, col) != pb) {
            rc = df_error_set(&e, DF_EFORMAT, "snapshot of %d bytes, %zu expected",
                              sqlite3_column_bytes(q, col), pb);
            break;
        }
        memcpy(col == 14 ? s->cur : s->rest, sqlite3_column_blob(q, col), pb);
    }
    if (rc == DF_OK) rc = df_session_history_reset(s, &e); /* undo starts at the snapshot */
    if (rc == DF_OK) rc = replay(st, s, &n_changes, &e);
    if (rc == DF_OK && memcmp(s->hist.state, s->cur, 3 * (size_t)s->nv * sizeof(double)) != 0) {
        /* the log ends inside a stroke or move (the daemon died before its end): it ends now,
         * as a disconnect ends a stroke: the positions become an undo step, logged first so
         * that the next restart replays the same history */
        df_change c;
        df_change_init(&c, NULL, NULL);
        c.hist = DF_HIST_COMMIT;
        rc = df_store_journal_ops.change(srv, s, &c, &e);
        if (rc == DF_OK) rc = df_session_history_commit(s, &e);
        df_change_clear(srv, &c);
        df_log(DF_LOG_INFO, "session %llu: the stroke or move open when the daemon stopped "
               "ends here (one undo step)", (unsigned long long)id);
    }

    const uint8_t *h = sqlite3_column_blob(q, 13);
    if (rc == DF_OK && h)
        rc = df_codec_handles_decode(h, (size_t)sqlite3_column_bytes(q, 13), s->nv, &s->hs, &e);
    if (rc != DF_OK) {
        df_session_destroy(s);
        return df_error_set(err, rc, "store %s: session %llu '%s': %s", df_store_path(st),
                            (unsigned long long)id, name, e.msg);
    }
    for (size_t i = 0; i < 3 * (size_t)s->nv; i++)
        s->uf[i] = (float)(s->cur[i] - s->mesh.V[i]);
    df_log(DF_LOG_INFO, "session %llu '%s' restored at version %llu (%llu logged changes)",
           (unsigned long long)id, s->name, (unsigned long long)atomic_load(&s->version),
           (unsigned long long)n_changes);
    return DF_OK;
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
    if (sqlite3_prepare_v2(db, "SELECT id, name, kind, planar, nv, ne, nf, base, elems, faces,"
                           " version, brush, brush_seq, handles, cur, rest FROM sessions"
                           " ORDER BY id",
                           -1, &q, NULL) != SQLITE_OK)
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
