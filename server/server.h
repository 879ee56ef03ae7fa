/* server.h — deformd's central state: the server, its connections and sessions.
 *
 * Threading (see README-internals in main.c): everything in these structs is owned by the loop
 * thread, except what a session's running job (df_job) reads while it runs on a worker. */
#ifndef DF_SERVER_SERVER_H
#define DF_SERVER_SERVER_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <uv.h>

#include "core/common/df_error.h"
#include "proto/frame.h"
#include "server/config.h"
#include "server/session/membudget.h"
#include "server/net/outq.h"
#include "server/stats.h"

struct df_session;
struct df_job;
struct df_change;
struct df_req;
struct df_msg_device_list;
struct df_msg_device_view;
struct df_server;

/* The HID subsystem's entry points for the layers below it (server/hid/ builds on handlers,
 * exec and session, so those reach it only through these pointers; hid_manager.h documents
 * each; srv->hid_ops is set by df_server_start, NULL in a df_server made without it). */
typedef struct df_hid_ops {
    int (*list)(struct df_server *srv, struct df_msg_device_list *out, df_error *err);
    int (*bind)(struct df_server *srv, uint64_t device_id, uint64_t session_id, df_error *err);
    int (*view)(struct df_server *srv, const struct df_msg_device_view *v, df_error *err);
    int (*device_stats)(struct df_server *srv, uint64_t device_id,
                        void (*put)(void *ctx, const char *key, double v), void *ctx,
                        df_error *err);
    void (*counts)(const struct df_server *srv, uint32_t *devices, uint32_t *open,
                   uint64_t *events);
    void (*session_active)(struct df_server *srv, struct df_session *s);
    void (*session_gone)(struct df_server *srv, struct df_session *s);
    void (*strokes_changed)(struct df_server *srv, struct df_session *s);
} df_hid_ops;

/* The durable store's entry points for the layers below it (server/store/ builds on session;
 * journal.h documents each; srv->store_ops is set by df_server_start once the store is open and
 * its sessions restored, NULL with store = none). Each returns DF_OK or an error (DF_EIO,
 * DF_ELIMIT for a full disk / store_max_mb) after which the caller changes nothing and fails
 * its request. Loop thread. */
struct df_brush_state;
struct df_membership;
typedef struct df_store_ops {
    int (*session_created)(struct df_server *srv, const struct df_session *s, df_error *err);
    int (*session_closing)(struct df_server *srv, const struct df_session *s, df_error *err);
    int (*change)(struct df_server *srv, const struct df_session *s, const struct df_change *c,
                  df_error *err);
    int (*brush)(struct df_server *srv, const struct df_session *s,
                 const struct df_brush_state *next, uint64_t who, df_error *err);
    int (*access)(struct df_server *srv, const struct df_session *s,
                  const struct df_membership *next, df_error *err);
} df_store_ops;

#define DF_CONN_READ_CHUNK 65536       /* bytes requested from libuv per read */

