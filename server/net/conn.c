/* conn.c — client connections: read/frame, bounded output queue, close (see conn.h). */
#include "server/net/conn.h"

#include <stdlib.h>
#include <string.h>

#include "proto/buf.h"
#include "proto/frame_codec.h"
#include "proto/messages.h"
#include "server/net/guard.h"
#include "server/net/peer.h"
#include "server/log.h"
#include "server/net/reply.h"
#include "server/net/tls.h"

static void kick_write(df_conn *c);
static void on_fanout_idle(uv_idle_t *h);
static void conn_start(df_conn *c);

void df_conn_ref(df_conn *c) { c->refs++; }

void df_conn_unref(df_conn *c)
{
    if (--c->refs == 0) {
        if (c->srv->on_conn_free) c->srv->on_conn_free(c); /* its unfinished upload */
        df_outq_clear(&c->outq);
        df_tls_conn_free(c->tls);
        free(c->rbuf);
        free(c);
    }
}

static void on_closed(uv_handle_t *h)
{
    df_conn *c = h->data;
    df_server *srv = c->srv;
    if (c->prev) c->prev->next = c->next;
    else srv->conns = c->next;
    if (c->next) c->next->prev = c->prev;
    srv->n_conns--;
    if (c->refused) srv->n_refusing--;
    else srv->n_closing--;
    if (c->admit_waiting) srv->n_admit_waiting--;
    df_outq_clear(&c->outq);
    df_conn_unref(c);
}

void df_conn_close(df_conn *c, const char *why, int warn)
{
    if (c->closing) return;
    c->closing = 1;
    if (!c->refused) c->srv->n_closing++; /* its slot is free for max_clients (guard.h) */
    /* refused connections are logged by guard.c's rate limit, not one line each */
    df_log(c->refused ? DF_LOG_DEBUG : warn ? DF_LOG_WARN : DF_LOG_INFO, "client %llu closed: %s",
           (unsigned long long)c->id, why ? why : "closed");
    if (c->srv->on_conn_close) c->srv->on_conn_close(c); /* sessions and jobs forget it */
    uv_read_stop(&c->h.stream);
    uv_close((uv_handle_t *)&c->h.stream, on_closed);
}

void df_conn_close_after_flush(df_conn *c, const char *why)
{
    if (c->closing || c->flush_close) return;
    c->flush_close = 1;
    c->flush_why = why;
    c->flush_deadline = uv_now(c->srv->loop) + DF_CONN_FLUSH_TIMEOUT_MS;
    uv_read_stop(&c->h.stream);
    if (!c->wbusy && c->outq.count == 0 && !(c->tls && df_tls_has_output(c->tls)))
        df_conn_close(c, why, 1);
}

void df_conn_sweep(df_server *srv)
{
    uint64_t now = uv_now(srv->loop);
    df_conn *c = srv->conns;
    while (c) {
        df_conn *next = c->next;
        if (c->flush_close && !c->closing && now >= c->flush_deadline)
            df_conn_close(c, "peer did not read its error frame in time", 1);
        c = next;
    }
}

static void on_written(uv_write_t *req, int status)
{
    df_conn *c = req->data;
    size_t n = c->wcount;
    size_t bytes = c->outq.bytes;
    df_outq_complete(&c->outq, n);
    c->srv->stats.bytes_out += bytes - c->outq.bytes;
    c->srv->stats.frames_out += n;
    c->wcount = 0;
    c->wbusy = 0;
    if (c->tls) df_tls_conn_trim(c->tls); /* the ciphertext is written */
    if (c->closing) {
        df_conn_unref(c);
        return;
    }
    if (status < 0) {
        df_conn_close(c, uv_strerror(status), 0);
    } else if (c->outq.count > 0 || (c->tls && df_tls_has_output(c->tls))) {
        kick_write(c);
    } else if (c->flush_close) {
        df_conn_close(c, c->flush_why, 1);
    }
    df_conn_unref(c);
}

