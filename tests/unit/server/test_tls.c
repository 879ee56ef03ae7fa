/* Unit tests of server/net/tls.c, the memory-BIO seam between libuv and OpenSSL: a client SSL
 * (also on memory BIOs) and the server state exchange bytes by hand, so every step of the
 * handshake and of the record layer is driven by the test. The certificate and keys are made
 * here with OpenSSL's API into a temporary directory. Checked: the handshake completes through
 * df_tls_recv / df_tls_seal; bytes written by the client arrive unchanged in the sink whatever
 * the split of the ciphertext; sealed frames reach the client unchanged; plaintext before the
 * handshake is dropped; a plaintext peer is a handshake error; bad files refuse with a message. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cmocka.h>

#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>

#include "server/net/tls.h"

static char g_dir[256], g_cert[300], g_key[300], g_key2[300];

static EVP_PKEY *new_key(void) { return EVP_EC_gen("P-256"); }

static void write_key(EVP_PKEY *k, const char *path)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_int_equal(PEM_write_PrivateKey(f, k, NULL, NULL, 0, NULL, NULL), 1);
    fclose(f);
    chmod(path, 0600);
}

/* A self-signed certificate for CN=localhost with key k. */
static void write_cert(EVP_PKEY *k, const char *path)
{
    X509 *x = X509_new();
    X509_set_version(x, 2);
    ASN1_INTEGER_set(X509_get_serialNumber(x), 1);
    X509_gmtime_adj(X509_getm_notBefore(x), -3600);
    X509_gmtime_adj(X509_getm_notAfter(x), 86400);
    X509_NAME *n = X509_get_subject_name(x);
    X509_NAME_add_entry_by_txt(n, "CN", MBSTRING_ASC, (const unsigned char *)"localhost", -1, -1,
                               0);
    X509_set_issuer_name(x, n);
    X509_set_pubkey(x, k);
    assert_true(X509_sign(x, k, EVP_sha256()) > 0);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    PEM_write_X509(f, x);
    fclose(f);
    X509_free(x);
}

static int setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/deformd-tls-XXXXXX");
    if (!mkdtemp(g_dir)) return -1;
    snprintf(g_cert, sizeof g_cert, "%s/cert.pem", g_dir);
    snprintf(g_key, sizeof g_key, "%s/key.pem", g_dir);
    snprintf(g_key2, sizeof g_key2, "%s/other.pem", g_dir);
    EVP_PKEY *k = new_key(), *k2 = new_key();
    if (!k || !k2) return -1;
    write_key(k, g_key);
    write_key(k2, g_key2);
    write_cert(k, g_cert);
    EVP_PKEY_free(k);
    EVP_PKEY_free(k2);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    unlink(g_cert);
    unlink(g_key);
    unlink(g_key2);
    rmdir(g_dir);
    return 0;
}

/* The client side: an SSL on two memory BIOs that trusts g_cert and checks "localhost". */
typedef struct client {
    SSL_CTX *ctx;
    SSL *ssl;
    BIO *rbio, *wbio;
} client;

static void client_init(client *c)
{
    c->ctx = SSL_CTX_new(TLS_client_method());
    assert_int_equal(SSL_CTX_load_verify_locations(c->ctx, g_cert, NULL), 1);
    SSL_CTX_set_verify(c->ctx, SSL_VERIFY_PEER, NULL);
    c->ssl = SSL_new(c->ctx);
    c->rbio = BIO_new(BIO_s_mem());
    c->wbio = BIO_new(BIO_s_mem());
    BIO_set_mem_eof_return(c->rbio, -1);
    SSL_set_bio(c->ssl, c->rbio, c->wbio);
    assert_int_equal(SSL_set1_host(c->ssl, "localhost"), 1);
    SSL_set_connect_state(c->ssl);
}

static void client_free(client *c)
{
    SSL_free(c->ssl);
    SSL_CTX_free(c->ctx);
}

/* Growable byte sink (df_tls_sink). */
typedef struct bytes {
    uint8_t *p;
    size_t n, cap;
} bytes;

static int sink(void *ctx, const uint8_t *d, size_t n)
{
    bytes *b = ctx;
    if (b->n + n > b->cap) {
        b->cap = (b->n + n) * 2;
        b->p = realloc(b->p, b->cap);
        if (!b->p) return -1;
    }
    memcpy(b->p + b->n, d, n);
    b->n += n;
    return 0;
}

/* Moves the client's pending ciphertext into the server in pieces of `piece` bytes. */
static int client_to_server(client *c, df_tls_conn *t, size_t piece, bytes *plain, df_error *e)
{
    uint8_t buf[65536];
    int r, rc = DF_OK;
    while (rc == DF_OK && (r = BIO_read(c->wbio, buf, sizeof buf)) > 0)
        for (size_t off = 0; rc == DF_OK && off < (size_t)r; off += piece)
            rc = df_tls_recv(t, buf + off, (size_t)r - off < piece ? (size_t)r - off : piece,
                             sink, plain, e);
    return rc;
}

/* Seals the `n` buffers and hands the ciphertext to the client. The output goes over the first
 * buffer, as conn.c does it (wbufs[0]). */
static void server_to_client(df_tls_conn *t, client *c, const uv_buf_t *plain, size_t n)
{
    df_error e;
    uv_buf_t copy[4];
    if (n) memcpy(copy, plain, n * sizeof *plain);
    uv_buf_t *outp = &copy[0], out;
    assert_int_equal(df_tls_seal(t, copy, n, outp, &e), DF_OK);
    out = *outp;
    if (out.len) assert_int_equal(BIO_write(c->rbio, out.base, (int)out.len), (int)out.len);
}

