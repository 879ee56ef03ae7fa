/* Unit tests for the store's recipe records (server/store/record.h, journal.h, replay.h):
 * brush versions of an unrebased stroke are logged as their recipe (no delta), a stroke's end
 * carries it too, everything else keeps a delta; the restore replays them from the kept base
 * states, skips the versions a later one of the same stroke supersedes, and is bit-identical
 * to the live session (positions, rest shape, version, undo states); a record whose replay
 * does not reproduce its checksum stops that session's restore at the last verified state,
 * counted, folded into a snapshot; the replay-cost estimate drives snapshots; the record's
 * byte layout round-trips and malformed records are refused. The strokes are driven through
 * df_session_commit with change records as h_brush.c fills them. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <sqlite3.h>

#include "server/session/commit.h"
#include "server/session/session.h"
#include "server/session/stroke_end.h"
#include "server/session/stroke_recipe.h"
#include "server/store/journal.h"
#include "server/store/record.h"
#include "server/store/restore.h"
#include "server/store/store.h"
#include "tests/unit/server/store_rig.h"

#define G 20 /* grid side: 400 vertices */
#define CONN 42

static df_session *grid_session(df_server *srv, const char *name)
{
    df_mesh m;
    memset(&m, 0, sizeof m);
    m.kind = DF_MESH_TRIANGLE;
    m.nv = G * G;
    m.ne = 2 * (G - 1) * (G - 1);
    m.V = malloc(3 * (size_t)m.nv * sizeof(double));
    m.E = malloc(3 * (size_t)m.ne * sizeof(int32_t));
    assert_true(m.V && m.E);
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            double *v = m.V + 3 * (j * G + i);
            v[0] = i / (double)(G - 1) + 1e-9 * j;
            v[1] = j / (double)(G - 1);
            v[2] = 0.01 * i * j / (double)(G * G);
        }
    int32_t *e = m.E;
    for (int j = 0; j + 1 < G; j++)
        for (int i = 0; i + 1 < G; i++) {
            int32_t a = j * G + i;
            *e++ = a, *e++ = a + 1, *e++ = a + G;
            *e++ = a + 1, *e++ = a + G + 1, *e++ = a + G;
        }
    df_session *s;
    df_error err;
    assert_int_equal(df_session_create(srv, &m, name, &s, &err), DF_OK);
    return s;
}

/* A grab recipe at vertex k with tip scale t (pins: 2 pinned points when pinned). */
static df_stroke_recipe recipe(const df_session *s, int k, double t, int pinned)
{
    df_stroke_recipe r;
    memset(&r, 0, sizeof r);
    df_kelvinlet_brush_defaults(&r.brush);
    r.brush.radius = 0.15;
    r.brush.nu = 0.45;
    memcpy(r.brush.centre, s->mesh.V + 3 * k, sizeof r.brush.centre);
    r.strength = 0.9;
    r.load[0] = 0.01 * t;
    r.load[2] = 0.03 * t;
    if (pinned) {
        r.n_pins = 2;
        r.pin_flags = DF_KELVINLET_PIN_DISPLACEMENT;
        r.pins = malloc(6 * sizeof(double));
        memcpy(r.pins, s->mesh.V + 3 * (k + 3), 3 * sizeof(double));
        memcpy(r.pins + 3, s->mesh.V + 3 * (k + 2 * G), 3 * sizeof(double));
    }
    return r;
}

/* Commits one brush version of the stroke (begin when st is NULL: a new stroke from s->cur)
 * as h_brush.c's stroke_publish fills the change: positions = the recipe's motion over the
 * stroke's base. replayable 0: a rebased publish (logged as a delta). Returns the stroke. */
