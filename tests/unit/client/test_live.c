/* Live test of libdeformclient against the real daemon ($BUILD/bin/deformd next to this test's
 * build tree; skipped when it is not built): two writers stroke one session concurrently while
 * four connections keep df_client_replica copies from the displacement stream (two of them
 * through the shared-memory ring, df_client_stream_shm); every replica must end byte-identical
 * to the daemon's positions, and a stale replica must resync by snapshot. A replica reading too
 * slowly for a small ring sees the lost frames as a gap and resyncs. A replica that reconnects
 * resyncs from the version it holds (df_client_subscribe_from): the missed versions replayed, or a
 * snapshot from a version the session never reached. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

#include "client/deformclient.h"
#include "tests/unit/client/live_daemon.h"
#include "tests/unit/unit_skip.h"

#define LIVE_CLIENTS 4      /* connections with a replica; clients 0 and 1 also write */
#define LIVE_UPDATES 6      /* brush updates per writer */
#define LIVE_WAIT_MS 10000  /* longest wait for the stream to catch up */

typedef struct live {
    live_daemon d;
    df_client *c[LIVE_CLIENTS];
    df_client_replica r[LIVE_CLIENTS];
    int feed_errors[LIVE_CLIENTS];
} live;

/* Fills `exe` with the deformd next to this test, or skips the test (naming why). */
static void daemon_or_skip(char *exe, size_t cap)
{
    if (live_daemon_path(exe, cap) != 0)
        unit_skip("deformd is not built next to this test (make -j2 builds it)");
}

/* Value of stats key `key` (asserts it is present). */
static double stat_of(const df_msg_stats *st, const char *key)
{
    for (uint32_t i = 0; i < st->count; i++)
        if (strcmp(st->items[i].key, key) == 0) return st->items[i].value;
    fail_msg("stats key %s missing", key);
    return 0;
}

static void on_event(void *user, const df_frame_header *h, const uint8_t *p)
{
    df_client_replica *r = user;
    if (df_client_replica_feed(r, h, p, NULL) < 0)
        r->stale = 1;
}

static void stroke_update(df_client *c, uint64_t sid, int writer, int i)
{
    df_msg_brush_update u;
    memset(&u, 0, sizeof u);
    u.session_id = sid;
    u.move[writer] = 0.01 * (i + 1);
    u.move[2] = -0.003 * i;
    df_error e;
    assert_int_equal(df_client_brush_update(c, &u, NULL, &e), DF_OK);
}

/* Pumps every client until its replica reaches `version` (or the wait runs out). */
static void catch_up(live *L, uint64_t version)
{
    for (int k = 0; k < LIVE_CLIENTS; k++)
        for (int t = 0; t < LIVE_WAIT_MS / 10 && L->r[k].version < version; t++)
            assert_true(df_client_pump(L->c[k], 10, NULL) >= 0);
}

