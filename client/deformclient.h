/* deformclient.h — libdeformclient: the C client of the deformd daemon (proto/PROTOCOL.md).
 *
 * A df_client is one connection (Unix socket or TCP). Requests are blocking: each call sends one
 * request (several frames for a chunked upload), then reads frames until the reply carrying the
 * same request id is complete (all DF_FLAG_MORE chunks), dispatching every event frame that
 * arrives meanwhile (displacement stream, progress, session closed) to the event callback.
 * Replies to other request ids (e.g. of a request that timed out) are discarded.
 *
 * Errors: every function returns DF_OK or a negative code and fills `err` when non-NULL. Errors
 * the server reported carry the server's wire code (core/common/df_error.h DF_E* or
 * proto/wire_error.h DF_EPROTO_*) and message; df_client_last_error_was_remote tells them apart
 * from local failures (DF_EIO: connection lost, DF_ESTATE: timeout, DF_EINVAL: bad arguments,
 * DF_EFORMAT/DF_EPROTO_*: malformed reply). After DF_EIO or a malformed reply the connection is
 * unusable; close it.
 *
 * Threading: a df_client is used by one thread at a time. The event callback runs inside
 * whichever call is reading; it must not call back into the same df_client.
 *
 * Message bodies are the proto/messages.h structs; decoded replies that own memory are released
 * with their df_msg_X_free. */
#ifndef DEFORMCLIENT_H
#define DEFORMCLIENT_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "proto/frame.h"
#include "proto/messages.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Buffered bytes read from the socket at once, and the client name sent in hello. */
#define DF_CLIENT_READ_BUF 65536
#define DF_CLIENT_NAME "libdeformclient"

typedef struct df_client df_client;

/* Event callback: `h` is the frame header (DF_FLAG_EVENT set; DF_FLAG_MORE on all but the last
 * chunk of a chunked event), `payload` its h->payload_len bytes (valid during the call only). */
typedef void (*df_client_event_fn)(void *user, const df_frame_header *h, const uint8_t *payload);

/* ------------------------------------------------------------------------- connection */

/* Connects to the Unix socket `path` and performs the hello handshake (protocol version 1,
 * client name `name`, NULL -> DF_CLIENT_NAME). *out receives the client. Errors: DF_EINVAL,
 * DF_EIO (cannot connect / connection lost), DF_ENOMEM, or the server's error for the hello. */
int df_client_connect_unix(const char *path, const char *name, df_client **out, df_error *err);

/* Same over TCP to `host`:`port` (TCP_NODELAY set). */
int df_client_connect_tcp(const char *host, int port, const char *name, df_client **out,
                          df_error *err);

/* Same over TCP with TLS 1.3 when `tls_ca` is a PEM file (NULL: plain TCP, as
 * df_client_connect_tcp): the daemon's certificate (its tls_cert) must chain to a CA in `tls_ca`
 * and name `host` (DNS name, or IP address when `host` is numeric). The handshake precedes the
 * hello; key authentication (df_client_authenticate) then runs inside TLS. The socket becomes
 * non-blocking; with TLS, decrypted bytes may wait inside the library, so a poll()-based loop
 * must call df_client_pump with timeout 0 until it has nothing before polling df_client_fd again.
 * Errors: as df_client_connect_tcp, and DF_EIO "TLS handshake with HOST failed: REASON" (a
 * certificate from another CA or for another name: "certificate verify failed: ...", a server
 * without TLS) or "TLS CA file F: ..." (unreadable CA file). */
int df_client_connect_tcp_tls(const char *host, int port, const char *name, const char *tls_ca,
                              df_client **out, df_error *err);

/* Cluster mode (PROTOCOL.md 4.39): a request answered EMOVED ("MOVED <id> <host:port>": the
 * session is owned by another daemon) reconnects the client to that address (TCP; TLS with the
 * same CA file, the same hello name and stream encoding, AUTH with the key it authenticated with) and is sent there
 * once more; subscriptions and shared-memory rings of the old connection are gone (subscribe
 * again). on = 0 turns that off (the EMOVED error is returned). Default on. */