static df_stroke *publish(df_session *s, df_stroke *st, const df_stroke_recipe *r,
                          int replayable, uint64_t work_ns)
{
    size_t n = 3 * (size_t)s->nv;
    df_change c;
    df_error e;
    df_req q = {.srv = s->srv, .type = st ? DF_MSG_BRUSH_UPDATE : DF_MSG_BRUSH_BEGIN, .id = 1,
                .origin_id = CONN};
    df_change_init(&c, &q, &e);
    if (!st) {
        st = calloc(1, sizeof *st);
        st->conn_id = CONN;
        st->base = malloc(n * sizeof(double));
        st->startf = malloc(n * sizeof(float));
        st->applied = calloc(n, sizeof(float));
        memcpy(st->base, s->cur, n * sizeof(double));
        for (size_t i = 0; i < n; i++) st->startf[i] = (float)s->cur[i];
        st->base_version = st->last_version = atomic_load(&s->version);
        st->brush = r->brush;
        st->strength = r->strength;
        st->n_pins = r->n_pins;
        st->pin_flags = r->pin_flags;
        if (r->n_pins) {
            st->pins = malloc(24 * (size_t)r->n_pins);
            memcpy(st->pins, r->pins, 24 * (size_t)r->n_pins);
        }
        st->work_ns = work_ns;
        c.link = st;
    } else {
        c.stroke = st;
        c.set_work_ns = 1;
        c.work_ns = work_ns;
    }
    c.own_buffers = 1;
    c.pos = malloc(n * sizeof(double));
    c.uf = malloc(n * sizeof(float));
    if (df_stroke_recipe_replay(r, st->base, s->nv, 0, 1, c.pos, &e) != DF_OK)
        fail_msg("replay: %s", e.msg);
    if (!replayable) c.pos[0] += 1e-6; /* what a rebase would make of it: not the recipe's */
    for (size_t i = 0; i < n; i++) c.uf[i] = (float)(c.pos[i] - s->mesh.V[i]);
    c.version = atomic_load(&s->version) + 1;
    c.set_recipe = 1;
    c.recipe_brush = r->brush;
    c.recipe_strength = r->strength;
    memcpy(c.recipe_load, r->load, sizeof c.recipe_load);
    c.recipe_replayable = replayable;
    if (!replayable) c.base = malloc(n * sizeof(double)), memcpy(c.base, st->base, n * 8);
    assert_int_equal(df_session_commit(s, &c), DF_OK);
    df_change_clear(s->srv, &c);
    return st;
}

/* BRUSH_END of the stroke: one undo step planned as h_brush.c's end_work does (a RECIPE step
 * when its last publish is replayable from the history's state), the stroke dropped. */
static void end(df_session *s)
{
    df_change c;
    df_error e;
    df_req q = {.srv = s->srv, .type = DF_MSG_BRUSH_END, .id = 2, .origin_id = CONN};
    df_change_init(&c, &q, &e);
    c.hist = DF_HIST_COMMIT;
    c.drop_stroke = 1;
    assert_non_null(s->strokes);
    assert_int_equal(df_stroke_end_plan(s, s->strokes, &c.hplan, &e), DF_OK);
    assert_int_equal(df_session_commit(s, &c), DF_OK);
    df_change_clear(s->srv, &c);
}

/* A whole stroke of `updates` versions (tip scale growing), ended. */
static void stroke(df_session *s, int k, int updates, int pinned, uint64_t work_ns)
{
    df_stroke *st = NULL;
    for (int u = 1; u <= updates; u++) {
        df_stroke_recipe r = recipe(s, k, u, pinned);
        st = publish(s, st, &r, 1, work_ns);
        df_stroke_recipe_free(&r);
    }
    end(s);
}

/* A handle-move-like change: every vertex shifted, one undo step (a delta row). */
static void move(df_session *s)
{
    size_t n = 3 * (size_t)s->nv;
    df_change c;
    df_error e;
    df_req q = {.srv = s->srv, .type = DF_MSG_HANDLES_MOVE, .id = 3, .origin_id = 7};
    df_change_init(&c, &q, &e);
    c.own_buffers = 1;
    c.pos = malloc(n * sizeof(double));
    c.uf = malloc(n * sizeof(float));
    for (size_t i = 0; i < n; i++) c.pos[i] = s->cur[i] + 1e-4 * (double)(i % 5);
    for (size_t i = 0; i < n; i++) c.uf[i] = (float)(c.pos[i] - s->mesh.V[i]);
    c.version = atomic_load(&s->version) + 1;
    c.hist = DF_HIST_COMMIT;
    assert_int_equal(df_session_commit(s, &c), DF_OK);
    df_change_clear(s->srv, &c);
}

