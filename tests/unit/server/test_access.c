/* Unit tests for server/access_config.c (peer_key, session_access, quota_* parsing and their
 * errors) and server/session/access.c (the right each request needs, the rights of owners,
 * admins, others and devices under both session_access values, EPERM messages, quotas). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "proto/messages.h"
#include "server/access_config.h"
#include "server/session/access.h"
#include "server/session/session.h"

static void test_parse_access_keys(void **state)
{
    (void)state;
    df_access_config a;
    df_access_config_defaults(&a);
    df_error e;
    assert_int_equal(a.session_access, DF_SESSION_ACCESS_OPEN);
    assert_int_equal(a.quota_sessions + a.quota_upload_mb + a.quota_memory_mb, 0);
    assert_int_equal(df_access_config_set(&a, "peer_key", "alice  /etc/a.key", &e), DF_OK);
    assert_int_equal(df_access_config_set(&a, "peer_key", "bob\t/etc/b key", &e), DF_OK);
    assert_int_equal(a.n_peer_keys, 2);
    assert_string_equal(a.peer_keys[0].name, "alice");
    assert_string_equal(a.peer_keys[0].file, "/etc/a.key");
    assert_string_equal(a.peer_keys[1].file, "/etc/b key");
    assert_int_equal(df_access_config_set(&a, "peer_key", "alice /x", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "given twice"));
    assert_int_equal(df_access_config_set(&a, "peer_key", "carol", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "NAME FILE"));
    assert_int_equal(df_access_config_set(&a, "peer_key", "a/b /x", &e), DF_EINVAL);
    assert_int_equal(a.n_peer_keys, 2); /* refused entries add nothing */
    assert_int_equal(df_access_config_set(&a, "session_access", "owner", &e), DF_OK);
    assert_int_equal(a.session_access, DF_SESSION_ACCESS_OWNER);
    assert_int_equal(df_access_config_set(&a, "session_access", "all", &e), DF_EINVAL);
    assert_int_equal(a.session_access, DF_SESSION_ACCESS_OWNER);
    assert_int_equal(df_access_config_set(&a, "quota_sessions", "3", &e), DF_OK);
    assert_int_equal(df_access_config_set(&a, "quota_upload_mb", "0", &e), DF_OK);
    assert_int_equal(df_access_config_set(&a, "quota_memory_mb", "-1", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "quota_memory_mb"));
    assert_int_equal(a.quota_sessions, 3);
    assert_int_equal(a.quota_memory_mb, 0);
}

/* A server, a session owned by key:alice and connections of three principals. */
typedef struct fixture {
    df_server srv;
    df_session s;
    df_conn owner, other, admin;
} fixture;

static void setup_fixture(fixture *f, int mode)
{
    memset(f, 0, sizeof *f);
    df_access_config_defaults(&f->srv.cfg.access);
    f->srv.cfg.access.session_access = mode;
    f->s.srv = &f->srv;
    df_membership_init(&f->s.acc, mode, 1); /* as df_session_create_as with observers on */
    snprintf(f->s.name, sizeof f->s.name, "spot");
    snprintf(f->s.owner, sizeof f->s.owner, "key:alice");
    snprintf(f->owner.principal, sizeof f->owner.principal, "key:alice");
    snprintf(f->other.principal, sizeof f->other.principal, "key:bob");
    snprintf(f->admin.principal, sizeof f->admin.principal, "admin");
    f->admin.admin = 1;
}

