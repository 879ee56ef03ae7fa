/* auth.c — TCP key authentication: challenge, proof, rate limit (see auth.h). */
#include "server/net/auth.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <openssl/crypto.h>

#include "proto/auth_mac.h"
#include "server/log.h"
#include "server/net/auth_limit.h"
#include "server/net/conn.h"
#include "server/net/reply.h"

/* Key 0 is key_file (the admin; key_len 0 when only peer keys are set), keys 1.. the
 * peer_key entries in config order. */
typedef struct df_auth_server {
    int nkeys;
    uint8_t key[1 + DF_ACCESS_MAX_PEER_KEYS][DF_AUTH_KEY_CAP_BYTES];
    size_t key_len[1 + DF_ACCESS_MAX_PEER_KEYS];
    df_auth_limit limit;
} df_auth_server;

int df_auth_start(df_server *srv, df_error *err)
{
    const df_access_config *a = &srv->cfg.access;
    if (!a->key_file[0] && a->n_peer_keys == 0) return DF_OK;
    df_auth_server *s = calloc(1, sizeof *s);
    if (!s) return df_error_set(err, DF_ENOMEM, "key_file: out of memory");
    int rc = DF_OK;
    if (a->key_file[0])
        rc = df_auth_key_load(a->key_file, s->key[0], sizeof s->key[0], &s->key_len[0], err);
    s->nkeys = 1;
    for (int i = 0; rc == DF_OK && i < a->n_peer_keys; i++, s->nkeys++) {
        rc = df_auth_key_load(a->peer_keys[i].file, s->key[i + 1], sizeof s->key[i + 1],
                              &s->key_len[i + 1], err);
        for (int k = 0; rc == DF_OK && k <= i; k++) /* a key must name one principal */
            if (s->key_len[k] == s->key_len[i + 1] &&
                CRYPTO_memcmp(s->key[k], s->key[i + 1], s->key_len[k]) == 0)
                rc = df_error_set(err, DF_EINVAL, "peer_key %s: the same key as %s%s",
                                  a->peer_keys[i].name, k ? "peer_key " : "key_file",
                                  k ? a->peer_keys[k - 1].name : "");
    }
    if (rc != DF_OK) {
        OPENSSL_cleanse(s, sizeof *s);
        free(s);
        return rc;
    }
    df_auth_limit_init(&s->limit, a->fail_burst, a->fail_refill_s);
    srv->auth = s;
    df_log(DF_LOG_INFO, "TCP clients must authenticate (key_file %s, %d peer_key)",
           a->key_file[0] ? a->key_file : "none", a->n_peer_keys);
    return DF_OK;
}

void df_auth_free(df_server *srv)
{
    if (!srv->auth) return;
    OPENSSL_cleanse(srv->auth, sizeof *srv->auth);
    free(srv->auth);
    srv->auth = NULL;
}

int df_auth_enabled(const df_server *srv) { return srv->auth != NULL; }

int df_auth_required(const df_conn *c) { return c->is_tcp && c->srv->auth && !c->auth_ok; }

int df_auth_blocks(const df_conn *c, uint16_t type)
{
    return df_auth_required(c) && type != DF_MSG_HELLO && type != DF_MSG_PING &&
           type != DF_MSG_AUTH;
}

/* Sends the AUTH reply with `method` and a 32-byte token. */
static void reply_token(df_req *r, uint16_t method, const uint8_t *token)
{
    df_msg_auth out = {.method = method, .token_len = 32, .token = token};
    df_req_reply_auth(r, &out);
}

/* Answers r with `code` and `msg`, closes the connection once that is sent. */
static int refuse(df_req *r, int code, const char *msg, const char *why)
{
    df_error e;
    df_error_set(&e, code, "%s", msg);
    df_req_fail(r, &e);
    df_conn_close_after_flush(r->c, why);
    return DF_OK;
}