/* The positions one undo away (a copy), or NULL when none. */
static double *undo_state(const df_session *s)
{
    double *p = malloc(3 * (size_t)s->nv * sizeof(double));
    df_error e;
    if (df_history_peek(&s->hist, -1, p, &e) != DF_OK) {
        free(p);
        return NULL;
    }
    return p;
}

static void test_records_and_restore(void **state)
{
    (void)state;
    static df_server srv, srv2;
    server_open(&srv, "r.db");
    df_session *s = grid_session(&srv, "grid");
    uint64_t id = s->id;
    size_t pb = 24 * (size_t)s->nv;
    stroke(s, 30, 3, 0, 1000);           /* versions 1-3 */
    move(s);                             /* 4: a delta */
    stroke(s, 210, 4, 1, 1000);          /* 5-8, pinned */
    {                                    /* 9-10: rebased after its first version: a delta */
        df_stroke_recipe r = recipe(s, 150, 1, 0);
        df_stroke *st = publish(s, NULL, &r, 1, 1000);
        df_stroke_recipe_free(&r);
        r = recipe(s, 150, 2, 0);
        publish(s, st, &r, 0, 1000);
        df_stroke_recipe_free(&r);
        end(s);
    }
    stroke(s, 333, 2, 0, 1000);          /* 11-12 */
    /* brush versions of unrebased strokes: recipes, no delta; ends of strokes right after
     * their last publish: the recipe without the flag; the rest: deltas */
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes WHERE flags & 8"), 3 + 4 + 1 + 2);
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes WHERE flags & 8 AND delta IS NOT"
                                 " NULL"), 0);
    char sql[160];
    snprintf(sql, sizeof sql, "SELECT count(*) FROM changes WHERE kind = %d AND recipe IS NOT "
             "NULL AND NOT flags & 8", DF_MSG_BRUSH_END);
    assert_int_equal(query(&srv, sql), 3);   /* not the rebased stroke's end */
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes WHERE delta IS NOT NULL"), 2);
    assert_int_equal(srv.stats.store_recipe_records, 3 + 4 + 1 + 2 + 3);
    /* a recipe record is a few hundred bytes, a pinned one 48 more */
    assert_int_equal(query(&srv, "SELECT length(recipe) FROM changes WHERE version = 1"),
                     DF_RECORD_HEADER + DF_STROKE_RECIPE_FIXED);
    assert_int_equal(query(&srv, "SELECT length(recipe) FROM changes WHERE version = 5"),
                     DF_RECORD_HEADER + DF_STROKE_RECIPE_FIXED + 48);
    double *cur = malloc(pb), *rest = malloc(pb), *u1 = undo_state(s);
    memcpy(cur, s->cur, pb);
    memcpy(rest, s->rest, pb);
    int depth = df_history_can_undo(&s->hist);
    int recipes = df_history_steps_of(&s->hist, DF_HISTORY_RECIPE);
    assert_int_equal(recipes, 3);         /* the unrebased strokes' ends */
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes WHERE flags & 128"), 3);
    uint64_t version = atomic_load(&s->version);
    assert_int_equal(version, 12);
    server_close(&srv);

    server_open(&srv2, "r.db");
    s = df_session_find(&srv2, id);
    assert_non_null(s);
    assert_int_equal(atomic_load(&s->version), version);
    assert_memory_equal(s->cur, cur, pb);
    assert_memory_equal(s->rest, rest, pb);
    assert_int_equal(df_history_can_undo(&s->hist), depth);
    assert_int_equal(df_history_steps_of(&s->hist, DF_HISTORY_RECIPE), recipes);
    double *r1 = undo_state(s);
    assert_non_null(r1);
    assert_memory_equal(r1, u1, pb);
    /* replayed: the last version of each unrebased stroke (its end reads it) and the rebased
     * stroke's first (its delta applies to it); superseded: the others */
    assert_int_equal(srv2.stats.store_recipes_replayed, 4);
    assert_int_equal(srv2.stats.store_recipes_skipped, (3 + 4 + 1 + 2) - 4);
    assert_int_equal(srv2.stats.store_replay_mismatches, 0);
    server_close(&srv2);
    free(cur);
    free(rest);
    free(u1);
    free(r1);
}

