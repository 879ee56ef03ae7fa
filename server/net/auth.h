/* auth.h — TCP key authentication (config key_file; PROTOCOL.md 4.3). Loop thread.
 *
 * With a key configured, every TCP connection must complete the HMAC-SHA256 exchange of
 * proto/auth_mac.h before any request other than HELLO, PING and AUTH: until then those are
 * answered EPROTO_AUTH and not executed (df_auth_blocks). Unix-socket connections need no AUTH
 * (their peers are checked by the socket's mode and allow_uids / allow_gids, peer.h) but may
 * authenticate too. A wrong proof is answered EPROTO_AUTH and the connection is closed; failures
 * are counted per peer address (Unix: per uid; auth_limit.h: auth_fail_burst,
 * auth_fail_refill_s), and an address without tokens gets ELIMIT ("retry in N s") for any AUTH,
 * without its MAC being checked, and is closed. Every failure and refusal is logged (warn) with
 * the peer address, never the key or a MAC. Counters: stats auth_ok, auth_failed, auth_limited.
 * Named keys (peer_key NAME FILE): the proof is checked against key_file and every peer key; the
 * one that matches names the connection's principal ("admin" for key_file, "key:NAME"). Any
 * key (key_file or a peer_key) turns authentication on. */
#ifndef DF_SERVER_AUTH_H
#define DF_SERVER_AUTH_H

#include "proto/messages.h"
#include "server/net/req.h"
#include "server/server.h"

/* Loads srv->cfg.access.key_file when set (df_auth_key_load: refuses a file others can read)
 * and sets up the rate limit; with no key file nothing is needed. Errors: DF_EIO / DF_EINVAL
 * naming the file (start-up is refused). */
int df_auth_start(df_server *srv, df_error *err);

/* Wipes and frees the key. Idempotent. */
void df_auth_free(df_server *srv);

/* 1 when srv has a key (feature bit AUTH). */
int df_auth_enabled(const df_server *srv);

/* 1 when connection `c` must authenticate before it may send other requests (a TCP connection
 * of a server with a key, not yet authenticated). */
int df_auth_required(const df_conn *c);

/* 1 when request `type` on `c` must be refused because `c` has not authenticated (see above). */
int df_auth_blocks(const df_conn *c, uint16_t type);

/* The AUTH request `r` with body `m`: answers it (the challenge or the server's proof) and
 * returns DF_OK, or returns an error for dispatch to answer (EUNSUPPORTED when the server has
 * no key; EINVAL / ESTATE for a bad method, token size or order); a wrong proof or a
 * rate-limited peer is answered here (EPROTO_AUTH / ELIMIT) and the connection closed. */
int df_auth_request(df_req *r, const df_msg_auth *m, df_error *err);

#endif
