/* journal.c — the store's writes: session rows and the change log (see journal.h). */
#include "server/store/journal.h"

#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>

#include "server/log.h"
#include "server/net/req.h"
#include "server/session/commit.h"
#include "server/session/session.h"
#include "server/store/codec.h"
#include "server/store/store.h"

/* One statement with its bindings: blobs (ptr, len) and integers, in order of `types`
 * ('i' int64, 'b' blob, 't' text, 'n' null). Returns DF_OK or DF_EIO / DF_ELIMIT (full). */
static int run(df_store *st, const char *sql, const char *types, const void *const *ptrs,
               const int64_t *vals, const char *what, df_error *err)
{
    sqlite3 *db = df_store_db(st);
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(db, sql, -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, what, err);
    int rc = SQLITE_OK;
    for (int i = 0; types[i] && rc == SQLITE_OK; i++) {
        switch (types[i]) {
        case 'i': rc = sqlite3_bind_int64(q, i + 1, vals[i]); break;
        case 'b': rc = sqlite3_bind_blob64(q, i + 1, ptrs[i], (sqlite3_uint64)vals[i],
                                           SQLITE_STATIC); break;
        case 't': rc = sqlite3_bind_text(q, i + 1, ptrs[i], -1, SQLITE_STATIC); break;
        default: rc = sqlite3_bind_null(q, i + 1); break;
        }
    }
    if (rc == SQLITE_OK) rc = sqlite3_step(q);
    sqlite3_finalize(q);
    if (rc == SQLITE_DONE || rc == SQLITE_ROW) return DF_OK;
    int full = rc == SQLITE_FULL;
    return df_store_fail(st, full ? DF_ELIMIT : DF_EIO, what, err);
}

static int begin(df_store *st, df_error *err)
{
    return df_store_exec(st, "BEGIN IMMEDIATE", "begin", err);
}

/* COMMIT, or ROLLBACK after an error (rc != DF_OK); returns the first error. */
static int finish(df_store *st, int rc, df_error *err)
{
    if (rc == DF_OK) rc = df_store_exec(st, "COMMIT", "commit", err);
    if (rc != DF_OK) sqlite3_exec(df_store_db(st), "ROLLBACK", NULL, NULL, NULL);
    return rc;
}

/* The store's and the server's counters after a change-log write. */
static void count(df_server *srv, int rc, uint64_t bytes)
{
    if (rc != DF_OK) {
        srv->stats.store_errors++;
        return;
    }
    df_store_count_change(srv->store, bytes);
    srv->stats.store_changes++;
    srv->stats.store_log_bytes += bytes;
}

static int session_created(df_server *srv, const df_session *s, df_error *err)
{
    df_store *st = srv->store;
    const df_mesh *m = &s->mesh;
    size_t es = (size_t)df_mesh_elem_size(m->kind);
    uint8_t brush[DF_CODEC_BRUSH_BYTES];
    df_codec_brush_pack(&s->brush, brush);
    const void *p[14] = {NULL, s->name, NULL, NULL, NULL, NULL, NULL, m->V, m->E, m->F, NULL,
                         brush};
    int64_t v[14] = {(int64_t)s->id, 0, m->kind, m->planar, m->nv, m->ne, m->nf,
                     (int64_t)(24 * (size_t)m->nv), (int64_t)(4 * es * (size_t)m->ne),
                     (int64_t)(12 * (size_t)m->nf), (int64_t)atomic_load(&s->version),
                     DF_CODEC_BRUSH_BYTES, (int64_t)s->brush_seq};
    char types[] = "itiiiiibbbibi";
    if (!m->E || !m->ne) types[8] = 'n';
    if (!m->F || !m->nf) types[9] = 'n';
    int rc = begin(st, err);
    if (rc != DF_OK) return rc;
    rc = run(st, "INSERT INTO sessions(id, name, kind, planar, nv, ne, nf, base, elems, faces,"
             " version, brush, brush_seq) VALUES(?,?,?,?,?,?,?,?,?,?,?,?,?)",
             types, p, v, "saving the new session", err);
    if (rc == DF_OK) {
        int64_t id[1] = {(int64_t)s->id};
        rc = run(st, "UPDATE meta SET value = max(value, ?) WHERE key = 'next_session_id'", "i",
                 NULL, id, "saving the session id", err);
    }
    rc = finish(st, rc, err);
    if (rc != DF_OK) srv->stats.store_errors++;
    return rc;
}

static int session_closing(df_server *srv, const df_session *s, df_error *err)
{
    df_store *st = srv->store;
    int64_t id[1] = {(int64_t)s->id};
    int rc = begin(st, err);
    if (rc != DF_OK) return rc;
    rc = run(st, "DELETE FROM changes WHERE session = ?", "i", NULL, id,
             "deleting the session's log", err);
    if (rc == DF_OK)
        rc = run(st, "DELETE FROM sessions WHERE id = ?", "i", NULL, id, "deleting the session",
                 err);
    rc = finish(st, rc, err);
    if (rc == DF_OK) df_store_forget_session(st, s->id);
    return rc;
}

/* In the change's transaction: once the session's log since its last snapshot, `logged` bytes
 * with this change, exceeds max(snapshot_min, 2 x its position bytes), the positions and rest
 * shape after this change and its version become the session row's snapshot and the log rows
 * are deleted (*snap = 1). The only per-change write to the session row (journal.h). */
