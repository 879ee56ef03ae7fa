/* route.c — cluster routing: a request for a session held elsewhere is redirected, one held
 * nowhere is taken over; the cluster's session list (see cluster.h). */
#include <hiredis/hiredis.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include "server/cluster/cluster.h"
#include "server/cluster/cluster_int.h"
#include "server/cluster/rebuild.h"
#include "server/log.h"
#include "server/session/session.h"

int df_cluster_route(df_server *srv, uint64_t id, df_session **out, df_error *err)
{
    df_cluster *cl = srv->cluster;
    *out = NULL;
    if (!cl || !id) return df_error_set(err, DF_ENOTFOUND, "no session %" PRIu64, id);
    df_owned *o = df_cluster_owned(cl, id);
    if (o && o->dropping)
        return df_error_set(err, DF_EIO, "cluster: session %" PRIu64 " is leaving this daemon "
                            "(retry)", id);
    char token[DF_LEASE_VALUE_MAX];
    int got = df_lease_acquire(cl->r, id, cl->advertise, cl->ttl_ms, token, err);
    if (got < 0) return got;
    if (got == 0) {
        uint64_t epoch;
        const char *addr;
        if (df_lease_parse(token, &epoch, &addr, err) != DF_OK) return DF_EINTERNAL;
        return df_error_set(err, DF_EMOVED, "MOVED %" PRIu64 " %s", id, addr);
    }
    int rc = df_cluster_rebuild(cl, id, token, out, err);
    if (rc != DF_OK) { /* give the lease back: nothing here */
        char kl[64];
        df_lease_key(id, "lease", kl, sizeof kl);
        redisReply *rep = NULL;
        df_error e;
        if (df_redis_cmdv(cl->r, &rep, &e, 5, "EVAL",
                          "if redis.call('GET', KEYS[1]) == ARGV[1] then "
                          "return redis.call('DEL', KEYS[1]) end return 0",
                          "1", kl, token) == DF_OK)
            df_redis_reply_free(rep);
    }
    return rc;
}
