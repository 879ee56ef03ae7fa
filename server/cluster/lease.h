/* lease.h — session ownership leases in Redis, with their fencing token (cluster.h).
 *
 * Keys of session ID (one Redis Cluster hash slot per session: the {ID} hash tag):
 *   deformd:{ID}:lease   "EPOCH HOST:PORT" of the owner, with a PX ttl (cluster_lease_ms)
 *   deformd:{ID}:epoch   the session's lease epoch counter (INCR at every take-over)
 * The lease value is the fencing token: every write of the owner (rlog.h) runs in a Lua
 * script that first checks that the lease still holds exactly that value, so an owner whose
 * lease expired (paused, partitioned) and was taken by another daemon (a new epoch) cannot
 * write any more.
 * Acquire: granted when the lease is absent, or held under our own address (a daemon restarted
 * at the same address takes back its sessions at once), with a new epoch; refused with the
 * holder's value otherwise. Renew: PEXPIRE when the value is still ours, else lost.
 * Loop thread (the connection's, redis.h). */
#ifndef DF_SERVER_CLUSTER_LEASE_H
#define DF_SERVER_CLUSTER_LEASE_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "server/cluster/redis.h"

#define DF_LEASE_VALUE_MAX 320

/* Key `what` ("lease", "epoch", "snap", "log") of session id into buf (cap bytes). */
void df_lease_key(uint64_t id, const char *what, char *buf, size_t cap);

/* Takes session id's lease for `addr` ("HOST:PORT") for ttl_ms. Returns 1 (taken: `value`
 * gets the new "EPOCH ADDR" token), 0 (held by another daemon: `value` gets its token), or a
 * negative error (DF_EIO: Redis unreachable, DF_EINTERNAL: an unexpected reply). value: cap
 * DF_LEASE_VALUE_MAX. */
int df_lease_acquire(df_redis *r, uint64_t id, const char *addr, int ttl_ms, char *value,
                     df_error *err);

/* Extends session id's lease held under `value` by ttl_ms. Returns 1 (renewed), 0 (lost: the
 * lease expired or another daemon holds it), or DF_EIO / DF_EINTERNAL. */
int df_lease_renew(df_redis *r, uint64_t id, const char *value, int ttl_ms, df_error *err);

/* df_lease_renew of n leases in one pipelined round trip: ok[i] = 1 (renewed) or 0 (lost) for
 * session ids[i] held under tokens[i]. Errors: DF_EIO (Redis unreachable: ok untouched),
 * DF_ENOMEM; an unexpected reply counts as lost. */
int df_lease_renew_many(df_redis *r, size_t n, const uint64_t *ids, const char *const *tokens,
                        int ttl_ms, int *ok, df_error *err);

/* The current lease value of session id into `value` (cap DF_LEASE_VALUE_MAX). Returns 1 (a
 * lease), 0 (none), or DF_EIO / DF_EINTERNAL. */
int df_lease_get(df_redis *r, uint64_t id, char *value, df_error *err);

/* Splits a lease value "EPOCH ADDR": *epoch and a pointer to ADDR inside value. Returns DF_OK
 * or DF_EFORMAT. Pure. */
int df_lease_parse(const char *value, uint64_t *epoch, const char **addr, df_error *err);

#endif