/* Writes pending frames: first synchronously with uv_try_write (no request, no callback, no
 * epoll change: the common case of a small reply to a reading client), then whatever the socket
 * did not take with a queued uv_write. On a TLS connection the frames of a batch are encrypted
 * into one ciphertext buffer (with any handshake output) that takes their place (tls.h). */
static void kick_write(df_conn *c)
{
    if (c->wbusy || c->closing) return;
    df_sbuf *items[DF_OUTQ_MAX_BATCH];
    size_t n;
    for (;;) {
        n = df_outq_take(&c->outq, items, DF_OUTQ_MAX_BATCH);
        size_t nb = n, total = 0;
        for (size_t i = 0; i < n; i++)
            c->wbufs[i] = uv_buf_init((char *)items[i]->data, (unsigned)items[i]->len);
        if (c->tls) { /* the seam: plaintext frames in, ciphertext out */
            df_error e;
            if (df_tls_seal(c->tls, c->wbufs, n, &c->wbufs[0], &e) != DF_OK) {
                df_outq_complete(&c->outq, n);
                df_conn_close(c, e.msg, 1);
                return;
            }
            nb = c->wbufs[0].len > 0;
        }
        if (nb == 0 && n == 0) break;
        for (size_t i = 0; i < nb; i++) total += c->wbufs[i].len;
        int w = nb ? uv_try_write(&c->h.stream, c->wbufs, (unsigned)nb) : 0;
        if (w < 0 && w != UV_EAGAIN && w != UV_ENOSYS) {
            df_outq_complete(&c->outq, n);
            df_conn_close(c, uv_strerror(w), 0);
            return;
        }
        size_t done = w > 0 ? (size_t)w : 0;
        if (done == total) { /* all of it went out */
            size_t before = c->outq.bytes;
            df_outq_complete(&c->outq, n);
            c->srv->stats.bytes_out += before - c->outq.bytes;
            c->srv->stats.frames_out += n;
            continue;
        }
        /* The rest goes through uv_write; every item stays in flight until on_written. */
        size_t first = 0;
        while (done >= c->wbufs[first].len) done -= c->wbufs[first++].len;
        c->wbufs[first].base += done;
        c->wbufs[first].len -= done;
        c->wcount = n;
        c->wbusy = 1;
        c->srv->stats.writes_blocked++;
        c->wreq.data = c;
        df_conn_ref(c);
        int rc = uv_write(&c->wreq, &c->h.stream, c->wbufs + first, (unsigned)(nb - first),
                          on_written);
        if (rc < 0) {
            c->wcount = 0;
            c->wbusy = 0;
            df_outq_complete(&c->outq, n);
            df_conn_unref(c);
            df_conn_close(c, uv_strerror(rc), 0);
        }
        return;
    }
    if (c->tls) df_tls_conn_trim(c->tls); /* everything sealed went out */
    if (c->flush_close && c->outq.count == 0) df_conn_close(c, c->flush_why, 1);
}

/* Starts the writes of the connections on deferred-write list k, in list order, until the list
 * is empty (returns 1) or uv_hrtime() passes deadline_ns (0: no deadline; returns 0). */
static int flush_list(df_server *srv, int k, uint64_t deadline_ns)
{
    while (srv->kick_first[k]) {
        if (deadline_ns && uv_hrtime() >= deadline_ns) return 0;
        df_conn *c = srv->kick_first[k];
        srv->kick_first[k] = c->kick_next;
        if (!srv->kick_first[k]) srv->kick_last[k] = NULL;
        c->kick_next = NULL;
        c->kick_queued = 0;
        if (!c->closing) kick_write(c);
        df_conn_unref(c);
    }
    return 1;
}

/* One fan-out pass (cork timer or idle handle): the idle handle stays active, so the loop polls
 * without blocking and reads requests between passes, while subscribers remain to be written. */
static void fanout_pass(df_server *srv)
{
    int done = flush_list(srv, 1, uv_hrtime() + DF_CONN_FANOUT_SLICE_US * 1000ull);
    if (done) uv_idle_stop(&srv->fanout_idle);
    else if (!uv_is_active((uv_handle_t *)&srv->fanout_idle) && !srv->stopping)
        uv_idle_start(&srv->fanout_idle, on_fanout_idle);
}