static void test_replicas_match_the_daemon(void **state)
{
    (void)state;
    char exe[PATH_MAX];
    daemon_or_skip(exe, sizeof exe);
    live L;
    memset(&L, 0, sizeof L);
    assert_int_equal(live_daemon_start(&L.d, exe, "live"), 0);
    df_error e;
    for (int k = 0; k < LIVE_CLIENTS; k++)
        assert_int_equal(df_client_connect_unix(L.d.sock, "live", &L.c[k], &e), DF_OK);
    size_t len;
    char *off = live_grid_off(30, &len);
    df_msg_session_info info;
    assert_int_equal(df_client_load_mesh_bytes(L.c[0], "live", DF_FMT_OFF, off, len, 0, &info, &e),
                     DF_OK);
    free(off);
    uint64_t sid = info.session_id;
    assert_int_equal(info.nv, 900);
    for (int k = 0; k < LIVE_CLIENTS; k++) {
        df_client_mesh m;
        assert_int_equal(df_client_get_mesh(L.c[k], sid, DF_GET_MESH_BASE, &m, &e), DF_OK);
        assert_int_equal(df_client_replica_init(&L.r[k], sid, m.nv, m.base, NULL, m.version, &e),
                         DF_OK);
        L.r[k].stale = 1; /* until the subscribe snapshot arrives */
        df_client_mesh_free(&m);
        df_client_set_event_callback(L.c[k], on_event, &L.r[k]);
        assert_int_equal(df_client_subscribe(L.c[k], sid, DF_SUBSCRIBE_SNAPSHOT, NULL, &e), DF_OK);
        if (k >= 2) { /* replicas 2 and 3 read the stream from the shared-memory ring */
            df_msg_shm_info si;
            assert_int_equal(df_client_stream_shm(L.c[k], sid, &si, &e), DF_OK);
            assert_true(si.session_id == sid && si.capacity >= 4096);
            assert_int_equal(si.path[0], '/');
        }
    }
    /* two concurrent strokes, interleaved updates */
    df_msg_brush b;
    df_msg_brush_defaults(&b);
    b.session_id = sid;
    b.radius = 0.2;
    b.nu = 0.4;
    for (int w = 0; w < 2; w++) {
        b.center[0] = 0.3 + 0.4 * w;
        b.center[1] = 0.5;
        assert_int_equal(df_client_brush_begin(L.c[w], &b, NULL, &e), DF_OK);
    }
    for (int i = 0; i < LIVE_UPDATES; i++)
        for (int w = 0; w < 2; w++)
            stroke_update(L.c[w], sid, w, i);
    df_msg_ack ack;
    for (int w = 0; w < 2; w++)
        assert_int_equal(df_client_brush_end(L.c[w], sid, &ack, &e), DF_OK);
    assert_int_equal(df_client_undo(L.c[0], sid, &ack, &e), DF_OK);
    assert_int_equal(df_client_redo(L.c[1], sid, &ack, &e), DF_OK);
    uint64_t final = ack.version;
    assert_true(final >= 2 * LIVE_UPDATES + 2);
    catch_up(&L, final);
    df_client_mesh m;
    assert_int_equal(df_client_get_mesh(L.c[2], sid, 0, &m, &e), DF_OK);
    assert_int_equal(m.version, final);
    float *pos = malloc((size_t)m.nv * 3 * sizeof(float));
    for (int k = 0; k < LIVE_CLIENTS; k++) {
        assert_int_equal(L.r[k].stale, 0);
        assert_int_equal(L.r[k].version, final);
        df_client_replica_positions(&L.r[k], pos);
        assert_memory_equal(pos, m.positions, (size_t)m.nv * 3 * sizeof(float));
    }
    /* the strokes moved something, and the stream carried every version */
    int moved = 0;
    for (size_t i = 0; i < (size_t)m.nv * 3; i++)
        moved += L.r[3].u[i] != 0.0f;
    assert_true(moved > 100);
    /* a replica that lost data resyncs by snapshot */
    memset(L.r[3].u, 0, (size_t)m.nv * 3 * sizeof(float));
    L.r[3].stale = 1;
    assert_int_equal(df_client_replica_resync(L.c[3], &L.r[3], &e), DF_OK);
    df_client_replica_positions(&L.r[3], pos);
    assert_memory_equal(pos, m.positions, (size_t)m.nv * 3 * sizeof(float));
    assert_int_equal(L.r[3].version, final);
    df_msg_stats st;
    assert_int_equal(df_client_stats(L.c[0], 0, &st, &e), DF_OK);
    double refs = stat_of(&st, "shm_refs");
    df_msg_stats_free(&st);
    /* 2 ring subscribers x every brush version (10.9 KB dense frames; the undo/redo frames here
     * carry no rows and, under DF_SHM_MIN_FRAME, stay on the socket) */
    assert_true(refs >= 2.0 * 2 * LIVE_UPDATES);
    printf("live: %d replicas byte-identical at version %llu (%d coordinates moved, %.0f "
           "versions read from the shared-memory ring)\n", LIVE_CLIENTS,
           (unsigned long long)final, moved, refs);
    free(pos);
    df_client_mesh_free(&m);
    for (int k = 0; k < LIVE_CLIENTS; k++) {
        df_client_replica_free(&L.r[k]);
        df_client_close(L.c[k]);
    }
    live_daemon_stop(&L.d);
}

