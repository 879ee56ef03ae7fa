/* Unit tests for server/session/membership.c (a session's access policy: rights per mode and
 * observers, join keys kept as SHA-256, members and their store form) and the EPERM messages of
 * server/session/access.c under each mode. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include <openssl/evp.h>

#include "proto/messages.h"
#include "server/session/access.h"
#include "server/session/membership.h"
#include "server/session/session.h"

enum { O = DF_MEMBER_OBSERVE, E = DF_MEMBER_EDIT, W = DF_MEMBER_OWN };

static void test_rights_per_mode(void **state)
{
    (void)state;
    df_membership m;
    df_error e;
    const int all = O | E | W;
    for (int mode = DF_ACCESS_MODE_OPEN; mode <= DF_ACCESS_MODE_OWNER; mode++)
        for (int obs = 0; obs <= 1; obs++) {
            df_membership_init(&m, mode, obs);
            assert_int_equal(df_membership_add(&m, "key:bob", &e), DF_OK);
            /* the owner and admins hold every right in every mode */
            assert_int_equal(df_membership_rights(&m, "key:alice", "key:alice", 0), all);
            assert_int_equal(df_membership_rights(&m, "key:alice", "admin", 1), all);
            int member = df_membership_rights(&m, "key:alice", "key:bob", 0);
            int other = df_membership_rights(&m, "key:alice", "key:carol", 0);
            int want_member = mode == DF_ACCESS_MODE_OWNER ? O : O | E;
            int want_other = mode == DF_ACCESS_MODE_OPEN ? O | E : obs ? O : 0;
            assert_int_equal(member, want_member);
            assert_int_equal(other, want_other);
            /* no recorded owner (a schema 1 store): nobody is the owner by an empty name */
            assert_int_equal(df_membership_rights(&m, "", "", 0) & W, 0);
            df_membership_free(&m);
            assert_int_equal(m.n, 0);
            assert_null(m.members);
        }
}

static void sha256(const uint8_t *p, size_t n, uint8_t *out)
{
    unsigned int len = 0;
    assert_int_equal(EVP_Digest(p, n, out, &len, EVP_sha256(), NULL), 1);
    assert_int_equal(len, 32);
}

static void test_join_keys(void **state)
{
    (void)state;
    df_membership m;
    df_error e;
    df_membership_init(&m, DF_ACCESS_MODE_KEY, 1);
    uint8_t k1[DF_JOIN_KEY_BYTES], k2[DF_JOIN_KEY_BYTES], h[32];
    assert_int_equal(df_membership_key_ok(&m, k1, 0), 0); /* no key yet: nothing joins */
    assert_int_equal(df_membership_new_key(&m, k1, &e), DF_OK);
    assert_int_equal(m.has_key, 1);
    sha256(k1, sizeof k1, h);                              /* only the hash is kept */
    assert_memory_equal(m.key_hash, h, sizeof h);
    assert_int_equal(df_membership_key_ok(&m, k1, sizeof k1), 1);
    assert_int_equal(df_membership_key_ok(&m, k1, sizeof k1 - 1), 0);
    uint8_t flip[DF_JOIN_KEY_BYTES];
    for (size_t i = 0; i < sizeof flip; i++) {            /* any one bit off fails */
        memcpy(flip, k1, sizeof flip);
        flip[i] ^= 1;
        assert_int_equal(df_membership_key_ok(&m, flip, sizeof flip), 0);
    }
    assert_int_equal(df_membership_new_key(&m, k2, &e), DF_OK);
    assert_memory_not_equal(k1, k2, sizeof k1);
    assert_int_equal(df_membership_key_ok(&m, k1, sizeof k1), 0); /* rotated: old key out */
    assert_int_equal(df_membership_key_ok(&m, k2, sizeof k2), 1);
    uint8_t before[32];
    memcpy(before, m.key_hash, sizeof before);
    assert_int_equal(df_membership_new_key(&m, NULL, &e), DF_OK); /* a key nobody learns */
    assert_memory_not_equal(before, m.key_hash, sizeof before);
    df_membership_free(&m);
    assert_int_equal(m.has_key, 0);
}

