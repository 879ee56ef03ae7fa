/* rlog.c — the replicated log in Redis: fenced writes and reads (see rlog.h). */
#include "server/cluster/rlog.h"

#include <hiredis/hiredis.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/cluster/lease.h"

/* KEYS lease, log; ARGV token, version, row */
static const char k_append[] =
    "if redis.call('GET', KEYS[1]) ~= ARGV[1] then return redis.error_reply('FENCED') end\n"
    "return redis.call('XADD', KEYS[2], '*', 'v', ARGV[2], 'r', ARGV[3])\n";

/* KEYS lease, snap, log[, index]; ARGV token, snap, id, info. Without the index key (Redis
 * Cluster: the index is in another slot) the caller sets the index entry after it. */
static const char k_snapshot[] =
    "if redis.call('GET', KEYS[1]) ~= ARGV[1] then return redis.error_reply('FENCED') end\n"
    "redis.call('SET', KEYS[2], ARGV[2])\n"
    "redis.call('DEL', KEYS[3])\n"
    "if KEYS[4] then redis.call('HSET', KEYS[4], ARGV[3], ARGV[4]) end\n"
    "return 1\n";

/* KEYS lease, snap, log, epoch[, index]; ARGV token, id. Index as k_snapshot. */
static const char k_close[] =
    "if redis.call('GET', KEYS[1]) ~= ARGV[1] then return redis.error_reply('FENCED') end\n"
    "redis.call('DEL', KEYS[1], KEYS[2], KEYS[3], KEYS[4])\n"
    "if KEYS[5] then redis.call('HDEL', KEYS[5], ARGV[2]) end\n"
    "return 1\n";

#define INDEX_KEY "deformd:sessions"

/* The reply of a fenced script: DF_OK, DF_ESTATE (FENCED) or DF_EINTERNAL. Frees rep. */
static int fenced_reply(redisReply *rep, uint64_t id, const char *what, df_error *err)
{
    int rc = DF_OK;
    if (rep->type == REDIS_REPLY_ERROR && strstr(rep->str, "FENCED"))
        rc = df_error_set(err, DF_ESTATE, "cluster: session %" PRIu64 ": %s refused: fenced "
                          "(its lease expired or another daemon took it over)", id, what);
    else if (rep->type == REDIS_REPLY_ERROR)
        rc = df_error_set(err, DF_EINTERNAL, "cluster redis: session %" PRIu64 ": %s: %s", id,
                          what, rep->str);
    df_redis_reply_free(rep);
    return rc;
}

/* HSET INDEX_KEY sid info / HDEL INDEX_KEY sid (info NULL): the index entry written apart
 * from the session's fenced script, in a Redis Cluster (its own slot). Errors: DF_EIO,
 * DF_EINTERNAL (an error reply). */
static int index_cmd(df_redis *r, const char *cmd, const char *sid, const char *info,
                     df_error *err)
{
    redisReply *rep;
    int rc = info ? df_redis_cmdv(r, &rep, err, 4, cmd, INDEX_KEY, sid, info)
                  : df_redis_cmdv(r, &rep, err, 3, cmd, INDEX_KEY, sid);
    if (rc != DF_OK) return rc;
    if (rep->type == REDIS_REPLY_ERROR)
        rc = df_error_set(err, DF_EINTERNAL, "cluster redis: %s %s %s: %s", cmd, INDEX_KEY, sid,
                          rep->str);
    df_redis_reply_free(rep);
    return rc;
}

int df_rlog_append(df_redis *r, uint64_t id, const char *token, uint64_t version,
                     const uint8_t *row, size_t len, df_error *err)
{
    char kl[64], kg[64], v[24];
    df_lease_key(id, "lease", kl, sizeof kl);
    df_lease_key(id, "log", kg, sizeof kg);
    snprintf(v, sizeof v, "%" PRIu64, version);
    const char *argv[8] = {"EVAL", k_append, "2", kl, kg, token, v, (const char *)row};
    size_t lens[8] = {4, strlen(k_append), 1, strlen(kl), strlen(kg), strlen(token), strlen(v),
                      len};
    redisReply *rep;
    int rc = df_redis_cmd(r, 8, argv, lens, &rep, err);
    return rc != DF_OK ? rc : fenced_reply(rep, id, "appending a change", err);
}

int df_rlog_snapshot(df_redis *r, uint64_t id, const char *token, const char *info,
                       const uint8_t *snap, size_t len, df_error *err)
{
    char kl[64], ks[64], kg[64], sid[24];
    df_lease_key(id, "lease", kl, sizeof kl);
    df_lease_key(id, "snap", ks, sizeof ks);
    df_lease_key(id, "log", kg, sizeof kg);
    snprintf(sid, sizeof sid, "%" PRIu64, id);
    /* one Redis: the index entry in the same script; a Redis Cluster: after it (other slot) */
    int split = df_redis_is_cluster(r);
    const char *argv[11] = {"EVAL", k_snapshot, "4", kl, ks, kg, INDEX_KEY, token,
                            (const char *)snap, sid, info};
    size_t lens[11] = {4, strlen(k_snapshot), 1, strlen(kl), strlen(ks), strlen(kg),
                       strlen(INDEX_KEY), strlen(token), len, strlen(sid), strlen(info)};
    if (split) { /* numkeys 3, no index key */
        argv[2] = "3";
        memmove(&argv[6], &argv[7], 4 * sizeof *argv);
        memmove(&lens[6], &lens[7], 4 * sizeof *lens);
    }
    redisReply *rep;
    int rc = df_redis_cmd(r, split ? 10 : 11, argv, lens, &rep, err);
    if (rc == DF_OK) rc = fenced_reply(rep, id, "writing a snapshot", err);
    if (rc == DF_OK && split) rc = index_cmd(r, "HSET", sid, info, err);
    return rc;
}

