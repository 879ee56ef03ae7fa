/* journal.c — the store's writes: session rows and the change log (see journal.h). */
#include "server/store/journal.h"

#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>

#include "server/log.h"
#include "server/net/req.h"
#include "server/session/commit.h"
#include "server/session/session.h"
#include "server/session/stroke_recipe.h"
#include "server/store/codec.h"
#include "server/store/record.h"
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

/* The store's and the server's counters after a change-log write (recipe: a recipe record). */
static void count(df_server *srv, int rc, uint64_t bytes, int recipe)
{
    if (rc != DF_OK) {
        srv->stats.store_errors++;
        return;
    }
    df_store_count_change(srv->store, bytes);
    srv->stats.store_changes++;
    srv->stats.store_log_bytes += bytes;
    if (recipe) srv->stats.store_recipe_records++;
}

/* Session id's large value `name` (store.h: blobs) becomes `len` bytes at p (NULL: none). */
static int put_blob(df_store *st, uint64_t id, const char *name, const void *p, size_t len,
                    const char *what, df_error *err)
{
    if (!p) {
        const void *pp[2] = {NULL, name};
        int64_t v[2] = {(int64_t)id};
        return run(st, "DELETE FROM blobs WHERE session = ? AND name = ?", "it", pp, v, what, err);
    }
    const void *pp[3] = {NULL, name, p};
    int64_t v[3] = {(int64_t)id, 0, (int64_t)len};
    return run(st, "INSERT OR REPLACE INTO blobs(session, name, data) VALUES(?,?,?)", "itb", pp, v,
               what, err);
}

/* The session's access row (store.h) holding owner s->owner and policy `acc`. */
static int write_access(df_store *st, const df_session *s, const df_membership *acc,
                        df_error *err)
{
    char *members = NULL;
    int rc = df_membership_members_join(acc, &members, err);
    if (rc != DF_OK) return rc;
    const void *p[6] = {NULL, s->owner, NULL, NULL, acc->key_hash, members};
    int64_t v[6] = {(int64_t)s->id, 0, acc->mode, acc->observers, DF_JOIN_HASH_BYTES, 0};
    char types[] = "itiibt";
    if (!acc->has_key) types[4] = 'n';
    rc = run(st, "INSERT OR REPLACE INTO access(session, owner, mode, observers, key_hash,"
             " members) VALUES(?,?,?,?,?,?)", types, p, v, "saving the session's access", err);
    free(members);
    return rc;
}

static int access_saved(df_server *srv, const df_session *s, const df_membership *next,
                        df_error *err)
{
    df_store *st = srv->store;
    int rc = begin(st, err);
    if (rc != DF_OK) return rc;
    rc = finish(st, write_access(st, s, next, err), err);
    if (rc != DF_OK) srv->stats.store_errors++;
    return rc;
}

static int session_created(df_server *srv, const df_session *s, df_error *err)
{
    df_store *st = srv->store;
    const df_mesh *m = &s->mesh;
    size_t es = (size_t)df_mesh_elem_size(m->kind);
    uint8_t brush[DF_CODEC_BRUSH_BYTES];
    df_codec_brush_pack(&s->brush, brush);
    const void *p[10] = {NULL, s->name, NULL, NULL, NULL, NULL, NULL, NULL, brush};
    int64_t v[10] = {(int64_t)s->id, 0, m->kind, m->planar, m->nv, m->ne, m->nf,
                     (int64_t)atomic_load(&s->version), DF_CODEC_BRUSH_BYTES,
                     (int64_t)s->brush_seq};
    int rc = begin(st, err);
    if (rc != DF_OK) return rc;
    rc = run(st, "INSERT INTO sessions(id, name, kind, planar, nv, ne, nf, version, brush,"
             " brush_seq) VALUES(?,?,?,?,?,?,?,?,?,?)", "itiiiiiibi", p, v,
             "saving the new session", err);
    if (rc == DF_OK)
        rc = put_blob(st, s->id, "base", m->V, 24 * (size_t)m->nv, "saving the mesh", err);
    if (rc == DF_OK && m->E && m->ne)
        rc = put_blob(st, s->id, "elems", m->E, 4 * es * (size_t)m->ne, "saving the mesh", err);
    if (rc == DF_OK && m->F && m->nf)
        rc = put_blob(st, s->id, "faces", m->F, 12 * (size_t)m->nf, "saving the mesh", err);
    if (rc == DF_OK) {
        int64_t id[1] = {(int64_t)s->id};
        rc = run(st, "UPDATE meta SET value = max(value, ?) WHERE key = 'next_session_id'", "i",
                 NULL, id, "saving the session id", err);
    }
    if (rc == DF_OK) rc = write_access(st, s, &s->acc, err);
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
        rc = run(st, "DELETE FROM blobs WHERE session = ?", "i", NULL, id,
                 "deleting the session's mesh", err);
    if (rc == DF_OK)
        rc = run(st, "DELETE FROM access WHERE session = ?", "i", NULL, id,
                 "deleting the session's access", err);
    if (rc == DF_OK)
        rc = run(st, "DELETE FROM sessions WHERE id = ?", "i", NULL, id, "deleting the session",
                 err);
    return finish(st, rc, err);
}

