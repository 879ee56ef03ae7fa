/* Unit tests for server/store/journal.c, codec.c and restore.c: a session's creation, its
 * committed changes (sparse deltas, rest shape, handle set), its brush and its close are written
 * before they take effect; a store write error (read-only store, full store) fails the change and
 * leaves the session as it was; a new df_server on the same store restores every session with
 * its id, name, version, brush, handle set and bit-identical positions and rest shape, and gives
 * new sessions new ids. The blob codecs round-trip and refuse malformed blobs. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <sqlite3.h>

#include "tests/unit/server/tiny_mesh.h"
#include "server/session/commit.h"
#include "server/session/session.h"
#include "server/store/codec.h"
#include "server/store/restore.h"
#include "server/store/store.h"
#include "tests/unit/server/store_rig.h"

/* Commits `pos` (owned copy) as version `version` with the given extras; returns the rc. */
static int commit(df_session *s, const double *pos, uint64_t version, int rest_from_cur,
                  df_handleset *hs, df_req *r, df_error *e)
{
    df_change c;
    df_change_init(&c, r, e);
    if (pos) {
        c.own_buffers = 1;
        c.pos = malloc(3 * (size_t)s->nv * sizeof(double));
        c.uf = malloc(3 * (size_t)s->nv * sizeof(float));
        memcpy(c.pos, pos, 3 * (size_t)s->nv * sizeof(double));
        for (int i = 0; i < 3 * s->nv; i++) c.uf[i] = (float)(pos[i] - s->mesh.V[i]);
    }
    c.version = version;
    c.rest_from_cur = rest_from_cur;
    c.hs = hs;
    c.hist = pos ? DF_HIST_COMMIT : DF_HIST_NONE;
    if (r && r->type == DF_MSG_UNDO) c.hist = DF_HIST_UNDO;
    int rc = df_session_commit(s, &c);
    df_change_clear(s->srv, &c);
    return rc;
}

static df_handleset *handles(int32_t a, int32_t b)
{
    df_handleset *hs = calloc(1, sizeof *hs);
    assert_non_null(hs);
    df_admm_params_default(&hs->params, DF_ADMM_ARAP);
    hs->params.w = 0.123456789;
    hs->nh = 2;
    hs->handles = malloc(2 * sizeof(int32_t));
    hs->handles[0] = a;
    hs->handles[1] = b;
    hs->max_iters = 77;
    return hs;
}