static void on_fanout_idle(uv_idle_t *h)
{
    df_server *srv = h->data;
    srv->stats.fanout_resumed++;
    fanout_pass(srv);
}

void df_conn_flush_all(df_server *srv, int everything)
{
    flush_list(srv, 0, 0);
    if (everything) {
        flush_list(srv, 1, 0);
        uv_idle_stop(&srv->fanout_idle);
    }
}

static void on_cork(uv_timer_t *t) { fanout_pass(t->data); }

/* Puts c on the deferred-write list (k = 0: it has a reply). */
static void schedule_write(df_conn *c, int k)
{
    df_server *srv = c->srv;
    if (c->wbusy) return; /* a running write picks the frame up */
    int have_ref = 0;
    if (c->kick_queued) {
        if (k == 1 || c->kick_queued == 1) return;
        /* corked, now has a reply: move it to the reply list */
        df_conn **pp = &srv->kick_first[1];
        df_conn *prev = NULL;
        while (*pp && *pp != c) prev = *pp, pp = &(*pp)->kick_next;
        if (*pp) {
            *pp = c->kick_next;
            if (srv->kick_last[1] == c) srv->kick_last[1] = prev;
            c->kick_next = NULL;
            have_ref = 1; /* the list's reference moves with it */
        }
    }
    c->kick_queued = k + 1;
    if (!have_ref) df_conn_ref(c);
    if (srv->kick_last[k]) srv->kick_last[k]->kick_next = c;
    else srv->kick_first[k] = c;
    srv->kick_last[k] = c;
    if (k == 1 && !uv_is_active((uv_handle_t *)&srv->cork_timer) &&
        !uv_is_active((uv_handle_t *)&srv->fanout_idle) && !srv->stopping)
        uv_timer_start(&srv->cork_timer, on_cork, DF_CONN_CORK_MS, 0);
}

/* 1 when `frame` may wait for the cork (DF_CONN_CORK_MS): stream events (displacement
 * versions, move progress, shared-memory references), which batch into one writev per
 * subscriber. Replies and the small control events (brush state, cursor, device state, session
 * closed, errors) start writing at the end of this loop iteration: a knob turn's BRUSH_STATE
 * must not wait a millisecond for frames that may never come. The connection's one output queue
 * keeps every frame in order either way. */
static int corked_frame(const df_sbuf *frame)
{
    if (frame->len < DF_FRAME_HEADER_SIZE) return 1;
    if (df_le16_load(frame->data + 8) & DF_FLAG_REPLY) return 0;
    uint16_t type = df_le16_load(frame->data + 6);
    return type == DF_MSG_DISPLACEMENT || type == DF_MSG_PROGRESS || type == DF_MSG_SHM_REF;
}

int df_conn_send(df_conn *c, df_sbuf *frame)
{
    if (c->closing) return DF_ESTATE;
    int rc = df_outq_push(&c->outq, frame);
    if (rc != DF_OK) {
        char why[160];
        snprintf(why, sizeof why,
                 "dropped: output queue full (%zu bytes queued + %zu > limit %zu); client not "
                 "reading",
                 c->outq.bytes, frame->len, c->outq.limit);
        c->srv->stats.clients_dropped++;
        df_conn_close(c, why, 1);
        return DF_ELIMIT;
    }
    schedule_write(c, corked_frame(frame) ? 1 : 0);
    return DF_OK;
}

/* Ciphertext of TLS connections goes here (loop thread only; on_read consumes it before the
 * next allocation), the plaintext to rbuf (append_plain). */
static uint8_t tls_rx[1 << 16];

/* df_tls_sink: appends decrypted bytes to c->rbuf. */
static int append_plain(void *ctx, const uint8_t *data, size_t len)
{
    df_conn *c = ctx;
    if (c->rlen + len > c->rcap) {
        size_t ncap = c->rcap ? c->rcap : DF_CONN_READ_CHUNK;
        while (ncap < c->rlen + len) ncap *= 2;
        uint8_t *n = realloc(c->rbuf, ncap);
        if (!n) return -1;
        c->rbuf = n;
        c->rcap = ncap;
    }
    memcpy(c->rbuf + c->rlen, data, len);
    c->rlen += len;
    return 0;
}

