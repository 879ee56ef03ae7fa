/* Live test of libdeformclient's df_client_session_peers (SESSION_PEERS, PROTOCOL.md 4.38)
 * against the real daemon ($BUILD/bin/deformd next to this test's build tree; skipped when it
 * is not built): two named connections subscribe one session; each lists both rows (its own
 * with DF_PEER_SELF only), with the HELLO names, the uid principal, the Unix transport and
 * DF_PEER_EDIT (one uid: the owner); the shared-memory subscriber has DF_PEER_SHM; an
 * unsubscribe removes its row; an unknown session is DF_ENOTFOUND, *out untouched. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "client/deformclient.h"
#include "tests/unit/client/live_daemon.h"
#include "tests/unit/unit_skip.h"

static const char TRI[] = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

/* The row of `l` whose flags have DF_PEER_SELF (asserts there is exactly one). */
static const df_msg_peer_info *own_row(const df_msg_peer_list *l)
{
    const df_msg_peer_info *mine = NULL;
    for (uint32_t i = 0; i < l->count; i++)
        if (l->items[i].flags & DF_PEER_SELF) {
            assert_null(mine);
            mine = &l->items[i];
        }
    assert_non_null(mine);
    return mine;
}

static void test_two_connections_list_each_other(void **state)
{
    (void)state;
    char exe[PATH_MAX];
    if (live_daemon_path(exe, sizeof exe) != 0)
        unit_skip("deformd is not built next to this test (make -j2 builds it)");
    live_daemon d;
    assert_int_equal(live_daemon_start(&d, exe, "peers"), 0);
    df_client *a, *b;
    df_error e;
    assert_int_equal(df_client_connect_unix(d.sock, "c-one", &a, &e), DF_OK);
    assert_int_equal(df_client_connect_unix(d.sock, "c-two", &b, &e), DF_OK);
    df_msg_session_info info;
    assert_int_equal(df_client_load_mesh_bytes(a, "tri", DF_FMT_OFF, TRI, sizeof TRI - 1, 0,
                                               &info, &e), DF_OK);
    uint64_t sid = info.session_id;
    assert_int_equal(df_client_subscribe(a, sid, 0, NULL, &e), DF_OK);
    assert_int_equal(df_client_subscribe(b, sid, 0, NULL, &e), DF_OK);
    df_msg_shm_info shm;
    assert_int_equal(df_client_stream_shm(b, sid, &shm, &e), DF_OK);

    char uid[32];
    snprintf(uid, sizeof uid, "uid:%u", (unsigned)getuid());
    df_msg_peer_list la, lb;
    assert_int_equal(df_client_session_peers(a, sid, &la, &e), DF_OK);
    assert_int_equal(df_client_session_peers(b, sid, &lb, &e), DF_OK);
    assert_int_equal(la.count, 2);
    assert_int_equal(lb.count, 2);
    const df_msg_peer_info *ma = own_row(&la), *mb = own_row(&lb);
    assert_true(ma->client_id != mb->client_id);
    assert_string_equal(ma->name, "c-one");
    assert_string_equal(mb->name, "c-two");
    for (uint32_t i = 0; i < 2; i++) {
        /* the same rows from both sides, in subscription order: a's, then b's */
        const df_msg_peer_info *p = &la.items[i], *q = &lb.items[i];
        assert_true(p->client_id == q->client_id);
        assert_string_equal(p->name, q->name);
        assert_string_equal(p->principal, uid);
        assert_int_equal(p->transport, DF_TRANSPORT_UNIX);
        assert_true(p->flags & DF_PEER_EDIT);
        assert_int_equal(p->flags & ~DF_PEER_SELF, q->flags & ~DF_PEER_SELF);
        int is_b = p->client_id == mb->client_id;
        assert_int_equal(!!(p->flags & DF_PEER_SHM), is_b);
    }
    assert_true(la.items[0].client_id == ma->client_id && la.items[1].client_id == mb->client_id);
    df_msg_peer_list_free(&la);
    df_msg_peer_list_free(&lb);

    assert_int_equal(df_client_unsubscribe(b, sid, &e), DF_OK);
    assert_int_equal(df_client_session_peers(b, sid, &lb, &e), DF_OK); /* b still observes */
    assert_int_equal(lb.count, 1);
    assert_string_equal(lb.items[0].name, "c-one");
    assert_int_equal(lb.items[0].flags & DF_PEER_SELF, 0);
    df_msg_peer_list_free(&lb);

    df_msg_peer_list keep = {7, NULL};
    assert_int_equal(df_client_session_peers(a, sid + 1000, &keep, &e), DF_ENOTFOUND);
    assert_true(df_client_last_error_was_remote(a));
    assert_true(keep.count == 7 && keep.items == NULL);
    df_client_close(b);
    df_client_close(a);
    live_daemon_stop(&d);
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_connections_list_each_other),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