void df_client_set_follow_moved(df_client *c, int on);

/* Redirects followed so far (df_client_set_follow_moved). */
int df_client_moves(const df_client *c);

/* Connects like df_client_connect_unix (`unix_path` non-NULL) or df_client_connect_tcp_tls
 * (`host`, `port`, `tls_ca` may be NULL) and asks in the hello for stream encoding `encoding`
 * (DF_STREAM_ENC_* bits; 0: exact float32) with absolute error bound `error_bound` (mesh
 * units, QUANTIZED only, else 0; PROTOCOL.md 4.2, 6.3). The hello always carries the stream
 * trailer, encoding 0 included: the daemon then coalesces this connection's stream when it
 * cannot keep up (PROTOCOL.md 6.3 "Bandwidth"; the other connects send the original hello and
 * are never coalesced). Needs a daemon that knows the trailer (protocol of issue 16). The
 * granted encoding is in df_client_server_info(c)->stream_encoding. Stream events then include DF_MSG_QDISP
 * and DF_MSG_ZFRAME frames, which df_client_replica_feed takes. Errors: as the connects, and
 * DF_EINVAL for a bad encoding request (checked before connecting). */
int df_client_connect_enc(const char *unix_path, const char *host, int port, const char *tls_ca,
                          const char *name, uint8_t encoding, double error_bound,
                          df_client **out, df_error *err);

/* Closes the connection and frees the client. NULL-safe. */
void df_client_close(df_client *c);

/* The server's hello reply (limits, features, name) as received at connect. */
const df_msg_hello_reply *df_client_server_info(const df_client *c);

/* Registers the event callback (NULL: events are dropped). */
void df_client_set_event_callback(df_client *c, df_client_event_fn fn, void *user);

/* Timeout in ms for each wait on the socket inside a request (< 0: wait forever, the default).
 * A timeout returns DF_ESTATE; the late reply is discarded by later calls. */
void df_client_set_timeout(df_client *c, int timeout_ms);

/* The socket fd, for poll()-based event loops (read readiness: call df_client_pump). */
int df_client_fd(const df_client *c);

/* 1 when the error of the last failed call was reported by the server, else 0. */
int df_client_last_error_was_remote(const df_client *c);

/* ---------------------------------------------------------------------- low level */

/* Sends one frame of `type` with `flags` (0 or DF_FLAG_MORE) and request id `id` (0: allocate
 * the next id) carrying `len` bytes of `payload`. *id_out (may be NULL) receives the id used.
 * Errors: DF_EINVAL (len > DF_MAX_FRAME_PAYLOAD), DF_EIO; when the server had closed the
 * connection after a connection-level ERROR event (refused at max_clients, a timeout), that
 * event's code and message (df_client_last_error_was_remote then returns 1). */
int df_client_send(df_client *c, uint16_t type, uint16_t flags, uint64_t id, const void *payload,
                   size_t len, uint64_t *id_out, df_error *err);

/* Reads the next frame (waiting at most `timeout_ms`, < 0 forever) WITHOUT dispatching it: *h
 * receives its header and *payload its bytes, valid until the next call on `c`. Errors:
 * DF_ESTATE (timeout, nothing consumed), DF_EIO, DF_EPROTO_* (bad header: connection unusable). */
int df_client_recv(df_client *c, int timeout_ms, df_frame_header *h, const uint8_t **payload,
                   df_error *err);

/* Reads and dispatches frames for up to `timeout_ms` (0: only what is already readable without
 * blocking; < 0: until one event frame was dispatched). Returns the number of event frames
 * dispatched (>= 0), or a negative error (DF_EIO...). Stray replies are discarded. */
int df_client_pump(df_client *c, int timeout_ms, df_error *err);

/* Reply frame callback of df_client_transact: one call per reply chunk, in order. Return DF_OK
 * to continue, or a negative code to fail the request (the remaining chunks are still drained). */
typedef int (*df_client_reply_fn)(void *user, const df_frame_header *h, const uint8_t *payload,
                                  df_error *err);