static void on_alloc(uv_handle_t *h, size_t suggested, uv_buf_t *buf)
{
    (void)suggested;
    df_conn *c = h->data;
    if (c->tls) {
        *buf = uv_buf_init((char *)tls_rx, sizeof tls_rx);
        return;
    }
    size_t want = c->rlen + DF_CONN_READ_CHUNK;
    /* A frame in progress: make room for all of it at once to avoid repeated growth. */
    if (c->rlen >= DF_FRAME_HEADER_SIZE) {
        uint32_t pl = df_le32_load(c->rbuf + 20);
        if (pl <= DF_MAX_FRAME_PAYLOAD && DF_FRAME_HEADER_SIZE + (size_t)pl > want)
            want = DF_FRAME_HEADER_SIZE + (size_t)pl;
    }
    if (want > c->rcap) {
        size_t ncap = c->rcap ? c->rcap : DF_CONN_READ_CHUNK;
        while (ncap < want) ncap *= 2;
        uint8_t *n = realloc(c->rbuf, ncap);
        if (!n) {
            *buf = uv_buf_init(NULL, 0);
            return;
        }
        c->rbuf = n;
        c->rcap = ncap;
    }
    *buf = uv_buf_init((char *)c->rbuf + c->rlen, (unsigned)(c->rcap - c->rlen));
}

static void on_read(uv_stream_t *s, ssize_t nread, const uv_buf_t *buf)
{
    (void)buf;
    df_conn *c = s->data;
    if (nread == UV_ENOBUFS) {
        df_conn_close(c, "out of memory for the read buffer", 1);
        return;
    }
    if (nread < 0) {
        df_conn_close(c, nread == UV_EOF ? "end of stream" : uv_strerror((int)nread), 0);
        return;
    }
    if (nread == 0) return;
    if (c->tls) { /* the seam: ciphertext in, plaintext appended to rbuf */
        df_error e;
        int trc = df_tls_recv(c->tls, (const uint8_t *)buf->base, (size_t)nread, append_plain, c,
                              &e);
        if (df_tls_has_output(c->tls)) schedule_write(c, 0); /* handshake messages, alerts */
        if (trc == DF_ESTATE) {
            df_conn_close(c, e.msg, 0);
            return;
        }
        if (trc != DF_OK) {
            df_log(DF_LOG_WARN, "client %llu (%s): %s", (unsigned long long)c->id, c->peer_addr,
                   e.msg);
            c->srv->stats.clients_dropped++;
            df_conn_close_after_flush(c, df_tls_established(c->tls) ? "TLS error"
                                                                     : "TLS handshake failed");
            return;
        }
    } else {
        c->rlen += (size_t)nread;
    }
    c->bytes_in += (size_t)nread;
    c->last_rx_ms = uv_now(c->srv->loop);
    c->srv->stats.bytes_in += (size_t)nread;
    size_t off = 0;
    df_conn_ref(c); /* dispatch may close c */
    while (!c->closing && !c->flush_close && c->rlen - off >= DF_FRAME_HEADER_SIZE) {
        df_frame_header h;
        df_error err;
        memset(&h, 0, sizeof h);
        int hrc = df_frame_header_decode(c->rbuf + off, c->rlen - off, &h, &err);
        if (hrc != DF_OK && (df_frame_error_is_fatal(hrc) || hrc == DF_EPROTO_TRUNCATED)) {
            df_log(DF_LOG_WARN, "client %llu: framing error: %s", (unsigned long long)c->id,
                   err.msg);
            /* PROTOCOL.md 7: an ERROR event (type ERROR, flags ERROR, request id 0) */
            df_reply_error(c, DF_MSG_ERROR, 0, hrc, "%s", err.msg);
            c->srv->stats.clients_dropped++;
            df_conn_close_after_flush(c, "framing error");
            break;
        }
        size_t total = DF_FRAME_HEADER_SIZE + (size_t)h.payload_len;
        if (c->rlen - off < total) break;
        if (hrc != DF_OK) { /* answerable header error: reply, skip the payload */
            df_reply_error(c, h.type, h.request_id, hrc, "%s", err.msg);
            c->srv->stats.requests_failed++;
            off += total;
            continue;
        }
        c->srv->stats.frames_in++;
        if (c->srv->on_frame) c->srv->on_frame(c, &h, c->rbuf + off + DF_FRAME_HEADER_SIZE);
        off += total;
    }
    if (!c->closing && off > 0) {
        memmove(c->rbuf, c->rbuf + off, c->rlen - off);
        c->rlen -= off;
    }
    /* Give back memory after a large frame. */
    if (!c->closing && c->rcap > 4 * DF_CONN_READ_CHUNK && c->rlen < DF_CONN_READ_CHUNK) {
        uint8_t *n = realloc(c->rbuf, 2 * DF_CONN_READ_CHUNK);
        if (n) {
            c->rbuf = n;
            c->rcap = 2 * DF_CONN_READ_CHUNK;
        }
    }
    df_conn_unref(c);
}

