/* Cluster mode's leases and fenced writes (server/cluster/lease.h, rlog.h) against a real
 * redis-server started on a free loopback port (skipped when redis-server is not installed):
 * acquire / renew / expiry with epochs, and the Lua fencing of appends, snapshots and closes. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "../unit_skip.h"
#include "redis_rig.h"

#include <hiredis/hiredis.h>

#include "server/cluster/lease.h"
#include "server/cluster/redis.h"
#include "server/cluster/rlog.h"

static char g_url[64];

/* redis-server on a free port (no persistence, see redis_rig.h); g_url its redis:// URL. */
static int start_redis(void **state)
{
    (void)state;
    int rc = redis_rig_start("/tmp/df-unit-redis-XXXXXX", 0);
    if (g_pid > 0) snprintf(g_url, sizeof g_url, "redis://127.0.0.1:%d", g_port);
    return rc;
}

static df_redis *connect_or_skip(void)
{
    if (g_pid <= 0) unit_skip("redis-server is not installed (make deps installs it)");
    df_redis *r;
    assert_int_equal(df_redis_new(g_url, &r, NULL), DF_OK);
    return r;
}

static long long xlen(df_redis *r, uint64_t id)
{
    char k[64];
    df_lease_key(id, "log", k, sizeof k);
    struct redisReply *rep;
    assert_int_equal(df_redis_cmdv(r, &rep, NULL, 2, "XLEN", k), DF_OK);
    assert_int_equal(rep->type, REDIS_REPLY_INTEGER);
    long long n = rep->integer;
    df_redis_reply_free(rep);
    return n;
}

static void test_acquire_renew_and_epochs(void **state)
{
    (void)state;
    df_redis *r = connect_or_skip();
    char a[DF_LEASE_VALUE_MAX], b[DF_LEASE_VALUE_MAX];
    assert_int_equal(df_lease_acquire(r, 101, "127.0.0.1:1111", 10000, a, NULL), 1);
    assert_string_equal(a, "1 127.0.0.1:1111");
    /* another daemon is refused and told the holder */
    assert_int_equal(df_lease_acquire(r, 101, "127.0.0.1:2222", 10000, b, NULL), 0);
    assert_string_equal(b, a);
    assert_int_equal(df_lease_renew(r, 101, a, 10000, NULL), 1);
    assert_int_equal(df_lease_renew(r, 101, "1 127.0.0.1:2222", 10000, NULL), 0);
    /* the holder's own address (a restarted daemon) takes it back with a new epoch */
    assert_int_equal(df_lease_acquire(r, 101, "127.0.0.1:1111", 10000, b, NULL), 1);
    assert_string_equal(b, "2 127.0.0.1:1111");
    assert_int_equal(df_lease_renew(r, 101, a, 10000, NULL), 0); /* the old token is stale */
    uint64_t epoch;
    const char *addr;
    assert_int_equal(df_lease_parse(b, &epoch, &addr, NULL), DF_OK);
    assert_int_equal(epoch, 2);
    assert_string_equal(addr, "127.0.0.1:1111");
    df_error e;
    assert_int_equal(df_lease_parse("x 127.0.0.1:1", &epoch, &addr, &e), DF_EFORMAT);
    assert_int_equal(df_lease_parse("3", &epoch, &addr, &e), DF_EFORMAT);
    df_redis_free(r);
}

