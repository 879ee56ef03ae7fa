/* auth_mac.h — the HMAC-SHA256 challenge-response of AUTH (PROTOCOL.md 4.3), shared by the daemon
 * and the clients: the MACs each side sends, their constant-time check, nonces, and the key file.
 * OpenSSL libcrypto (HMAC via EVP_MAC, RAND_bytes, CRYPTO_memcmp). Thread-safe; no state.
 *
 * The exchange (nonces and MACs are DF_AUTH_NONCE_BYTES / DF_AUTH_MAC_BYTES = 32 bytes):
 *   client -> AUTH method HMAC_CHALLENGE, token Nc (client nonce)
 *   server <- reply method HMAC_CHALLENGE, token Ns (server nonce)
 *   client -> AUTH method HMAC_PROOF, token HMAC-SHA256(K, Ns || Nc || "deformd-auth-v1 client")
 *   server <- reply method HMAC_PROOF, token HMAC-SHA256(K, Ns || Nc || "deformd-auth-v1 server")
 * The client checks the server's MAC before it trusts the connection (mutual). */
#ifndef DF_PROTO_AUTH_MAC_H
#define DF_PROTO_AUTH_MAC_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "proto/wire_schema.h"

#define DF_AUTH_KEY_MIN_BYTES 32   /* shortest key a key file may hold */
#define DF_AUTH_KEY_CAP_BYTES 1024 /* longest key a key file may hold */

/* Who computes the MAC: the context string that ends the MAC input. */
typedef enum df_auth_role { DF_AUTH_ROLE_CLIENT = 0, DF_AUTH_ROLE_SERVER = 1 } df_auth_role;

/* HMAC-SHA256 of `msg` (`mlen` bytes, may be NULL when 0) under `key` (`klen` bytes, may be 0)
 * into out[32]. Errors: DF_EINVAL (NULL out, or NULL key/msg with a nonzero length),
 * DF_EINTERNAL (libcrypto failed; message names the call). */
int df_auth_hmac_sha256(const uint8_t *key, size_t klen, const uint8_t *msg, size_t mlen,
                        uint8_t out[32], df_error *err);

/* The MAC of `role` over the exchange's nonces: HMAC-SHA256(key, ns || nc || context) with the
 * context DF_AUTH_CONTEXT_CLIENT or DF_AUTH_CONTEXT_SERVER (no NUL). ns, nc: 32 bytes each.
 * Errors: as df_auth_hmac_sha256, DF_EINVAL for a bad role. */
int df_auth_mac(const uint8_t *key, size_t klen, const uint8_t ns[DF_AUTH_NONCE_BYTES],
                const uint8_t nc[DF_AUTH_NONCE_BYTES], df_auth_role role,
                uint8_t out[DF_AUTH_MAC_BYTES], df_error *err);

/* 1 when the `n` bytes at a and b are equal, compared in time independent of where they differ
 * (CRYPTO_memcmp), else 0. */
int df_auth_equal(const uint8_t *a, const uint8_t *b, size_t n);

/* Fills out[n] with cryptographically random bytes (RAND_bytes). Errors: DF_EINTERNAL. */
int df_auth_random(uint8_t *out, size_t n, df_error *err);

/* Reads the secret key from the file at `path`: its bytes without trailing blanks, tabs, CR and
 * LF (so `openssl rand -hex 32 > FILE` makes a 64-byte key), DF_AUTH_KEY_MIN_BYTES ..
 * DF_AUTH_KEY_CAP_BYTES bytes, into key[cap] (cap >= DF_AUTH_KEY_CAP_BYTES) and *len.
 * The file must be a regular file that others (not owner, not group) can neither read nor write.
 * Errors (message names the file and says what to do): DF_EIO (cannot open / read), DF_EINVAL
 * (not a regular file, readable or writable by others, too short, too long). On error key and
 * *len are untouched. */
int df_auth_key_load(const char *path, uint8_t *key, size_t cap, size_t *len, df_error *err);

#endif