void df_conn_accept(df_server *srv, uv_stream_t *listener, int is_tcp)
{
    df_conn *c = calloc(1, sizeof *c);
    if (!c) {
        df_log(DF_LOG_ERROR, "out of memory accepting a client");
        return;
    }
    int rc = is_tcp ? uv_tcp_init(srv->loop, &c->h.tcp) : uv_pipe_init(srv->loop, &c->h.pipe, 0);
    if (rc < 0) {
        free(c);
        return;
    }
    c->srv = srv;
    c->refs = 1;
    c->is_tcp = is_tcp;
    c->h.stream.data = c;
    c->id = ++srv->next_conn_id;
    c->accepted_ms = c->last_rx_ms = uv_now(srv->loop);
    df_outq_init(&c->outq, srv->cfg.output_queue_limit);
    c->next = srv->conns;
    if (srv->conns) srv->conns->prev = c;
    srv->conns = c;
    srv->n_conns++;
    rc = uv_accept(listener, &c->h.stream);
    if (rc < 0) {
        df_conn_close(c, uv_strerror(rc), 1);
        return;
    }
    if (srv->stopping) {
        df_conn_close(c, "server shutting down", 0);
        return;
    }
    if (df_guard_over_limit(c)) { /* decided at the end of this iteration (df_conn_admit_waiting) */
        c->admit_waiting = 1;
        srv->n_admit_waiting++;
        return;
    }
    conn_start(c);
}

void df_conn_admit_waiting(df_server *srv)
{
    for (df_conn *c = srv->conns, *next; c && srv->n_admit_waiting > 0; c = next) {
        next = c->next;
        if (!c->admit_waiting) continue;
        c->admit_waiting = 0;
        srv->n_admit_waiting--;
        if (!c->closing) conn_start(c);
    }
}

/* The rest of accepting c: admission (guard.h), socket options, peer check, TLS, reading. */
static void conn_start(df_conn *c)
{
    df_server *srv = c->srv;
    int is_tcp = c->is_tcp, rc;
    if (df_guard_admit(c)) return; /* max_clients, out of descriptors: ERROR frame, close */
    if (is_tcp) {
        uv_tcp_nodelay(&c->h.tcp, 1);
    } else {
        int sndbuf = DF_CONN_UNIX_SNDBUF; /* best effort: the default works, only slower */
        uv_send_buffer_size((uv_handle_t *)&c->h.stream, &sndbuf);
    }
    srv->stats.clients_total++;
    if (df_peer_admit(c)) return; /* logs the peer; allow_uids / allow_gids: ERROR frame, close */
    if (is_tcp && srv->tls) { /* every byte after this point is TLS (tls.h) */
        df_error e;
        if (!(c->tls = df_tls_conn_new(srv->tls, &e))) {
            df_conn_close(c, e.msg, 1);
            return;
        }
    }
    rc = uv_read_start(&c->h.stream, on_alloc, on_read);
    if (rc < 0) df_conn_close(c, uv_strerror(rc), 1);
}
