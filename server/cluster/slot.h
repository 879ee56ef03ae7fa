/* slot.h — Redis Cluster addressing, pure (no I/O): the seed list of config `cluster`, the hash
 * slot of a key, and the -MOVED / -ASK redirect replies. Used by redis.c's slot routing.
 *
 * Redis Cluster splits the key space into DF_SLOTS hash slots: slot = CRC16(tag) mod 16384,
 * CRC16 the XMODEM one (poly 0x1021, init 0), tag the bytes between the first '{' and the next
 * '}' when that is non-empty, else the whole key (Redis Cluster specification, "Keys hash
 * tags"). deformd's per-session keys are deformd:{ID}:..., so one session is one slot.
 * Any thread (no state). */
#ifndef DF_SERVER_CLUSTER_SLOT_H
#define DF_SERVER_CLUSTER_SLOT_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

#define DF_SLOTS 16384
#define DF_REDIS_SEEDS_MAX 16
#define DF_REDIS_HOST_MAX 256

/* One node address. */
typedef struct df_redis_node_addr {
    char host[DF_REDIS_HOST_MAX];
    int port; /* 1..65535 */
} df_redis_node_addr;

/* CRC16/XMODEM of len bytes of buf. */
uint16_t df_slot_crc16(const void *buf, size_t len);

/* The hash slot (0..DF_SLOTS-1) of the key of len bytes (binary-safe), hash tag honoured. */
int df_slot_of_key(const char *key, size_t len);

/* Parses config `cluster`: "redis://HOST:PORT[,HOST:PORT...]" (later entries may repeat the
 * "redis://" prefix; spaces around commas allowed) into out[0..*n-1] (cap entries, at most
 * DF_REDIS_SEEDS_MAX). Errors: DF_EINVAL (not that form, an empty entry, a port outside
 * 1..65535, a host over 255 bytes, more than cap seeds: the message names the entry). */
int df_slot_parse_seeds(const char *url, df_redis_node_addr *out, size_t cap, size_t *n,
                        df_error *err);

/* Redirect kinds of an error reply. */
enum { DF_REDIR_NONE = 0, DF_REDIR_MOVED = 1, DF_REDIR_ASK = 2 };

/* Reads an error reply's text (`str`, len bytes, without the leading '-'): "MOVED SLOT HOST:PORT"
 * or "ASK SLOT HOST:PORT" fill *slot and *to and return DF_REDIR_MOVED / DF_REDIR_ASK; any
 * other text (or a malformed redirect: slot out of range, no port) returns DF_REDIR_NONE. A
 * HOST of "" (Redis 7 may say ":PORT" for "the host you reached me by") is left empty: the
 * caller fills it in. */
int df_slot_parse_redirect(const char *str, size_t len, int *slot, df_redis_node_addr *to);

#endif