/* A recipe record whose checksum does not match its replay: the restore stops at the last
 * verified version (the state before that stroke), publishes it as a new version, counts it,
 * and folds it into a snapshot so that the next start restores the same. */
static void test_mismatch_stops_at_the_last_verified(void **state)
{
    (void)state;
    static df_server srv, srv2, srv3;
    server_open(&srv, "m.db");
    df_session *s = grid_session(&srv, "grid");
    uint64_t id = s->id;
    size_t pb = 24 * (size_t)s->nv;
    stroke(s, 30, 2, 0, 1000);           /* 1-2 */
    double *verified = malloc(pb);
    memcpy(verified, s->cur, pb);
    stroke(s, 90, 2, 0, 1000);           /* 3-4: version 4's record is damaged below */
    stroke(s, 250, 1, 0, 1000);          /* 5 */
    assert_int_equal(atomic_load(&s->version), 5);
    server_close(&srv);
    sqlite3 *db;
    char path[128];
    snprintf(path, sizeof path, "%s/m.db", g_dir);
    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    /* the checksum field (record.h: bytes 16..23) of version 4's record, one bit flipped */
    assert_int_equal(sqlite3_exec(db, "UPDATE changes SET recipe = substr(recipe, 1, 16) || "
                                      "(CASE WHEN substr(recipe, 17, 1) = x'00' THEN x'01' ELSE "
                                      "x'00' END) || substr(recipe, 18) WHERE version = 4 AND "
                                      "flags & 8", NULL, NULL, NULL), SQLITE_OK);
    assert_int_equal(sqlite3_changes(db), 1);
    sqlite3_close(db);

    server_open(&srv2, "m.db");
    s = df_session_find(&srv2, id);
    assert_non_null(s);
    assert_int_equal(srv2.stats.store_replay_mismatches, 1);
    assert_memory_equal(s->cur, verified, pb);
    assert_int_equal(atomic_load(&s->version), 6);  /* a new number for those positions */
    assert_int_equal(query(&srv2, "SELECT count(*) FROM changes"), 0);
    assert_int_equal(query(&srv2, "SELECT snap_version FROM sessions"), 6);
    server_close(&srv2);
    server_open(&srv3, "m.db");
    s = df_session_find(&srv3, id);
    assert_int_equal(srv3.stats.store_replay_mismatches, 0);
    assert_memory_equal(s->cur, verified, pb);
    assert_int_equal(atomic_load(&s->version), 6);
    server_close(&srv3);
    free(verified);
}

/* Snapshots by replay cost: each stroke costs its last version's measured time (a superseded
 * version stops counting), and past the threshold the log is folded into a snapshot. */
static void test_snapshot_by_replay_cost(void **state)
{
    (void)state;
    static df_server srv, srv2;
    server_open(&srv, "c.db");
    df_session *s = grid_session(&srv, "grid");
    /* the estimated restore time of a replayed record: its field time (1000 ns here) and the
     * per-vertex work around it (journal.h); a stroke costs two: its last version, and its end
     * (a RECIPE undo step, replayed again by the history) */
    int64_t cost = 1000 + DF_STORE_REPLAY_VERTEX_NS * (int64_t)s->nv;
    df_store_set_snapshot_replay_ns(srv.store, (uint64_t)(9 * cost / 2));
    uint64_t id = s->id;
    size_t pb = 24 * (size_t)s->nv;
    stroke(s, 30, 3, 0, 1000);
    assert_int_equal(query(&srv, "SELECT replay_ns FROM sessions"), 2 * cost);
    stroke(s, 60, 2, 0, 1000);
    assert_int_equal(query(&srv, "SELECT replay_ns FROM sessions"), 4 * cost);
    assert_int_equal(query(&srv, "SELECT snap_version FROM sessions"), 0);
    stroke(s, 90, 2, 0, 1000);           /* its begin (version 6) passes 4.5 x cost ... */
    assert_int_equal(query(&srv, "SELECT snap_version FROM sessions"), 7); /* ... its end */
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes"), 0);
    assert_int_equal(query(&srv, "SELECT length(data) FROM blobs WHERE name = 'cur'"), (int64_t)pb);
    assert_int_equal(query(&srv, "SELECT count(*) FROM blobs WHERE name = 'rest'"), 0); /* base */
    /* inside a stroke only past DF_STORE_SNAPSHOT_REPLAY_FORCE x the threshold: the stroke
     * began at version 7, before that snapshot (of version 8): its version 9 and its end are no
     * recipe any more (the log cannot rebuild version 7), a delta and a plain end */
    stroke(s, 120, 2, 0, (uint64_t)(DF_STORE_SNAPSHOT_REPLAY_FORCE * 9 * cost / 2));
    assert_int_equal(query(&srv, "SELECT snap_version FROM sessions"), 8);
    assert_int_equal(query(&srv, "SELECT replay_ns FROM sessions"), 0);
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes"), 2);
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes WHERE recipe IS NOT NULL"), 0);
    assert_int_equal(query(&srv, "SELECT count(*) FROM changes WHERE delta IS NOT NULL"), 1);
    double *cur = malloc(pb);
    memcpy(cur, s->cur, pb);
    server_close(&srv);
    server_open(&srv2, "c.db");
    s = df_session_find(&srv2, id);
    assert_memory_equal(s->cur, cur, pb);
    assert_int_equal(srv2.stats.store_recipes_replayed, 0);
    server_close(&srv2);
    free(cur);
}

