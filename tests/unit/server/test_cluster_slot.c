/* Redis Cluster addressing (server/cluster/slot.h): CRC16 and key slots, checked against the
 * CLUSTER KEYSLOT of a real cluster-enabled redis-server (started on a free loopback port;
 * skipped when redis-server is not installed), hash tags, seed lists and -MOVED / -ASK
 * replies. */
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

#include "server/cluster/slot.h"

/* A cluster-enabled redis-server (CLUSTER KEYSLOT needs no slots assigned; see redis_rig.h). */
static int start_redis(void **state)
{
    (void)state;
    return redis_rig_start("/tmp/df-unit-rcslot-XXXXXX", 1);
}

/* The published check value of CRC16/XMODEM, and the spec's hash tag rules. */
static void test_crc16_and_hash_tags(void **state)
{
    (void)state;
    assert_int_equal(df_slot_crc16("123456789", 9), 0x31C3);
    assert_int_equal(df_slot_crc16("", 0), 0);
    /* the tag alone is hashed: a session's keys share one slot */
    int s = df_slot_of_key("deformd:{42}:lease", 18);
    assert_int_equal(df_slot_of_key("deformd:{42}:log", 16), s);
    assert_int_equal(df_slot_of_key("42", 2), s);
    assert_int_equal(df_slot_of_key("{user1000}.following", 21), df_slot_of_key("user1000", 8));
    /* empty tag "{}": the whole key; only the first '{' counts */
    assert_int_equal(df_slot_of_key("foo{}{bar}", 10), df_slot_crc16("foo{}{bar}", 10) & 16383);
    assert_int_equal(df_slot_of_key("foo{{bar}}zap", 13), df_slot_of_key("{bar", 4));
    assert_int_equal(df_slot_of_key("foo{bar}{zap}", 13), df_slot_of_key("bar", 3));
    assert_int_equal(df_slot_of_key("foo{bar", 7), df_slot_crc16("foo{bar", 7) & 16383);
}

/* Every computed slot equals the server's CLUSTER KEYSLOT: deformd's keys of 2000 sessions,
 * its global keys, and 500 pseudo-random binary keys (with '{' and '}' in them). */
static void test_slots_match_cluster_keyslot(void **state)
{
    (void)state;
    if (g_pid <= 0) unit_skip("redis-server is not installed (make deps installs it)");
    redisContext *c = redisConnect("127.0.0.1", g_port);
    assert_true(c && !c->err);
    char key[64];
    uint32_t x = 12345;
    for (int i = 0; i < 2502; i++) {
        size_t len;
        if (i < 2000) len = (size_t)snprintf(key, sizeof key, "deformd:{%d}:%s", i + 1,
                                             i % 2 ? "log" : "lease");
        else if (i < 2500) {
            len = 1 + (size_t)(i % 20);
            for (size_t k = 0; k < len; k++) {
                x = x * 1103515245u + 12345u;
                key[k] = (char)(k % 5 == 2 ? "{}{}x"[x % 5] : (char)(x >> 16));
            }
        } else len = (size_t)snprintf(key, sizeof key, "%s",
                                      i == 2500 ? "deformd:sessions" : "deformd:next_id");
        const char *argv[3] = {"CLUSTER", "KEYSLOT", key};
        size_t lens[3] = {7, 7, len};
        redisReply *rep = redisCommandArgv(c, 3, argv, lens);
        assert_non_null(rep);
        assert_int_equal(rep->type, REDIS_REPLY_INTEGER);
        assert_int_equal(df_slot_of_key(key, len), (int)rep->integer);
        freeReplyObject(rep);
    }
    redisFree(c);
}

static void test_seed_lists(void **state)
{
    (void)state;
    df_redis_node_addr a[DF_REDIS_SEEDS_MAX];
    size_t n = 99;
    df_error e;
    assert_int_equal(df_slot_parse_seeds("redis://h:6379", a, DF_REDIS_SEEDS_MAX, &n, &e), DF_OK);
    assert_int_equal(n, 1);
    assert_string_equal(a[0].host, "h");
    assert_int_equal(a[0].port, 6379);
    assert_int_equal(df_slot_parse_seeds("redis://10.0.0.1:7000, b:7001,redis://c.d:7002", a,
                                         DF_REDIS_SEEDS_MAX, &n, &e), DF_OK);
    assert_int_equal(n, 3);
    assert_string_equal(a[1].host, "b");
    assert_int_equal(a[1].port, 7001);
    assert_string_equal(a[2].host, "c.d");
    assert_int_equal(a[2].port, 7002);
    const char *bad[] = {"h:1", "redis://", "redis://h", "redis://h:", "redis://h:0",
                         "redis://h:65536", "redis://h:1x", "redis://:1", "redis://h:1,",
                         "redis://h:1,,h:2", "redis://h:1,h", "redis://h:-1", "redis://h:+1"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        assert_int_equal(df_slot_parse_seeds(bad[i], a, DF_REDIS_SEEDS_MAX, &n, &e), DF_EINVAL);
        assert_non_null(strstr(e.msg, "cluster"));
    }
    char many[512] = "redis://h:1";
    for (int i = 0; i < DF_REDIS_SEEDS_MAX; i++) strcat(many, ",h:2");
    assert_int_equal(df_slot_parse_seeds(many, a, DF_REDIS_SEEDS_MAX, &n, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "more than"));
}

static void test_redirect_replies(void **state)
{
    (void)state;
    int slot = -1;
    df_redis_node_addr a;
    const char *m = "MOVED 3999 127.0.0.1:6381";
    assert_int_equal(df_slot_parse_redirect(m, strlen(m), &slot, &a), DF_REDIR_MOVED);
    assert_int_equal(slot, 3999);
    assert_string_equal(a.host, "127.0.0.1");
    assert_int_equal(a.port, 6381);
    const char *k = "ASK 16383 node-b:7002";
    assert_int_equal(df_slot_parse_redirect(k, strlen(k), &slot, &a), DF_REDIR_ASK);
    assert_int_equal(slot, 16383);
    assert_string_equal(a.host, "node-b");
    assert_int_equal(a.port, 7002);
    const char *nohost = "MOVED 0 :7003"; /* host unknown: the caller's */
    assert_int_equal(df_slot_parse_redirect(nohost, strlen(nohost), &slot, &a), DF_REDIR_MOVED);
    assert_string_equal(a.host, "");
    assert_int_equal(a.port, 7003);
    const char *none[] = {"ERR unknown command", "FENCED", "MOVED", "MOVED 16384 h:1",
                          "MOVED x h:1", "MOVED 12 h", "MOVED 12 h:0", "ASK 1 h:99999",
                          "MOVED 12  h:1", "CLUSTERDOWN The cluster is down", "TRYAGAIN x"};
    for (size_t i = 0; i < sizeof none / sizeof *none; i++) {
        slot = -7;
        assert_int_equal(df_slot_parse_redirect(none[i], strlen(none[i]), &slot, &a),
                         DF_REDIR_NONE);
        assert_int_equal(slot, -7);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc16_and_hash_tags),
        cmocka_unit_test(test_slots_match_cluster_keyslot),
        cmocka_unit_test(test_seed_lists),
        cmocka_unit_test(test_redirect_replies),
    };
    return cmocka_run_group_tests(tests, start_redis, stop_redis);
}
