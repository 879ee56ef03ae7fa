/* dc_tls.h — libdeformclient's TLS (internal): TLS 1.3 over a connected TCP socket with OpenSSL
 * libssl, and the byte I/O of a client whichever transport it uses (plain fd or TLS). Not
 * installed. Calling thread (the client's). */
#ifndef DF_CLIENT_DC_TLS_H
#define DF_CLIENT_DC_TLS_H

#include <stddef.h>

#include "client/dc_client.h"

/* Runs the TLS 1.3 handshake on c->fd (a connected TCP socket; it is made non-blocking) and
 * keeps the session in c->ssl / c->ssl_ctx. The server's certificate must chain to a CA of the
 * PEM file `ca_file` and name `host` (a DNS name is checked against the certificate's names, a
 * numeric IPv4/IPv6 address against its IP addresses; SNI carries a DNS name). Waits at most
 * c->timeout_ms per step (< 0: no limit). Errors (nothing kept): DF_EIO for an unreadable CA
 * file, a failed handshake or a certificate that does not verify (the message gives OpenSSL's
 * reason, e.g. "certificate verify failed: unable to get local issuer certificate"),
 * DF_ENOMEM. */
int dc_tls_start(df_client *c, const char *host, const char *ca_file, df_error *err);

/* Frees c's TLS state (sends close_notify when the session is up). NULL-safe fields. */
void dc_tls_end(df_client *c);

/* The byte I/O of df_client: through TLS when c->ssl is set, else dc_net.h's functions on c->fd,
 * with the same semantics (dc_net_write2, dc_net_read_some, dc_net_read_exact). */
int dc_io_write2(df_client *c, const void *a, size_t alen, const void *b, size_t blen,
                 df_error *err);
long dc_io_read_some(df_client *c, void *buf, size_t cap, int timeout_ms, df_error *err);
int dc_io_read_exact(df_client *c, void *buf, size_t len, int timeout_ms, df_error *err);

#endif