/* A ring subscriber that does not read while 12 versions of 19 KB go through a 64 KiB ring:
 * the early frames are overwritten before it reads their SHM_REFs, so its replica goes stale
 * (no wrong positions are ever applied) and a snapshot brings it back to the daemon's state. */
static void test_shm_subscriber_too_slow_for_the_ring_resyncs(void **state)
{
    (void)state;
    char exe[PATH_MAX];
    daemon_or_skip(exe, sizeof exe);
    live_daemon d;
    assert_int_equal(live_daemon_start_config(&d, exe, "shm", "shm_ring_bytes = 64k\n"), 0);
    df_client *w, *r;
    df_error e;
    assert_int_equal(df_client_connect_unix(d.sock, "writer", &w, &e), DF_OK);
    assert_int_equal(df_client_connect_unix(d.sock, "reader", &r, &e), DF_OK);
    size_t len;
    char *off = live_grid_off(40, &len);
    df_msg_session_info info;
    assert_int_equal(df_client_load_mesh_bytes(w, "ring", DF_FMT_OFF, off, len, 0, &info, &e),
                     DF_OK);
    free(off);
    uint64_t sid = info.session_id;
    df_client_mesh m;
    assert_int_equal(df_client_get_mesh(r, sid, DF_GET_MESH_BASE, &m, &e), DF_OK);
    df_client_replica rep;
    assert_int_equal(df_client_replica_init(&rep, sid, m.nv, m.base, NULL, m.version, &e), DF_OK);
    df_client_mesh_free(&m);
    df_client_set_event_callback(r, on_event, &rep);
    assert_int_equal(df_client_subscribe(r, sid, 0, NULL, &e), DF_OK);
    df_msg_shm_info si;
    assert_int_equal(df_client_stream_shm(r, sid, &si, &e), DF_OK);
    assert_true(si.capacity == 65536 && si.max_frame == 32768);
    df_msg_brush b;
    df_msg_brush_defaults(&b);
    b.session_id = sid;
    b.radius = 0.3;
    b.center[0] = b.center[1] = 0.5;
    assert_int_equal(df_client_brush_begin(w, &b, NULL, &e), DF_OK);
    for (int i = 0; i < 12; i++) stroke_update(w, sid, 0, i);
    df_msg_ack ack;
    assert_int_equal(df_client_brush_end(w, sid, &ack, &e), DF_OK);
    for (int t = 0; t < LIVE_WAIT_MS / 10 && !rep.stale; t++)
        assert_true(df_client_pump(r, 10, NULL) >= 0);
    assert_int_equal(rep.stale, 1);
    assert_true(rep.version < ack.version); /* stopped at the gap */
    assert_int_equal(df_client_replica_resync(r, &rep, &e), DF_OK);
    assert_int_equal(rep.stale, 0);
    assert_int_equal(df_client_get_mesh(w, sid, 0, &m, &e), DF_OK);
    assert_int_equal(rep.version, m.version);
    float *pos = malloc((size_t)m.nv * 3 * sizeof(float));
    df_client_replica_positions(&rep, pos);
    assert_memory_equal(pos, m.positions, (size_t)m.nv * 3 * sizeof(float));
    free(pos);
    df_client_mesh_free(&m);
    df_client_replica_free(&rep);
    df_client_close(r);
    df_client_close(w);
    live_daemon_stop(&d);
}

/* One stroke of `n` updates by `w` (its own begin / end); returns the end's version. */
static uint64_t one_stroke(df_client *w, uint64_t sid, int n)
{
    df_msg_brush b;
    df_msg_brush_defaults(&b);
    b.session_id = sid;
    b.radius = 0.3;
    b.nu = 0.4;
    b.center[0] = b.center[1] = 0.5;
    df_error e;
    df_msg_ack ack;
    assert_int_equal(df_client_brush_begin(w, &b, NULL, &e), DF_OK);
    for (int i = 0; i < n; i++) stroke_update(w, sid, 0, i);
    assert_int_equal(df_client_brush_end(w, sid, &ack, &e), DF_OK);
    return ack.version;
}

