/* redis.c — the synchronous Redis connections and their slot routing (see redis.h). */
#include "server/cluster/redis.h"

#include <hiredis/hiredis.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "server/cluster/slot.h"

#define NODES_MAX 64     /* masters (and moved-to nodes) known at once */
#define REDIRECTS_MAX 5  /* MOVED / ASK hops of one command */

enum { MODE_UNKNOWN = 0, MODE_SINGLE, MODE_CLUSTER };

typedef struct node {
    df_redis_node_addr a;
    redisContext *ctx;
} node;

struct df_redis {
    df_redis_node_addr seeds[DF_REDIS_SEEDS_MAX];
    size_t n_seeds;
    char addr[300];
    int mode;
    node nodes[NODES_MAX];
    size_t n_nodes;
    int16_t slot_node[DF_SLOTS]; /* index into nodes, -1: unknown */
    int map_stale;               /* reload CLUSTER SLOTS before the next command */
};

int df_redis_new(const char *url, df_redis **out, df_error *err)
{
    df_redis *r = calloc(1, sizeof *r);
    if (!r) return df_error_set(err, DF_ENOMEM, "out of memory");
    int rc = df_slot_parse_seeds(url, r->seeds, DF_REDIS_SEEDS_MAX, &r->n_seeds, err);
    if (rc != DF_OK) {
        free(r);
        return rc;
    }
    size_t off = 0;
    for (size_t i = 0; i < r->n_seeds && off < sizeof r->addr; i++)
        off += (size_t)snprintf(r->addr + off, sizeof r->addr - off, "%s%s:%d", i ? "," : "",
                                r->seeds[i].host, r->seeds[i].port);
    memset(r->slot_node, 0xff, sizeof r->slot_node);
    *out = r;
    return DF_OK;
}

static void drop_conn(node *n)
{
    if (n->ctx) redisFree(n->ctx);
    n->ctx = NULL;
}

void df_redis_free(df_redis *r)
{
    if (!r) return;
    for (size_t i = 0; i < r->n_nodes; i++) drop_conn(&r->nodes[i]);
    free(r);
}

const char *df_redis_addr(const df_redis *r)
{
    return r->addr;
}

int df_redis_is_cluster(const df_redis *r)
{
    return r->mode == MODE_CLUSTER;
}

/* The index of node a in r->nodes, added when new; -1 when the table is full. */
static int node_index(df_redis *r, const df_redis_node_addr *a)
{
    for (size_t i = 0; i < r->n_nodes; i++)
        if (r->nodes[i].a.port == a->port && !strcmp(r->nodes[i].a.host, a->host))
            return (int)i;
    if (r->n_nodes == NODES_MAX) return -1;
    r->nodes[r->n_nodes].a = *a;
    r->nodes[r->n_nodes].ctx = NULL;
    return (int)r->n_nodes++;
}

static int connect_node(node *n, df_error *err)
{
    if (n->ctx) return DF_OK;
    struct timeval tv = {DF_REDIS_TIMEOUT_MS / 1000, (DF_REDIS_TIMEOUT_MS % 1000) * 1000};
    redisContext *c = redisConnectWithTimeout(n->a.host, n->a.port, tv);
    if (!c || c->err) {
        df_error_set(err, DF_EIO, "cluster redis %s:%d: cannot connect: %s", n->a.host,
                     n->a.port, c ? c->errstr : "out of memory");
        if (c) redisFree(c);
        return DF_EIO;
    }
    redisSetTimeout(c, tv);
    n->ctx = c;
    return DF_OK;
}

/* Reads a CLUSTER SLOTS reply (asked of node `from`) into the slot map. 0 when malformed. */
static int load_map(df_redis *r, const redisReply *rep, const node *from)
{
    if (rep->type != REDIS_REPLY_ARRAY || !rep->elements) return 0;
    memset(r->slot_node, 0xff, sizeof r->slot_node);
    for (size_t i = 0; i < rep->elements; i++) {
        const redisReply *e = rep->element[i];
        if (e->type != REDIS_REPLY_ARRAY || e->elements < 3 ||
            e->element[0]->type != REDIS_REPLY_INTEGER ||
            e->element[1]->type != REDIS_REPLY_INTEGER ||
            e->element[2]->type != REDIS_REPLY_ARRAY || e->element[2]->elements < 2)
            return 0;
        const redisReply *m = e->element[2];
        long long lo = e->element[0]->integer, hi = e->element[1]->integer;
        if (m->element[0]->type != REDIS_REPLY_STRING || m->element[1]->type != REDIS_REPLY_INTEGER ||
            lo < 0 || hi >= DF_SLOTS || lo > hi || m->element[1]->integer < 1 ||
            m->element[1]->integer > 65535 || m->element[0]->len >= DF_REDIS_HOST_MAX)
            return 0;
        df_redis_node_addr a;
        /* an empty or "?" host: the address the asked node was reached by */
        snprintf(a.host, sizeof a.host, "%s", m->element[0]->len && strcmp(m->element[0]->str, "?")
                                                  ? m->element[0]->str : from->a.host);
        a.port = (int)m->element[1]->integer;
        int ni = node_index(r, &a);
        if (ni < 0) return 0;
        for (long long s = lo; s <= hi; s++) r->slot_node[s] = (int16_t)ni;
    }
    return 1;
}

