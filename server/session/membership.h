/* membership.h — one session's access policy (PROTOCOL.md 4.34): its mode, whether non-members
 * may observe, its join key (only the SHA-256 of it is kept) and its members. Pure data and
 * logic, no I/O; the key comes from OpenSSL RAND_bytes. Loop thread.
 *
 * Modes (DF_ACCESS_MODE_*, the wire's access_info mode):
 *   OPEN   every principal is a member: members observe and edit
 *   KEY    a principal becomes a member by JOIN with the session's join key (32 random bytes;
 *          compared by SHA-256 with CRYPTO_memcmp); members observe and edit
 *   OWNER  only the owner and admins edit; members observe
 * observers 1: principals that are not members may observe (subscribe, get mesh, snapshot,
 * handles get, brush state get); 0: they may not, and LIST_SESSIONS hides the session from them.
 * The owner and admins hold every right in every mode; only they close a session, reset its
 * rest shape or change its policy (the own right). Membership is per principal: it outlives
 * the connection that joined and persists in the store. */
#ifndef DF_SERVER_MEMBERSHIP_H
#define DF_SERVER_MEMBERSHIP_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "proto/messages.h" /* DF_ACCESS_MODE_OPEN / KEY / OWNER, DF_JOIN_KEY_BYTES (32) */

#define DF_JOIN_HASH_BYTES 32      /* SHA-256 of it */
#define DF_PRINCIPAL_MAX 48        /* bytes of a principal, NUL included (df_conn.principal) */
#define DF_MEMBERS_MAX 4096        /* members of one session */

enum { DF_MEMBER_OBSERVE = 1, DF_MEMBER_EDIT = 2, DF_MEMBER_OWN = 4 }; /* = DF_RIGHT_* */

typedef struct df_membership {
    int mode;                            /* DF_ACCESS_MODE_* */
    int observers;                       /* 0/1 */
    int has_key;                         /* key_hash holds a key's SHA-256 */
    uint8_t key_hash[DF_JOIN_HASH_BYTES];
    int n, cap;                          /* members */
    char (*members)[DF_PRINCIPAL_MAX];   /* malloc'd, n principals, unique */
} df_membership;

/* Sets `m` to `mode` (DF_ACCESS_MODE_*) and `observers` (0/1) with no key and no members. */
void df_membership_init(df_membership *m, int mode, int observers);

/* Frees the member list and wipes the key hash. NULL-safe; `m` is then as after init. */
void df_membership_free(df_membership *m);

/* Deep copy of `src` into `dst` (dst is overwritten, not freed). DF_OK or DF_ENOMEM. */
int df_membership_copy(df_membership *dst, const df_membership *src, df_error *err);

/* A new random join key: key_out (DF_JOIN_KEY_BYTES, may be NULL to keep it from everyone)
 * gets it, m->key_hash its SHA-256, has_key 1; the old key no longer joins. Errors:
 * DF_EINTERNAL when RAND_bytes or SHA-256 fails (`m` unchanged). */
int df_membership_new_key(df_membership *m, uint8_t *key_out, df_error *err);

/* 1 when `key` (len bytes) is the session's join key (SHA-256 compared with CRYPTO_memcmp),
 * else 0 (also when it has no key). */
int df_membership_key_ok(const df_membership *m, const uint8_t *key, size_t len);

/* 1 when `principal` is in the member list (OPEN mode counts everyone: see rights). */
int df_membership_is_member(const df_membership *m, const char *principal);

/* Adds `principal` (1..DF_PRINCIPAL_MAX-1 bytes) to the members; a member already is: DF_OK.
 * Errors: DF_EINVAL (empty or too long), DF_ELIMIT (DF_MEMBERS_MAX), DF_ENOMEM. */
int df_membership_add(df_membership *m, const char *principal, df_error *err);

/* The rights (DF_MEMBER_* bits) of `principal` on a session owned by `owner` under `m`;
 * `admin` 1 for an admin (every right). */
int df_membership_rights(const df_membership *m, const char *owner, const char *principal,
                         int admin);

/* "open", "key", "owner" ("?" for anything else). */
const char *df_membership_mode_name(int mode);

/* The mode named `name` ("open", "key", "owner") into *mode: DF_OK, else DF_EINVAL. */
int df_membership_mode_parse(const char *name, int *mode, df_error *err);

/* The members as one string of principals each ended by '\n' (malloc'd, "" when none; the
 * store's column), and back: df_membership_members_parse adds each line of `text` (len bytes)
 * to m. DF_OK, DF_ENOMEM, or add's errors. */
int df_membership_members_join(const df_membership *m, char **out, df_error *err);
int df_membership_members_parse(df_membership *m, const char *text, size_t len, df_error *err);

#endif