static void test_journal_and_restore(void **state)
{
    (void)state;
    static df_server srv, srv2;
    server_open(&srv, "j.db");
    df_mesh m = tiny_mesh();
    df_session *s;
    df_error e;
    assert_int_equal(df_session_create(&srv, &m, "alpha", &s, &e), DF_OK);
    uint64_t id = s->id;
    assert_int_equal(query(&srv, "SELECT count(*) FROM sessions"), 1);
    assert_int_equal(query(&srv, "SELECT value FROM meta"), (int64_t)id);

    /* a sparse change: vertex 1 only, by an amount that is not a short decimal */
    double pos[9];
    memcpy(pos, s->cur, sizeof pos);
    pos[3] += 1.0 / 3.0;
    pos[5] = -1e-300;
    df_req r = {.srv = &srv, .type = DF_MSG_BRUSH_UPDATE, .id = 1, .origin_id = 42};
    assert_int_equal(commit(s, pos, 1, 0, NULL, &r, &e), DF_OK);
    assert_int_equal(query(&srv, "SELECT length(delta) FROM changes"), 8 + 4 + 24);
    assert_int_equal(query(&srv, "SELECT who FROM changes"), 42);
    assert_int_equal(query(&srv, "SELECT kind FROM changes"), DF_MSG_BRUSH_UPDATE);
    assert_int_equal(query(&srv, "SELECT version FROM sessions"), 1);
    double cur1[9];
    memcpy(cur1, s->cur, sizeof cur1);

    /* a dense change (every vertex), then the rest shape from it and a handle set */
    for (int i = 0; i < 9; i++) pos[i] = pos[i] * 1.0000001 + 1e-7;
    df_req r2 = {.srv = &srv, .type = DF_MSG_RESET_REST, .id = 2};
    assert_int_equal(commit(s, pos, 2, 1, handles(0, 2), &r2, &e), DF_OK);
    assert_int_equal(query(&srv, "SELECT length(delta) FROM changes ORDER BY id DESC"), 8 + 72);
    df_brush_state b = s->brush;
    b.radius = 0.7071067811865476;
    assert_int_equal(df_brush_state_apply(s, DF_BS_RADIUS, &b, NULL, &e), DF_OK);
    assert_int_equal(query(&srv, "SELECT brush_seq FROM sessions"), 1);

    /* store errors: the change fails, nothing of it is applied or kept */
    double cur0[9], rest0[9];
    memcpy(cur0, s->cur, sizeof cur0);
    memcpy(rest0, s->rest, sizeof rest0);
    int64_t rows = query(&srv, "SELECT count(*) FROM changes");
    assert_int_equal(sqlite3_exec(df_store_db(srv.store), "PRAGMA query_only=1", NULL, NULL,
                                  NULL), SQLITE_OK);
    double pos3[9];
    for (int i = 0; i < 9; i++) pos3[i] = pos[i] + 5;
    df_req r3 = {.srv = &srv, .type = DF_MSG_BRUSH_UPDATE, .id = 3};
    assert_int_equal(commit(s, pos3, 3, 0, NULL, &r3, &e), DF_EIO);
    assert_non_null(strstr(e.msg, srv.cfg.store_path));
    assert_int_equal(r3.answered, 1);
    assert_int_equal(atomic_load(&s->version), 2);
    assert_memory_equal(s->cur, cur0, sizeof cur0);
    b.radius = 9;
    assert_int_equal(df_brush_state_apply(s, DF_BS_RADIUS, &b, NULL, &e), DF_EIO);
    assert_true(s->brush.radius == 0.7071067811865476);
    assert_int_equal(s->brush_seq, 1);
    /* a second session cannot be created in a read-only store */
    df_mesh m2 = tiny_mesh();
    df_session *s2;
    assert_int_equal(df_session_create(&srv, &m2, "beta", &s2, &e), DF_EIO);
    assert_int_equal(srv.n_sessions, 1);
    assert_int_equal(sqlite3_exec(df_store_db(srv.store), "PRAGMA query_only=0", NULL, NULL,
                                  NULL), SQLITE_OK);
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes"), rows);

    /* a full store (a disk full simulated by max_page_count): DF_ELIMIT, nothing changes */
    int64_t pages = query(&srv, "PRAGMA page_count");
    char sql[64];
    snprintf(sql, sizeof sql, "PRAGMA max_page_count=%lld", (long long)pages);
    assert_int_equal(sqlite3_exec(df_store_db(srv.store), sql, NULL, NULL, NULL), SQLITE_OK);
    df_mesh big = tiny_mesh();
    double *V = realloc(big.V, 3 * 20000 * sizeof(double));
    assert_non_null(V);
    for (int i = 9; i < 60000; i++) V[i] = i * 1e-3;
    big.V = V;
    big.nv = 20000;
    assert_int_equal(df_session_create(&srv, &big, "big", &s2, &e), DF_ELIMIT);
    assert_non_null(strstr(e.msg, "full"));
    assert_int_equal(srv.n_sessions, 1);
    assert_int_equal(query(&srv, "SELECT count(*) FROM sessions"), 1);
    assert_int_equal(sqlite3_exec(df_store_db(srv.store), "PRAGMA max_page_count=1000000", NULL,
                                  NULL, NULL), SQLITE_OK);
    server_close(&srv);

    /* restart: the session as it was acknowledged, bit for bit */
    server_open(&srv2, "j.db");
    assert_int_equal(srv2.n_sessions, 1);
    s = df_session_find(&srv2, id);
    assert_non_null(s);
    assert_string_equal(s->name, "alpha");
    assert_int_equal(atomic_load(&s->version), 2);
    assert_memory_equal(s->cur, cur0, sizeof cur0);
    assert_memory_equal(s->rest, rest0, sizeof rest0);
    assert_memory_equal(s->rest, cur0, sizeof cur0); /* reset-rest took the positions */
    for (int i = 0; i < 9; i++) assert_true(s->uf[i] == (float)(cur0[i] - s->mesh.V[i]));
    assert_true(s->brush.radius == 0.7071067811865476);
    assert_int_equal(s->brush_seq, 1);
    assert_non_null(s->hs);
    assert_int_equal(s->hs->nh, 2);
    assert_int_equal(s->hs->handles[1], 2);
    assert_int_equal(s->hs->max_iters, 77);
    assert_true(s->hs->params.w == 0.123456789);
    assert_null(s->hs->solver); /* rebuilt on first use */
    /* the undo history, rebuilt from the rows' history steps: base -> cur1 -> cur0 */
    assert_int_equal(df_history_can_undo(&s->hist), 2);
    assert_int_equal(df_history_can_redo(&s->hist), 0);
    double back[9];
    assert_int_equal(df_history_peek(&s->hist, -1, back, &e), DF_OK);
    assert_memory_equal(back, cur1, sizeof back);
    df_mesh m3 = tiny_mesh();
    df_session *s3;
    assert_int_equal(df_session_create(&srv2, &m3, "gamma", &s3, &e), DF_OK);
    assert_true(s3->id > id);
    /* closing deletes the session and its log */
    assert_int_equal(srv2.store_ops->session_closing(&srv2, s, &e), DF_OK);
    assert_int_equal(query(&srv2, "SELECT count(*) FROM changes WHERE session = 1"), 0);
    uint64_t id3 = s3->id;
    server_close(&srv2);
    server_open(&srv2, "j.db");
    assert_int_equal(srv2.n_sessions, 1);
    assert_non_null(df_session_find(&srv2, id3));
    server_close(&srv2);
}

