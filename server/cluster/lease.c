/* lease.c — session leases and fencing tokens in Redis (see lease.h). */
#include "server/cluster/lease.h"

#include <hiredis/hiredis.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* KEYS lease, epoch; ARGV addr, ttl. {1, value} taken, {0, holder} refused. */
static const char k_acquire[] =
    "local v = redis.call('GET', KEYS[1])\n"
    "if v and string.sub(v, string.find(v, ' ') + 1) ~= ARGV[1] then return {0, v} end\n"
    "local e = redis.call('INCR', KEYS[2])\n"
    "v = e .. ' ' .. ARGV[1]\n"
    "redis.call('SET', KEYS[1], v, 'PX', ARGV[2])\n"
    "return {1, v}\n";

/* KEYS lease; ARGV value, ttl. 1 renewed, 0 lost. */
static const char k_renew[] =
    "if redis.call('GET', KEYS[1]) == ARGV[1] then\n"
    "  redis.call('PEXPIRE', KEYS[1], ARGV[2]) return 1 end\n"
    "return 0\n";

void df_lease_key(uint64_t id, const char *what, char *buf, size_t cap)
{
    snprintf(buf, cap, "deformd:{%" PRIu64 "}:%s", id, what);
}

static int bad_reply(redisReply *rep, const char *what, df_error *err)
{
    df_error_set(err, DF_EINTERNAL, "cluster redis: %s: unexpected reply%s%s", what,
                 rep && rep->type == REDIS_REPLY_ERROR ? ": " : "",
                 rep && rep->type == REDIS_REPLY_ERROR ? rep->str : "");
    df_redis_reply_free(rep);
    return DF_EINTERNAL;
}

int df_lease_acquire(df_redis *r, uint64_t id, const char *addr, int ttl_ms, char *value,
                     df_error *err)
{
    char kl[64], ke[64], ttl[16];
    df_lease_key(id, "lease", kl, sizeof kl);
    df_lease_key(id, "epoch", ke, sizeof ke);
    snprintf(ttl, sizeof ttl, "%d", ttl_ms);
    redisReply *rep;
    int rc = df_redis_cmdv(r, &rep, err, 7, "EVAL", k_acquire, "2", kl, ke, addr, ttl);
    if (rc != DF_OK) return rc;
    if (rep->type != REDIS_REPLY_ARRAY || rep->elements != 2 ||
        rep->element[0]->type != REDIS_REPLY_INTEGER || rep->element[1]->type != REDIS_REPLY_STRING)
        return bad_reply(rep, "lease acquire", err);
    int got = (int)rep->element[0]->integer;
    snprintf(value, DF_LEASE_VALUE_MAX, "%s", rep->element[1]->str);
    df_redis_reply_free(rep);
    return got ? 1 : 0;
}

int df_lease_renew(df_redis *r, uint64_t id, const char *value, int ttl_ms, df_error *err)
{
    char kl[64], ttl[16];
    df_lease_key(id, "lease", kl, sizeof kl);
    snprintf(ttl, sizeof ttl, "%d", ttl_ms);
    redisReply *rep;
    int rc = df_redis_cmdv(r, &rep, err, 6, "EVAL", k_renew, "1", kl, value, ttl);
    if (rc != DF_OK) return rc;
    if (rep->type != REDIS_REPLY_INTEGER) return bad_reply(rep, "lease renew", err);
    int ok = rep->integer == 1;
    df_redis_reply_free(rep);
    return ok;
}

int df_lease_renew_many(df_redis *r, size_t n, const uint64_t *ids, const char *const *tokens,
                        int ttl_ms, int *ok, df_error *err)
{
    if (!n) return DF_OK;
    char ttl[16];
    snprintf(ttl, sizeof ttl, "%d", ttl_ms);
    char (*keys)[64] = malloc(n * sizeof *keys);
    const char **args = malloc(6 * n * sizeof *args);
    size_t *lens = malloc(6 * n * sizeof *lens);
    const char *const **argv = malloc(n * sizeof *argv);
    const size_t **argvlen = malloc(n * sizeof *argvlen);
    int *argc = malloc(n * sizeof *argc);
    redisReply **rep = malloc(n * sizeof *rep);
    int rc = DF_OK;
    if (!keys || !args || !lens || !argv || !argvlen || !argc || !rep)
        rc = df_error_set(err, DF_ENOMEM, "out of memory");
    for (size_t i = 0; rc == DF_OK && i < n; i++) {
        df_lease_key(ids[i], "lease", keys[i], sizeof keys[i]);
        const char *a[6] = {"EVAL", k_renew, "1", keys[i], tokens[i], ttl};
        for (int k = 0; k < 6; k++) {
            args[6 * i + k] = a[k];
            lens[6 * i + k] = strlen(a[k]);
        }
        argv[i] = &args[6 * i];
        argvlen[i] = &lens[6 * i];
        argc[i] = 6;
    }
    if (rc == DF_OK) rc = df_redis_pipeline(r, n, argc, argv, argvlen, rep, err);
    for (size_t i = 0; rc == DF_OK && i < n; i++) {
        ok[i] = rep[i]->type == REDIS_REPLY_INTEGER && rep[i]->integer == 1;
        df_redis_reply_free(rep[i]);
    }
    free(keys);
    free(args);
    free(lens);
    free(argv);
    free(argvlen);
    free(argc);
    free(rep);
    return rc;
}

int df_lease_get(df_redis *r, uint64_t id, char *value, df_error *err)
{
    char kl[64];
    df_lease_key(id, "lease", kl, sizeof kl);
    redisReply *rep;
    int rc = df_redis_cmdv(r, &rep, err, 2, "GET", kl);
    if (rc != DF_OK) return rc;
    if (rep->type == REDIS_REPLY_NIL) {
        df_redis_reply_free(rep);
        value[0] = '\0';
        return 0;
    }
    if (rep->type != REDIS_REPLY_STRING) return bad_reply(rep, "lease get", err);
    snprintf(value, DF_LEASE_VALUE_MAX, "%s", rep->str);
    df_redis_reply_free(rep);
    return 1;
}

int df_lease_parse(const char *value, uint64_t *epoch, const char **addr, df_error *err)
{
    char *end = NULL;
    unsigned long long e = strtoull(value, &end, 10);
    if (!end || end == value || *end != ' ' || !end[1])
        return df_error_set(err, DF_EFORMAT, "cluster: malformed lease value '%s'", value);
    *epoch = e;
    *addr = end + 1;
    return DF_OK;
}