/* Sends a single-frame request and waits for its whole reply. Without an error flag each reply
 * frame goes to `on_reply` (may be NULL: reply ignored); an error reply is decoded into `err` and
 * its code returned. Events that arrive meanwhile go to the event callback. */
int df_client_transact(df_client *c, uint16_t type, const void *payload, size_t len,
                       df_client_reply_fn on_reply, void *user, df_error *err);

/* ------------------------------------------------------------------ one call per message */

/* Ping: sends `len` (<= DF_MAX_PING_BYTES) bytes and checks the echo. *rtt_us (may be NULL)
 * receives the round trip in microseconds. */
int df_client_ping(df_client *c, const void *data, uint32_t len, double *rtt_us, df_error *err);

/* Auth with `method` and a token (<= DF_MAX_AUTH_TOKEN bytes); the reply's token is not
 * returned (df_client_authenticate runs the whole exchange). Servers without a key answer
 * DF_EUNSUPPORTED. */
int df_client_auth(df_client *c, uint16_t method, const void *token, uint32_t len, df_error *err);

/* Key authentication (PROTOCOL.md 4.3): the mutual HMAC-SHA256 challenge-response with the
 * `key_len` (1..1024) bytes of `key`, usually right after connecting (a TCP connection to a
 * daemon with a key, hello reply auth_required = 1, must do it before other requests; on the
 * Unix socket it is optional). Errors: the server's DF_EPROTO_AUTH (wrong key: the server then
 * closes the connection), DF_ELIMIT (too many failures from this address: retry later),
 * DF_EUNSUPPORTED (the server has no key); DF_EPROTO_AUTH from the client itself (remote 0:
 * the server's proof is wrong, so it does not know the key; the connection is then unusable),
 * DF_EINVAL, DF_EIO, DF_EINTERNAL (no random numbers). */
int df_client_authenticate(df_client *c, const void *key, size_t key_len, df_error *err);

/* df_client_authenticate with the key in the file `key_file` (its bytes without trailing
 * blanks and newlines, 32..1024 bytes; refused when others may read or write the file).
 * Errors: as df_client_authenticate, plus DF_EIO / DF_EINVAL for the file (the message names
 * it and says what to do). The key is wiped from memory afterwards. */
int df_client_authenticate_file(df_client *c, const char *key_file, df_error *err);

/* Sets extra load_mesh option bits (DF_LOAD_OPT_2D: a 2D session even if the file gives z;
 * DF_LOAD_OPT_PROGRESS: WORK_PROGRESS events of the upload and parse, PROTOCOL.md 4.37, which
 * reach the event callback during the load, all before it returns) ORed into the options of
 * every later load on `c` (df_client_load_mesh_bytes / _file / _path and their _ex forms, which
 * always set DF_LOAD_OPT_EXT themselves); 0 at connect. Unknown bits are refused by the server
 * (DF_EPROTO_RESERVED). */
void df_client_set_load_flags(df_client *c, uint16_t flags);

/* Uploads `len` bytes of a mesh file in `format` (DF_FMT_*, DF_FMT_AUTO sniffs) as session
 * `name` (may be NULL/""), in chunks that fit the server's max frame payload. For DF_FMT_TETGEN
 * `bytes` holds the .node bytes then the .ele bytes, the .ele starting at `part2_offset`
 * (0 for other formats). *info receives the new session. Limit: DF_MAX_MESH_BYTES. */
int df_client_load_mesh_bytes(df_client *c, const char *name, uint8_t format, const void *bytes,
                              uint64_t len, uint64_t part2_offset, df_msg_session_info *info,
                              df_error *err);

/* Reads the local file `path` (.obj .off .ply .mesh, any case; X.node or X.ele: the pair, the
 * other half with the same case of extension, e.g. T1.NODE + T1.ELE) and uploads it inline with
 * its base name as file_name (see df_client_load_mesh_bytes_ex). DF_EIO when a file cannot be
 * read; DF_EINVAL for another extension (DF_CLIENT_FORMATS_MSG; use df_client_load_mesh_bytes
 * with DF_FMT_AUTO to sniff the content). */
int df_client_load_mesh_file(df_client *c, const char *path, const char *name,
                             df_msg_session_info *info, df_error *err);