/* Snapshots: with the threshold at its floor (2 x 24 x nv = 144 bytes for 3 vertices) the log
 * is folded into the session row every few changes; the restore starts from the snapshot and
 * still ends bit-identical, rest shape included. */
static void test_snapshots(void **state)
{
    (void)state;
    static df_server srv, srv2;
    server_open(&srv, "snap.db");
    df_store_set_snapshot_min(srv.store, 1);
    df_mesh m = tiny_mesh();
    df_session *s;
    df_error e;
    assert_int_equal(df_session_create(&srv, &m, "snap", &s, &e), DF_OK);
    double pos[9];
    int64_t max_rows = 0;
    for (int k = 1; k <= 20; k++) {
        memcpy(pos, s->cur, sizeof pos);
        pos[k % 9] += 1.0 / (k + 2);            /* one vertex: 8 + 4 + 24 bytes */
        if (k % 4 == 0) pos[0] -= 1.0 / 7;
        df_req r = {.srv = &srv, .type = DF_MSG_BRUSH_UPDATE, .id = (uint64_t)k};
        assert_int_equal(commit(s, pos, (uint64_t)k, k == 7, NULL, &r, &e), DF_OK);
        int64_t rows = query(&srv, "SELECT count(*) FROM changes");
        if (rows > max_rows) max_rows = rows;
    }
    assert_true(max_rows <= 5);                /* 144 / 36: trimmed after at most 5 rows */
    assert_int_equal(query(&srv, "SELECT length(data) FROM blobs WHERE name = 'cur'"), 72);
    assert_int_equal(query(&srv, "SELECT length(data) FROM blobs WHERE name = 'rest'"), 72); /* reset at k = 7 */
    double cur[9], rest[9];
    memcpy(cur, s->cur, sizeof cur);
    memcpy(rest, s->rest, sizeof rest);
    assert_memory_not_equal(rest, s->mesh.V, sizeof rest); /* reset at k = 7 */
    uint64_t id = s->id;
    server_close(&srv);
    server_open(&srv2, "snap.db");
    s = df_session_find(&srv2, id);
    assert_non_null(s);
    assert_int_equal(atomic_load(&s->version), 20);
    assert_memory_equal(s->cur, cur, sizeof cur);
    assert_memory_equal(s->rest, rest, sizeof rest);
    server_close(&srv2);
}