static void test_renew_many_in_one_round_trip(void **state)
{
    (void)state;
    df_redis *r = connect_or_skip();
    char t[3][DF_LEASE_VALUE_MAX];
    uint64_t ids[3] = {401, 402, 403};
    for (int i = 0; i < 3; i++)
        assert_int_equal(df_lease_acquire(r, ids[i], "127.0.0.1:1111", 10000, t[i], NULL), 1);
    char other[DF_LEASE_VALUE_MAX];
    assert_int_equal(df_lease_acquire(r, 402, "127.0.0.1:1111", 10000, other, NULL), 1);
    const char *tokens[3] = {t[0], t[1], t[2]}; /* t[1] is stale now */
    int ok[3] = {-1, -1, -1};
    assert_int_equal(df_lease_renew_many(r, 3, ids, tokens, 10000, ok, NULL), DF_OK);
    assert_int_equal(ok[0], 1);
    assert_int_equal(ok[1], 0);
    assert_int_equal(ok[2], 1);
    assert_int_equal(df_lease_renew_many(r, 0, ids, tokens, 10000, ok, NULL), DF_OK);
    df_redis_free(r);
}

static void test_fenced_append_after_expiry(void **state)
{
    (void)state;
    df_redis *r = connect_or_skip();
    char a[DF_LEASE_VALUE_MAX], b[DF_LEASE_VALUE_MAX], v[DF_LEASE_VALUE_MAX];
    const uint8_t row[5] = {1, 0, 2, 0, 3}; /* binary-safe */
    assert_int_equal(df_lease_acquire(r, 202, "127.0.0.1:1111", 300, a, NULL), 1);
    assert_int_equal(df_rlog_append(r, 202, a, 1, row, sizeof row, NULL), DF_OK);
    /* B polls for the lease: granted once A's 300 ms ttl passed (A does not renew) */
    double deadline = now_s() + 10;
    int got = 0;
    while (!got && now_s() < deadline) {
        got = df_lease_acquire(r, 202, "127.0.0.1:2222", 10000, b, NULL);
        assert_true(got >= 0);
        if (!got) usleep(20000);
    }
    assert_int_equal(got, 1);
    assert_string_equal(b, "2 127.0.0.1:2222");
    assert_int_equal(df_lease_get(r, 202, v, NULL), 1);
    assert_string_equal(v, b);
    /* the stale owner A cannot append, renew, snapshot or close any more */
    df_error e;
    assert_int_equal(df_rlog_append(r, 202, a, 2, row, sizeof row, &e), DF_ESTATE);
    assert_non_null(strstr(e.msg, "fenced"));
    assert_int_equal(df_lease_renew(r, 202, a, 10000, NULL), 0);
    assert_int_equal(df_rlog_snapshot(r, 202, a, "s", row, sizeof row, &e), DF_ESTATE);
    assert_int_equal(df_rlog_close(r, 202, a, &e), DF_ESTATE);
    assert_int_equal(xlen(r, 202), 1);
    assert_int_equal(df_rlog_append(r, 202, b, 2, row, 3, NULL), DF_OK);
    assert_int_equal(xlen(r, 202), 2);
    df_redis_free(r);
}

static void test_snapshot_read_and_close(void **state)
{
    (void)state;
    df_redis *r = connect_or_skip();
    char t[DF_LEASE_VALUE_MAX];
    uint8_t snap[300];
    for (size_t i = 0; i < sizeof snap; i++) snap[i] = (uint8_t)(i * 7);
    assert_int_equal(df_lease_acquire(r, 303, "127.0.0.1:1111", 10000, t, NULL), 1);
    assert_int_equal(df_rlog_snapshot(r, 303, t, "name", snap, 100, NULL), DF_OK);
    for (uint64_t v = 1; v <= 3; v++)
        assert_int_equal(df_rlog_append(r, 303, t, v, snap + v, (size_t)v, NULL), DF_OK);
    uint8_t *s;
    size_t sl, n;
    df_rlog_entry *e;
    assert_int_equal(df_rlog_read(r, 303, &s, &sl, &e, &n, NULL), DF_OK);
    assert_int_equal(sl, 100);
    assert_memory_equal(s, snap, 100);
    assert_int_equal(n, 3);
    for (size_t i = 0; i < n; i++) {
        assert_int_equal(e[i].version, i + 1);
        assert_int_equal(e[i].len, i + 1);
        assert_memory_equal(e[i].row, snap + i + 1, i + 1);
    }
    free(s);
    df_rlog_entries_free(e, n);
    /* a snapshot holds everything so far: the log is emptied */
    assert_int_equal(df_rlog_snapshot(r, 303, t, "name", snap, sizeof snap, NULL), DF_OK);
    assert_int_equal(df_rlog_read(r, 303, &s, &sl, &e, &n, NULL), DF_OK);
    assert_int_equal(sl, sizeof snap);
    assert_int_equal(n, 0);
    free(s);
    df_rlog_entries_free(e, n);
    assert_int_equal(df_rlog_close(r, 303, t, NULL), DF_OK);
    assert_int_equal(df_rlog_read(r, 303, &s, &sl, &e, &n, NULL), DF_OK);
    assert_null(s);
    assert_int_equal(df_lease_get(r, 303, t, NULL), 0);
    uint64_t id1, id2;
    assert_int_equal(df_rlog_new_id(r, &id1, NULL), DF_OK);
    assert_int_equal(df_rlog_new_id(r, &id2, NULL), DF_OK);
    assert_int_equal(id2, id1 + 1);
    df_redis_free(r);
}

