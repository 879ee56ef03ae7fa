/* dc_client.h — libdeformclient internals: the df_client struct and the request helpers shared
 * by the per-message call files (dc_calls_*.c). Not installed. */
#ifndef DF_CLIENT_DC_CLIENT_H
#define DF_CLIENT_DC_CLIENT_H

#include "client/deformclient.h"
#include "proto/buf.h"

struct df_client {
    int fd;
    void *ssl, *ssl_ctx;         /* TLS (dc_tls.h: SSL *, SSL_CTX *), NULL on a plain socket */
    int timeout_ms;              /* per-wait timeout inside requests, < 0 forever */
    uint64_t next_id;            /* next request id (starts at 1) */
    df_client_event_fn on_event;
    void *event_user;
    int remote_err;              /* 1 when the last failed call's error came from the server */
    int broken;                  /* 1 after a framing error or lost connection */
    uint8_t *rbuf;               /* DF_CLIENT_READ_BUF buffered socket bytes */
    size_t rpos, rlen;           /* unread bytes are rbuf[rpos .. rlen) */
    uint8_t *pbuf;               /* payload storage for frames larger than the buffered part */
    size_t pcap;
    df_buf out;                  /* encoded request scratch */
    df_msg_hello_reply server;   /* hello reply */
    struct dc_shm *shm;          /* mapped shared-memory stream rings (dc_shm.c), nshm of them */
    int nshm;
    uint8_t *shm_frame;          /* copy of the frame an SHM_REF points at */
    size_t shm_cap;
    uint16_t load_flags;         /* DF_LOAD_OPT_* ORed into every load (df_client_set_load_flags) */
    /* cluster redirects (dc_move.c): what a reconnection to the owner repeats */
    int follow_moved;            /* 1 (default): EMOVED reconnects to the owner and retries */
    int moves;                   /* redirects followed */
    char name[DF_MAX_NAME_LEN + 1]; /* the hello's client name */
    char *tls_ca;                /* the TLS CA file of the connection (NULL: plain) */
    uint8_t *key;                /* the key it authenticated with (NULL: none), key_len bytes */
    size_t key_len;
};

/* Cluster redirect (dc_move.c): after an EMOVED error whose message is "MOVED <id> <host:port>",
 * reconnects c to host:port (TCP, TLS with c->tls_ca when set, hello with c->name, AUTH with
 * c->key) in place of its connection (subscriptions and rings are dropped). Returns DF_OK, or
 * DF_EINVAL (not a MOVED message: the caller keeps the original error), or the connection's
 * error (c is then broken). */
int dc_move(df_client *c, const char *moved_msg, df_error *err);

/* The hello handshake on c's connection with client name `name` (c->server gets the reply).
 * Errors: the server's, DF_EIO. */
int dc_hello(df_client *c, const char *name, df_error *err);

/* One mapped ring of a session this client streams through shared memory. */
typedef struct dc_shm {
    uint64_t session_id;
    const uint8_t *base;         /* read-only mapping of the whole ring file */
    size_t map_bytes;
} dc_shm;

/* Handles an SHM_REF event (dc_shm.c): copies the referenced frame out of the session's ring and
 * passes it to the event callback as if it had come on the socket; a frame lost to the ring
 * (overwritten), or a reference the client cannot resolve, reaches the callback as the SHM_REF
 * event itself (the application resyncs with a snapshot). */
void dc_shm_dispatch(df_client *c, const df_frame_header *h, const uint8_t *p);

/* Unmaps session `session_id`'s ring (0: every ring). */
void dc_shm_drop(df_client *c, uint64_t session_id);

/* Encodes a request body with `enc` into c->out (reset first) and runs df_client_transact.
 * `enc` is a df_msg_X_encode function cast to this type together with its message. */
typedef int (*dc_encode_fn)(const void *m, df_buf *out, df_error *err);
int dc_request(df_client *c, uint16_t type, dc_encode_fn enc, const void *msg,
               df_client_reply_fn on_reply, void *user, df_error *err);

/* Waits for the whole reply of request `id` of `type` (see df_client_transact), dispatching
 * events meanwhile. */
int dc_wait_reply(df_client *c, uint16_t type, uint64_t id, df_client_reply_fn on_reply,
                  void *user, df_error *err);

/* Reply decoders for the common single-frame replies (user points at the output struct, which
 * may be NULL to ignore the body). */
int dc_reply_ack(void *user, const df_frame_header *h, const uint8_t *p, df_error *err);
int dc_reply_session_info(void *user, const df_frame_header *h, const uint8_t *p, df_error *err);

/* dc_encode_fn for a df_msg_session_ref body (requests made only of a session id). */
int dc_enc_session_ref(const void *m, df_buf *out, df_error *err);

/* Sends a request made only of a session id (brush end/cancel, undo, redo, reset rest, close,
 * unsubscribe) and decodes an ack reply into *ack (may be NULL). */
int dc_session_ref_call(df_client *c, uint16_t type, uint64_t session_id, df_msg_ack *ack,
                        df_error *err);

/* Applies one QDISP chunk to a replica (dc_stream_enc.c, PROTOCOL.md 6.3); `last`: no MORE.
 * Returns 1 when it completed a version, 0 when more chunks follow or it was ignored (another
 * session, a version already held), or DF_ESTATE (a gap) / DF_EFORMAT / DF_EINVAL / DF_ENOMEM
 * with r->stale set. */
int dc_replica_feed_qdisp(df_client_replica *r, const df_msg_qdisp *q, int last, df_error *err);

/* Monotonic clock in microseconds. */
double dc_now_us(void);

#endif
