/* redis.c — the synchronous Redis connection (see redis.h). */
#include "server/cluster/redis.h"

#include <hiredis/hiredis.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

struct df_redis {
    char host[256];
    int port;
    char addr[300];
    redisContext *ctx;
};

int df_redis_new(const char *url, df_redis **out, df_error *err)
{
    const char *p = strncmp(url, "redis://", 8) == 0 ? url + 8 : NULL;
    const char *colon = p ? strrchr(p, ':') : NULL;
    char *end = NULL;
    long port = colon ? strtol(colon + 1, &end, 10) : 0;
    if (!p || !colon || colon == p || (size_t)(colon - p) >= 256 || !end || *end || port < 1 ||
        port > 65535)
        return df_error_set(err, DF_EINVAL, "cluster: '%s' is not redis://HOST:PORT", url);
    df_redis *r = calloc(1, sizeof *r);
    if (!r) return df_error_set(err, DF_ENOMEM, "out of memory");
    memcpy(r->host, p, (size_t)(colon - p));
    r->port = (int)port;
    snprintf(r->addr, sizeof r->addr, "%s:%d", r->host, r->port);
    *out = r;
    return DF_OK;
}

void df_redis_free(df_redis *r)
{
    if (!r) return;
    if (r->ctx) redisFree(r->ctx);
    free(r);
}

const char *df_redis_addr(const df_redis *r)
{
    return r->addr;
}

static int connect_now(df_redis *r, df_error *err)
{
    if (r->ctx) return DF_OK;
    struct timeval tv = {DF_REDIS_TIMEOUT_MS / 1000, (DF_REDIS_TIMEOUT_MS % 1000) * 1000};
    redisContext *c = redisConnectWithTimeout(r->host, r->port, tv);
    if (!c || c->err) {
        df_error_set(err, DF_EIO, "cluster redis %s: cannot connect: %s", r->addr,
                     c ? c->errstr : "out of memory");
        if (c) redisFree(c);
        return DF_EIO;
    }
    redisSetTimeout(c, tv);
    r->ctx = c;
    return DF_OK;
}

int df_redis_cmd(df_redis *r, int argc, const char **argv, const size_t *argvlen,
                 redisReply **out, df_error *err)
{
    *out = NULL;
    int rc = connect_now(r, err);
    if (rc != DF_OK) return rc;
    redisReply *rep = redisCommandArgv(r->ctx, argc, argv, argvlen);
    if (!rep) {
        df_error_set(err, DF_EIO, "cluster redis %s: %s: %s", r->addr, argv[0],
                     r->ctx->errstr[0] ? r->ctx->errstr : "connection lost");
        redisFree(r->ctx); /* reconnected at the next command */
        r->ctx = NULL;
        return DF_EIO;
    }
    *out = rep;
    return DF_OK;
}

int df_redis_pipeline(df_redis *r, size_t n, const int *argc, const char *const *const *argv,
                      const size_t *const *argvlen, redisReply **out, df_error *err)
{
    for (size_t i = 0; i < n; i++) out[i] = NULL;
    int rc = connect_now(r, err);
    if (rc != DF_OK) return rc;
    for (size_t i = 0; i < n && rc == DF_OK; i++)
        if (redisAppendCommandArgv(r->ctx, argc[i], (const char **)argv[i], argvlen[i]) !=
            REDIS_OK)
            rc = DF_EIO;
    for (size_t i = 0; i < n && rc == DF_OK; i++) {
        void *rep = NULL;
        if (redisGetReply(r->ctx, &rep) != REDIS_OK || !rep) rc = DF_EIO;
        out[i] = rep;
    }
    if (rc != DF_OK) {
        df_error_set(err, DF_EIO, "cluster redis %s: pipeline of %zu: %s", r->addr, n,
                     r->ctx->errstr[0] ? r->ctx->errstr : "connection lost");
        for (size_t i = 0; i < n; i++) {
            df_redis_reply_free(out[i]);
            out[i] = NULL;
        }
        redisFree(r->ctx);
        r->ctx = NULL;
    }
    return rc;
}

int df_redis_cmdv(df_redis *r, redisReply **out, df_error *err, int argc, ...)
{
    const char *argv[16];
    size_t len[16];
    if (argc > 16) return df_error_set(err, DF_EINVAL, "redis: too many arguments");
    va_list ap;
    va_start(ap, argc);
    for (int i = 0; i < argc; i++) {
        argv[i] = va_arg(ap, const char *);
        len[i] = strlen(argv[i]);
    }
    va_end(ap);
    return df_redis_cmd(r, argc, argv, len, out, err);
}

void df_redis_reply_free(redisReply *rep)
{
    if (rep) freeReplyObject(rep);
}