static void test_bad_url_and_unreachable_server(void **state)
{
    (void)state;
    df_redis *r;
    df_error e;
    assert_int_equal(df_redis_new("http://x:1", &r, &e), DF_EINVAL);
    assert_int_equal(df_redis_new("redis://host", &r, &e), DF_EINVAL);
    assert_int_equal(df_redis_new("redis://host:0", &r, &e), DF_EINVAL);
    int port = free_port();
    char url[64];
    snprintf(url, sizeof url, "redis://127.0.0.1:%d", port);
    assert_int_equal(df_redis_new(url, &r, NULL), DF_OK);
    char t[DF_LEASE_VALUE_MAX];
    assert_int_equal(df_lease_acquire(r, 1, "127.0.0.1:1", 1000, t, &e), DF_EIO);
    assert_non_null(strstr(e.msg, url + 8));
    df_redis_free(r);
}

/* A plain Redis (cluster support disabled) given as one seed is used as it is (the one-node
 * mode: not a cluster); given with other seeds it is refused with a clear error. A dead first
 * seed is skipped. */
static void test_seed_list_of_a_plain_redis(void **state)
{
    (void)state;
    df_redis *r = connect_or_skip();
    struct redisReply *rep = NULL;
    df_error e;
    assert_int_equal(df_redis_cmdv(r, &rep, &e, 1, "PING"), DF_OK);
    df_redis_reply_free(rep);
    assert_int_equal(df_redis_is_cluster(r), 0);
    df_redis_free(r);
    char url[160];
    snprintf(url, sizeof url, "%s,127.0.0.1:%d", g_url, g_port);
    assert_int_equal(df_redis_new(url, &r, NULL), DF_OK);
    assert_int_equal(df_redis_cmdv(r, &rep, &e, 1, "PING"), DF_EINVAL);
    assert_null(rep);
    assert_non_null(strstr(e.msg, "not a Redis Cluster node"));
    df_redis_free(r);
    int dead = free_port();
    snprintf(url, sizeof url, "redis://127.0.0.1:%d,127.0.0.1:%d", dead, g_port);
    assert_int_equal(df_redis_new(url, &r, NULL), DF_OK);
    assert_int_equal(df_redis_cmdv(r, &rep, &e, 1, "PING"), DF_EINVAL); /* still 2 seeds */
    df_redis_free(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_acquire_renew_and_epochs),
        cmocka_unit_test(test_renew_many_in_one_round_trip),
        cmocka_unit_test(test_fenced_append_after_expiry),
        cmocka_unit_test(test_snapshot_read_and_close),
        cmocka_unit_test(test_bad_url_and_unreachable_server),
        cmocka_unit_test(test_seed_list_of_a_plain_redis),
    };
    return cmocka_run_group_tests(tests, start_redis, stop_redis);
}