int df_journal_write_snapshot(df_store *st, const df_session *s, const double *cur,
                              const double *rest, uint64_t version, df_error *err)
{
    size_t pb = 24 * (size_t)s->nv;
    if (!memcmp(rest, s->mesh.V, pb)) rest = NULL; /* still the base: none kept */
    int rc = put_blob(st, s->id, "cur", cur, pb, "writing a snapshot", err);
    if (rc == DF_OK) rc = put_blob(st, s->id, "rest", rest, pb, "writing a snapshot", err);
    int64_t v[2] = {(int64_t)version, (int64_t)s->id};
    if (rc == DF_OK)
        rc = run(st, "UPDATE sessions SET snap_version = ?, log_bytes = 0, replay_ns = 0 WHERE"
                 " id = ?", "ii", NULL, v, "writing a snapshot", err);
    if (rc == DF_OK)
        rc = run(st, "DELETE FROM changes WHERE session = ?", "i", NULL, v + 1,
                 "trimming the log after a snapshot", err);
    return rc;
}

/* The session row's log state since its last snapshot, read in the change's transaction. */
typedef struct log_state {
    int64_t bytes;          /* blob bytes logged */
    int64_t replay_ns;      /* estimated replay time of its recipe records */
    int64_t snap_version;   /* the snapshot's version */
    int prev_recipe;        /* the session's last row is a recipe brush version ... */
    uint64_t prev_version, prev_base, prev_ns; /* ... of this version, base and cost */
} log_state;

/* The estimated restore time of a recipe record whose field took field_ns live on an nv-vertex
 * session: the field again plus the per-vertex work around it (store.h). */
static uint64_t restore_cost(uint64_t field_ns, int32_t nv)
{
    return field_ns + DF_STORE_REPLAY_VERTEX_NS * (uint64_t)nv;
}