/* Asks the known nodes, then the seeds, for CLUSTER SLOTS until one answers; the first answer
 * sets the mode when still unknown (an error "cluster support disabled": a single Redis). */
static int refresh(df_redis *r, df_error *err)
{
    df_error last;
    df_error_set(&last, DF_EIO, "cluster redis %s: no node answers", r->addr);
    for (size_t i = 0; i < r->n_seeds; i++)
        if (node_index(r, &r->seeds[i]) < 0) break;
    for (size_t i = 0; i < r->n_nodes; i++) {
        node *n = &r->nodes[i];
        if (connect_node(n, &last) != DF_OK) continue;
        redisReply *rep = redisCommand(n->ctx, "CLUSTER SLOTS");
        if (!rep) {
            df_error_set(&last, DF_EIO, "cluster redis %s:%d: CLUSTER SLOTS: %s", n->a.host,
                         n->a.port, n->ctx->errstr[0] ? n->ctx->errstr : "connection lost");
            drop_conn(n);
            continue;
        }
        int single = rep->type == REDIS_REPLY_ERROR && strcasestr(rep->str, "cluster support");
        int ok = !single && load_map(r, rep, n);
        if (!ok && !single)
            df_error_set(&last, DF_EIO, "cluster redis %s:%d: CLUSTER SLOTS: %s", n->a.host,
                         n->a.port, rep->type == REDIS_REPLY_ERROR ? rep->str
                                                                    : "unexpected reply");
        freeReplyObject(rep);
        if (single && r->mode != MODE_CLUSTER) {
            if (r->n_seeds > 1) {
                return df_error_set(err, DF_EINVAL, "cluster redis %s:%d is not a Redis Cluster "
                                    "node (cluster-enabled no): give one seed, or a cluster",
                                    n->a.host, n->a.port);
            }
            r->mode = MODE_SINGLE;
            r->map_stale = 0;
            return DF_OK;
        }
        if (ok) {
            r->mode = MODE_CLUSTER;
            r->map_stale = 0;
            return DF_OK;
        }
    }
    if (err) *err = last;
    return DF_EIO;
}

/* The key of a command (deformd's commands only: EVAL numkeys keys..., else argv[1]), or NULL
 * for a keyless one (PING, CONFIG, INFO, CLUSTER, SCAN, ASKING). */
static const char *key_of(int argc, const char **argv, const size_t *len, size_t *klen)
{
    static const char *const keyless[] = {"PING", "CONFIG", "INFO", "CLUSTER", "SCAN", "ASKING"};
    for (size_t i = 0; i < sizeof keyless / sizeof *keyless; i++)
        if (!strcasecmp(argv[0], keyless[i])) return NULL;
    int k = 1;
    if (!strcasecmp(argv[0], "EVAL") || !strcasecmp(argv[0], "EVALSHA"))
        k = argc > 3 && atoi(argv[2]) > 0 ? 3 : -1;
    if (k < 0 || k >= argc) return NULL;
    *klen = len[k];
    return argv[k];
}

/* The node a command goes to first: the single Redis, the owner of its key's slot, or (keyless)
 * any node. Loads the mode / map first when needed. */
static int pick(df_redis *r, int argc, const char **argv, const size_t *len, int *ni,
                df_error *err)
{
    if (r->mode == MODE_UNKNOWN || (r->mode == MODE_CLUSTER && r->map_stale)) {
        int rc = refresh(r, err);
        if (rc != DF_OK && (r->mode == MODE_UNKNOWN || rc != DF_EIO)) return rc;
    }
    if (r->mode == MODE_SINGLE) {
        *ni = node_index(r, &r->seeds[0]);
        return DF_OK;
    }
    size_t kl = 0;
    const char *key = key_of(argc, argv, len, &kl);
    int s = key ? df_slot_of_key(key, kl) : -1;
    *ni = s >= 0 ? r->slot_node[s] : 0;
    if (s < 0) /* keyless: a connected node if there is one */
        for (size_t i = 0; i < r->n_nodes; i++)
            if (r->nodes[i].ctx) {
                *ni = (int)i;
                break;
            }
    if (*ni < 0) {
        r->map_stale = 1;
        return df_error_set(err, DF_EIO, "cluster redis %s: slot %d is served by no node "
                            "(cluster down?)", r->addr, s);
    }
    return DF_OK;
}

/* An I/O failure on node n: its connection dropped (reconnected at its next command), the
 * map reloaded at the next command (a failed master's slots may have moved). */
static int io_fail(df_redis *r, node *n, const char *what, df_error *err)
{
    df_error_set(err, DF_EIO, "cluster redis %s:%d: %s: %s", n->a.host, n->a.port, what,
                 n->ctx && n->ctx->errstr[0] ? n->ctx->errstr : "connection lost");
    drop_conn(n);
    if (r->mode == MODE_CLUSTER) r->map_stale = 1;
    return DF_EIO;
}

