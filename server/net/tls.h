/* tls.h — TLS 1.3 on the TCP listener (config tls_cert / tls_key; OpenSSL libssl). Loop thread.
 *
 * The socket stays libuv's: a connection's SSL object reads ciphertext from a memory BIO that
 * conn.c fills with what uv_read delivered (df_tls_recv, which hands the decrypted bytes on), and
 * writes ciphertext into a memory BIO that conn.c drains into its uv_write (df_tls_seal). That is
 * the whole seam with the connection code; framing, dispatch and the output queue see plaintext.
 * The Unix socket is never encrypted. Only TLS 1.3 is offered; no session tickets are issued. */
#ifndef DF_SERVER_TLS_H
#define DF_SERVER_TLS_H

#include <stddef.h>
#include <stdint.h>

#include <uv.h>

#include "core/common/df_error.h"

struct df_server;
typedef struct df_tls_server df_tls_server; /* the SSL_CTX (certificate and key) */
typedef struct df_tls_conn df_tls_conn;     /* one connection's SSL and its two memory BIOs */

/* Loads `cert` (PEM certificate chain) and `key` (PEM private key) into a TLS 1.3 server context
 * in *out (caller frees with df_tls_server_free). Errors (the message names the file and the
 * reason; nothing allocated): DF_EINVAL when only one of the two is set, when the key file can be
 * read by group or others (chmod 600), or when the key does not match the certificate; DF_EIO
 * when a file cannot be read or is not PEM. */
int df_tls_server_new(const char *cert, const char *key, df_tls_server **out, df_error *err);

/* Frees the context (NULL-safe). Connections hold their own reference to it. */
void df_tls_server_free(df_tls_server *s);

/* srv->cfg.access.tls_cert / tls_key: loads them into srv->tls when set (DF_OK and srv->tls NULL
 * when neither is set). Errors: those of df_tls_server_new (start-up is refused). */
int df_tls_start(struct df_server *srv, df_error *err);

/* Frees srv->tls. Idempotent. */
void df_tls_free(struct df_server *srv);

/* A new server-side connection state of `s`, or NULL (out of memory; err says so). */
df_tls_conn *df_tls_conn_new(df_tls_server *s, df_error *err);

/* Frees the connection state (NULL-safe). */
void df_tls_conn_free(df_tls_conn *t);

/* Where df_tls_recv hands decrypted bytes: returns 0 to go on, nonzero to stop (out of memory). */
typedef int (*df_tls_sink)(void *ctx, const uint8_t *data, size_t len);

/* Feeds `len` ciphertext bytes `in` received from the peer: advances the handshake, and once it
 * is complete passes every decrypted byte to `sink` (in order, in pieces of up to 16 KiB).
 * Any handshake or record output (df_tls_has_output) is left for df_tls_seal. Returns DF_OK
 * (more input needed or all consumed), DF_ESTATE when the peer sent close_notify, DF_EIO
 * for a handshake or record failure (err holds OpenSSL's reason, e.g. "wrong version number"
 * for a plaintext client; an alert for the peer may be pending), DF_ENOMEM. */
int df_tls_recv(df_tls_conn *t, const uint8_t *in, size_t len, df_tls_sink sink, void *ctx,
                df_error *err);

/* 1 when ciphertext waits to be sent (handshake messages, an alert). */
int df_tls_has_output(const df_tls_conn *t);

/* 1 once the handshake has completed. */
int df_tls_established(const df_tls_conn *t);

/* Encrypts the `n` plaintext buffers `plain` (frames; dropped unsent while the handshake is not
 * complete: the peer could not read them) and moves all ciphertext waiting in the write BIO into
 * one buffer owned by `t`, described in *out (len 0 when there is none; `out` may
 * point at plain[0]). The buffer stays valid
 * until the next df_tls_seal or df_tls_conn_free, so it must be fully written before sealing
 * again. Errors: DF_EIO (SSL_write failed), DF_ENOMEM. */
int df_tls_seal(df_tls_conn *t, const uv_buf_t *plain, size_t n, uv_buf_t *out, df_error *err);

/* Ciphertext buffer kept between writes; a larger one (after a big frame) is freed by
 * df_tls_conn_trim. */
#define DF_TLS_KEEP_BYTES (1u << 20)

/* Frees the ciphertext buffer of the last df_tls_seal when it is larger than DF_TLS_KEEP_BYTES.
 * Only once that ciphertext has been written. */
void df_tls_conn_trim(df_tls_conn *t);

#endif
