/* dc_auth.c — the HMAC-SHA256 key authentication of libdeformclient (deformclient.h,
 * PROTOCOL.md 4.3): challenge, proof, and the check of the server's proof. */
#include <stdlib.h>
#include <string.h>

#include <openssl/crypto.h>

#include "client/dc_client.h"
#include "proto/auth_mac.h"

typedef struct auth_reply {
    uint16_t method;
    uint8_t token[DF_AUTH_MAC_BYTES];
    int got;
} auth_reply;

static int enc_auth(const void *m, df_buf *out, df_error *err)
{
    return df_msg_auth_encode(m, out, err);
}

/* Keeps a 32-byte token of the expected method. */
static int reply_auth(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    auth_reply *r = user;
    df_msg_auth m;
    int rc = df_msg_auth_decode(p, h->payload_len, &m, err);
    if (rc != DF_OK) return rc;
    if (m.method != r->method || m.token_len != DF_AUTH_MAC_BYTES)
        return df_error_set(err, DF_EFORMAT, "auth: reply method %u with %u bytes, expected "
                            "method %u with %u", m.method, m.token_len, r->method,
                            DF_AUTH_MAC_BYTES);
    memcpy(r->token, m.token, DF_AUTH_MAC_BYTES);
    r->got = 1;
    return DF_OK;
}

int df_client_authenticate(df_client *c, const void *key, size_t key_len, df_error *err)
{
    if (!c || !key || key_len == 0 || key_len > DF_AUTH_KEY_CAP_BYTES)
        return df_error_set(err, DF_EINVAL, "authenticate: no client or key (1..%d bytes)",
                            DF_AUTH_KEY_CAP_BYTES);
    uint8_t nc[DF_AUTH_NONCE_BYTES], ns[DF_AUTH_NONCE_BYTES], mc[DF_AUTH_MAC_BYTES],
        ms[DF_AUTH_MAC_BYTES];
    int rc = df_auth_random(nc, sizeof nc, err);
    if (rc != DF_OK) return rc;
    auth_reply r = {.method = DF_AUTH_HMAC_CHALLENGE};
    df_msg_auth m = {DF_AUTH_HMAC_CHALLENGE, DF_AUTH_NONCE_BYTES, nc};
    rc = dc_request(c, DF_MSG_AUTH, enc_auth, &m, reply_auth, &r, err);
    if (rc == DF_OK && !r.got) rc = df_error_set(err, DF_EFORMAT, "auth: empty challenge reply");
    if (rc != DF_OK) return rc;
    memcpy(ns, r.token, sizeof ns);
    rc = df_auth_mac(key, key_len, ns, nc, DF_AUTH_ROLE_CLIENT, mc, err);
    if (rc == DF_OK) rc = df_auth_mac(key, key_len, ns, nc, DF_AUTH_ROLE_SERVER, ms, err);
    if (rc != DF_OK) return rc;
    r = (auth_reply){.method = DF_AUTH_HMAC_PROOF};
    m = (df_msg_auth){DF_AUTH_HMAC_PROOF, DF_AUTH_MAC_BYTES, mc};
    rc = dc_request(c, DF_MSG_AUTH, enc_auth, &m, reply_auth, &r, err);
    if (rc == DF_OK && (!r.got || !df_auth_equal(ms, r.token, sizeof ms))) {
        c->broken = 1; /* an impostor: nothing more goes to it */
        c->remote_err = 0;
        rc = df_error_set(err, DF_EPROTO_AUTH,
                          "auth: the server did not prove that it knows the key; do not trust "
                          "this connection");
    }
    OPENSSL_cleanse(mc, sizeof mc);
    OPENSSL_cleanse(ms, sizeof ms);
    if (rc == DF_OK && c->key != key) { /* kept for a cluster redirect (dc_move.c) */
        uint8_t *k = malloc(key_len);
        if (k) {
            memcpy(k, key, key_len);
            if (c->key) OPENSSL_cleanse(c->key, c->key_len);
            free(c->key);
            c->key = k;
            c->key_len = key_len;
        }
    }
    return rc;
}

int df_client_authenticate_file(df_client *c, const char *key_file, df_error *err)
{
    uint8_t key[DF_AUTH_KEY_CAP_BYTES];
    size_t len = 0;
    int rc = df_auth_key_load(key_file, key, sizeof key, &len, err);
    if (rc == DF_OK) rc = df_client_authenticate(c, key, len, err);
    OPENSSL_cleanse(key, sizeof key);
    return rc;
}
