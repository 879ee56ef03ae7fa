/* Live test of coalescing for an exact C subscriber (PROTOCOL.md 6.3 "Bandwidth") against the real
 * daemon (skipped when it is not built): output_queue_limit 4 MiB; a client connected with
 * df_client_connect_enc(encoding 0) (the hello carries the stream trailer, the stream stays exact
 * float32) subscribes to a 40,000-vertex grid and does not read while 40 grab updates (dense
 * ~480 KB versions) are broadcast. It must not be dropped, must receive at least one coalesced
 * version (version > base_version + 1: versions folded while its queue was full), its replica must
 * apply every version it receives without a gap error, and end byte-identical to GET_MESH. A
 * client with the original hello on the same session is checked to get no trailer back. */
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

#define GRID 200           /* 40,000 vertices: a dense version is ~480 KB */
#define UPDATES 40
#define WAIT_MS 30000

typedef struct slow_sub {
    df_client_replica r;
    uint64_t prev;         /* the last version completed */
    int coalesced;         /* versions completed with a jump (version > previous + 1) */
    int failures;          /* frames the replica refused */
} slow_sub;

static void on_event(void *user, const df_frame_header *h, const uint8_t *p)
{
    slow_sub *s = user;
    int rc = df_client_replica_feed(&s->r, h, p, NULL);
    if (rc < 0) {
        s->failures++;
        return;
    }
    if (rc == 1) {
        if (s->r.version > s->prev + 1) s->coalesced++;
        s->prev = s->r.version;
    }
}

static void test_slow_exact_c_subscriber_is_coalesced(void **state)
{
    (void)state;
    char exe[PATH_MAX];
    if (live_daemon_path(exe, sizeof exe) != 0)
        unit_skip("deformd is not built next to this test (make -j2 builds it)");
    live_daemon d;
    assert_int_equal(live_daemon_start_config(&d, exe, "coal", "output_queue_limit = 4m\n"), 0);
    df_error e;
    df_client *ed, *slow, *old;
    assert_int_equal(df_client_connect_unix(d.sock, "editor", &ed, &e), DF_OK);
    assert_int_equal(df_client_connect_enc(d.sock, NULL, 0, NULL, "slow", 0, 0, &slow, &e), DF_OK);
    const df_msg_hello_reply *hr = df_client_server_info(slow);
    assert_true(hr->has_stream && hr->stream_encoding == 0 && hr->error_bound == 0);
    assert_int_equal(df_client_connect_unix(d.sock, "old", &old, &e), DF_OK);
    assert_int_equal(df_client_server_info(old)->has_stream, 0); /* the original hello */
    df_client_close(old);
    size_t len;
    char *off = live_grid_off(GRID, &len);
    df_msg_session_info info;
    assert_int_equal(df_client_load_mesh_bytes(ed, "coal", DF_FMT_OFF, off, len, 0, &info, &e),
                     DF_OK);
    free(off);
    uint64_t sid = info.session_id;
    df_client_mesh m;
    assert_int_equal(df_client_get_mesh(ed, sid, DF_GET_MESH_BASE, &m, &e), DF_OK);
    static slow_sub s;
    memset(&s, 0, sizeof s);
    assert_int_equal(df_client_replica_init(&s.r, sid, m.nv, m.base, NULL, 0, &e), DF_OK);
    df_client_mesh_free(&m);
    df_client_set_event_callback(slow, on_event, &s);
    assert_int_equal(df_client_subscribe(slow, sid, 0, NULL, &e), DF_OK);
    /* the slow client reads nothing while the editor's versions are broadcast */
    df_msg_brush b;
    df_msg_brush_defaults(&b);
    b.session_id = sid;
    b.radius = 0.5;
    b.center[0] = b.center[1] = 0.5;
    assert_int_equal(df_client_brush_begin(ed, &b, NULL, &e), DF_OK);
    for (int i = 1; i <= UPDATES; i++) {
        df_msg_brush_update u;
        memset(&u, 0, sizeof u);
        u.session_id = sid;
        u.move[0] = 0.001 * i;
        u.move[2] = 0.0005 * i;
        assert_int_equal(df_client_brush_update(ed, &u, NULL, &e), DF_OK);
    }
    df_msg_ack ack;
    assert_int_equal(df_client_brush_end(ed, sid, &ack, &e), DF_OK);
    assert_int_equal(df_client_get_mesh(ed, sid, 0, &m, &e), DF_OK);
    uint64_t last = m.version;
    assert_true(last >= UPDATES);
    for (int t = 0; t < WAIT_MS / 10 && s.r.version < last; t++)
        assert_true(df_client_pump(slow, 10, NULL) >= 0);
    assert_int_equal(s.failures, 0);
    assert_true(s.r.version == last);
    assert_true(s.coalesced > 0);                 /* versions were folded for it */
    float *pos = malloc((size_t)m.nv * 3 * sizeof(float));
    df_client_replica_positions(&s.r, pos);
    assert_memory_equal(pos, m.positions, (size_t)m.nv * 3 * sizeof(float));
    free(pos);
    printf("slow exact subscriber: %d coalesced versions of %llu\n", s.coalesced,
           (unsigned long long)last);
    assert_int_equal(df_client_ping(slow, "alive", 5, NULL, &e), DF_OK); /* not dropped */
    df_client_mesh_free(&m);
    df_client_replica_free(&s.r);
    df_client_close(slow);
    df_client_close(ed);
    live_daemon_stop(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_slow_exact_c_subscriber_is_coalesced),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