static void test_record_layout(void **state)
{
    (void)state;
    uint8_t recipe[5] = {1, 2, 3, 4, 5};
    df_recipe_record r = {.base_version = 0x0102030405060708ULL, .checksum = 0xfedcba9876543210ULL,
                          .replay_ns = 12345, .recipe = recipe, .recipe_len = sizeof recipe};
    uint8_t *b;
    size_t len;
    df_error e;
    assert_int_equal(df_record_encode(&r, &b, &len, &e), DF_OK);
    assert_int_equal(len, DF_RECORD_HEADER + sizeof recipe);
    uint32_t u32;
    uint64_t u64;
    memcpy(&u32, b, 4);
    assert_int_equal(u32, DF_RECORD_MAGIC);
    assert_memory_equal(b, "DJR1", 4);   /* little-endian hosts (the store's stated byte order) */
    memcpy(&u32, b + 4, 4);
    assert_int_equal(u32, sizeof recipe);
    memcpy(&u64, b + 8, 8);
    assert_true(u64 == r.base_version);
    memcpy(&u64, b + 16, 8);
    assert_true(u64 == r.checksum);
    memcpy(&u64, b + 24, 8);
    assert_true(u64 == r.replay_ns);
    assert_memory_equal(b + DF_RECORD_HEADER, recipe, sizeof recipe);
    df_recipe_record d;
    assert_int_equal(df_record_decode(b, len, &d, &e), DF_OK);
    assert_true(d.base_version == r.base_version && d.checksum == r.checksum &&
                d.replay_ns == r.replay_ns && d.recipe_len == sizeof recipe);
    assert_ptr_equal(d.recipe, b + DF_RECORD_HEADER);
    /* refused: short, one byte missing or extra, wrong magic, an empty recipe */
    assert_int_equal(df_record_decode(b, DF_RECORD_HEADER - 1, &d, &e), DF_EFORMAT);
    assert_int_equal(df_record_decode(b, len - 1, &d, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "recipe of 5 bytes"));
    uint8_t *big = malloc(len + 1);
    memcpy(big, b, len);
    big[len] = 0;
    assert_int_equal(df_record_decode(big, len + 1, &d, &e), DF_EFORMAT);
    big[0] ^= 1;
    assert_int_equal(df_record_decode(big, len, &d, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "magic"));
    free(big);
    r.recipe_len = 0;
    assert_int_equal(df_record_encode(&r, &big, &len, &e), DF_EINVAL);
    free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_record_layout),
        cmocka_unit_test(test_records_and_restore),
        cmocka_unit_test(test_mismatch_stops_at_the_last_verified),
        cmocka_unit_test(test_snapshot_by_replay_cost),
    };
    return cmocka_run_group_tests(tests, rig_setup, rig_teardown);
}
