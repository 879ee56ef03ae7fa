/* access_config.c — allow_uids / allow_gids / key_file / auth_fail_* (see access_config.h). */
#include "server/access_config.h"

#include <errno.h>
#include <grp.h>
#include <pwd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void df_access_config_defaults(df_access_config *a)
{
    memset(a, 0, sizeof *a);
    a->fail_burst = DF_ACCESS_DEFAULT_BURST;
    a->fail_refill_s = DF_ACCESS_DEFAULT_REFILL_S;
    a->session_access = DF_SESSION_ACCESS_OPEN;
    a->session_observers = 1;
}

int df_access_config_has(const char *key)
{
    return key && (strcmp(key, "allow_uids") == 0 || strcmp(key, "allow_gids") == 0 ||
                   strcmp(key, "key_file") == 0 || strcmp(key, "tls_cert") == 0 ||
                   strcmp(key, "tls_key") == 0 || strcmp(key, "auth_fail_burst") == 0 ||
                   strcmp(key, "auth_fail_refill_s") == 0 || strcmp(key, "peer_key") == 0 ||
                   strcmp(key, "session_access") == 0 || strcmp(key, "session_observers") == 0 ||
                   strcmp(key, "quota_sessions") == 0 ||
                   strcmp(key, "quota_upload_mb") == 0 || strcmp(key, "quota_memory_mb") == 0);
}

/* A decimal id (no sign, no blanks) below 2^32 - 1 into *out: 1, else 0. */
static int parse_id(const char *s, uint32_t *out)
{
    if (!s[0] || s[0] < '0' || s[0] > '9') return 0;
    char *end = NULL;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (errno || !end || *end || v >= 0xFFFFFFFFull) return 0;
    *out = (uint32_t)v;
    return 1;
}

/* One user or group entry: a name (looked up) or a number. */
static int resolve(const char *key, int is_user, const char *name, uint32_t *out, df_error *err)
{
    char buf[16384];
    if (is_user) {
        struct passwd pw, *res = NULL;
        if (getpwnam_r(name, &pw, buf, sizeof buf, &res) == 0 && res) {
            *out = (uint32_t)res->pw_uid;
            return DF_OK;
        }
    } else {
        struct group gr, *res = NULL;
        if (getgrnam_r(name, &gr, buf, sizeof buf, &res) == 0 && res) {
            *out = (uint32_t)res->gr_gid;
            return DF_OK;
        }
    }
    if (parse_id(name, out)) return DF_OK;
    return df_error_set(err, DF_EINVAL, "%s: no %s '%s' (a name or a number)", key,
                        is_user ? "user" : "group", name);
}

static int add_ids(const char *key, int is_user, const char *value, uint32_t *ids, int *n,
                   df_error *err)
{
    uint32_t tmp[DF_ACCESS_MAX_IDS];
    int k = *n;
    memcpy(tmp, ids, sizeof tmp);
    char copy[4096];
    if (strlen(value) >= sizeof copy)
        return df_error_set(err, DF_EINVAL, "%s: value longer than %zu bytes", key,
                            sizeof copy - 1);
    snprintf(copy, sizeof copy, "%s", value);
    char *save = NULL;
    int any = 0;
    for (char *t = strtok_r(copy, ", \t", &save); t; t = strtok_r(NULL, ", \t", &save)) {
        uint32_t id;
        int rc = resolve(key, is_user, t, &id, err);
        if (rc != DF_OK) return rc;
        any = 1;
        int dup = 0;
        for (int i = 0; i < k; i++) dup |= tmp[i] == id;
        if (dup) continue;
        if (k >= DF_ACCESS_MAX_IDS)
            return df_error_set(err, DF_EINVAL, "%s: more than %d entries", key,
                                DF_ACCESS_MAX_IDS);
        tmp[k++] = id;
    }
    if (!any) return df_error_set(err, DF_EINVAL, "%s: empty list (give names or numbers)", key);
    memcpy(ids, tmp, sizeof tmp);
    *n = k;
    return DF_OK;
}

static int set_int(const char *key, const char *value, int lo, int hi, int *out, df_error *err)
{
    uint32_t v;
    if (!parse_id(value, &v) || v < (uint32_t)lo || v > (uint32_t)hi)
        return df_error_set(err, DF_EINVAL, "%s: '%s' not in %d..%d", key, value, lo, hi);
    *out = (int)v;
    return DF_OK;
}