typedef struct df_conn {
    union {
        uv_stream_t stream;
        uv_pipe_t pipe;
        uv_tcp_t tcp;
    } h;
    struct df_server *srv;
    uint64_t id;
    int is_tcp;
    int closing;             /* uv_close called (or about to be) */
    int flush_close;         /* close once the output queue is flushed; reading stopped */
    const char *flush_why;   /* static reason logged at that close */
    uint64_t flush_deadline; /* uv_now() after which a flush-close happens regardless */
    int refs;                /* 1 for the open handle + 1 per job/reference held */
    uint8_t *rbuf;           /* bytes received, not yet framed */
    size_t rlen, rcap;
    df_outq outq;
    uv_write_t wreq;
    size_t wcount;           /* buffers in the current uv_write, 0 when idle */
    uv_buf_t wbufs[DF_OUTQ_MAX_BATCH];
    int pending;             /* requests accepted and not yet answered */
    int hello_done;          /* a HELLO succeeded (required before most requests) */
    char name[DF_MAX_NAME_LEN + 1]; /* the client_name of its HELLO ("" before / when none) */
    uint8_t stream_enc;      /* DF_STREAM_ENC_* bits of its HELLO (0: exact float32) */
    uint8_t stream_neg;      /* its HELLO carried the stream trailer (any encoding, 0 too):
                              * its stream is coalesced when it cannot keep up (stream_lag.h) */
    double stream_err;       /* QUANTIZED: the error bound E of its HELLO (mesh units) */
    uint64_t coalesced;      /* stream versions folded into a coalesced one (stream_lag.h) */
    double bytes_per_s;      /* bytes written per second over the last sweep period */
    uint64_t rate_bytes;     /* outq.total_bytes at the last sweep */
    uint64_t rate_ms;        /* uv_now() at the last sweep */
    struct df_upload *upload;/* mesh upload in progress (chunked load), or NULL */
    uint64_t bytes_in;
    int refused;             /* refused at admission (guard.h): closes quietly */
    int want_owners;         /* its HELLO set DF_HELLO_WANT_OWNERS (cluster/cluster.h list) */
    int admit_waiting;       /* accepted at max_clients: admitted or refused at the end of the
                              * loop iteration (guard.h), not reading until then */
    uint64_t accepted_ms;    /* uv_now() at accept (handshake timeout) */
    uint64_t last_rx_ms;     /* uv_now() when bytes last arrived (idle timeout) */
    uint64_t sub_epoch;      /* == srv->sweep_epoch: subscribed somewhere at the last sweep */
    /* Peer identity (server/net/peer.h): Unix peers' SO_PEERCRED, TCP peers' address. */
    int peer_cred;           /* 1 when peer_uid/gid/pid were read (Unix socket) */
    uint32_t peer_uid, peer_gid;
    int32_t peer_pid;
    char peer_addr[64];      /* TCP: "ADDR port P" of the peer ("" for Unix) */
    char peer_host[48];      /* TCP: the peer's address alone (rate-limit key, auth.h) */
    int peer_loopback;       /* TCP: 1 when the peer address is loopback */
    /* TCP key authentication (server/net/auth.h) */
    int auth_ok;             /* 1: authenticated (or none required) */
    int auth_step;           /* 0 none, 1 challenge sent (nonces below are valid) */
    /* Access control (server/session/access.h, PROTOCOL.md 4.34): the principal this peer acts
     * as: "uid:N" (Unix), "tcp" (TCP, server without keys), "key:NAME" (peer_key), "admin". */
    char principal[48];
    int admin;               /* 1: every right on every session (key_file, the daemon's uid) */
    uint8_t auth_nc[32], auth_ns[32]; /* client and server nonces of the exchange */
    struct df_tls_conn *tls; /* TLS state (server/net/tls.h) of a TCP connection, or NULL */
    int wbusy;               /* a uv_write of wbufs is running */
    int kick_queued;         /* on the server's deferred-write list */
    struct df_conn *kick_next;
    struct df_conn *prev, *next;
} df_conn;