static void test_members(void **state)
{
    (void)state;
    df_membership m, c;
    df_error e;
    df_membership_init(&m, DF_ACCESS_MODE_KEY, 0);
    assert_int_equal(df_membership_add(&m, "key:bob", &e), DF_OK);
    assert_int_equal(df_membership_add(&m, "uid:1000", &e), DF_OK);
    assert_int_equal(df_membership_add(&m, "key:bob", &e), DF_OK); /* once */
    assert_int_equal(m.n, 2);
    assert_int_equal(df_membership_add(&m, "", &e), DF_EINVAL);
    char long_name[DF_PRINCIPAL_MAX + 1];
    memset(long_name, 'x', sizeof long_name - 1);
    long_name[sizeof long_name - 1] = '\0';
    assert_int_equal(df_membership_add(&m, long_name, &e), DF_EINVAL);
    assert_int_equal(m.n, 2);
    /* the store's form and back */
    char *text = NULL;
    assert_int_equal(df_membership_members_join(&m, &text, &e), DF_OK);
    assert_string_equal(text, "key:bob\nuid:1000\n");
    df_membership_init(&c, DF_ACCESS_MODE_KEY, 0);
    assert_int_equal(df_membership_members_parse(&c, text, strlen(text), &e), DF_OK);
    assert_int_equal(c.n, 2);
    assert_int_equal(df_membership_is_member(&c, "uid:1000"), 1);
    assert_int_equal(df_membership_is_member(&c, "uid:1001"), 0);
    df_membership_free(&c);
    free(text);
    assert_int_equal(df_membership_members_parse(&c, "a\n\nb\n", 5, &e), DF_EFORMAT);
    df_membership_free(&c);
    /* a copy is independent */
    assert_int_equal(df_membership_copy(&c, &m, &e), DF_OK);
    assert_int_equal(df_membership_add(&c, "key:carol", &e), DF_OK);
    assert_int_equal(c.n, 3);
    assert_int_equal(m.n, 2);
    assert_int_equal(df_membership_is_member(&m, "key:carol"), 0);
    df_membership_free(&c);
    /* the limit */
    for (int i = m.n; i < DF_MEMBERS_MAX; i++) {
        char p[32];
        snprintf(p, sizeof p, "uid:%d", 5000 + i);
        assert_int_equal(df_membership_add(&m, p, &e), DF_OK);
    }
    assert_int_equal(m.n, DF_MEMBERS_MAX);
    assert_int_equal(df_membership_add(&m, "key:one-more", &e), DF_ELIMIT);
    assert_int_equal(df_membership_add(&m, "key:bob", &e), DF_OK); /* already one */
    df_membership_free(&m);
}

static void test_mode_names(void **state)
{
    (void)state;
    df_error e;
    int mode = 0;
    for (int k = DF_ACCESS_MODE_OPEN; k <= DF_ACCESS_MODE_OWNER; k++) {
        assert_int_equal(df_membership_mode_parse(df_membership_mode_name(k), &mode, &e), DF_OK);
        assert_int_equal(mode, k);
    }
    assert_int_equal(df_membership_mode_parse("members", &mode, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "open, key or owner"));
    assert_string_equal(df_membership_mode_name(0), "?");
}

/* EPERM messages name the right, the session, the mode and how to get the right. */
static void test_eperm_messages(void **state)
{
    (void)state;
    static df_server srv;
    static df_session s;
    static df_conn bob;
    memset(&srv, 0, sizeof srv);
    memset(&s, 0, sizeof s);
    memset(&bob, 0, sizeof bob);
    s.srv = &srv;
    snprintf(s.name, sizeof s.name, "spot");
    snprintf(s.owner, sizeof s.owner, "key:alice");
    snprintf(bob.principal, sizeof bob.principal, "key:bob");
    df_membership_init(&s.acc, DF_ACCESS_MODE_KEY, 0);
    df_error e;
    df_req r = {.srv = &srv, .c = &bob, .type = DF_MSG_BRUSH_BEGIN, .id = 1};
    assert_int_equal(df_access_check(&r, &s, &e), DF_EPERM);
    assert_string_equal(e.msg, "brush_begin: session 'spot' needs the edit right (you are "
                               "key:bob, not admitted; owner key:alice; key mode): join with "
                               "the session's key: JOIN, deformctl join SESSION --key HEX");
    r.type = DF_MSG_SUBSCRIBE;
    assert_int_equal(df_access_check(&r, &s, &e), DF_EPERM);
    assert_non_null(strstr(e.msg, "needs the observe right"));
    assert_int_equal(df_membership_add(&s.acc, "key:bob", &e), DF_OK);
    assert_int_equal(df_access_check(&r, &s, &e), DF_OK);
    r.type = DF_MSG_CLOSE_SESSION;
    assert_int_equal(df_access_check(&r, &s, &e), DF_EPERM);
    assert_non_null(strstr(e.msg, "needs the own right (you are key:bob, a member;"));
    assert_non_null(strstr(e.msg, "only the owner or an admin key has it"));
    s.acc.mode = DF_ACCESS_MODE_OWNER;
    r.type = DF_MSG_UNDO;
    assert_int_equal(df_access_check(&r, &s, &e), DF_EPERM);
    assert_non_null(strstr(e.msg, "an observer"));
    assert_non_null(strstr(e.msg, "owner-only"));
    assert_int_equal(df_access_require(&r, &s, DF_RIGHT_OBSERVE, &e), DF_OK);
    df_membership_free(&s.acc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rights_per_mode),
        cmocka_unit_test(test_join_keys),
        cmocka_unit_test(test_members),
        cmocka_unit_test(test_mode_names),
        cmocka_unit_test(test_eperm_messages),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