/* Asks the server to read `path` itself (needs DF_FEAT_PATH_LOAD and a path allowed by its
 * config). */
int df_client_load_mesh_path(df_client *c, const char *path, const char *name, uint8_t format,
                             df_msg_session_info *info, df_error *err);

/* Message for a file name whose extension names no mesh format. */
#define DF_CLIENT_FORMATS_MSG                                                                    \
    "mesh format not recognised from the file name; formats: .obj, .off, .ply, .mesh (MEDIT), "  \
    ".node + .ele (TetGen)"

/* The same three loads with the LOAD_MESH EXT option (PROTOCOL.md 4.5): the server names errors
 * after `file_name` (uploads; may be NULL/"": "upload"), names the session after the file when
 * `name` is empty ("spot", "spot-2", ...), and *reply (may be NULL) receives the session and the
 * reader's report (reply->has_report = 1): dropped lower-dimensional elements, duplicate,
 * degenerate and inverted elements, non-manifold edges/faces, boundary, unused vertices. A server
 * older than the option answers DF_EPROTO_RESERVED. Other arguments and errors as above. */
int df_client_load_mesh_bytes_ex(df_client *c, const char *name, const char *file_name,
                                 uint8_t format, const void *bytes, uint64_t len,
                                 uint64_t part2_offset, df_msg_load_reply *reply, df_error *err);
int df_client_load_mesh_file_ex(df_client *c, const char *path, const char *name,
                                df_msg_load_reply *reply, df_error *err);
int df_client_load_mesh_path_ex(df_client *c, const char *path, const char *name,
                                uint8_t format, df_msg_load_reply *reply, df_error *err);

/* Lists the sessions; free *out with df_msg_session_list_free. */
int df_client_list_sessions(df_client *c, df_msg_session_list *out, df_error *err);

/* Opens a session by id (session_id != 0) or by `name` (session_id == 0); *info may be NULL. */
int df_client_open_session(df_client *c, uint64_t session_id, const char *name,
                           df_msg_session_info *info, df_error *err);

/* Destroys a session (subscribers receive DF_MSG_SESSION_CLOSED). *ack may be NULL. */
int df_client_close_session(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err);

/* Subscribes to a session's displacement stream; `flags` DF_SUBSCRIBE_SNAPSHOT asks for a dense
 * snapshot event first. *info (may be NULL) receives the session state at subscription. */
int df_client_subscribe(df_client *c, uint64_t session_id, uint32_t flags,
                        df_msg_session_info *info, df_error *err);

/* Subscribes and resyncs from `from_version`, the version whose published displacements the
 * caller holds (e.g. a df_client_replica's r->version after a reconnect; PROTOCOL.md 6.2).
 * *info (may be NULL) receives the session state: info->version is the version the stream
 * brings the caller to. Then, through the event callback and before any live frame, come
 * either the frames of versions from_version+1 .. info->version exactly as they were
 * broadcast (none when from_version == info->version), or, when the daemon no longer keeps
 * them (too old, a restart) or from_version > info->version, one dense snapshot of
 * info->version (DF_MSG_DISPLACEMENT events of kind DF_CHANGE_SNAPSHOT carrying this
 * request's id). Both feed a df_client_replica unchanged (df_client_replica_feed). Errors: the
 * server's (DF_ENOTFOUND, DF_EPERM, ...), transport errors. */
int df_client_subscribe_from(df_client *c, uint64_t session_id, uint64_t from_version,
                             df_msg_session_info *info, df_error *err);
int df_client_unsubscribe(df_client *c, uint64_t session_id, df_error *err);

/* Who is connected to a session (SESSION_PEERS, PROTOCOL.md 4.38): one row per connection
 * subscribed to session_id, in subscription order, into *out (items malloc'd:
 * df_msg_peer_list_free; count 0 when nobody is subscribed). Each row: the connection id, its
 * HELLO client_name and principal, its transport (DF_TRANSPORT_UNIX / _TCP) and DF_PEER_* flags
 * (SELF: this connection, EDIT: it may edit the session, SHM: it reads the shared-memory
 * stream). Needs the observe right. Errors: DF_ENOTFOUND (no such session), DF_EPERM (no
 * observe right), transport errors; *out is unchanged on error. Caller's thread. */
