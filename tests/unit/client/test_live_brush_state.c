/* Live test of libdeformclient's session brush calls against the real daemon ($BUILD/bin/deformd
 * next to this test's build tree; skipped when it is not built): df_client_brush_state_set from
 * one connection reaches a subscribed one as a DF_MSG_BRUSH_STATE event through the event
 * callback, carrying the setter's HELLO name and the reply's values; df_client_brush_state_get
 * agrees; a value refused locally (encoder) or by the daemon changes nothing. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "client/deformclient.h"
#include "tests/unit/client/live_daemon.h"
#include "tests/unit/unit_skip.h"

#define WAIT_ROUNDS 1000 /* pumps of 10 ms at most while waiting for the event (a guard) */

typedef struct seen {
    int events, bad;
    df_msg_brush_state last;
} seen;

static void on_event(void *user, const df_frame_header *h, const uint8_t *p)
{
    seen *s = user;
    if (h->type != DF_MSG_BRUSH_STATE)
        return;
    if (df_msg_brush_state_decode(p, h->payload_len, &s->last, NULL) == DF_OK)
        s->events++;
    else
        s->bad++;
}

static const char TRI[] = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

static void test_set_get_and_event(void **state)
{
    (void)state;
    char exe[PATH_MAX];
    if (live_daemon_path(exe, sizeof exe) != 0)
        unit_skip("deformd is not built next to this test (make -j2 builds it)");
    live_daemon d;
    assert_int_equal(live_daemon_start(&d, exe, "bstate"), 0);
    df_client *w, *v;
    df_error e;
    assert_int_equal(df_client_connect_unix(d.sock, "knob-box", &w, &e), DF_OK);
    assert_int_equal(df_client_connect_unix(d.sock, "viewer", &v, &e), DF_OK);
    df_msg_session_info info;
    assert_int_equal(df_client_load_mesh_bytes(w, "tri", DF_FMT_OFF, TRI, sizeof TRI - 1, 0,
                                               &info, &e),
                     DF_OK);
    uint64_t sid = info.session_id;
    seen s;
    memset(&s, 0, sizeof s);
    df_client_set_event_callback(v, on_event, &s);
    assert_int_equal(df_client_subscribe(v, sid, 0, NULL, &e), DF_OK);

    df_msg_brush_state st;
    assert_int_equal(df_client_brush_state_get(w, sid, &st, &e), DF_OK);
    assert_true(st.seq == 0 && st.origin_kind == DF_ORIGIN_NONE && st.v.radius == 1.0);

    const double nu0 = st.v.nu;
    df_msg_brush_state_set m = {sid, DF_BS_RADIUS | DF_BS_FALLOFF, st.v};
    m.v.radius = 0.125;
    m.v.falloff = 3;
    df_msg_brush_state reply;
    assert_int_equal(df_client_brush_state_set(w, &m, &reply, &e), DF_OK);
    assert_true(reply.seq == 1 && reply.changed == (DF_BS_RADIUS | DF_BS_FALLOFF));
    assert_string_equal(reply.origin_name, "knob-box");
    for (int i = 0; i < WAIT_ROUNDS && s.events == 0; i++)
        assert_true(df_client_pump(v, 10, &e) >= 0);
    assert_int_equal(s.events, 1);
    assert_int_equal(s.bad, 0);
    assert_true(s.last.seq == 1 && s.last.origin_id == reply.origin_id);
    assert_string_equal(s.last.origin_name, "knob-box");
    assert_true(s.last.v.radius == 0.125 && s.last.v.falloff == 3 && s.last.v.nu == st.v.nu);

    /* refused locally (the encoder) and by the daemon: nothing changes */
    m.mask = DF_BS_RADIUS;
    m.v.radius = -1;
    assert_int_equal(df_client_brush_state_set(w, &m, NULL, &e), DF_EINVAL);
    assert_false(df_client_last_error_was_remote(w));
    m.mask = DF_BS_NU;
    m.v.nu = 0.9;
    assert_int_equal(df_client_brush_state_set(w, &m, NULL, &e), DF_EINVAL);
    assert_true(df_client_last_error_was_remote(w));
    assert_non_null(strstr(e.msg, "nu 0.9"));
    assert_int_equal(df_client_brush_state_get(v, sid, &st, &e), DF_OK);
    assert_true(st.seq == 1 && st.v.radius == 0.125 && st.v.nu == nu0 && st.changed == 0);
    assert_int_equal(df_client_brush_state_get(v, sid + 100, &st, &e), DF_ENOTFOUND);
    df_client_close(v);
    df_client_close(w);
    live_daemon_stop(&d);
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_set_get_and_event),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
