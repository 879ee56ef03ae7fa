/* tls.c — TLS 1.3 through memory BIOs (see tls.h). */
#include "server/net/tls.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <openssl/err.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>

#include "server/log.h"
#include "server/server.h"

struct df_tls_server {
    SSL_CTX *ctx;
};

struct df_tls_conn {
    SSL *ssl;
    BIO *rbio, *wbio; /* owned by ssl */
    uint8_t *out;     /* the ciphertext of the last df_tls_seal */
    size_t out_cap;
};

/* OpenSSL's oldest queued error as text (or `fallback`); clears the queue. */
static void ssl_reason(char *buf, size_t cap, const char *fallback)
{
    unsigned long e = ERR_get_error();
    if (e) {
        const char *r = ERR_reason_error_string(e);
        if (r) snprintf(buf, cap, "%s", r);
        else ERR_error_string_n(e, buf, cap);
    } else {
        snprintf(buf, cap, "%s", fallback);
    }
    ERR_clear_error();
}

/* A readable regular file (and, for a key, one only its owner can read). */
static int check_file(const char *what, const char *path, int secret, df_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) return df_error_set(err, DF_EIO, "%s %s: %s", what, path, strerror(errno));
    struct stat st;
    int rc = fstat(fileno(f), &st);
    fclose(f);
    if (rc != 0 || !S_ISREG(st.st_mode))
        return df_error_set(err, DF_EIO, "%s %s: not a regular file", what, path);
    if (secret && (st.st_mode & 077))
        return df_error_set(err, DF_EINVAL,
                            "%s %s: the private key can be read by others (mode %04o); "
                            "chmod 600 it",
                            what, path, (unsigned)(st.st_mode & 0777));
    return DF_OK;
}

int df_tls_server_new(const char *cert, const char *key, df_tls_server **out, df_error *err)
{
    if (!cert || !key || !out) return df_error_set(err, DF_EINVAL, "tls: NULL argument");
    if (!cert[0] || !key[0])
        return df_error_set(err, DF_EINVAL,
                            "tls: set both tls_cert and tls_key (--tls-cert, --tls-key); "
                            "only %s is set",
                            cert[0] ? "tls_cert" : "tls_key");
    int rc = check_file("tls_cert", cert, 0, err);
    if (rc == DF_OK) rc = check_file("tls_key", key, 1, err);
    if (rc != DF_OK) return rc;
    char why[200];
    ERR_clear_error();
    SSL_CTX *ctx = SSL_CTX_new(TLS_server_method());
    if (!ctx) return df_error_set(err, DF_ENOMEM, "tls: cannot create an SSL context");
    if (SSL_CTX_set_min_proto_version(ctx, TLS1_3_VERSION) != 1) {
        ssl_reason(why, sizeof why, "unsupported");
        SSL_CTX_free(ctx);
        return df_error_set(err, DF_EIO, "tls: TLS 1.3 unavailable: %s", why);
    }
    SSL_CTX_set_num_tickets(ctx, 0); /* no resumption: nothing to send after the handshake */
    if (SSL_CTX_use_certificate_chain_file(ctx, cert) != 1) {
        ssl_reason(why, sizeof why, "unreadable");
        SSL_CTX_free(ctx);
        return df_error_set(err, DF_EIO, "tls_cert %s: not a PEM certificate (%s)", cert, why);
    }
    if (SSL_CTX_use_PrivateKey_file(ctx, key, SSL_FILETYPE_PEM) != 1) {
        int mismatch = ERR_GET_REASON(ERR_peek_last_error()) == X509_R_KEY_VALUES_MISMATCH;
        ssl_reason(why, sizeof why, "unreadable");
        SSL_CTX_free(ctx);
        if (mismatch)
            return df_error_set(err, DF_EINVAL,
                                "tls_key %s does not match the certificate of tls_cert %s", key,
                                cert);
        return df_error_set(err, DF_EIO, "tls_key %s: not a PEM private key (%s)", key, why);
    }
    if (SSL_CTX_check_private_key(ctx) != 1) {
        ssl_reason(why, sizeof why, "mismatch");
        SSL_CTX_free(ctx);
        return df_error_set(err, DF_EINVAL,
                            "tls_key %s does not match the certificate of tls_cert %s (%s)", key,
                            cert, why);
    }
    df_tls_server *s = calloc(1, sizeof *s);
    if (!s) {
        SSL_CTX_free(ctx);
        return df_error_set(err, DF_ENOMEM, "tls: out of memory");
    }
    s->ctx = ctx;
    *out = s;
    return DF_OK;
}

void df_tls_server_free(df_tls_server *s)
{
    if (!s) return;
    SSL_CTX_free(s->ctx);
    free(s);
}

int df_tls_start(df_server *srv, df_error *err)
{
    const df_access_config *a = &srv->cfg.access;
    if (!a->tls_cert[0] && !a->tls_key[0]) return DF_OK;
    int rc = df_tls_server_new(a->tls_cert, a->tls_key, &srv->tls, err);
    if (rc == DF_OK)
        df_log(DF_LOG_INFO, "TCP connections use TLS 1.3 (tls_cert %s)", a->tls_cert);
    return rc;
}