int df_rlog_close(df_redis *r, uint64_t id, const char *token, df_error *err)
{
    char kl[64], ks[64], kg[64], ke[64], sid[24];
    df_lease_key(id, "lease", kl, sizeof kl);
    df_lease_key(id, "snap", ks, sizeof ks);
    df_lease_key(id, "log", kg, sizeof kg);
    df_lease_key(id, "epoch", ke, sizeof ke);
    snprintf(sid, sizeof sid, "%" PRIu64, id);
    redisReply *rep;
    int split = df_redis_is_cluster(r);
    int rc = split ? df_redis_cmdv(r, &rep, err, 9, "EVAL", k_close, "4", kl, ks, kg, ke,
                                   token, sid)
                   : df_redis_cmdv(r, &rep, err, 10, "EVAL", k_close, "5", kl, ks, kg, ke,
                                   INDEX_KEY, token, sid);
    if (rc == DF_OK) rc = fenced_reply(rep, id, "closing", err);
    if (rc == DF_OK && split) rc = index_cmd(r, "HDEL", sid, NULL, err);
    return rc;
}

void df_rlog_entries_free(df_rlog_entry *e, size_t n)
{
    for (size_t i = 0; e && i < n; i++) free(e[i].row);
    free(e);
}

/* One XRANGE entry [id, [field, value, ...]] into *out. */
static int read_entry(const redisReply *x, df_rlog_entry *out)
{
    if (x->type != REDIS_REPLY_ARRAY || x->elements != 2 ||
        x->element[1]->type != REDIS_REPLY_ARRAY)
        return DF_EINTERNAL;
    const redisReply *f = x->element[1];
    int have_v = 0;
    for (size_t k = 0; k + 1 < f->elements; k += 2) {
        const redisReply *key = f->element[k], *val = f->element[k + 1];
        if (key->type != REDIS_REPLY_STRING || val->type != REDIS_REPLY_STRING) continue;
        if (!strcmp(key->str, "v")) {
            out->version = strtoull(val->str, NULL, 10);
            have_v = 1;
        } else if (!strcmp(key->str, "r")) {
            if (!(out->row = malloc(val->len ? val->len : 1))) return DF_ENOMEM;
            memcpy(out->row, val->str, val->len);
            out->len = val->len;
        }
    }
    return have_v && out->row ? DF_OK : DF_EINTERNAL;
}

int df_rlog_read(df_redis *r, uint64_t id, uint8_t **snap, size_t *snap_len,
                   df_rlog_entry **entries, size_t *n, df_error *err)
{
    char ks[64], kg[64];
    df_lease_key(id, "snap", ks, sizeof ks);
    df_lease_key(id, "log", kg, sizeof kg);
    *snap = NULL;
    *snap_len = 0;
    *entries = NULL;
    *n = 0;
    redisReply *rep;
    int rc = df_redis_cmdv(r, &rep, err, 2, "GET", ks);
    if (rc != DF_OK) return rc;
    if (rep->type == REDIS_REPLY_NIL) {
        df_redis_reply_free(rep);
        return DF_OK;
    }
    if (rep->type != REDIS_REPLY_STRING || !(*snap = malloc(rep->len ? rep->len : 1))) {
        rc = rep->type != REDIS_REPLY_STRING
                 ? df_error_set(err, DF_EINTERNAL, "cluster redis: session %" PRIu64
                                ": snapshot of an unexpected type", id)
                 : df_error_set(err, DF_ENOMEM, "out of memory");
        df_redis_reply_free(rep);
        return rc;
    }
    memcpy(*snap, rep->str, rep->len);
    *snap_len = rep->len;
    df_redis_reply_free(rep);
    if ((rc = df_redis_cmdv(r, &rep, err, 4, "XRANGE", kg, "-", "+")) != DF_OK) goto fail;
    if (rep->type != REDIS_REPLY_ARRAY) {
        df_redis_reply_free(rep);
        rc = df_error_set(err, DF_EINTERNAL, "cluster redis: session %" PRIu64 ": log of an "
                          "unexpected type", id);
        goto fail;
    }
    *entries = calloc(rep->elements ? rep->elements : 1, sizeof **entries);
    if (!*entries) rc = df_error_set(err, DF_ENOMEM, "out of memory");
    for (size_t i = 0; rc == DF_OK && i < rep->elements; i++, (*n)++)
        if ((rc = read_entry(rep->element[i], &(*entries)[i])) != DF_OK) {
            (*n)++;
            df_error_set(err, rc, "cluster redis: session %" PRIu64 ": log entry %zu "
                         "malformed", id, i);
        }
    df_redis_reply_free(rep);
    if (rc == DF_OK) return DF_OK;
fail:
    free(*snap);
    *snap = NULL;
    df_rlog_entries_free(*entries, *n);
    *entries = NULL;
    *n = 0;
    return rc;
}

int df_rlog_new_id(df_redis *r, uint64_t *id, df_error *err)
{
    redisReply *rep;
    int rc = df_redis_cmdv(r, &rep, err, 2, "INCR", "deformd:next_id");
    if (rc != DF_OK) return rc;
    if (rep->type != REDIS_REPLY_INTEGER || rep->integer < 1) {
        df_redis_reply_free(rep);
        return df_error_set(err, DF_EINTERNAL, "cluster redis: INCR deformd:next_id: "
                            "unexpected reply");
    }
    *id = (uint64_t)rep->integer;
    df_redis_reply_free(rep);
    return DF_OK;
}
