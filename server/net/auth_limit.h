/* auth_limit.h — the rate limit of failed TCP authentications, per peer address (token bucket).
 *
 * Each address has a bucket of at most `burst` tokens, full when first seen; a failed
 * authentication takes one token; a token comes back every `refill_ms`. An address whose bucket
 * holds less than one token is refused (without checking its MAC) until a token is back. The table
 * holds DF_AUTH_LIMIT_SLOTS addresses; when it is full, the slot of the address that failed least
 * recently is reused (its bucket counts as refilled). Pure: the time is passed in (ms, any
 * monotonic clock). Loop thread. */
#ifndef DF_SERVER_AUTH_LIMIT_H
#define DF_SERVER_AUTH_LIMIT_H

#include <stdint.h>

#define DF_AUTH_LIMIT_SLOTS 1024
#define DF_AUTH_LIMIT_HOST 48 /* bytes of an address string, NUL included */

/* A bucket counts credit in milliseconds: one token is refill_ms of credit, gained one per ms,
 * so every computation is exact integer arithmetic. */
typedef struct df_auth_limit_slot {
    char host[DF_AUTH_LIMIT_HOST]; /* "" = free */
    uint64_t credit_ms;            /* credit at t_ms, <= burst x refill_ms */
    uint64_t t_ms;                 /* time of the last failure */
} df_auth_limit_slot;

typedef struct df_auth_limit {
    uint64_t cap_ms;               /* burst x refill_ms: a full bucket */
    uint64_t refill_ms;            /* one token per refill_ms */
    df_auth_limit_slot slots[DF_AUTH_LIMIT_SLOTS];
} df_auth_limit;

/* Sets up an empty table: `burst` >= 1 failures in a row, one more per `refill_s` >= 1 seconds. */
void df_auth_limit_init(df_auth_limit *l, int burst, int refill_s);

/* 0 when `host` may try to authenticate at `now_ms`, else the milliseconds (>= 1) until it may.
 * Changes nothing. */
uint64_t df_auth_limit_wait(df_auth_limit *l, const char *host, uint64_t now_ms);

/* Records a failed authentication of `host` at `now_ms` (takes one token). */
void df_auth_limit_fail(df_auth_limit *l, const char *host, uint64_t now_ms);

#endif
