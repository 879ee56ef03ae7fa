/* Unit tests of server/net/auth_limit.c (failed-authentication rate limit) and
 * server/access_config.c (allow_uids / allow_gids / key_file / auth_fail_* parsing and the peer
 * check). Time is passed in, so every expectation is a count, never a measured delay. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "server/access_config.h"
#include "server/net/auth_limit.h"

static void test_burst_then_refused_then_one_token_per_refill(void **state)
{
    (void)state;
    df_auth_limit *l = malloc(sizeof *l);
    df_auth_limit_init(l, 3, 60);
    uint64_t t = 1000;
    for (int i = 0; i < 3; i++) { /* three failures are allowed */
        assert_int_equal(df_auth_limit_wait(l, "10.0.0.1", t), 0);
        df_auth_limit_fail(l, "10.0.0.1", t);
    }
    uint64_t w = df_auth_limit_wait(l, "10.0.0.1", t);
    assert_int_equal(w, 60000);                       /* one refill period */
    assert_int_equal(df_auth_limit_wait(l, "10.0.0.2", t), 0); /* per address */
    assert_int_equal(df_auth_limit_wait(l, "10.0.0.1", t + 59999), 1);
    assert_int_equal(df_auth_limit_wait(l, "10.0.0.1", t + 60000), 0);
    df_auth_limit_fail(l, "10.0.0.1", t + 60000);     /* that one token is used up again */
    assert_true(df_auth_limit_wait(l, "10.0.0.1", t + 60000) > 0);
    /* after a long quiet time the bucket is full again, never above the burst */
    uint64_t later = t + 1000ull * 3600 * 24;
    for (int i = 0; i < 3; i++) {
        assert_int_equal(df_auth_limit_wait(l, "10.0.0.1", later), 0);
        df_auth_limit_fail(l, "10.0.0.1", later);
    }
    assert_true(df_auth_limit_wait(l, "10.0.0.1", later) > 0);
    free(l);
}

static void test_full_table_reuses_the_stalest_slot(void **state)
{
    (void)state;
    df_auth_limit *l = malloc(sizeof *l);
    df_auth_limit_init(l, 1, 3600);
    char host[32];
    for (int i = 0; i < DF_AUTH_LIMIT_SLOTS; i++) { /* every slot blocked, host i at time i */
        snprintf(host, sizeof host, "h%d", i);
        df_auth_limit_fail(l, host, (uint64_t)i);
    }
    assert_true(df_auth_limit_wait(l, "h0", DF_AUTH_LIMIT_SLOTS) > 0);
    df_auth_limit_fail(l, "newcomer", DF_AUTH_LIMIT_SLOTS); /* takes h0's slot */
    assert_true(df_auth_limit_wait(l, "newcomer", DF_AUTH_LIMIT_SLOTS) > 0);
    assert_int_equal(df_auth_limit_wait(l, "h0", DF_AUTH_LIMIT_SLOTS), 0); /* forgotten */
    assert_true(df_auth_limit_wait(l, "h1", DF_AUTH_LIMIT_SLOTS) > 0);     /* kept */
    free(l);
}

static void test_access_config_parsing(void **state)
{
    (void)state;
    df_access_config a;
    df_access_config_defaults(&a);
    df_error e;
    assert_false(df_access_restricted(&a));
    assert_int_equal(a.fail_burst, DF_ACCESS_DEFAULT_BURST);
    assert_true(df_access_config_has("allow_uids") && df_access_config_has("key_file"));
    assert_false(df_access_config_has("allow_paths"));
    assert_int_equal(df_access_config_set(&a, "allow_uids", "root, 1000 1000", &e), DF_OK);
    assert_int_equal(a.n_uids, 2); /* root = 0, 1000 once */
    assert_int_equal(a.uids[0], 0);
    assert_int_equal(a.uids[1], 1000);
    assert_int_equal(df_access_config_set(&a, "allow_uids", "1001", &e), DF_OK); /* appends */
    assert_int_equal(a.n_uids, 3);
    df_access_config before = a;
    assert_int_equal(df_access_config_set(&a, "allow_uids", "1002,no-such-user-xyz", &e),
                     DF_EINVAL);
    assert_non_null(strstr(e.msg, "allow_uids: no user 'no-such-user-xyz'"));
    assert_memory_equal(&a, &before, sizeof a); /* untouched */
    assert_int_equal(df_access_config_set(&a, "allow_gids", "-5", &e), DF_EINVAL);
    assert_int_equal(df_access_config_set(&a, "allow_gids", "4294967295", &e), DF_EINVAL);
    assert_int_equal(df_access_config_set(&a, "allow_gids", " , ", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "empty list"));
    char many[1024] = "";
    for (int i = 0; i <= DF_ACCESS_MAX_IDS; i++)
        snprintf(many + strlen(many), sizeof many - strlen(many), "%d,", 2000 + i);
    assert_int_equal(df_access_config_set(&a, "allow_gids", many, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "more than"));
    assert_int_equal(a.n_gids, 0);
    assert_int_equal(df_access_config_set(&a, "auth_fail_burst", "0", &e), DF_EINVAL);
    assert_int_equal(df_access_config_set(&a, "auth_fail_burst", "7", &e), DF_OK);
    assert_int_equal(a.fail_burst, 7);
    assert_int_equal(df_access_config_set(&a, "auth_fail_refill_s", "86401", &e), DF_EINVAL);
    assert_int_equal(df_access_config_set(&a, "key_file", "/etc/deformd/key", &e), DF_OK);
    assert_string_equal(a.key_file, "/etc/deformd/key");
    assert_int_equal(df_access_config_set(&a, "key_file", "none", &e), DF_OK);
    assert_string_equal(a.key_file, "");
}

static void test_peer_allowed_by_uid_or_any_group(void **state)
{
    (void)state;
    df_access_config a;
    df_access_config_defaults(&a);
    df_error e;
    assert_true(df_access_peer_allowed(&a, 1234, 1234, NULL, 0)); /* unrestricted */
    assert_int_equal(df_access_config_set(&a, "allow_uids", "1000", &e), DF_OK);
    assert_int_equal(df_access_config_set(&a, "allow_gids", "50", &e), DF_OK);
    uint32_t groups[] = {7, 50};
    assert_true(df_access_peer_allowed(&a, 1000, 1000, NULL, 0));   /* uid */
    assert_true(df_access_peer_allowed(&a, 1001, 50, NULL, 0));     /* primary group */
    assert_true(df_access_peer_allowed(&a, 1001, 1001, groups, 2)); /* supplementary */
    assert_false(df_access_peer_allowed(&a, 1001, 1001, groups, 1));
    assert_false(df_access_peer_allowed(&a, 0, 0, NULL, 0));        /* root is not special */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_burst_then_refused_then_one_token_per_refill),
        cmocka_unit_test(test_full_table_reuses_the_stalest_slot),
        cmocka_unit_test(test_access_config_parsing),
        cmocka_unit_test(test_peer_allowed_by_uid_or_any_group),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
