/* Unit tests for df_session_peers_fill (server/handlers/h_peers.c, SESSION_PEERS rows,
 * PROTOCOL.md 4.38): rows in subscription order with each connection's id, HELLO name,
 * principal and transport; SELF only on the asker's row; EDIT from the session's access policy
 * (owner / admin / member / observer under each mode); SHM from the shared-memory subscribers;
 * the cap keeps the asker's own row; no subscribers gives an empty list. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "proto/messages.h"
#include "server/access_config.h"
#include "server/handlers/handlers.h"
#include "server/session/access.h"
#include "server/session/membership.h"
#include "server/session/session.h"

enum { NCONN = 4 };

/* A session owned by key:alice; subscribers alice (Unix), bob (TCP, shm), admin (TCP), carol
 * (TCP), in that order. */
typedef struct fixture {
    df_server srv;
    df_session s;
    df_conn c[NCONN];
    df_conn *subs[NCONN];
    uint8_t shm[NCONN];
} fixture;

static void setup_fixture(fixture *f, int mode)
{
    static const char *const who[NCONN] = {"key:alice", "key:bob", "admin", "key:carol"};
    static const char *const names[NCONN] = {"blender", "", "ops console", "viewer"};
    memset(f, 0, sizeof *f);
    df_access_config_defaults(&f->srv.cfg.access);
    f->s.srv = &f->srv;
    df_membership_init(&f->s.acc, mode, 1);
    snprintf(f->s.name, sizeof f->s.name, "spot");
    snprintf(f->s.owner, sizeof f->s.owner, "key:alice");
    for (int i = 0; i < NCONN; i++) {
        f->c[i].id = 100 + 7 * (uint64_t)i;
        f->c[i].is_tcp = i > 0;
        snprintf(f->c[i].principal, sizeof f->c[i].principal, "%s", who[i]);
        snprintf(f->c[i].name, sizeof f->c[i].name, "%s", names[i]);
        f->subs[i] = &f->c[i];
    }
    f->c[2].admin = 1;
    f->shm[1] = 1;
    f->s.subs = f->subs;
    f->s.sub_shm = f->shm;
    f->s.nsubs = f->s.capsubs = NCONN;
    f->s.nshm = 1;
}

/* The flags expected for subscriber i seen by `asker`, from the access rules themselves. */
static uint8_t want_flags(const fixture *f, int i, const df_conn *asker)
{
    uint8_t fl = 0;
    if (&f->c[i] == asker) fl |= DF_PEER_SELF;
    if (df_access_rights(&f->c[i], &f->s) & DF_RIGHT_EDIT) fl |= DF_PEER_EDIT;
    if (f->shm[i]) fl |= DF_PEER_SHM;
    return fl;
}

static void test_rows_in_order_with_identity(void **state)
{
    (void)state;
    static fixture f;
    setup_fixture(&f, DF_SESSION_ACCESS_OPEN);
    df_msg_peer_list l;
    df_error e;
    assert_int_equal(df_session_peers_fill(&f.s, &f.c[1], DF_MAX_PEERS, &l, &e), DF_OK);
    assert_int_equal(l.count, NCONN);
    for (int i = 0; i < NCONN; i++) {
        assert_true(l.items[i].client_id == f.c[i].id);
        assert_string_equal(l.items[i].name, f.c[i].name);
        assert_string_equal(l.items[i].principal, f.c[i].principal);
        assert_int_equal(l.items[i].transport, i ? DF_TRANSPORT_TCP : DF_TRANSPORT_UNIX);
        assert_int_equal(l.items[i].flags, want_flags(&f, i, &f.c[1]));
        assert_int_equal(!!(l.items[i].flags & DF_PEER_EDIT), 1); /* open: everyone edits */
    }
    assert_int_equal(l.items[1].flags, DF_PEER_SELF | DF_PEER_EDIT | DF_PEER_SHM);
    /* the rows encode (every field within the wire's rules) */
    df_buf b;
    df_buf_init(&b);
    assert_int_equal(df_msg_peer_list_encode(&l, &b, &e), DF_OK);
    df_buf_free(&b);
    df_msg_peer_list_free(&l);
    /* an asker that is not subscribed (or an internal request): no SELF row */
    assert_int_equal(df_session_peers_fill(&f.s, NULL, DF_MAX_PEERS, &l, &e), DF_OK);
    for (uint32_t i = 0; i < l.count; i++) assert_int_equal(l.items[i].flags & DF_PEER_SELF, 0);
    df_msg_peer_list_free(&l);
}

static void test_edit_follows_the_mode(void **state)
{
    (void)state;
    static fixture f;
    df_msg_peer_list l;
    df_error e;
    /* owner mode: the owner and the admin edit, bob and carol observe */
    setup_fixture(&f, DF_SESSION_ACCESS_OWNER);
    assert_int_equal(df_session_peers_fill(&f.s, &f.c[3], DF_MAX_PEERS, &l, &e), DF_OK);
    const uint8_t edit_owner[NCONN] = {1, 0, 1, 0};
    for (int i = 0; i < NCONN; i++) {
        assert_int_equal(!!(l.items[i].flags & DF_PEER_EDIT), edit_owner[i]);
        assert_int_equal(l.items[i].flags, want_flags(&f, i, &f.c[3]));
    }
    df_msg_peer_list_free(&l);
    /* key mode: carol joined, bob did not */
    setup_fixture(&f, DF_SESSION_ACCESS_KEY);
    assert_int_equal(df_membership_add(&f.s.acc, "key:carol", &e), DF_OK);
    assert_int_equal(df_session_peers_fill(&f.s, &f.c[0], DF_MAX_PEERS, &l, &e), DF_OK);
    const uint8_t edit_key[NCONN] = {1, 0, 1, 1};
    for (int i = 0; i < NCONN; i++)
        assert_int_equal(!!(l.items[i].flags & DF_PEER_EDIT), edit_key[i]);
    df_msg_peer_list_free(&l);
    df_membership_free(&f.s.acc);
}

static void test_cap_keeps_the_askers_row(void **state)
{
    (void)state;
    static fixture f;
    setup_fixture(&f, DF_SESSION_ACCESS_OPEN);
    df_msg_peer_list l;
    df_error e;
    /* carol (the 4th subscriber) asks with room for 2: alice, then carol in the last slot */
    assert_int_equal(df_session_peers_fill(&f.s, &f.c[3], 2, &l, &e), DF_OK);
    assert_int_equal(l.count, 2);
    assert_true(l.items[0].client_id == f.c[0].id && l.items[1].client_id == f.c[3].id);
    assert_int_equal(l.items[1].flags & DF_PEER_SELF, DF_PEER_SELF);
    df_msg_peer_list_free(&l);
    /* bob, within the cap, keeps his place */
    assert_int_equal(df_session_peers_fill(&f.s, &f.c[1], 2, &l, &e), DF_OK);
    assert_true(l.items[0].client_id == f.c[0].id && l.items[1].client_id == f.c[1].id);
    df_msg_peer_list_free(&l);
    /* nobody subscribed: an empty list */
    f.s.nsubs = 0;
    assert_int_equal(df_session_peers_fill(&f.s, &f.c[1], DF_MAX_PEERS, &l, &e), DF_OK);
    assert_int_equal(l.count, 0);
    assert_null(l.items);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rows_in_order_with_identity),
        cmocka_unit_test(test_edit_follows_the_mode),
        cmocka_unit_test(test_cap_keeps_the_askers_row),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