void df_tls_free(df_server *srv)
{
    df_tls_server_free(srv->tls);
    srv->tls = NULL;
}

df_tls_conn *df_tls_conn_new(df_tls_server *s, df_error *err)
{
    df_tls_conn *t = calloc(1, sizeof *t);
    if (!t) {
        df_error_set(err, DF_ENOMEM, "tls: out of memory");
        return NULL;
    }
    ERR_clear_error();
    t->ssl = SSL_new(s->ctx); /* takes a reference on the context */
    t->rbio = BIO_new(BIO_s_mem());
    t->wbio = BIO_new(BIO_s_mem());
    if (!t->ssl || !t->rbio || !t->wbio) {
        SSL_free(t->ssl);
        BIO_free(t->rbio);
        BIO_free(t->wbio);
        free(t);
        ERR_clear_error();
        df_error_set(err, DF_ENOMEM, "tls: out of memory");
        return NULL;
    }
    BIO_set_mem_eof_return(t->rbio, -1); /* empty: "retry", not end of stream */
    BIO_set_mem_eof_return(t->wbio, -1);
    SSL_set_bio(t->ssl, t->rbio, t->wbio);
    SSL_set_accept_state(t->ssl);
    return t;
}

void df_tls_conn_free(df_tls_conn *t)
{
    if (!t) return;
    SSL_free(t->ssl); /* frees both BIOs */
    free(t->out);
    free(t);
}

int df_tls_has_output(const df_tls_conn *t) { return BIO_ctrl_pending(t->wbio) > 0; }

int df_tls_established(const df_tls_conn *t) { return SSL_is_init_finished(t->ssl); }

/* Maps a failed SSL call's result `r` to DF_OK (wants more input), DF_ESTATE or DF_EIO. */
static int ssl_failure(df_tls_conn *t, int r, const char *stage, df_error *err)
{
    int e = SSL_get_error(t->ssl, r);
    if (e == SSL_ERROR_WANT_READ) return DF_OK;
    if (e == SSL_ERROR_ZERO_RETURN) {
        ERR_clear_error();
        return df_error_set(err, DF_ESTATE, "TLS close_notify from the peer");
    }
    char why[200];
    ssl_reason(why, sizeof why, "protocol error");
    return df_error_set(err, DF_EIO, "TLS %s failed: %s", stage, why);
}

int df_tls_recv(df_tls_conn *t, const uint8_t *in, size_t len, df_tls_sink sink, void *ctx,
                df_error *err)
{
    ERR_clear_error();
    while (len > 0) {
        int w = BIO_write(t->rbio, in, len > INT32_MAX ? INT32_MAX : (int)len);
        if (w <= 0) return df_error_set(err, DF_ENOMEM, "tls: out of memory for input");
        in += w;
        len -= (size_t)w;
    }
    if (!SSL_is_init_finished(t->ssl)) {
        int r = SSL_do_handshake(t->ssl);
        if (r != 1) return ssl_failure(t, r, "handshake", err);
    }
    uint8_t buf[16384];
    for (;;) {
        int r = SSL_read(t->ssl, buf, sizeof buf);
        if (r <= 0) return ssl_failure(t, r, "read", err);
        if (sink(ctx, buf, (size_t)r) != 0)
            return df_error_set(err, DF_ENOMEM, "out of memory for the read buffer");
    }
}

int df_tls_seal(df_tls_conn *t, const uv_buf_t *plain, size_t n, uv_buf_t *out, df_error *err)
{
    ERR_clear_error(); /* out may alias plain[0]: it is only written at the end */
    if (SSL_is_init_finished(t->ssl)) {
        for (size_t i = 0; i < n; i++) {
            const char *p = plain[i].base;
            size_t left = plain[i].len;
            while (left > 0) { /* a memory BIO takes everything: SSL_write completes */
                int chunk = left > (1u << 30) ? (1 << 30) : (int)left;
                int r = SSL_write(t->ssl, p, chunk);
                if (r <= 0) {
                    char why[200];
                    ssl_reason(why, sizeof why, "write failed");
                    return df_error_set(err, DF_EIO, "TLS write failed: %s", why);
                }
                p += r;
                left -= (size_t)r;
            }
        }
    }
    size_t pending = BIO_ctrl_pending(t->wbio);
    if (pending == 0) {
        *out = uv_buf_init(NULL, 0);
        return DF_OK;
    }
    if (pending > t->out_cap) {
        uint8_t *nb = realloc(t->out, pending);
        if (!nb) return df_error_set(err, DF_ENOMEM, "tls: out of memory for %zu bytes", pending);
        t->out = nb;
        t->out_cap = pending;
    }
    size_t got = 0;
    while (got < pending) {
        size_t want = pending - got;
        int r = BIO_read(t->wbio, t->out + got, want > INT32_MAX ? INT32_MAX : (int)want);
        if (r <= 0) break;
        got += (size_t)r;
    }
    *out = uv_buf_init((char *)t->out, (unsigned)got);
    return DF_OK;
}

void df_tls_conn_trim(df_tls_conn *t)
{
    if (t->out_cap > DF_TLS_KEEP_BYTES) {
        free(t->out);
        t->out = NULL;
        t->out_cap = 0;
    }
}
