/* dc_tls.c — client TLS 1.3 and transport-independent byte I/O (see dc_tls.h). */
#include "client/dc_tls.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <string.h>

#include <openssl/err.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>

#include "client/dc_net.h"

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

/* Waits for the readiness SSL asked for (SSL_ERROR_WANT_READ / WANT_WRITE `e`): 1 ready,
 * 0 timeout, -1 error (errno). */
static int wait_for(int fd, int e, int timeout_ms)
{
    struct pollfd p = {fd, e == SSL_ERROR_WANT_WRITE ? POLLOUT : POLLIN, 0};
    for (;;) {
        int r = poll(&p, 1, timeout_ms);
        if (r < 0 && errno == EINTR) continue;
        return r;
    }
}

int dc_tls_start(df_client *c, const char *host, const char *ca_file, df_error *err)
{
    char why[256];
    ERR_clear_error();
    SSL_CTX *ctx = SSL_CTX_new(TLS_client_method());
    if (!ctx) return df_error_set(err, DF_ENOMEM, "TLS: cannot create an SSL context");
    SSL_CTX_set_min_proto_version(ctx, TLS1_3_VERSION);
    SSL_CTX_set_verify(ctx, SSL_VERIFY_PEER, NULL);
    if (SSL_CTX_load_verify_locations(ctx, ca_file, NULL) != 1) {
        ssl_reason(why, sizeof why, "unreadable");
        SSL_CTX_free(ctx);
        return df_error_set(err, DF_EIO, "TLS CA file %s: %s", ca_file, why);
    }
    SSL *ssl = SSL_new(ctx);
    if (!ssl || SSL_set_fd(ssl, c->fd) != 1) {
        SSL_free(ssl);
        SSL_CTX_free(ctx);
        return df_error_set(err, DF_ENOMEM, "TLS: cannot create a session");
    }
    unsigned char ip[16];
    int is_ip = inet_pton(AF_INET, host, ip) == 1 || inet_pton(AF_INET6, host, ip) == 1;
    int ok = is_ip ? X509_VERIFY_PARAM_set1_ip_asc(SSL_get0_param(ssl), host)
                   : SSL_set1_host(ssl, host) && SSL_set_tlsext_host_name(ssl, host);
    if (ok != 1) {
        SSL_free(ssl);
        SSL_CTX_free(ctx);
        return df_error_set(err, DF_EINVAL, "TLS: bad host name '%s'", host);
    }
    int fl = fcntl(c->fd, F_GETFL);
    if (fl >= 0) fcntl(c->fd, F_SETFL, fl | O_NONBLOCK);
    for (;;) {
        int r = SSL_connect(ssl);
        if (r == 1) break;
        int e = SSL_get_error(ssl, r);
        if (e == SSL_ERROR_WANT_READ || e == SSL_ERROR_WANT_WRITE) {
            int w = wait_for(c->fd, e, c->timeout_ms);
            if (w > 0) continue;
            snprintf(why, sizeof why, "%s", w == 0 ? "timed out" : strerror(errno));
        } else if (SSL_get_verify_result(ssl) != X509_V_OK) {
            snprintf(why, sizeof why, "certificate verify failed: %s",
                     X509_verify_cert_error_string(SSL_get_verify_result(ssl)));
            ERR_clear_error();
        } else {
            ssl_reason(why, sizeof why,
                       e == SSL_ERROR_SYSCALL ? "connection closed by peer" : "protocol error");
        }
        SSL_free(ssl);
        SSL_CTX_free(ctx);
        return df_error_set(err, DF_EIO, "TLS handshake with %s failed: %s", host, why);
    }
    c->ssl = ssl;
    c->ssl_ctx = ctx;
    return DF_OK;
}

void dc_tls_end(df_client *c)
{
    if (c->ssl) {
        if (!c->broken) SSL_shutdown(c->ssl); /* close_notify; non-blocking, best effort */
        SSL_free(c->ssl);
    }
    SSL_CTX_free(c->ssl_ctx);
    c->ssl = NULL;
    c->ssl_ctx = NULL;
    ERR_clear_error();
}

/* Writes all `len` bytes of `p` through TLS. */
static int tls_write(df_client *c, const void *p, size_t len, df_error *err)
{
    while (len > 0) {
        int chunk = len > (1u << 30) ? (1 << 30) : (int)len;
        int r = SSL_write(c->ssl, p, chunk); /* retried with the same arguments until done */
        if (r > 0) {
            p = (const char *)p + r;
            len -= (size_t)r;
            continue;
        }
        int e = SSL_get_error(c->ssl, r);
        if ((e == SSL_ERROR_WANT_READ || e == SSL_ERROR_WANT_WRITE) &&
            wait_for(c->fd, e, -1) > 0)
            continue;
        char why[256];
        ssl_reason(why, sizeof why, e == SSL_ERROR_SYSCALL ? "connection closed by peer"
                                                          : "TLS error");
        return df_error_set(err, DF_EIO, "write: %s", why);
    }
    return DF_OK;
}

int dc_io_write2(df_client *c, const void *a, size_t alen, const void *b, size_t blen,
                 df_error *err)
{
    if (!c->ssl) return dc_net_write2(c->fd, a, alen, b, blen, err);
    int rc = tls_write(c, a, alen, err);
    return rc == DF_OK && blen ? tls_write(c, b, blen, err) : rc;
}

long dc_io_read_some(df_client *c, void *buf, size_t cap, int timeout_ms, df_error *err)
{
    if (!c->ssl) return dc_net_read_some(c->fd, buf, cap, timeout_ms, err);
    for (;;) {
        int r = SSL_read(c->ssl, buf, cap > INT32_MAX ? INT32_MAX : (int)cap);
        if (r > 0) return r;
        int e = SSL_get_error(c->ssl, r);
        if (e == SSL_ERROR_WANT_READ || e == SSL_ERROR_WANT_WRITE) {
            int w = wait_for(c->fd, e, timeout_ms);
            if (w > 0) continue;
            if (w == 0) return df_error_set(err, DF_ESTATE, "timed out");
            return df_error_set(err, DF_EIO, "read: %s", strerror(errno));
        }
        char why[256];
        ssl_reason(why, sizeof why, "connection closed by peer");
        if (e == SSL_ERROR_ZERO_RETURN) snprintf(why, sizeof why, "connection closed by peer");
        return df_error_set(err, DF_EIO, "read: %s", why);
    }
}

int dc_io_read_exact(df_client *c, void *buf, size_t len, int timeout_ms, df_error *err)
{
    if (!c->ssl) return dc_net_read_exact(c->fd, buf, len, timeout_ms, err);
    size_t got = 0;
    while (got < len) {
        long r = dc_io_read_some(c, (char *)buf + got, len - got, timeout_ms, err);
        if (r == DF_ESTATE && got == 0) return DF_ESTATE;
        if (r < 0)
            return r == DF_ESTATE ? df_error_set(err, DF_EIO, "timed out after a partial read")
                                  : (int)r;
        got += (size_t)r;
    }
    return DF_OK;
}