int df_client_session_peers(df_client *c, uint64_t session_id, df_msg_peer_list *out,
                            df_error *err);

/* Switches this subscription to the shared-memory stream (PROTOCOL.md 6.1; Unix socket, same
 * host, subscribed first): the daemon writes each broadcast frame once into a ring file that this
 * client maps read-only, and sends a 24-byte SHM_REF in its place. The library resolves them:
 * the event callback keeps receiving DISPLACEMENT / PROGRESS frames as before. A frame
 * overwritten before this client read it (it fell more than the ring behind) reaches the
 * callback as a DF_MSG_SHM_REF event instead: resync with df_client_snapshot. *info (may be NULL)
 * receives the ring's description. Errors: the server's (DF_ESTATE not subscribed,
 * DF_EUNSUPPORTED over TCP or disabled, DF_ENOTFOUND), DF_EIO when the ring file cannot be opened
 * or mapped (e.g. the daemon runs as another user), DF_EFORMAT for a ring header that does not
 * match the reply. Unsubscribing unmaps the ring. */
int df_client_stream_shm(df_client *c, uint64_t session_id, df_msg_shm_info *info,
                         df_error *err);

/* Brush stroke: begin with every Kelvinlet parameter, cumulative updates, end (commits the
 * stroke as the session's change) or cancel (back to the stroke's start). *ack may be NULL. */
int df_client_brush_begin(df_client *c, const df_msg_brush *b, df_msg_ack *ack, df_error *err);
int df_client_brush_update(df_client *c, const df_msg_brush_update *u, df_msg_ack *ack,
                           df_error *err);
int df_client_brush_end(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err);
int df_client_brush_cancel(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err);

/* Sets one brush parameter (DF_BP_*) of this connection's brush on a session. */
int df_client_set_brush_param(df_client *c, uint64_t session_id, uint8_t param, double value,
                              df_error *err);

/* The session brush (PROTOCOL.md 4.14a): get fills *out (may be NULL) with the current state,
 * its seq and last changer (changed 0). set applies the fields m->mask selects (m->session_id,
 * values in m->v; start from df_msg_brush_values_defaults or a get) and fills *out with the new
 * state; subscribers receive it as a DF_MSG_BRUSH_STATE event naming this client. A bad value
 * is refused locally by the encoder (DF_EINVAL / DF_EPROTO_RESERVED) or by the daemon
 * (DF_EINVAL, nothing changed). BRUSH_STATE and BRUSH_CURSOR events (df_msg_brush_state /
 * df_msg_brush_cursor bodies) reach the event callback of a subscribed connection. */
int df_client_brush_state_get(df_client *c, uint64_t session_id, df_msg_brush_state *out,
                              df_error *err);
int df_client_brush_state_set(df_client *c, const df_msg_brush_state_set *m,
                              df_msg_brush_state *out, df_error *err);

/* The daemon's HID devices (PROTOCOL.md 4.30..4.33). list: every device in id order into *out
 * (items malloc'd: df_msg_device_list_free); none is not an error. bind: device_id drives
 * session_id (0: unbind, it follows the most recently active session). view: a pen's view of a
 * session (also binds it). Remote errors: DF_ENOTFOUND (unknown device or session). */
int df_client_devices_list(df_client *c, df_msg_device_list *out, df_error *err);
int df_client_device_bind(df_client *c, uint64_t device_id, uint64_t session_id, df_error *err);
int df_client_device_view(df_client *c, const df_msg_device_view *m, df_error *err);

/* Per-session access (PROTOCOL.md 4.34..4.36). session_access: m->mode, m->observers and
 * m->flags all 0 read the session's policy into *out (may be NULL); any other value changes it
 * (owner or admin only: remote DF_EPERM otherwise) and *out gets the new policy; with flag
 * DF_ACCESS_NEW_KEY (or a switch to key mode without a key) out->has_key is 1 and out->key the
 * new join key, sent this once: keep it secret. join: becomes a member of session_id with its
 * join key (DF_JOIN_KEY_BYTES bytes); *out (may be NULL) the policy. Remote errors: DF_ENOTFOUND,
 * DF_EPERM (a wrong key, nothing changed; an owner-only session), DF_ELIMIT (too many wrong
 * keys from this peer: retry later). Local: DF_EINVAL from the encoder, DF_EFORMAT when the
 * reply names another session. */