/* When rep is a -MOVED or -ASK redirect (cluster mode): its target into *ni (*asking set for
 * ASK; MOVED also updates the slot map and reloads it at the next command), rep freed,
 * returns 1. Else 0. */
static int redirected(df_redis *r, redisReply *rep, const node *from, int *ni, int *asking)
{
    int slot;
    df_redis_node_addr to;
    if (r->mode != MODE_CLUSTER || rep->type != REDIS_REPLY_ERROR) return 0;
    int kind = df_slot_parse_redirect(rep->str, rep->len, &slot, &to);
    if (kind == DF_REDIR_NONE) return 0;
    if (!to.host[0]) snprintf(to.host, sizeof to.host, "%s", from->a.host);
    int t = node_index(r, &to);
    if (t < 0) return 0;
    freeReplyObject(rep);
    *ni = t;
    *asking = kind == DF_REDIR_ASK;
    if (kind == DF_REDIR_MOVED) {
        r->slot_node[slot] = (int16_t)t;
        r->map_stale = 1;
    }
    return 1;
}

int df_redis_cmd(df_redis *r, int argc, const char **argv, const size_t *argvlen,
                 redisReply **out, df_error *err)
{
    *out = NULL;
    int ni, asking = 0;
    int rc = pick(r, argc, argv, argvlen, &ni, err);
    for (int hop = 0; rc == DF_OK; hop++) {
        node *n = &r->nodes[ni];
        if ((rc = connect_node(n, err)) != DF_OK) {
            if (r->mode == MODE_CLUSTER) r->map_stale = 1;
            return rc;
        }
        if (asking) { /* the one command after ASKING may touch the importing slot */
            redisReply *a = redisCommand(n->ctx, "ASKING");
            if (!a) return io_fail(r, n, "ASKING", err);
            freeReplyObject(a);
        }
        redisReply *rep = redisCommandArgv(n->ctx, argc, argv, argvlen);
        if (!rep) return io_fail(r, n, argv[0], err);
        if (hop < REDIRECTS_MAX && redirected(r, rep, n, &ni, &asking)) continue;
        *out = rep;
        return DF_OK;
    }
    return rc;
}

/* Pipelines commands idx[0..m-1] (of the df_redis_pipeline arrays) on node n. */
static int pipeline_node(df_redis *r, node *n, size_t m, const size_t *idx, const int *argc,
                         const char *const *const *argv, const size_t *const *argvlen,
                         redisReply **out, df_error *err)
{
    int rc = connect_node(n, err);
    if (rc != DF_OK) {
        if (r->mode == MODE_CLUSTER) r->map_stale = 1;
        return rc;
    }
    for (size_t i = 0; i < m; i++)
        if (redisAppendCommandArgv(n->ctx, argc[idx[i]], (const char **)argv[idx[i]],
                                   argvlen[idx[i]]) != REDIS_OK)
            return io_fail(r, n, "pipeline", err);
    for (size_t i = 0; i < m; i++) {
        void *rep = NULL;
        if (redisGetReply(n->ctx, &rep) != REDIS_OK || !rep)
            return io_fail(r, n, "pipeline", err);
        out[idx[i]] = rep;
    }
    return DF_OK;
}

int df_redis_pipeline(df_redis *r, size_t n, const int *argc, const char *const *const *argv,
                      const size_t *const *argvlen, redisReply **out, df_error *err)
{
    for (size_t i = 0; i < n; i++) out[i] = NULL;
    int *to = malloc((n ? n : 1) * sizeof *to);
    size_t *idx = malloc((n ? n : 1) * sizeof *idx);
    int rc = to && idx ? DF_OK : df_error_set(err, DF_ENOMEM, "out of memory");
    for (size_t i = 0; rc == DF_OK && i < n; i++)
        rc = pick(r, argc[i], (const char **)argv[i], argvlen[i], &to[i], err);
    /* one pipeline per node, in the order of first use */
    for (size_t i = 0; rc == DF_OK && i < n; i++) {
        if (to[i] < 0) continue;
        int t = to[i];
        size_t m = 0;
        for (size_t j = i; j < n; j++)
            if (to[j] == t) {
                idx[m++] = j;
                to[j] = -1;
            }
        rc = pipeline_node(r, &r->nodes[t], m, idx, argc, argv, argvlen, out, err);
    }
    /* a redirected command (its slot moved meanwhile) runs again, routed */
    for (size_t i = 0; rc == DF_OK && i < n; i++) {
        int slot;
        df_redis_node_addr a;
        if (r->mode != MODE_CLUSTER || out[i]->type != REDIS_REPLY_ERROR ||
            df_slot_parse_redirect(out[i]->str, out[i]->len, &slot, &a) == DF_REDIR_NONE)
            continue;
        freeReplyObject(out[i]);
        out[i] = NULL;
        rc = df_redis_cmd(r, argc[i], (const char **)argv[i], argvlen[i], &out[i], err);
    }
    if (rc != DF_OK)
        for (size_t i = 0; i < n; i++) {
            df_redis_reply_free(out[i]);
            out[i] = NULL;
        }
    free(to);
    free(idx);
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
