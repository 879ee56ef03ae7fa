/* auth_mac.c — HMAC-SHA256 of the AUTH exchange, nonces, key file (see auth_mac.h). */
#include "proto/auth_mac.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openssl/core_names.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/params.h>
#include <openssl/rand.h>

int df_auth_hmac_sha256(const uint8_t *key, size_t klen, const uint8_t *msg, size_t mlen,
                        uint8_t out[32], df_error *err)
{
    if (!out || (!key && klen) || (!msg && mlen))
        return df_error_set(err, DF_EINVAL, "hmac-sha256: NULL argument");
    static const uint8_t empty[1] = {0};
    EVP_MAC *mac = EVP_MAC_fetch(NULL, "HMAC", NULL);
    EVP_MAC_CTX *ctx = mac ? EVP_MAC_CTX_new(mac) : NULL;
    char digest[] = "SHA256";
    OSSL_PARAM params[] = {OSSL_PARAM_construct_utf8_string(OSSL_MAC_PARAM_DIGEST, digest, 0),
                           OSSL_PARAM_construct_end()};
    size_t outl = 0;
    const char *failed = !mac ? "EVP_MAC_fetch(HMAC)" : !ctx ? "EVP_MAC_CTX_new" : NULL;
    if (!failed && !EVP_MAC_init(ctx, klen ? key : empty, klen, params)) failed = "EVP_MAC_init";
    if (!failed && mlen && !EVP_MAC_update(ctx, msg, mlen)) failed = "EVP_MAC_update";
    if (!failed && (!EVP_MAC_final(ctx, out, &outl, 32) || outl != 32)) failed = "EVP_MAC_final";
    EVP_MAC_CTX_free(ctx);
    EVP_MAC_free(mac);
    if (failed) return df_error_set(err, DF_EINTERNAL, "hmac-sha256: %s failed", failed);
    return DF_OK;
}

int df_auth_mac(const uint8_t *key, size_t klen, const uint8_t ns[DF_AUTH_NONCE_BYTES],
                const uint8_t nc[DF_AUTH_NONCE_BYTES], df_auth_role role,
                uint8_t out[DF_AUTH_MAC_BYTES], df_error *err)
{
    if (!ns || !nc) return df_error_set(err, DF_EINVAL, "auth mac: NULL nonce");
    if (role != DF_AUTH_ROLE_CLIENT && role != DF_AUTH_ROLE_SERVER)
        return df_error_set(err, DF_EINVAL, "auth mac: role %d is not client or server", (int)role);
    const char *ctx = role == DF_AUTH_ROLE_CLIENT ? DF_AUTH_CONTEXT_CLIENT : DF_AUTH_CONTEXT_SERVER;
    size_t cl = strlen(ctx);
    uint8_t msg[2 * DF_AUTH_NONCE_BYTES + 64];
    memcpy(msg, ns, DF_AUTH_NONCE_BYTES);
    memcpy(msg + DF_AUTH_NONCE_BYTES, nc, DF_AUTH_NONCE_BYTES);
    memcpy(msg + 2 * DF_AUTH_NONCE_BYTES, ctx, cl);
    return df_auth_hmac_sha256(key, klen, msg, 2 * DF_AUTH_NONCE_BYTES + cl, out, err);
}

int df_auth_equal(const uint8_t *a, const uint8_t *b, size_t n)
{
    return CRYPTO_memcmp(a, b, n) == 0;
}

int df_auth_random(uint8_t *out, size_t n, df_error *err)
{
    if (!out || n > (size_t)0x7fffffff) return df_error_set(err, DF_EINVAL, "random: bad buffer");
    if (RAND_bytes(out, (int)n) != 1)
        return df_error_set(err, DF_EINTERNAL, "random: RAND_bytes failed (no entropy source?)");
    return DF_OK;
}

int df_auth_key_load(const char *path, uint8_t *key, size_t cap, size_t *len, df_error *err)
{
    if (!path || !path[0] || !key || !len || cap < DF_AUTH_KEY_CAP_BYTES)
        return df_error_set(err, DF_EINVAL, "key file: bad argument");
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) return df_error_set(err, DF_EIO, "key file %s: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        return df_error_set(err, DF_EIO, "key file %s: %s", path, strerror(e));
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        return df_error_set(err, DF_EINVAL, "key file %s: not a regular file", path);
    }
    if (st.st_mode & (S_IROTH | S_IWOTH)) {
        close(fd);
        return df_error_set(err, DF_EINVAL,
                            "key file %s: readable or writable by others (mode %04o): anyone on "
                            "this machine could read the secret; chmod 600 (or 640 for a group) "
                            "it",
                            path, (unsigned)(st.st_mode & 07777));
    }
    uint8_t buf[DF_AUTH_KEY_CAP_BYTES + 256];
    size_t n = 0;
    for (;;) {
        ssize_t r = read(fd, buf + n, sizeof buf - n);
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) {
            int e = errno;
            close(fd);
            return df_error_set(err, DF_EIO, "key file %s: %s", path, strerror(e));
        }
        if (r == 0 || n + (size_t)r == sizeof buf) {
            n += (size_t)r;
            break;
        }
        n += (size_t)r;
    }
    close(fd);
    while (n > 0 && (buf[n - 1] == ' ' || buf[n - 1] == '\t' || buf[n - 1] == '\n' ||
                     buf[n - 1] == '\r'))
        n--;
    int rc = DF_OK;
    if (n < DF_AUTH_KEY_MIN_BYTES)
        rc = df_error_set(err, DF_EINVAL,
                          "key file %s: key of %zu bytes is too short (at least %d: e.g. "
                          "`openssl rand -hex 32 > FILE`)",
                          path, n, DF_AUTH_KEY_MIN_BYTES);
    else if (n > DF_AUTH_KEY_CAP_BYTES)
        rc = df_error_set(err, DF_EINVAL, "key file %s: key longer than %d bytes", path,
                          DF_AUTH_KEY_CAP_BYTES);
    if (rc == DF_OK) {
        memcpy(key, buf, n);
        *len = n;
    }
    OPENSSL_cleanse(buf, sizeof buf);
    return rc;
}
