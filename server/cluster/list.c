/* list.c — LIST_SESSIONS in cluster mode: every session of the cluster, with the owners trailer
 * for clients that ask for it (see cluster.h df_cluster_list_sessions, PROTOCOL.md 4.10). */
#include <hiredis/hiredis.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/frame_codec.h"
#include "server/cluster/cluster.h"
#include "server/cluster/cluster_int.h"
#include "server/cluster/lease.h"
#include "server/net/conn.h"
#include "server/net/reply.h"
#include "server/net/req.h"
#include "server/session/session.h"

#define INDEX_KEY "deformd:sessions"

/* One index entry "KIND PLANAR NV NE VERSION OBSERVERS NAME" into *it / *observers. 0 when
 * malformed (skipped). */
static int parse_info(uint64_t id, const char *v, df_msg_session_info *it, int *observers)
{
    int kind, planar, obs, off = 0;
    unsigned nv, ne;
    unsigned long long version;
    if (sscanf(v, "%d %d %u %u %llu %d %n", &kind, &planar, &nv, &ne, &version, &obs, &off) !=
            6 || !off || kind < 1 || kind > 3 || nv < 1 || nv > DF_MAX_MESH_VERTICES)
        return 0;
    memset(it, 0, sizeof *it);
    it->session_id = id;
    it->version = version;
    it->kind = (uint8_t)kind;
    it->planar = (uint8_t)(planar != 0);
    it->nv = nv;
    it->ne = ne;
    snprintf(it->name, sizeof it->name, "%s", v + off);
    *observers = obs;
    return 1;
}

/* The version of session id's last replicated change (its stream's last entry), or `dflt`. */
static uint64_t last_version(df_redis *r, uint64_t id, uint64_t dflt)
{
    char kg[64];
    df_lease_key(id, "log", kg, sizeof kg);
    redisReply *rep;
    df_error e;
    if (df_redis_cmdv(r, &rep, &e, 6, "XREVRANGE", kg, "+", "-", "COUNT", "1") != DF_OK)
        return dflt;
    uint64_t v = dflt;
    if (rep->type == REDIS_REPLY_ARRAY && rep->elements == 1 &&
        rep->element[0]->type == REDIS_REPLY_ARRAY && rep->element[0]->elements == 2) {
        const redisReply *f = rep->element[0]->element[1];
        for (size_t k = 0; f->type == REDIS_REPLY_ARRAY && k + 1 < f->elements; k += 2)
            if (f->element[k]->type == REDIS_REPLY_STRING && !strcmp(f->element[k]->str, "v"))
                v = strtoull(f->element[k + 1]->str, NULL, 10);
    }
    df_redis_reply_free(rep);
    return v;
}

/* The owner address of session id ("" when unleased) into out (cap bytes). */
static int owner_of(df_redis *r, uint64_t id, char *out, size_t cap, df_error *err)
{
    char token[DF_LEASE_VALUE_MAX];
    const char *addr = "";
    uint64_t epoch;
    int l = df_lease_get(r, id, token, err);
    if (l < 0) return l;
    if (l == 1 && df_lease_parse(token, &epoch, &addr, NULL) != DF_OK) addr = "";
    snprintf(out, cap, "%s", addr);
    return DF_OK;
}

/* The reply frame: the session_list body, then (want_owners) the owners trailer. */
static int reply(df_req *r, const df_msg_session_list *l, char (*owners)[256], df_error *err)
{
    df_buf b;
    size_t start;
    df_buf_init(&b);
    int rc = df_frame_begin(&b, r->type, DF_FLAG_REPLY, r->id, &start, err);
    if (rc == DF_OK) rc = df_msg_session_list_encode(l, &b, err);
    if (rc == DF_OK && owners) {
        size_t need = 4;
        for (uint32_t i = 0; i < l->count; i++) need += 10 + strlen(owners[i]);
        rc = df_buf_reserve(&b, need, err);
        if (rc == DF_OK) {
            df_buf_put_u32(&b, l->count);
            for (uint32_t i = 0; i < l->count; i++) {
                df_buf_put_u64(&b, l->items[i].session_id);
                df_put_str(&b, owners[i]);
            }
        }
    }
    if (rc == DF_OK) rc = df_frame_end(&b, start, err);
    df_sbuf *s = rc == DF_OK ? df_sbuf_from_buf(&b) : NULL;
    if (!s) {
        df_buf_free(&b);
        return rc != DF_OK ? rc : df_error_set(err, DF_ENOMEM, "out of memory");
    }
    df_req_reply(r, s);
    df_sbuf_unref(s);
    return DF_OK;
}

int df_cluster_list_sessions(df_req *r, const df_msg_session_list *local, df_error *err)
{
    df_server *srv = r->srv;
    df_cluster *cl = srv->cluster;
    redisReply *rep;
    int rc = df_redis_cmdv(cl->r, &rep, err, 2, "HGETALL", INDEX_KEY);
    if (rc != DF_OK) return rc;
    if (rep->type != REDIS_REPLY_ARRAY) {
        df_redis_reply_free(rep);
        return df_error_set(err, DF_EINTERNAL, "cluster redis: HGETALL %s: unexpected reply",
                            INDEX_KEY);
    }
    size_t cap = local->count + rep->elements / 2;
    if (cap > DF_MAX_SESSIONS) cap = DF_MAX_SESSIONS;
    df_msg_session_list l = {0, calloc(cap ? cap : 1, sizeof *l.items)};
    char(*owners)[256] = calloc(cap ? cap : 1, sizeof *owners);
    if (!l.items || !owners) rc = df_error_set(err, DF_ENOMEM, "out of memory");
    for (uint32_t i = 0; rc == DF_OK && i < local->count && l.count < cap; i++) {
        l.items[l.count] = local->items[i];
        snprintf(owners[l.count++], sizeof owners[0], "%.255s", cl->advertise);
    }
    int admin = r->c && r->c->admin;
    for (size_t i = 0; rc == DF_OK && i + 1 < rep->elements && l.count < cap; i += 2) {
        const redisReply *k = rep->element[i], *v = rep->element[i + 1];
        if (k->type != REDIS_REPLY_STRING || v->type != REDIS_REPLY_STRING) continue;
        uint64_t id = strtoull(k->str, NULL, 10);
        int obs;
        df_msg_session_info *it = &l.items[l.count];
        if (!id || df_session_find(srv, id) || !parse_info(id, v->str, it, &obs)) continue;
        if (!obs && !admin) continue; /* admits no observers: its members ask its owner */
        it->version = last_version(cl->r, id, it->version);
        if ((rc = owner_of(cl->r, id, owners[l.count], sizeof owners[0], err)) == DF_OK) l.count++;
    }
    df_redis_reply_free(rep);
    if (rc == DF_OK) rc = reply(r, &l, r->c && r->c->want_owners ? owners : NULL, err);
    free(l.items);
    free(owners);
    return rc;
}