int df_client_session_access(df_client *c, const df_msg_session_access *m,
                             df_msg_access_info *out, df_error *err);
int df_client_join(df_client *c, uint64_t session_id, const uint8_t *key,
                   df_msg_access_info *out, df_error *err);

/* Defines the session's handle set (energy, w, s, rho, tol, max_iters, handles, affine sets).
 * h->options DF_WORK_OPT_PROGRESS asks for WORK_PROGRESS events of the solver build (stage
 * FACTORIZE, PROTOCOL.md 4.37), delivered to the event callback before this returns; a daemon
 * without them answers DF_EPROTO_TRAILING. */
int df_client_handles_set(df_client *c, const df_msg_handles *h, df_error *err);

/* Fetches the session's current handle set into *out: every parameter as set, the handle vertex
 * indices in handle order (the order of df_client_handles_move targets) and the affine sets.
 * Arrays are malloc'd: release with df_msg_handles_free(out). DF_ENOTFOUND (remote) when the
 * session does not exist or has no handle set; DF_EFORMAT when the reply names another session.
 * *out is untouched on error. */
int df_client_handles_get(df_client *c, uint64_t session_id, df_msg_handles *out, df_error *err);

/* Moves the handles to m->targets and waits for the final reply (*res). Progress iterates
 * arrive meanwhile as DF_MSG_PROGRESS events (the callback); with m->options
 * DF_WORK_OPT_PROGRESS also DF_MSG_WORK_PROGRESS events (stage SOLVE: iterations of the budget;
 * FACTORIZE when the solver is rebuilt; body df_msg_work_progress), all before this returns. */
int df_client_handles_move(df_client *c, const df_msg_handle_move *m, df_msg_move_result *res,
                           df_error *err);

/* Session-wide changes; *ack (may be NULL) receives the new version. */
int df_client_reset_rest(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err);
int df_client_undo(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err);
int df_client_redo(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err);

/* A whole mesh as returned by df_client_get_mesh (all arrays malloc'd, row-major). */
typedef struct df_client_mesh {
    uint64_t session_id;
    uint64_t version;     /* version of `positions` */
    uint8_t kind;         /* df_mesh_kind 1 polyline, 2 triangle, 3 tet */
    uint8_t planar;
    uint32_t nv, ne, nf;
    float *positions;     /* nv x 3 current positions */
    float *base;          /* nv x 3 load-time positions (the stream's reference), or NULL */
    float *rest;          /* nv x 3 current rest shape, or NULL */
    int32_t *elements;    /* ne x (2|3|4) */
    int32_t *faces;       /* nf x 3 tet boundary triangles, NULL when nf == 0 */
} df_client_mesh;

/* Fetches the current mesh (chunked reply reassembled); `flags` DF_GET_MESH_BASE / _REST also
 * fetch those sections. Free with df_client_mesh_free. Errors include DF_EFORMAT when the chunks
 * are inconsistent (counts, overlaps, missing rows). */
int df_client_get_mesh(df_client *c, uint64_t session_id, uint32_t flags, df_client_mesh *out,
                       df_error *err);
void df_client_mesh_free(df_client_mesh *m);

/* Dense displacement snapshot at `version` (0: current): u (nv x 3 floats, caller-allocated,
 * nv must be the session's vertex count) receives every vertex's displacement from the base,
 * *version_out the version. */
int df_client_snapshot(df_client *c, uint64_t session_id, uint64_t version, uint32_t nv, float *u,
                       uint64_t *version_out, df_error *err);

/* Daemon-wide (session_id 0) or per-session stats; free *out with df_msg_stats_free. */
int df_client_stats(df_client *c, uint64_t session_id, df_msg_stats *out, df_error *err);