typedef struct df_server {
    uv_loop_t *loop;
    df_server_config cfg;
    uv_pipe_t unix_srv;
    uv_tcp_t tcp_srv;
    int have_unix, have_tcp;
    int unix_owned;          /* 1 when we created the socket file (unlink on exit) */
    int tcp_port_bound;      /* actual TCP port (after binding port 0) */
    uv_signal_t sig_int, sig_term;
    uv_check_t kick_check;   /* starts the writes queued during this loop iteration */
    uv_timer_t cork_timer;   /* starts corked subscriber writes (DF_CONN_CORK_MS) */
    uv_idle_t fanout_idle;   /* continues corked writes that overran their slice (conn.h) */
    uv_timer_t sweep_timer;  /* closes connections whose flush-close deadline passed */
    df_conn *kick_first[2], *kick_last[2]; /* [0] connections with replies, [1] the others */
    df_conn *conns;          /* doubly linked list */
    int n_conns;
    uint64_t next_conn_id;
    struct df_session *sessions; /* singly linked, newest first */
    int n_sessions;
    uint64_t next_session_id;
    struct df_pool *pool;    /* compute pool: every job's work, its one channel back (pool.h) */
    int jobs_running;        /* jobs submitted to the thread pool and not completed */
    uint64_t inline_spent_ns;/* job work run on the loop thread this iteration (job.h) */
    int stopping;
    size_t cache_bytes;      /* bytes of cached factorizations over all sessions */
    df_membudget mem;        /* memory_max_mb accounting: uploads, sessions, rings, history */
    uint64_t history_dropped;/* undo steps dropped to history budgets, all sessions */
    uint64_t lru_clock;
    int reserve_fd;          /* spare descriptor (guard.h), -1 when none */
    int n_refusing;          /* refused connections still flushing their ERROR frame */
    int n_closing;           /* connections closed (c->closing) but not yet released, refused
                              * ones aside: no longer counted against max_clients */
    int n_admit_waiting;     /* connections with admit_waiting set */
    int refuse_logged;       /* a refusal was logged at refuse_log_ms */
    uint64_t refuse_log_ms, refuse_suppressed; /* refusal log rate limit (guard.h) */
    uint64_t sweep_epoch;
    int lagging_subs;        /* subscriptions being coalesced (stream_lag.h), all sessions */
    df_stats stats;
    uint64_t last_change_session; /* session of a client's last change request or subscribe
                                   * (df_job_is_change): unbound HID devices drive it */
    struct df_tls_server *tls;    /* TLS of the TCP listener (net/tls.h), NULL without */
    struct df_auth_server *auth;  /* TCP key authentication (net/auth.h), NULL without a key */
    struct df_auth_limit *join_limit; /* wrong JOIN keys per peer (h_access.c), made on use */
    struct df_hid_manager *hid;   /* HID devices (server/hid/hid_manager.h), NULL when off */
    const df_hid_ops *hid_ops;    /* its entry points (set by df_server_start) */
    /* Upward calls of the network layer (net never includes what is above it), set by
     * df_server_start: a complete request frame (dispatch), a connection that closes (its
     * sessions and jobs forget it), its last reference gone (its unfinished upload). NULL: none. */
    void (*on_frame)(struct df_conn *c, const df_frame_header *h, const uint8_t *payload);
    void (*on_conn_close)(struct df_conn *c);
    void (*on_conn_free)(struct df_conn *c);
    /* Step 4 of every session commit (commit.h): where a journal or replication log appends
     * its record. NULL: none. Loop thread. */
    void (*commit_hook)(void *arg, const struct df_session *s, const struct df_change *c);
    void *commit_hook_arg;
    struct df_store *store;       /* the durable store (server/store/store.h), NULL: none */
    const df_store_ops *store_ops;/* its entry points (journal.h), NULL: none */
    struct df_cluster *cluster;   /* cluster mode (server/cluster/cluster.h), NULL: off */
    /* Cluster mode's routing of a request for a session this daemon does not hold
     * (cluster.h df_cluster_route: redirect or take over), set by df_cluster_start; NULL: off.
     * A hook so that exec/ (below cluster/) reaches it. Loop thread. */
    int (*session_route)(struct df_server *srv, uint64_t id, struct df_session **out,
                         df_error *err);
} df_server;

/* The server's memory budget (membudget.h) with its caps taken from srv->cfg (memory_max_mb,
 * uploads_max_mb, shm_total_bytes), so that a df_server set up without df_server_start (unit
 * tests) charges against its config too. Loop thread. */
static inline df_membudget *df_server_mem(df_server *srv)
{
    df_mem_set_limits(&srv->mem, (uint64_t)srv->cfg.memory_max_mb << 20,
                      (uint64_t)srv->cfg.uploads_max_mb << 20, srv->cfg.shm_total_bytes);
    return &srv->mem;
}

/* Initializes `srv` on `loop` with `cfg` (copied): opens the listeners (socket-activated fds
 * first, then cfg->socket_path and cfg->tcp_*), installs SIGINT/SIGTERM handlers and starts the
 * compute pool (pool.h). Errors: DF_EIO (bind/listen failed, message names the address; or the
 * pool could not start), DF_EINVAL. On error
 * everything opened so far is closed again (run the loop once to finish closing handles). */
int df_server_start(df_server *srv, uv_loop_t *loop, const df_server_config *cfg, df_error *err);

/* Begins a clean shutdown: stops accepting, closes connections, cancels running handle moves;
 * the loop ends once the running jobs have completed and every handle is closed. Idempotent. */
void df_server_stop(df_server *srv);

/* Frees what remains after the loop has ended (sessions, caches). */
void df_server_free(df_server *srv);

/* Writes "unix:PATH" / "tcp:HOST:PORT" descriptions of the listeners into buf. */
void df_server_describe(const df_server *srv, char *buf, size_t cap);

#endif
