/* conn.h — one client connection: reading and framing, the bounded output queue, closing.
 *
 * Reads: bytes accumulate in rbuf; every complete frame (24-byte header + payload) is handed to
 * df_dispatch_frame. A header that breaks framing (bad magic or version, nonzero reserved,
 * payload_len > DF_MAX_FRAME_PAYLOAD) gets one error frame and the connection is closed after it
 * is flushed. Writes: df_conn_send pushes a shared frame buffer into the output queue and starts
 * a uv_write when none is running; a client whose queue would exceed output_queue_limit is
 * dropped with a log line. All functions run on the loop thread. */
#ifndef DF_SERVER_CONN_H
#define DF_SERVER_CONN_H

#include "server/net/sbuf.h"
#include "server/server.h"

/* Accepts one pending connection on `listener` (is_tcp: 1 for TCP) and starts reading.
 * Refuses it (accepts, sends an ERROR event saying why, closes) when max_clients are connected
 * or no file descriptor is left (guard.h). */
void df_conn_accept(df_server *srv, uv_stream_t *listener, int is_tcp);

/* Admits or refuses (guard.h) the connections accepted at max_clients during this loop
 * iteration, now that the closes read in it count: run from the server's uv_check handle. */
void df_conn_admit_waiting(df_server *srv);

/* Subscriber-only stream output (DISPLACEMENT, PROGRESS, SHM_REF events) is corked for up to
 * this long so that consecutive versions go out in one writev per subscriber instead of one
 * write per version. Replies and control events are not corked (conn.c, corked_frame). */
#define DF_CONN_CORK_MS 1

/* Loop time one pass over corked subscriber writes may take. A 1k-vertex version is 12 KB, so
 * 32 subscribers with a millisecond of versions each are ~4 MB of socket copies (~0.5 ms); done
 * in one go, every request arriving meanwhile waits for all of it. Passes of this length
 * alternate with the loop's reading (through an idle handle) until every subscriber is written. */
#define DF_CONN_FANOUT_SLICE_US 20

/* Kernel send buffer asked for on Unix-socket connections (Linux doubles it, capped by
 * net.core.wmem_max): room for a millisecond of versions to a subscriber even on large meshes,
 * so a fan-out pass rarely finds a socket full (a full socket costs a queued uv_write, an
 * EPOLLOUT round and a wake-up). TCP keeps the kernel's autotuning. */
#define DF_CONN_UNIX_SNDBUF (1 << 20)

/* Starts the writes of connections that got a reply in this loop iteration (run from the
 * server's uv_check handle, so a requester's ack and its own displacement frames are never
 * delayed behind a broadcast); with `everything` also every corked subscriber's, to the end
 * (shutdown). Corked subscriber output otherwise goes out from the cork timer in passes of
 * DF_CONN_FANOUT_SLICE_US, continued from the server's idle handle. */
void df_conn_flush_all(df_server *srv, int everything);

/* Queues `frame` (a reference is taken) for sending; the write starts at the end of the current
 * loop iteration (df_conn_flush_all), so frames queued together go out in one writev. Returns DF_OK, or DF_ELIMIT after dropping
 * the client (queue over the limit), or DF_ESTATE when the connection is closing (frame ignored). */
int df_conn_send(df_conn *c, df_sbuf *frame);

/* Closes the connection now (pending output is discarded). `why` is logged at info level
 * (warn when `warn` is 1). Idempotent. */
void df_conn_close(df_conn *c, const char *why, int warn);

/* How long a connection closing after an error frame may take to read it before it is closed
 * anyway (a peer that never reads must not hold its slot). */
#define DF_CONN_FLUSH_TIMEOUT_MS 5000

/* Closes every connection whose flush-close deadline has passed (server sweep timer). */
void df_conn_sweep(df_server *srv);

/* Stops reading and closes the connection once its output queue is flushed (or after
 * DF_CONN_FLUSH_TIMEOUT_MS). */
void df_conn_close_after_flush(df_conn *c, const char *why);

/* Reference counting: jobs hold a reference so that the struct outlives the socket; the memory is
 * released when the handle is closed and the last reference is dropped. */
void df_conn_ref(df_conn *c);
void df_conn_unref(df_conn *c);

#endif