/* ------------------------------------------------------------ displacement stream replica */

/* Pure helper: writes the rows of one displacement chunk into u (nv x 3 floats): dense rows
 * offset..offset+count-1, or sparse rows at their indices (u_i is SET: values are displacements
 * from the base, not increments). Errors (u untouched): DF_EINVAL when d->nv != nv, a row or
 * index is out of range, or a value is not finite. */
int df_client_disp_apply(const df_msg_disp *d, float *u, uint32_t nv, df_error *err);

/* Pure helper: out[i] = base[i] + u[i] in float32 for the nv x 3 arrays (out may alias u). */
void df_client_positions(const float *base, const float *u, uint32_t nv, float *out);

/* A local copy of one session's positions kept current from the displacement stream. */
typedef struct df_client_replica {
    uint64_t session_id;
    uint32_t nv;
    uint64_t version;       /* last complete version applied */
    float *base;            /* nv x 3 base positions */
    float *u;               /* nv x 3 current displacements */
    uint64_t building;      /* version whose chunks are being applied, 0 when none */
    uint32_t rows_seen;     /* rows of `building` applied so far */
    int stale;              /* 1 after a gap or bad chunk: resync with a snapshot */
    uint64_t versions_applied; /* complete versions applied */
    /* quantized stream (PROTOCOL.md 6.3), made by the first QDISP: */
    double step;            /* the stream's step q (2 x error bound), 0 before */
    int64_t *K;             /* nv x 3 quantized displacements (NULL before) */
    int k_exact;            /* 1: u holds exact values (a snapshot); K was derived from them */
} df_client_replica;

/* Initialises a replica from `base` (nv x 3, copied) at `version`, with u = 0 (or a copy of
 * `u0` when non-NULL). Free with df_client_replica_free. */
int df_client_replica_init(df_client_replica *r, uint64_t session_id, uint32_t nv,
                           const float *base, const float *u0, uint64_t version, df_error *err);
void df_client_replica_free(df_client_replica *r);

/* Feeds one frame (a DF_MSG_DISPLACEMENT or DF_MSG_PROGRESS event, a snapshot reply chunk, or
 * with a negotiated stream encoding a DF_MSG_QDISP event or a DF_MSG_ZFRAME wrapping any of
 * them) to the replica. QDISP: u becomes fl32(step x K) (within the error bound of the exact
 * displacements, PROTOCOL.md 6.3); a snapshot makes u exact again. Frames of other sessions are ignored (returns 0). Returns 1 when the frame
 * completed a version (r->version updated), 0 when more chunks are needed or the frame was
 * ignored, or a negative error: DF_ESTATE for a version gap (r->stale set: resync with
 * df_client_replica_resync), DF_EFORMAT/DF_EINVAL for a bad chunk (r->stale set). An SHM_REF
 * event of the replica's session (a frame lost to the shared-memory ring, df_client_stream_shm)
 * is a gap as well: DF_ESTATE with r->stale set. A snapshot (kind DF_CHANGE_SNAPSHOT) clears
 * `stale`. */
int df_client_replica_feed(df_client_replica *r, const df_frame_header *h, const uint8_t *payload,
                           df_error *err);

/* Resynchronises the replica with a dense snapshot of the current version. */
int df_client_replica_resync(df_client *c, df_client_replica *r, df_error *err);

/* Pure helper: decompresses a DF_MSG_ZFRAME event (h, payload) into the frame it stands for:
 * *inner gets its header (the inner type, same flags and request id, payload_len = raw_len)
 * and *raw a malloc'd copy of its payload (free it). Errors: DF_EINVAL / DF_EPROTO_* for a bad
 * zframe body, DF_EFORMAT when the zstd data is corrupt or not raw_len bytes, DF_ENOMEM. */
int df_client_zframe_unwrap(const df_frame_header *h, const uint8_t *payload,
                            df_frame_header *inner, uint8_t **raw, df_error *err);

/* Current positions base + u into out (nv x 3). */
void df_client_replica_positions(const df_client_replica *r, float *out);

#ifdef __cplusplus
}
#endif

#endif