static int read_log_state(df_store *st, uint64_t id, int32_t s_nv, log_state *ls,
                          df_error *err)
{
    memset(ls, 0, sizeof *ls);
    sqlite3 *db = df_store_db(st);
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(db, "SELECT log_bytes, replay_ns, snap_version FROM sessions WHERE"
                           " id = ?", -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, "reading the log size", err);
    sqlite3_bind_int64(q, 1, (sqlite3_int64)id);
    if (sqlite3_step(q) == SQLITE_ROW) {
        ls->bytes = sqlite3_column_int64(q, 0);
        ls->replay_ns = sqlite3_column_int64(q, 1);
        ls->snap_version = sqlite3_column_int64(q, 2);
    }
    sqlite3_finalize(q);
    if (sqlite3_prepare_v2(db, "SELECT version, flags, recipe FROM changes WHERE session = ?"
                           " ORDER BY id DESC LIMIT 1", -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, "reading the log's last row", err);
    sqlite3_bind_int64(q, 1, (sqlite3_int64)id);
    if (sqlite3_step(q) == SQLITE_ROW && (sqlite3_column_int(q, 1) & DF_JOURNAL_RECIPE)) {
        df_recipe_record r;
        df_error e;
        if (df_record_decode(sqlite3_column_blob(q, 2), (size_t)sqlite3_column_bytes(q, 2), &r,
                             &e) == DF_OK) {
            ls->prev_recipe = 1;
            ls->prev_version = (uint64_t)sqlite3_column_int64(q, 0);
            ls->prev_base = r.base_version;
            ls->prev_ns = restore_cost(r.replay_ns, s_nv);
        }
    }
    sqlite3_finalize(q);
    return DF_OK;
}

/* In the change's transaction: once the session's log since its last snapshot exceeds
 * max(snapshot_min, 2 x its position bytes), or replaying its recipe records would take longer
 * than the store's replay threshold, the positions and rest shape after this change become the
 * session row's snapshot (of `version`) and the log rows before it are deleted. */
/* Strokes still open after change c (a begin links one; an end or cancel drops its
 * requester's). */
static int strokes_left_open(const df_session *s, const df_change *c)
{
    int n = c->link != NULL;
    for (const df_stroke *x = s->strokes; x; x = x->next)
        n += !(c->drop_stroke && c->req && x->conn_id == df_req_origin(c->req));
    return n;
}

static int maybe_snapshot(df_store *st, const df_session *s, const df_change *c, uint64_t version,
                          uint64_t logged, uint64_t replay_ns, df_error *err)
{
    uint64_t pos_bytes = 24 * (uint64_t)s->nv, min = df_store_snapshot_min(st);
    uint64_t threshold = 2 * pos_bytes > min ? 2 * pos_bytes : min;
    uint64_t budget = df_store_snapshot_replay_ns(st);
    /* by replay cost: between strokes (a snapshot inside an open stroke would leave its later
     * versions without their base state: deltas), unless strokes stay open far too long */
    int by_cost = replay_ns > budget &&
                  (replay_ns > DF_STORE_SNAPSHOT_REPLAY_FORCE * budget ||
                   strokes_left_open(s, c) == 0);
    if (logged <= threshold && !by_cost) return DF_OK;
    const double *cur = c->pos ? c->pos : s->cur;
    return df_journal_write_snapshot(st, s, cur, c->rest_from_cur ? cur : s->rest, version, err);
}

/* The stroke whose recipe change `c` may be logged as: the stroke a brush version publishes,
 * or (*ending = 1) the stroke a BRUSH_END commits; NULL for any other change. */
static const df_stroke *change_stroke(const df_session *s, const df_change *c, int *ending)
{
    *ending = 0;
    if (c->pos && c->set_recipe) return c->link ? c->link : c->stroke;
    if (c->hist != DF_HIST_COMMIT || c->pos || !c->drop_stroke || !c->req ||
        c->req->type != DF_MSG_BRUSH_END)
        return NULL;
    uint64_t origin = df_req_origin(c->req);
    for (const df_stroke *x = s->strokes; x; x = x->next)
        if (x->conn_id == origin) {
            *ending = 1;
            return x;
        }
    return NULL;
}

/* The recipe record of change `c` (record.h) into a new blob *out, or *out = NULL when the
 * change is not one (journal.h: a brush version whose stroke is replayable from a version the
 * log can rebuild, or the end of such a stroke right after its last publish). *flags gets
 * DF_JOURNAL_RECIPE for a brush version; *ns its replay cost estimate. */
static int recipe_record(const df_session *s, const df_change *c, const log_state *ls,
                         uint8_t **out, size_t *len, int *flags, uint64_t *ns, df_error *err)
{
    *out = NULL;
    *len = 0;
    *ns = 0;
    int ending;
    const df_stroke *st = change_stroke(s, c, &ending);
    if (!st || st->base_version < (uint64_t)ls->snap_version) return DF_OK;
    df_stroke_recipe r = {.n_pins = st->n_pins, .pin_flags = st->pin_flags, .pins = st->pins};
    df_recipe_record rec = {.base_version = st->base_version};
    if (!ending) {
        if (!c->recipe_replayable || c->base || st->rebased) return DF_OK;
        r.brush = c->recipe_brush;
        r.strength = c->recipe_strength;
        memcpy(r.load, c->recipe_load, sizeof r.load);
        rec.checksum = df_positions_checksum(c->pos, 3 * (size_t)s->nv);
        rec.replay_ns = c->set_work_ns ? c->work_ns : st->work_ns;
        *flags |= DF_JOURNAL_RECIPE;
    } else {
        if (!st->last_replayable || st->rebased || st->last_version != atomic_load(&s->version))
            return DF_OK;
        r.brush = st->last_brush;
        r.strength = st->last_strength;
        memcpy(r.load, st->last_load, sizeof r.load);
        rec.checksum = df_positions_checksum(s->cur, 3 * (size_t)s->nv);
        rec.replay_ns = st->work_ns;
    }
    uint8_t *blob;
    size_t blen;
    int rc = df_stroke_recipe_encode(&r, &blob, &blen, err);
    if (rc != DF_OK) return rc;
    rec.recipe = blob;
    rec.recipe_len = blen;
    rc = df_record_encode(&rec, out, len, err);
    free(blob);
    if (rc == DF_OK) *ns = restore_cost(rec.replay_ns, s->nv);
    return rc;
}

static int change(df_server *srv, const df_session *s, const df_change *c, df_error *err)
{
    if (!c->pos && !c->version && !c->rest_from_cur && !c->hs && !c->hist)
        return DF_OK; /* nothing kept */
    df_store *st = srv->store;
    uint8_t *delta = NULL, *hs = NULL, *rec = NULL;
    size_t dlen = 0, hlen = 0, rlen = 0;
    uint64_t version = c->version ? c->version : atomic_load(&s->version), ns = 0;
    int flags = (c->rest_from_cur ? DF_JOURNAL_REST_FROM_CUR : 0) |
                ((c->hist & 7) << DF_JOURNAL_HIST_SHIFT);
    log_state ls;
    int rc = begin(st, err);
    if (rc != DF_OK) {
        count(srv, rc, 0, 0);
        return rc;
    }
    rc = read_log_state(st, s->id, s->nv, &ls, err);
    if (rc == DF_OK) rc = recipe_record(s, c, &ls, &rec, &rlen, &flags, &ns, err);
    if (rc == DF_OK && c->pos && !(flags & DF_JOURNAL_RECIPE))
        rc = df_codec_delta_encode(s->cur, c->pos, s->nv, &delta, &dlen, err);
    if (rc == DF_OK && c->hs) rc = df_codec_handles_encode(c->hs, &hs, &hlen, err);
    if (hs) flags |= DF_JOURNAL_HANDLES;
    /* a stroke's end whose undo step was a RECIPE live (history.h): the restore commits it
     * with the record's recipe, one more replay; any other end replays nothing */
    if (rec && !(flags & DF_JOURNAL_RECIPE)) {
        if (c->hplan.valid && !c->hplan.nochange && c->hplan.step.kind == DF_HISTORY_RECIPE)
            flags |= DF_JOURNAL_HIST_RECIPE;
        else
            ns = 0;
    }
    /* a brush version right after the previous one of the same stroke supersedes it: the
     * restore does not replay that one (restore.h), so its cost no longer counts */
    if ((flags & DF_JOURNAL_RECIPE) && ls.prev_recipe && ls.prev_version + 1 == version &&
        rec) {
        df_recipe_record r;
        if (df_record_decode(rec, rlen, &r, NULL) == DF_OK && r.base_version == ls.prev_base)
            ls.replay_ns -= ls.prev_ns <= (uint64_t)ls.replay_ns ? (int64_t)ls.prev_ns
                                                                 : ls.replay_ns;
    }
    if (rc == DF_OK) {
        const void *p[8] = {NULL, NULL, NULL, NULL, NULL, delta, hs, rec};
        int64_t v[8] = {(int64_t)s->id, (int64_t)version, c->req ? c->req->type : 0,
                        c->req ? (int64_t)df_req_origin(c->req) : 0, flags, (int64_t)dlen,
                        (int64_t)hlen, (int64_t)rlen};
        char types[] = "iiiiibbb";
        if (!delta) types[5] = 'n';
        if (!hs) types[6] = 'n';
        if (!rec) types[7] = 'n';
        rc = run(st, "INSERT INTO changes(session, version, kind, who, flags, delta, aux, recipe)"
                 " VALUES(?,?,?,?,?,?,?,?)", types, p, v, "appending the change", err);
    }
    uint64_t logged = (uint64_t)ls.bytes + dlen + hlen + rlen;
    uint64_t replay = (uint64_t)ls.replay_ns + ns;
    if (rc == DF_OK) {
        int64_t v2[4] = {(int64_t)version, (int64_t)logged, (int64_t)replay, (int64_t)s->id};
        rc = run(st, "UPDATE sessions SET version = ?, log_bytes = ?, replay_ns = ? WHERE id = ?",
                 "iiii", NULL, v2, "saving the version", err);
    }
    if (rc == DF_OK && hs)
        rc = put_blob(st, s->id, "handles", hs, hlen, "saving the handle set", err);
    if (rc == DF_OK) rc = maybe_snapshot(st, s, c, version, logged, replay, err);
    rc = finish(st, rc, err);
    count(srv, rc, dlen + hlen + rlen, rec != NULL);
    free(delta);
    free(hs);
    free(rec);
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
    if (rc == DF_OK) {
        const void *p2[3] = {b};
        int64_t v2[3] = {DF_CODEC_BRUSH_BYTES, (int64_t)s->id};
        rc = run(st, "UPDATE sessions SET brush = ?, brush_seq = brush_seq + 1 WHERE id = ?",
                 "bi", p2, v2, "saving the brush", err);
    }
    rc = finish(st, rc, err);
    count(srv, rc, DF_CODEC_BRUSH_BYTES, 0);
    return rc;
}

const df_store_ops df_store_journal_ops = {.session_created = session_created,
                                           .session_closing = session_closing,
                                           .change = change,
                                           .brush = brush,
                                           .access = access_saved};