/* An undo whose step predates the last snapshot (the snapshot folded in the change it reverts):
 * the restored history restarts at the undo's positions, so a later step's undo goes back to
 * them as it did live (found by tests/integration/test_crash.py). One-vertex rows are 36 bytes,
 * the snapshot threshold 144 (3 vertices): P1..P4 are logged, P5 folds them into a snapshot,
 * then an undo (back to P4) and P6 are logged; live and restored, undo from P6 gives P4. */
static void test_undo_across_a_snapshot(void **state)
{
    (void)state;
    static df_server srv, srv2;
    server_open(&srv, "undo.db");
    df_store_set_snapshot_min(srv.store, 1);
    df_mesh m = tiny_mesh();
    df_session *s;
    df_error e;
    assert_int_equal(df_session_create(&srv, &m, "undo", &s, &e), DF_OK);
    double pos[9], p4[9], p6[9];
    for (int k = 1; k <= 5; k++) {
        memcpy(pos, s->cur, sizeof pos);
        pos[k] += 0.25 * k;
        if (k == 4) memcpy(p4, pos, sizeof p4);
        df_req r = {.srv = &srv, .type = DF_MSG_BRUSH_UPDATE, .id = (uint64_t)k};
        assert_int_equal(commit(s, pos, (uint64_t)k, 0, NULL, &r, &e), DF_OK);
    }
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes"), 0); /* P5: a snapshot */
    df_req u = {.srv = &srv, .type = DF_MSG_UNDO, .id = 6};
    assert_int_equal(commit(s, p4, 6, 0, NULL, &u, &e), DF_OK);
    assert_memory_equal(s->cur, p4, sizeof p4);
    memcpy(p6, p4, sizeof p6);
    p6[8] -= 0.5;
    df_req r6 = {.srv = &srv, .type = DF_MSG_BRUSH_UPDATE, .id = 7};
    assert_int_equal(commit(s, p6, 7, 0, NULL, &r6, &e), DF_OK);
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes"), 2);
    double live[9];
    assert_int_equal(df_history_peek(&s->hist, -1, live, &e), DF_OK);
    assert_memory_equal(live, p4, sizeof live);
    uint64_t id = s->id;
    server_close(&srv);
    server_open(&srv2, "undo.db");
    s = df_session_find(&srv2, id);
    assert_non_null(s);
    assert_memory_equal(s->cur, p6, sizeof p6);
    double back[9];
    assert_int_equal(df_history_peek(&s->hist, -1, back, &e), DF_OK);
    assert_memory_equal(back, p4, sizeof back);
    server_close(&srv2);
}

/* A session row that cannot be restored (its base blob cut short, a delta of another mesh)
 * refuses the start with a message naming the store and the session; nothing stays restored. */
static void test_bad_rows_refuse_start(void **state)
{
    (void)state;
    static df_server srv;
    server_open(&srv, "bad.db");
    df_mesh m = tiny_mesh();
    df_session *s;
    df_error e;
    assert_int_equal(df_session_create(&srv, &m, "ok", &s, &e), DF_OK);
    m = tiny_mesh();
    assert_int_equal(df_session_create(&srv, &m, "cut", &s, &e), DF_OK);
    uint64_t id = s->id;
    char sql[160];
    snprintf(sql, sizeof sql, "UPDATE blobs SET data = substr(data, 1, 40) WHERE session = %llu"
             " AND name = 'base'", (unsigned long long)id);
    assert_int_equal(df_store_exec(srv.store, sql, "test", &e), DF_OK);
    server_close(&srv);
    memset(&srv, 0, sizeof srv);
    df_config_defaults(&srv.cfg, NULL);
    snprintf(srv.cfg.store_path, sizeof srv.cfg.store_path, "%s/bad.db", g_dir);
    assert_int_equal(df_store_start(&srv, &e), DF_EFORMAT);
    char want[64];
    snprintf(want, sizeof want, "session %llu 'cut'", (unsigned long long)id);
    if (!strstr(e.msg, want) || !strstr(e.msg, srv.cfg.store_path))
        fail_msg("message '%s' lacks '%s' or the path", e.msg, want);
    assert_non_null(strstr(e.msg, "base of 40 bytes, 72 expected"));
    assert_null(srv.sessions);
    assert_null(srv.store);
    assert_null(srv.store_ops);
}