/* Connects a reader feeding `rep`, resyncs it from `from` and pumps until it holds the version
 * the reply names; returns the complete versions applied meanwhile. */
static uint64_t resync_from(const live_daemon *d, df_client_replica *rep, uint64_t from)
{
    df_client *r;
    df_error e;
    assert_int_equal(df_client_connect_unix(d->sock, "resync", &r, &e), DF_OK);
    df_client_set_event_callback(r, on_event, rep);
    uint64_t applied = rep->versions_applied;
    df_msg_session_info info;
    assert_int_equal(df_client_subscribe_from(r, rep->session_id, from, &info, &e), DF_OK);
    for (int t = 0; t < LIVE_WAIT_MS / 10 && (rep->version != info.version || rep->building);
         t++)
        assert_true(df_client_pump(r, 10, NULL) >= 0);
    assert_int_equal(rep->version, info.version);
    assert_int_equal(rep->stale, 0);
    df_client_mesh m;
    assert_int_equal(df_client_get_mesh(r, rep->session_id, 0, &m, &e), DF_OK);
    assert_int_equal(m.version, info.version);
    float *pos = malloc((size_t)m.nv * 3 * sizeof(float));
    df_client_replica_positions(rep, pos);
    assert_memory_equal(pos, m.positions, (size_t)m.nv * 3 * sizeof(float));
    free(pos);
    df_client_mesh_free(&m);
    df_client_close(r);
    return rep->versions_applied - applied;
}

static void test_replica_resyncs_from_the_version_it_holds(void **state)
{
    (void)state;
    char exe[PATH_MAX];
    daemon_or_skip(exe, sizeof exe);
    live_daemon d;
    assert_int_equal(live_daemon_start(&d, exe, "resync"), 0);
    df_client *w;
    df_error e;
    assert_int_equal(df_client_connect_unix(d.sock, "writer", &w, &e), DF_OK);
    size_t len;
    char *off = live_grid_off(20, &len);
    df_msg_session_info info;
    assert_int_equal(df_client_load_mesh_bytes(w, "resync", DF_FMT_OFF, off, len, 0, &info, &e),
                     DF_OK);
    free(off);
    uint64_t sid = info.session_id;
    df_client_mesh m;
    assert_int_equal(df_client_get_mesh(w, sid, DF_GET_MESH_BASE, &m, &e), DF_OK);
    df_client_replica rep, ahead;
    assert_int_equal(df_client_replica_init(&rep, sid, m.nv, m.base, NULL, 0, &e), DF_OK);
    df_client_mesh_free(&m);
    uint64_t v = one_stroke(w, sid, 3);
    assert_int_equal(resync_from(&d, &rep, 0), v); /* every version so far, replayed */
    /* the reader is gone; the writer goes on: a stroke and an undo */
    one_stroke(w, sid, 4);
    df_msg_ack ack;
    assert_int_equal(df_client_undo(w, sid, &ack, &e), DF_OK);
    assert_true(ack.version == v + 5);
    assert_int_equal(resync_from(&d, &rep, rep.version), ack.version - v); /* the missed ones */
    /* a version the session never reached: one snapshot, whatever the replica held */
    assert_int_equal(df_client_replica_init(&ahead, sid, rep.nv, rep.base, NULL, 0, &e), DF_OK);
    assert_int_equal(resync_from(&d, &ahead, ack.version + 100), 1);
    df_msg_stats st;
    assert_int_equal(df_client_stats(w, 0, &st, &e), DF_OK);
    assert_true(stat_of(&st, "resync_replays") == 2 && stat_of(&st, "resync_snapshots") == 1);
    df_msg_stats_free(&st);
    df_client_replica_free(&ahead);
    df_client_replica_free(&rep);
    df_client_close(w);
    live_daemon_stop(&d);
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_replicas_match_the_daemon),
        cmocka_unit_test(test_shm_subscriber_too_slow_for_the_ring_resyncs),
        cmocka_unit_test(test_replica_resyncs_from_the_version_it_holds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