static void handshake(client *c, df_tls_conn *t)
{
    df_error e;
    bytes none = {0};
    for (int round = 0; round < 10 && !(SSL_is_init_finished(c->ssl) && df_tls_established(t));
         round++) {
        SSL_do_handshake(c->ssl);
        assert_int_equal(client_to_server(c, t, 1 << 20, &none, &e), DF_OK);
        server_to_client(t, c, NULL, 0);
    }
    assert_true(SSL_is_init_finished(c->ssl));
    assert_true(df_tls_established(t));
    assert_int_equal(SSL_get_verify_result(c->ssl), X509_V_OK);
    assert_string_equal(SSL_get_version(c->ssl), "TLSv1.3");
    assert_int_equal(none.n, 0);
    free(none.p);
}

static void test_round_trip_through_the_seam(void **state)
{
    (void)state;
    df_tls_server *s = NULL;
    df_error e;
    assert_int_equal(df_tls_server_new(g_cert, g_key, &s, &e), DF_OK);
    df_tls_conn *t = df_tls_conn_new(s, &e);
    assert_non_null(t);
    /* a frame sealed before the handshake is dropped (the peer could not read it) */
    uv_buf_t early = uv_buf_init((char *)"early", 5), out;
    assert_int_equal(df_tls_seal(t, &early, 1, &out, &e), DF_OK);
    assert_int_equal(out.len, 0);
    client c;
    client_init(&c);
    handshake(&c, t);
    /* client -> server: 300000 pattern bytes per piece size, the ciphertext fed in pieces of
     * 1, 7, 1000 and 16389 bytes (records split anywhere) */
    size_t n = 300000;
    uint8_t *msg = malloc(n);
    for (size_t i = 0; i < n; i++) msg[i] = (uint8_t)(i * 131u + (i >> 9));
    bytes got = {0};
    const size_t pieces[] = {1, 7, 1000, 16389};
    for (size_t k = 0; k < 4; k++) {
        assert_int_equal(SSL_write(c.ssl, msg, (int)n), (int)n);
        assert_int_equal(client_to_server(&c, t, pieces[k], &got, &e), DF_OK);
        assert_int_equal(got.n, (k + 1) * n);
        assert_memory_equal(got.p + k * n, msg, n);
    }
    /* server -> client: two frames sealed together arrive as their concatenation */
    uv_buf_t frames[2] = {uv_buf_init((char *)msg, 100000), uv_buf_init((char *)msg + 5, 77)};
    server_to_client(t, &c, frames, 2);
    uint8_t *back = malloc(100077);
    size_t have = 0;
    int r;
    while (have < 100077 && (r = SSL_read(c.ssl, back + have, (int)(100077 - have))) > 0)
        have += (size_t)r;
    assert_int_equal(have, 100077);
    assert_memory_equal(back, msg, 100000);
    assert_memory_equal(back + 100000, msg + 5, 77);
    /* close_notify from the client: DF_ESTATE */
    SSL_shutdown(c.ssl);
    got.n = 0;
    assert_int_equal(client_to_server(&c, t, 1 << 20, &got, &e), DF_ESTATE);
    free(back);
    free(got.p);
    free(msg);
    client_free(&c);
    df_tls_conn_free(t);
    df_tls_server_free(s);
}

static void test_plaintext_peer_is_a_handshake_error(void **state)
{
    (void)state;
    df_tls_server *s = NULL;
    df_error e;
    assert_int_equal(df_tls_server_new(g_cert, g_key, &s, &e), DF_OK);
    df_tls_conn *t = df_tls_conn_new(s, &e);
    /* a deformd frame header (magic "DFRM"-like bytes) instead of a ClientHello */
    uint8_t hello[64];
    memset(hello, 0, sizeof hello);
    memcpy(hello, "DFRM\x01\x00\x01\x00", 8);
    bytes got = {0};
    assert_int_equal(df_tls_recv(t, hello, sizeof hello, sink, &got, &e), DF_EIO);
    assert_non_null(strstr(e.msg, "TLS handshake failed"));
    assert_int_equal(got.n, 0);
    assert_false(df_tls_established(t));
    df_tls_conn_free(t);
    df_tls_server_free(s);
}

static void test_bad_files_refuse(void **state)
{
    (void)state;
    df_tls_server *s = NULL;
    df_error e;
    assert_int_equal(df_tls_server_new(g_cert, "", &s, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "set both tls_cert and tls_key"));
    assert_int_equal(df_tls_server_new(g_cert, g_key2, &s, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "does not match the certificate"));
    assert_int_equal(df_tls_server_new(g_key, g_key, &s, &e), DF_EIO); /* a key is no cert */
    assert_non_null(strstr(e.msg, "not a PEM certificate"));
    chmod(g_key, 0640);
    assert_int_equal(df_tls_server_new(g_cert, g_key, &s, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "chmod 600"));
    chmod(g_key, 0600);
    char missing[320];
    snprintf(missing, sizeof missing, "%s/none.pem", g_dir);
    assert_int_equal(df_tls_server_new(missing, g_key, &s, &e), DF_EIO);
    assert_non_null(strstr(e.msg, "No such file"));
    assert_null(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip_through_the_seam),
        cmocka_unit_test(test_plaintext_peer_is_a_handshake_error),
        cmocka_unit_test(test_bad_files_refuse),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