static void test_codecs(void **state)
{
    (void)state;
    double a[12] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, b[12];
    memcpy(b, a, sizeof a);
    b[4] = -0.0; /* +0 vs -0 differ bit-wise: kept */
    b[7] = 4.0;
    uint8_t *d;
    size_t len;
    df_error e;
    assert_int_equal(df_codec_delta_encode(a, b, 4, &d, &len, &e), DF_OK);
    assert_int_equal(len, 8 + 2 * 4 + 2 * 24);
    double c[12];
    memcpy(c, a, sizeof a);
    uint32_t n;
    assert_int_equal(df_codec_delta_apply(d, len, c, 4, &n, &e), DF_OK);
    assert_int_equal(n, 2);
    assert_memory_equal(c, b, sizeof b);
    assert_int_equal(df_codec_delta_apply(d, len, c, 5, &n, &e), DF_EFORMAT); /* wrong nv */
    assert_int_equal(df_codec_delta_apply(d, len - 1, c, 4, &n, &e), DF_EFORMAT);
    uint32_t bad = 9;
    memcpy(d + 8, &bad, 4); /* index out of range */
    assert_int_equal(df_codec_delta_apply(d, len, c, 4, &n, &e), DF_EFORMAT);
    assert_memory_equal(c, b, sizeof b); /* refused before writing */
    free(d);

    df_handleset *hs = handles(3, 1);
    hs->n_affine = 1;
    hs->affine = calloc(1, sizeof *hs->affine);
    int32_t *v = malloc(2 * sizeof(int32_t));
    v[0] = 0;
    v[1] = 2;
    hs->affine[0] = (df_admm_affine){.n = 2, .verts = v, .m = 1, .A = {0, 0, 1}, .b = {0.25}};
    assert_int_equal(df_codec_handles_encode(hs, &d, &len, &e), DF_OK);
    df_handleset *back;
    assert_int_equal(df_codec_handles_decode(d, len, 4, &back, &e), DF_OK);
    assert_int_equal(back->nh, 2);
    assert_int_equal(back->handles[0], 3);
    assert_int_equal(back->n_affine, 1);
    assert_int_equal(back->affine[0].verts[1], 2);
    assert_true(back->affine[0].b[0] == 0.25);
    assert_memory_equal(&back->params, &hs->params, sizeof hs->params);
    df_handleset_free(NULL, back);
    assert_int_equal(df_codec_handles_decode(d, len, 3, &back, &e), DF_EFORMAT); /* index 3 */
    assert_int_equal(df_codec_handles_decode(d, len - 1, 4, &back, &e), DF_EFORMAT);
    free(d);
    df_handleset_free(NULL, hs);

    df_brush_state bs, bs2;
    df_brush_state_defaults(&bs);
    bs.nu = -0.25;
    uint8_t p[DF_CODEC_BRUSH_BYTES];
    df_codec_brush_pack(&bs, p);
    assert_int_equal(df_codec_brush_unpack(p, sizeof p, &bs2, &e), DF_OK);
    assert_true(bs2.nu == -0.25 && bs2.type == bs.type && bs2.steps == bs.steps);
    assert_true(bs2.mirror_normal[0] == bs.mirror_normal[0]);
    assert_int_equal(df_codec_brush_unpack(p, sizeof p - 1, &bs2, &e), DF_EFORMAT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_journal_and_restore),
        cmocka_unit_test(test_snapshots),
        cmocka_unit_test(test_undo_across_a_snapshot),
        cmocka_unit_test(test_bad_rows_refuse_start),
        cmocka_unit_test(test_codecs),
    };
    return cmocka_run_group_tests(tests, rig_setup, rig_teardown);
}