static int maybe_snapshot(df_store *st, const df_session *s, const df_change *c, uint64_t version,
                          uint64_t logged, int *snap, df_error *err)
{
    uint64_t pos_bytes = 24 * (uint64_t)s->nv, min = df_store_snapshot_min(st);
    uint64_t threshold = 2 * pos_bytes > min ? 2 * pos_bytes : min;
    *snap = 0;
    if (logged <= threshold) return DF_OK;
    const double *cur = c->pos ? c->pos : s->cur;
    const double *rest = c->rest_from_cur ? cur : s->rest;
    uint8_t brush[DF_CODEC_BRUSH_BYTES];
    df_codec_brush_pack(&s->brush, brush);
    const void *p[6] = {cur, rest, NULL, brush};
    int64_t v[6] = {(int64_t)pos_bytes, (int64_t)pos_bytes, (int64_t)version,
                    DF_CODEC_BRUSH_BYTES, (int64_t)s->brush_seq, (int64_t)s->id};
    int rc = run(st, "UPDATE sessions SET cur = ?, rest = ?, version = ?, brush = ?,"
                 " brush_seq = ?, log_bytes = 0 WHERE id = ?", "bbibii", p, v,
                 "writing a snapshot", err);
    if (rc == DF_OK)
        rc = run(st, "DELETE FROM changes WHERE session = ?", "i", NULL, v + 5,
                 "trimming the log after a snapshot", err);
    *snap = rc == DF_OK;
    return rc;
}

static int change(df_server *srv, const df_session *s, const df_change *c, df_error *err)
{
    if (!c->pos && !c->version && !c->rest_from_cur && !c->hs && !c->hist)
        return DF_OK; /* nothing kept */
    df_store *st = srv->store;
    uint64_t *logged = df_store_session_log(st, s->id);
    if (!logged) return df_error_set(err, DF_ENOMEM, "store: out of memory");
    uint8_t *delta = NULL, *hs = NULL;
    size_t dlen = 0, hlen = 0;
    int rc = DF_OK, snap = 0;
    if (c->pos) rc = df_codec_delta_encode(s->cur, c->pos, s->nv, &delta, &dlen, err);
    if (rc == DF_OK && c->hs) rc = df_codec_handles_encode(c->hs, &hs, &hlen, err);
    if (rc != DF_OK) {
        free(delta);
        return rc;
    }
    uint64_t version = c->version ? c->version : atomic_load(&s->version);
    int flags = (c->rest_from_cur ? DF_JOURNAL_REST_FROM_CUR : 0) | (hs ? DF_JOURNAL_HANDLES : 0) |
                ((c->hist & 7) << DF_JOURNAL_HIST_SHIFT);
    const void *p[8] = {NULL, NULL, NULL, NULL, NULL, delta, hs};
    int64_t v[8] = {(int64_t)s->id, (int64_t)version, c->req ? c->req->type : 0,
                    c->req ? (int64_t)df_req_origin(c->req) : 0, flags, (int64_t)dlen,
                    (int64_t)hlen};
    char types[] = "iiiiibb";
    if (!delta) types[5] = 'n';
    if (!hs) types[6] = 'n';
    if ((rc = begin(st, err)) == DF_OK) {
        rc = run(st, "INSERT INTO changes(session, version, kind, who, flags, delta, aux)"
                 " VALUES(?,?,?,?,?,?,?)", types, p, v, "appending the change", err);
        if (rc == DF_OK && hs) { /* a new handle set (rare): the row keeps the current one */
            const void *p2[2] = {hs};
            int64_t v2[2] = {(int64_t)hlen, (int64_t)s->id};
            rc = run(st, "UPDATE sessions SET handles = ? WHERE id = ?", "bi", p2, v2,
                     "saving the handle set", err);
        }
        if (rc == DF_OK)
            rc = maybe_snapshot(st, s, c, version, *logged + dlen + hlen, &snap, err);
        rc = finish(st, rc, err);
    }
    if (rc == DF_OK) *logged = snap ? 0 : *logged + dlen + hlen;
    count(srv, rc, dlen + hlen);
    free(delta);
    free(hs);
    return rc;
}

static int brush(df_server *srv, const df_session *s, const df_brush_state *next, uint64_t who,
                 df_error *err)
{
    df_store *st = srv->store;
    uint8_t b[DF_CODEC_BRUSH_BYTES];
    df_codec_brush_pack(next, b);
    uint64_t version = atomic_load(&s->version);
    const void *p[8] = {NULL, NULL, NULL, NULL, NULL, b};
    int64_t v[8] = {(int64_t)s->id, (int64_t)version, DF_MSG_BRUSH_STATE_SET, (int64_t)who,
                    DF_JOURNAL_BRUSH, DF_CODEC_BRUSH_BYTES};
    int rc = begin(st, err);
    if (rc != DF_OK) return rc;
    rc = run(st, "INSERT INTO changes(session, version, kind, who, flags, aux)"
             " VALUES(?,?,?,?,?,?)", "iiiiib", p, v, "appending the brush change", err);
    rc = finish(st, rc, err); /* the session row takes the brush at the next snapshot */
    count(srv, rc, DF_CODEC_BRUSH_BYTES);
    return rc;
}

const df_store_ops df_store_journal_ops = {.session_created = session_created,
                                           .session_closing = session_closing,
                                           .change = change,
                                           .brush = brush};