static void test_rights(void **state)
{
    (void)state;
    static fixture f;
    const int all = DF_RIGHT_OBSERVE | DF_RIGHT_EDIT | DF_RIGHT_OWN;
    setup_fixture(&f, DF_SESSION_ACCESS_OPEN);
    assert_int_equal(df_access_rights(&f.owner, &f.s), all);
    assert_int_equal(df_access_rights(&f.admin, &f.s), all);
    assert_int_equal(df_access_rights(NULL, &f.s), all); /* a HID device */
    assert_int_equal(df_access_rights(&f.other, &f.s), DF_RIGHT_OBSERVE | DF_RIGHT_EDIT);
    setup_fixture(&f, DF_SESSION_ACCESS_OWNER);
    assert_int_equal(df_access_rights(&f.owner, &f.s), all);
    assert_int_equal(df_access_rights(&f.other, &f.s), DF_RIGHT_OBSERVE);

    assert_int_equal(df_access_needed(DF_MSG_SUBSCRIBE), DF_RIGHT_OBSERVE);
    assert_int_equal(df_access_needed(DF_MSG_SNAPSHOT), DF_RIGHT_OBSERVE);
    assert_int_equal(df_access_needed(DF_MSG_BRUSH_BEGIN), DF_RIGHT_EDIT);
    assert_int_equal(df_access_needed(DF_MSG_UNDO), DF_RIGHT_EDIT);
    assert_int_equal(df_access_needed(DF_MSG_DEVICE_BIND), DF_RIGHT_EDIT);
    assert_int_equal(df_access_needed(DF_MSG_CLOSE_SESSION), DF_RIGHT_OWN);
    assert_int_equal(df_access_needed(DF_MSG_RESET_REST), DF_RIGHT_OWN);
    assert_int_equal(df_access_needed(DF_MSG_LIST_SESSIONS), 0);
    assert_int_equal(df_access_needed(DF_MSG_STATS), 0);

    df_error e;
    df_req r = {.srv = &f.srv, .c = &f.other, .type = DF_MSG_BRUSH_BEGIN, .id = 1};
    assert_int_equal(df_access_check(&r, &f.s, &e), DF_EPERM);
    assert_string_equal(e.msg, "brush_begin: session 'spot' needs the edit right (you are "
                               "key:bob, an observer; owner key:alice; owner mode): the session "
                               "is owner-only: its owner may switch it to key mode");
    r.type = DF_MSG_GET_MESH;
    assert_int_equal(df_access_check(&r, &f.s, &e), DF_OK);
    r.c = NULL; /* a device's internal request */
    r.type = DF_MSG_CLOSE_SESSION;
    assert_int_equal(df_access_check(&r, &f.s, &e), DF_OK);
}

static void test_quotas(void **state)
{
    (void)state;
    static fixture f;
    static df_session t;
    setup_fixture(&f, DF_SESSION_ACCESS_OPEN);
    f.srv.sessions = &f.s;
    f.s.upload_bytes = 700u << 10;
    f.s.mem_bytes = 600u << 10;
    df_error e;
    assert_int_equal(df_access_quota_check(&f.srv, "key:alice", 1u << 30, 1u << 30, &e), DF_OK);
    f.srv.cfg.access.quota_sessions = 1;
    assert_int_equal(df_access_quota_check(&f.srv, "key:alice", 0, 0, &e), DF_ELIMIT);
    assert_string_equal(e.msg, "quota_sessions: key:alice owns 1 live sessions, the limit is 1 "
                               "(close one first)");
    assert_int_equal(df_access_quota_check(&f.srv, "key:bob", 0, 0, &e), DF_OK);
    f.s.closed = 1; /* a closed session counts no more */
    assert_int_equal(df_access_quota_check(&f.srv, "key:alice", 0, 0, &e), DF_OK);
    f.s.closed = 0;
    f.srv.cfg.access.quota_sessions = 0;
    f.srv.cfg.access.quota_upload_mb = 1;
    assert_int_equal(df_access_quota_check(&f.srv, "key:alice", 324u << 10, 0, &e), DF_OK);
    assert_int_equal(df_access_quota_check(&f.srv, "key:alice", 325u << 10, 0, &e), DF_ELIMIT);
    assert_non_null(strstr(e.msg, "quota_upload_mb: key:alice"));
    f.srv.cfg.access.quota_upload_mb = 0;
    f.srv.cfg.access.quota_memory_mb = 1;
    t = f.s; /* a second session of alice's: 600 + 600 KiB > 1 MiB already */
    t.next = NULL;
    f.s.next = &t;
    assert_int_equal(df_access_quota_check(&f.srv, "key:alice", 0, 1, &e), DF_ELIMIT);
    assert_non_null(strstr(e.msg, "quota_memory_mb: key:alice"));
    assert_non_null(strstr(e.msg, "limit of 1 MiB"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_access_keys),
        cmocka_unit_test(test_rights),
        cmocka_unit_test(test_quotas),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
