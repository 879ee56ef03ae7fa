/* access_config.h — the access-control settings of deformd's config (config.h): who may connect
 * to the Unix socket (allow_uids, allow_gids) and the TCP key authentication (key_file and the
 * rate limit of failed authentications). Pure parsing; loop thread or start-up only.
 *
 * Keys:
 *   allow_uids     users (names or numbers, separated by commas or blanks; repeated lines
 *                  append) whose processes may use the Unix socket
 *   allow_gids     groups (names or numbers, as above): a peer whose primary or supplementary
 *                  group is listed may use the Unix socket
 *                  With neither set (the default) every peer the socket's mode lets in is
 *                  served; with either set, a peer matching neither list gets an ERROR frame
 *                  (EPROTO_AUTH) and is closed.
 *   key_file       FILE holding the secret key of TCP authentication (server/net/auth.h,
 *                  PROTOCOL.md 4.3); "" or "none" = off (default)
 *   tls_cert       PEM certificate (chain) of the TCP listener's TLS 1.3 (server/net/tls.h);
 *                  "" or "none" = no TLS (default)
 *   tls_key        PEM private key of tls_cert (mode 0600 or narrower); both or neither
 *   auth_fail_burst     failed authentications a peer address may make before it is refused
 *                  (1 .. DF_ACCESS_MAX_BURST, default DF_ACCESS_DEFAULT_BURST)
 *   auth_fail_refill_s  seconds after which one more failure is allowed again (token bucket:
 *                  1 .. DF_ACCESS_MAX_REFILL_S, default DF_ACCESS_DEFAULT_REFILL_S)
 *   peer_key       "NAME FILE": a named TCP key (repeatable, up to DF_ACCESS_MAX_PEER_KEYS; NAME
 *                  1..31 bytes of [A-Za-z0-9_.-], unique). A TCP peer proving this key is the
 *                  principal "key:NAME"; one proving key_file is the admin (PROTOCOL.md 4.34)
 *   session_access the access mode of new sessions (server/session/membership.h): "open"
 *                  (default: every principal may observe and edit), "key" (principals that
 *                  JOIN with the session's join key may edit) or "owner" (only the owner and
 *                  admins edit); a session keeps its mode until its owner changes it
 *   session_observers  "on" (default) or "off": whether principals that are not members of
 *                  a new session may observe it (off: they get EPERM and LIST hides it)
 *   quota_sessions   live sessions one principal may own (0 = unlimited, default)
 *   quota_upload_mb  MiB of uploaded mesh files one principal's live sessions may hold (0 = off)
 *   quota_memory_mb  MiB of session memory (the memory budget's estimate) one principal's live
 *                  sessions may hold (0 = unlimited, default) */
#ifndef DF_SERVER_ACCESS_CONFIG_H
#define DF_SERVER_ACCESS_CONFIG_H

#include <stdint.h>

#include "core/common/df_error.h"

#define DF_ACCESS_MAX_IDS 64             /* entries of allow_uids, of allow_gids */
#define DF_ACCESS_PATH_MAX 4096
#define DF_ACCESS_DEFAULT_BURST 5
#define DF_ACCESS_MAX_BURST 1000
#define DF_ACCESS_DEFAULT_REFILL_S 60
#define DF_ACCESS_MAX_REFILL_S 86400
#define DF_ACCESS_MAX_PEER_KEYS 16
#define DF_ACCESS_KEY_NAME_MAX 32        /* peer_key NAME: 1..31 bytes */
#define DF_ACCESS_MAX_QUOTA 1000000      /* quota_* upper bound (sessions, MiB) */

/* The values of server/session/membership.h's DF_ACCESS_MODE_* (checked there). */
enum { DF_SESSION_ACCESS_OPEN = 1, DF_SESSION_ACCESS_KEY = 2, DF_SESSION_ACCESS_OWNER = 3 };

typedef struct df_access_peer_key {
    char name[DF_ACCESS_KEY_NAME_MAX];
    char file[DF_ACCESS_PATH_MAX];
} df_access_peer_key;

typedef struct df_access_config {
    int n_uids, n_gids;                      /* 0 and 0: no uid/gid restriction */
    uint32_t uids[DF_ACCESS_MAX_IDS];
    uint32_t gids[DF_ACCESS_MAX_IDS];
    char key_file[DF_ACCESS_PATH_MAX];       /* "" = no TCP authentication */
    char tls_cert[DF_ACCESS_PATH_MAX];       /* "" = TCP is not encrypted */
    char tls_key[DF_ACCESS_PATH_MAX];
    int fail_burst;                          /* auth_fail_burst */
    int fail_refill_s;                       /* auth_fail_refill_s */
    int n_peer_keys;
    df_access_peer_key peer_keys[DF_ACCESS_MAX_PEER_KEYS];
    int session_access;                      /* DF_SESSION_ACCESS_*: mode of new sessions */
    int session_observers;                   /* 0/1: observers of new sessions */
    int quota_sessions;                      /* 0 = unlimited */
    int quota_upload_mb, quota_memory_mb;    /* 0 = unlimited */
} df_access_config;

/* Fills `a` with the defaults (no restriction, no key, burst and refill defaults, new sessions
 * open with observers on). */
void df_access_config_defaults(df_access_config *a);

/* 1 when `key` is one of the keys above, else 0. */
int df_access_config_has(const char *key);

/* Applies `key` = `value` (one of the keys above; NUL-terminated, trimmed) to `a`. User and group
 * names are resolved now (getpwnam_r / getgrnam_r). Errors: DF_EINVAL (message names the key and
 * the bad entry: unknown user or group, bad number, too many entries, out of range); `a` is then
 * untouched. */
int df_access_config_set(df_access_config *a, const char *key, const char *value, df_error *err);

/* 1 when `a` restricts the Unix socket (allow_uids or allow_gids set). */
int df_access_restricted(const df_access_config *a);

/* 1 when a peer with `uid`, primary `gid` and the `ngroups` supplementary groups `groups` (may be
 * NULL when 0) is allowed by `a` (always 1 when unrestricted). */
int df_access_peer_allowed(const df_access_config *a, uint32_t uid, uint32_t gid,
                           const uint32_t *groups, int ngroups);

#endif