int df_auth_request(df_req *r, const df_msg_auth *m, df_error *err)
{
    df_conn *c = r->c;
    df_server *srv = r->srv;
    df_auth_server *a = srv->auth;
    if (!a)
        return df_error_set(err, DF_EUNSUPPORTED,
                            "auth: this server has no key (no key_file): nothing to authenticate");
    if (m->method != DF_AUTH_HMAC_CHALLENGE && m->method != DF_AUTH_HMAC_PROOF)
        return df_error_set(err, DF_EINVAL, "auth: method %u unknown (1 HMAC_CHALLENGE, "
                            "2 HMAC_PROOF)", m->method);
    if (m->token_len != 32)
        return df_error_set(err, DF_EINVAL, "auth: %s token of %u bytes, need 32",
                            m->method == DF_AUTH_HMAC_CHALLENGE ? "nonce" : "MAC", m->token_len);
    if (c->auth_ok)
        return df_error_set(err, DF_ESTATE, "auth: this connection is already authenticated");
    char unix_who[48]; /* Unix peers (AUTH is optional there) are limited per uid */
    snprintf(unix_who, sizeof unix_who, "unix uid %u", c->peer_uid);
    const char *who = c->is_tcp ? c->peer_addr : unix_who;
    const char *host = c->is_tcp ? c->peer_host : unix_who;
    uint64_t wait = df_auth_limit_wait(&a->limit, host, uv_now(srv->loop));
    if (wait) {
        srv->stats.auth_limited++;
        char msg[160];
        snprintf(msg, sizeof msg, "auth: too many failed authentications from %s; retry in %llu s",
                 host, (unsigned long long)((wait + 999) / 1000));
        df_log(DF_LOG_WARN, "client %llu (%s): %s", (unsigned long long)c->id, who, msg);
        return refuse(r, DF_ELIMIT, msg, "authentication rate limit");
    }
    if (m->method == DF_AUTH_HMAC_CHALLENGE) {
        int rc = df_auth_random(c->auth_ns, sizeof c->auth_ns, err);
        if (rc != DF_OK) return rc;
        memcpy(c->auth_nc, m->token, 32);
        c->auth_step = 1;
        reply_token(r, DF_AUTH_HMAC_CHALLENGE, c->auth_ns);
        return DF_OK;
    }
    if (c->auth_step != 1)
        return df_error_set(err, DF_ESTATE, "auth: HMAC_PROOF before HMAC_CHALLENGE: send the "
                            "challenge (your nonce) first");
    uint8_t want[32], mine[32];
    int rc = DF_OK, match = -1;
    for (int k = 0; rc == DF_OK && k < a->nkeys; k++) { /* every key: which principal is it? */
        if (!a->key_len[k]) continue;
        rc = df_auth_mac(a->key[k], a->key_len[k], c->auth_ns, c->auth_nc, DF_AUTH_ROLE_CLIENT,
                         want, err);
        if (rc == DF_OK && match < 0 && df_auth_equal(want, m->token, 32)) match = k;
    }
    if (rc == DF_OK && match >= 0)
        rc = df_auth_mac(a->key[match], a->key_len[match], c->auth_ns, c->auth_nc,
                         DF_AUTH_ROLE_SERVER, mine, err);
    c->auth_step = 0; /* one proof per challenge */
    if (rc != DF_OK) return rc;
    if (match < 0) {
        OPENSSL_cleanse(want, sizeof want);
        OPENSSL_cleanse(mine, sizeof mine);
        srv->stats.auth_failed++;
        df_auth_limit_fail(&a->limit, host, uv_now(srv->loop));
        df_log(DF_LOG_WARN, "client %llu (%s): authentication failed (wrong key)",
               (unsigned long long)c->id, who);
        return refuse(r, DF_EPROTO_AUTH, "auth: authentication failed: the MAC does not match "
                      "this server's key", "authentication failed");
    }
    c->auth_ok = 1;
    if (match == 0) {
        snprintf(c->principal, sizeof c->principal, "admin");
        c->admin = 1;
    } else {
        snprintf(c->principal, sizeof c->principal, "key:%s",
                 srv->cfg.access.peer_keys[match - 1].name);
        c->admin = 0;
    }
    srv->stats.auth_ok++;
    df_log(DF_LOG_INFO, "client %llu (%s) authenticated as %s", (unsigned long long)c->id, who,
           c->principal);
    reply_token(r, DF_AUTH_HMAC_PROOF, mine);
    OPENSSL_cleanse(want, sizeof want);
    OPENSSL_cleanse(mine, sizeof mine);
    return DF_OK;
}