/* "NAME FILE" of a peer_key line. */
static int add_peer_key(df_access_config *a, const char *value, df_error *err)
{
    const char *sp = value;
    while (*sp && *sp != ' ' && *sp != '\t') sp++;
    size_t nl = (size_t)(sp - value);
    while (*sp == ' ' || *sp == '\t') sp++;
    if (nl == 0 || !*sp)
        return df_error_set(err, DF_EINVAL, "peer_key: '%s': give NAME FILE", value);
    if (nl >= DF_ACCESS_KEY_NAME_MAX)
        return df_error_set(err, DF_EINVAL, "peer_key: name longer than %d bytes",
                            DF_ACCESS_KEY_NAME_MAX - 1);
    for (size_t i = 0; i < nl; i++) {
        char ch = value[i];
        if (!((ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
              ch == '_' || ch == '.' || ch == '-'))
            return df_error_set(err, DF_EINVAL, "peer_key: name '%.*s': use [A-Za-z0-9_.-]",
                                (int)nl, value);
    }
    if (strlen(sp) >= DF_ACCESS_PATH_MAX)
        return df_error_set(err, DF_EINVAL, "peer_key: path longer than %d bytes",
                            DF_ACCESS_PATH_MAX - 1);
    for (int i = 0; i < a->n_peer_keys; i++)
        if (strlen(a->peer_keys[i].name) == nl && memcmp(a->peer_keys[i].name, value, nl) == 0)
            return df_error_set(err, DF_EINVAL, "peer_key: name '%.*s' given twice", (int)nl,
                                value);
    if (a->n_peer_keys >= DF_ACCESS_MAX_PEER_KEYS)
        return df_error_set(err, DF_EINVAL, "peer_key: more than %d keys",
                            DF_ACCESS_MAX_PEER_KEYS);
    df_access_peer_key *k = &a->peer_keys[a->n_peer_keys++];
    memcpy(k->name, value, nl);
    k->name[nl] = '\0';
    snprintf(k->file, sizeof k->file, "%s", sp);
    return DF_OK;
}

int df_access_config_set(df_access_config *a, const char *key, const char *value, df_error *err)
{
    if (!a || !key || !value) return df_error_set(err, DF_EINVAL, "config: NULL argument");
    if (strcmp(key, "allow_uids") == 0)
        return add_ids(key, 1, value, a->uids, &a->n_uids, err);
    if (strcmp(key, "allow_gids") == 0)
        return add_ids(key, 0, value, a->gids, &a->n_gids, err);
    if (strcmp(key, "auth_fail_burst") == 0)
        return set_int(key, value, 1, DF_ACCESS_MAX_BURST, &a->fail_burst, err);
    if (strcmp(key, "auth_fail_refill_s") == 0)
        return set_int(key, value, 1, DF_ACCESS_MAX_REFILL_S, &a->fail_refill_s, err);
    if (strcmp(key, "peer_key") == 0) return add_peer_key(a, value, err);
    if (strcmp(key, "quota_sessions") == 0)
        return set_int(key, value, 0, DF_ACCESS_MAX_QUOTA, &a->quota_sessions, err);
    if (strcmp(key, "quota_upload_mb") == 0)
        return set_int(key, value, 0, DF_ACCESS_MAX_QUOTA, &a->quota_upload_mb, err);
    if (strcmp(key, "quota_memory_mb") == 0)
        return set_int(key, value, 0, DF_ACCESS_MAX_QUOTA, &a->quota_memory_mb, err);
    if (strcmp(key, "session_access") == 0) {
        if (strcmp(value, "open") == 0) a->session_access = DF_SESSION_ACCESS_OPEN;
        else if (strcmp(value, "key") == 0) a->session_access = DF_SESSION_ACCESS_KEY;
        else if (strcmp(value, "owner") == 0) a->session_access = DF_SESSION_ACCESS_OWNER;
        else return df_error_set(err, DF_EINVAL, "session_access: '%s' (open, key or owner)",
                                 value);
        return DF_OK;
    }
    if (strcmp(key, "session_observers") == 0) {
        if (strcmp(value, "on") == 0) a->session_observers = 1;
        else if (strcmp(value, "off") == 0) a->session_observers = 0;
        else return df_error_set(err, DF_EINVAL, "session_observers: '%s' (on or off)", value);
        return DF_OK;
    }
    char *path = strcmp(key, "key_file") == 0   ? a->key_file
                 : strcmp(key, "tls_cert") == 0 ? a->tls_cert
                 : strcmp(key, "tls_key") == 0  ? a->tls_key
                                                : NULL;
    if (path) { /* each is a char[DF_ACCESS_PATH_MAX] */
        if (strcmp(value, "none") == 0 || !value[0]) {
            path[0] = '\0';
            return DF_OK;
        }
        if (strlen(value) >= DF_ACCESS_PATH_MAX)
            return df_error_set(err, DF_EINVAL, "%s: path longer than %d bytes", key,
                                DF_ACCESS_PATH_MAX - 1);
        snprintf(path, DF_ACCESS_PATH_MAX, "%s", value);
        return DF_OK;
    }
    return df_error_set(err, DF_EINVAL, "unknown access key '%s'", key);
}

int df_access_restricted(const df_access_config *a) { return a->n_uids > 0 || a->n_gids > 0; }

int df_access_peer_allowed(const df_access_config *a, uint32_t uid, uint32_t gid,
                           const uint32_t *groups, int ngroups)
{
    if (!df_access_restricted(a)) return 1;
    for (int i = 0; i < a->n_uids; i++)
        if (a->uids[i] == uid) return 1;
    for (int i = 0; i < a->n_gids; i++) {
        if (a->gids[i] == gid) return 1;
        for (int j = 0; j < ngroups; j++)
            if (groups && a->gids[i] == groups[j]) return 1;
    }
    return 0;
}
