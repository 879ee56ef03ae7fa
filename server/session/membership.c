/* membership.c — one session's access policy and members (see membership.h). */
#include "server/session/membership.h"

#include <stdlib.h>
#include <string.h>

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/rand.h>

void df_membership_init(df_membership *m, int mode, int observers)
{
    memset(m, 0, sizeof *m);
    m->mode = mode;
    m->observers = observers != 0;
}

void df_membership_free(df_membership *m)
{
    if (!m) return;
    free(m->members);
    OPENSSL_cleanse(m->key_hash, sizeof m->key_hash);
    df_membership_init(m, m->mode, m->observers);
}

int df_membership_copy(df_membership *dst, const df_membership *src, df_error *err)
{
    df_membership t = *src;
    t.members = NULL;
    t.cap = src->n;
    if (src->n) {
        t.members = malloc((size_t)src->n * sizeof *t.members);
        if (!t.members) return df_error_set(err, DF_ENOMEM, "out of memory copying members");
        memcpy(t.members, src->members, (size_t)src->n * sizeof *t.members);
    }
    *dst = t;
    return DF_OK;
}

/* SHA-256 of `len` bytes into out (32 bytes): 1 on success. */
static int sha256(const uint8_t *p, size_t len, uint8_t *out)
{
    unsigned int n = 0;
    return EVP_Digest(p, len, out, &n, EVP_sha256(), NULL) == 1 && n == DF_JOIN_HASH_BYTES;
}

int df_membership_new_key(df_membership *m, uint8_t *key_out, df_error *err)
{
    uint8_t key[DF_JOIN_KEY_BYTES], h[DF_JOIN_HASH_BYTES];
    if (RAND_bytes(key, (int)sizeof key) != 1 || !sha256(key, sizeof key, h)) {
        OPENSSL_cleanse(key, sizeof key);
        return df_error_set(err, DF_EINTERNAL, "join key: OpenSSL RAND_bytes / SHA-256 failed");
    }
    if (key_out) memcpy(key_out, key, sizeof key);
    memcpy(m->key_hash, h, sizeof h);
    m->has_key = 1;
    OPENSSL_cleanse(key, sizeof key);
    return DF_OK;
}

int df_membership_key_ok(const df_membership *m, const uint8_t *key, size_t len)
{
    uint8_t h[DF_JOIN_HASH_BYTES];
    if (!m->has_key || !key || !sha256(key, len, h)) return 0;
    return CRYPTO_memcmp(h, m->key_hash, sizeof h) == 0;
}

int df_membership_is_member(const df_membership *m, const char *principal)
{
    for (int i = 0; i < m->n; i++)
        if (strcmp(m->members[i], principal) == 0) return 1;
    return 0;
}

int df_membership_add(df_membership *m, const char *principal, df_error *err)
{
    size_t len = principal ? strlen(principal) : 0;
    if (len == 0 || len >= DF_PRINCIPAL_MAX)
        return df_error_set(err, DF_EINVAL, "member: principal of %zu bytes (1..%d)", len,
                            DF_PRINCIPAL_MAX - 1);
    if (df_membership_is_member(m, principal)) return DF_OK;
    if (m->n >= DF_MEMBERS_MAX)
        return df_error_set(err, DF_ELIMIT, "member: the session has %d members, the most "
                            "one session keeps", DF_MEMBERS_MAX);
    if (m->n == m->cap) {
        int cap = m->cap ? 2 * m->cap : 4;
        if (cap > DF_MEMBERS_MAX) cap = DF_MEMBERS_MAX;
        void *p = realloc(m->members, (size_t)cap * sizeof *m->members);
        if (!p) return df_error_set(err, DF_ENOMEM, "out of memory adding a member");
        m->members = p;
        m->cap = cap;
    }
    memset(m->members[m->n], 0, DF_PRINCIPAL_MAX);
    memcpy(m->members[m->n], principal, len);
    m->n++;
    return DF_OK;
}

int df_membership_rights(const df_membership *m, const char *owner, const char *principal,
                         int admin)
{
    const int all = DF_MEMBER_OBSERVE | DF_MEMBER_EDIT | DF_MEMBER_OWN;
    if (admin || (owner[0] && strcmp(owner, principal) == 0)) return all;
    int member = m->mode == DF_ACCESS_MODE_OPEN || df_membership_is_member(m, principal);
    if (member && m->mode != DF_ACCESS_MODE_OWNER) return DF_MEMBER_OBSERVE | DF_MEMBER_EDIT;
    if (member || m->observers) return DF_MEMBER_OBSERVE;
    return 0;
}

const char *df_membership_mode_name(int mode)
{
    return mode == DF_ACCESS_MODE_OPEN ? "open" : mode == DF_ACCESS_MODE_KEY ? "key"
                                              : mode == DF_ACCESS_MODE_OWNER ? "owner" : "?";
}

int df_membership_mode_parse(const char *name, int *mode, df_error *err)
{
    for (int k = DF_ACCESS_MODE_OPEN; k <= DF_ACCESS_MODE_OWNER; k++)
        if (name && strcmp(name, df_membership_mode_name(k)) == 0) {
            *mode = k;
            return DF_OK;
        }
    return df_error_set(err, DF_EINVAL, "access mode '%s' (open, key or owner)",
                        name ? name : "");
}

int df_membership_members_join(const df_membership *m, char **out, df_error *err)
{
    size_t len = 1;
    for (int i = 0; i < m->n; i++) len += strlen(m->members[i]) + 1;
    char *s = malloc(len), *p = s;
    if (!s) return df_error_set(err, DF_ENOMEM, "out of memory listing members");
    for (int i = 0; i < m->n; i++) {
        size_t l = strlen(m->members[i]);
        memcpy(p, m->members[i], l);
        p[l] = '\n';
        p += l + 1;
    }
    *p = '\0';
    *out = s;
    return DF_OK;
}

int df_membership_members_parse(df_membership *m, const char *text, size_t len, df_error *err)
{
    size_t i = 0;
    while (i < len) {
        const char *nl = memchr(text + i, '\n', len - i);
        size_t l = nl ? (size_t)(nl - (text + i)) : len - i;
        char one[DF_PRINCIPAL_MAX];
        if (l == 0 || l >= sizeof one || memchr(text + i, '\0', l))
            return df_error_set(err, DF_EFORMAT, "member list: malformed entry of %zu bytes", l);
        memcpy(one, text + i, l);
        one[l] = '\0';
        int rc = df_membership_add(m, one, err);
        if (rc != DF_OK) return rc;
        i += l + 1;
    }
    return DF_OK;
}
