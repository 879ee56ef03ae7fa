/* redis.h — the daemon's synchronous connections to the cluster's Redis (cluster.h): one
 * Redis, or a Redis Cluster of several masters with slot routing.
 *
 * Cluster mode writes every acknowledged change to Redis before the ack, as the SQLite store
 * (server/store/journal.h) writes before it: a synchronous hiredis context on the loop thread,
 * the simplest correct choice (an async context on the loop would need the commit to wait for
 * the reply; see cluster.h). Every command has a timeout (DF_REDIS_TIMEOUT_MS); a connection
 * that failed is dropped and reconnected at the next command, so a restarted Redis is used
 * again without a restart of the daemon.
 *
 * Redis Cluster (config `cluster = redis://HOST:PORT,HOST:PORT...`, seed nodes): the first
 * command asks a seed for CLUSTER SLOTS. A Redis with cluster support disabled is used as the
 * single Redis it is (exactly the one-node behaviour; several seeds are then refused); a cluster
 * node gives the slot map (slot.h), and every command then goes, on one hiredis context per
 * master, to the owner of its key's slot: argv[1], or an EVAL's first key (deformd's scripts
 * touch one session's keys, one hash tag, so one slot). A -MOVED reply updates the slot and
 * reloads the whole map before the next command, an -ASK reply sends ASKING then the command
 * to the importing node, both followed at most 5 hops. A node that fails (connection lost,
 * timeout) is dropped like the single Redis above, and the map is reloaded (from any node or
 * seed that answers) at the next command. Loop thread. */
#ifndef DF_SERVER_CLUSTER_REDIS_H
#define DF_SERVER_CLUSTER_REDIS_H

#include <stddef.h>

#include "core/common/df_error.h"

#define DF_REDIS_TIMEOUT_MS 2000 /* connect and command timeout */

struct redisReply;
typedef struct df_redis df_redis;

/* Parses `url` ("redis://HOST:PORT[,HOST:PORT...]", slot.h df_slot_parse_seeds) into a new,
 * not yet connected df_redis (*out). Errors: DF_EINVAL (not that form; message names it),
 * DF_ENOMEM. */
int df_redis_new(const char *url, df_redis **out, df_error *err);

/* Closes and frees. NULL-safe. */
void df_redis_free(df_redis *r);

/* "HOST:PORT[,HOST:PORT...]" of the seed(s) (owned by r). */
const char *df_redis_addr(const df_redis *r);

/* 1 when the Redis answered as a Redis Cluster (known after the first command), else 0:
 * multi-key commands must then stay within one slot. */
int df_redis_is_cluster(const df_redis *r);

/* Runs one command given as argc strings of lengths argvlen (binary-safe), connecting first
 * when needed. *out gets the reply (free with df_redis_reply_free). A Redis error reply is
 * returned as DF_OK with *out of type REDIS_REPLY_ERROR: the caller reads it (redirects are
 * followed here, not returned). Errors: DF_EINVAL (several seeds, not a cluster), DF_EIO
 * (cannot connect, timeout, connection lost: the connection is dropped and retried at the
 * next call; message names the server). */
int df_redis_cmd(df_redis *r, int argc, const char **argv, const size_t *argvlen,
                 struct redisReply **out, df_error *err);

/* df_redis_cmd of NUL-terminated strings. */
int df_redis_cmdv(df_redis *r, struct redisReply **out, df_error *err, int argc, ...);

/* Sends n commands at once (pipelined: one round trip, and with appendfsync always one fsync
 * for the batch), command i of argc[i] strings argv[i] of lengths argvlen[i]; out[i] gets its
 * reply (free each with df_redis_reply_free; NULL after an error). In a Redis Cluster, one
 * pipeline per master (each command to its slot's owner; a redirected one runs again alone,
 * routed). Errors: as df_redis_cmd
 * (every out[i] is then NULL). */
int df_redis_pipeline(df_redis *r, size_t n, const int *argc, const char *const *const *argv,
                      const size_t *const *argvlen, struct redisReply **out, df_error *err);

/* Frees a reply (NULL-safe). */
void df_redis_reply_free(struct redisReply *rep);

#endif
