/* dc_conn.c — libdeformclient connection core: connect + hello, frame send/receive with
 * buffering, event dispatch and the request/reply loop (see deformclient.h). */
#include "client/dc_client.h"

#include <openssl/crypto.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "client/dc_net.h"
#include "client/dc_tls.h"

double dc_now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e6 + (double)ts.tv_nsec * 1e-3;
}

static int hello(df_client *c, const char *name, int trailer, uint8_t enc, double bound,
                 df_error *err);

/* A client on connected socket `fd` (closed on error): TLS first when `tls_ca` is set (the
 * certificate must name `host`), then the hello (with the stream trailer when `trailer`:
 * asking for stream encoding `enc`, 0 = exact, with error bound `bound`). */
static int wrap_fd_enc(int fd, const char *name, const char *host, const char *tls_ca,
                       int trailer, uint8_t enc, double bound, df_client **out, df_error *err)
{
    df_client *c = calloc(1, sizeof *c);
    uint8_t *rb = malloc(DF_CLIENT_READ_BUF);
    if (!c || !rb) {
        free(c);
        free(rb);
        close(fd);
        return df_error_set(err, DF_ENOMEM, "out of memory for a client");
    }
    c->fd = fd;
    c->timeout_ms = -1;
    c->next_id = 1;
    c->rbuf = rb;
    c->follow_moved = 1;
    snprintf(c->name, sizeof c->name, "%s", name ? name : DF_CLIENT_NAME);
    if (tls_ca && !(c->tls_ca = strdup(tls_ca))) {
        free(c);
        free(rb);
        close(fd);
        return df_error_set(err, DF_ENOMEM, "out of memory for a client");
    }
    df_buf_init(&c->out);
    int rc = tls_ca ? dc_tls_start(c, host, tls_ca, err) : DF_OK;
    if (rc == DF_OK) rc = hello(c, name, trailer, enc, bound, err);
    if (rc) {
        df_client_close(c);
        return rc;
    }
    *out = c;
    return DF_OK;
}

static int wrap_fd(int fd, const char *name, const char *host, const char *tls_ca,
                   df_client **out, df_error *err)
{
    return wrap_fd_enc(fd, name, host, tls_ca, 0, 0, 0, out, err);
}

int df_client_connect_enc(const char *unix_path, const char *host, int port, const char *tls_ca,
                          const char *name, uint8_t encoding, double error_bound,
                          df_client **out, df_error *err)
{
    if (!out || (!unix_path && !host))
        return df_error_set(err, DF_EINVAL, "df_client_connect_enc: NULL out or no address");
    int rc = df_msg_stream_enc_check(encoding != 0, encoding, error_bound, "connect", err);
    if (rc)
        return rc;
    int fd = unix_path ? dc_net_connect_unix(unix_path, err) : dc_net_connect_tcp(host, port, err);
    if (fd < 0)
        return fd;
    return wrap_fd_enc(fd, name, unix_path ? NULL : host, unix_path ? NULL : tls_ca, 1, encoding,
                       error_bound, out, err);
}

int df_client_connect_unix(const char *path, const char *name, df_client **out, df_error *err)
{
    if (!out)
        return df_error_set(err, DF_EINVAL, "df_client_connect_unix: NULL out");
    int fd = dc_net_connect_unix(path, err);
    if (fd < 0)
        return fd;
    return wrap_fd(fd, name, NULL, NULL, out, err);
}

int df_client_connect_tcp(const char *host, int port, const char *name, df_client **out,
                          df_error *err)
{
    if (!out)
        return df_error_set(err, DF_EINVAL, "df_client_connect_tcp: NULL out");
    return df_client_connect_tcp_tls(host, port, name, NULL, out, err);
}

int df_client_connect_tcp_tls(const char *host, int port, const char *name, const char *tls_ca,
                              df_client **out, df_error *err)
{
    if (!out)
        return df_error_set(err, DF_EINVAL, "df_client_connect_tcp: NULL out");
    int fd = dc_net_connect_tcp(host, port, err);
    if (fd < 0)
        return fd;
    return wrap_fd(fd, name, host, tls_ca, out, err);
}

void df_client_close(df_client *c)
{
    if (!c)
        return;
    dc_tls_end(c);
    if (c->fd >= 0)
        close(c->fd);
    dc_shm_drop(c, 0);
    free(c->shm);
    free(c->shm_frame);
    free(c->rbuf);
    free(c->pbuf);
    df_buf_free(&c->out);
    free(c->tls_ca);
    if (c->key) OPENSSL_cleanse(c->key, c->key_len);
    free(c->key);
    free(c);
}

const df_msg_hello_reply *df_client_server_info(const df_client *c)
{
    return &c->server;
}

void df_client_set_event_callback(df_client *c, df_client_event_fn fn, void *user)
{
    c->on_event = fn;
    c->event_user = user;
}

void df_client_set_timeout(df_client *c, int timeout_ms)
{
    c->timeout_ms = timeout_ms;
}

int df_client_fd(const df_client *c)
{
    return c->fd;
}

int df_client_last_error_was_remote(const df_client *c)
{
    return c->remote_err;
}

/* The server closed the connection under a write: finds the connection-level ERROR event it
 * sent before closing (refused at max_clients, a timeout) among the bytes still unread. Returns
 * its code (err filled, remote_err set), or 0 when there is none. */
static int why_closed(df_client *c, df_error *err)
{
    df_frame_header h;
    const uint8_t *p;
    df_error ignore;
    while (df_client_recv(c, 0, &h, &p, &ignore) == DF_OK) {
        if (h.type == DF_MSG_ERROR && (h.flags & DF_FLAG_ERROR) && h.request_id == 0) {
            df_error e;
            df_error_clear(&e);
            df_msg_error_decode(p, h.payload_len, &e, NULL);
            c->remote_err = 1;
            return df_error_set(err, e.code ? e.code : DF_EINTERNAL, "%s", e.msg);
        }
    }
    return 0;
}

int df_client_send(df_client *c, uint16_t type, uint16_t flags, uint64_t id, const void *payload,
                   size_t len, uint64_t *id_out, df_error *err)
{
    if (c->broken)
        return df_error_set(err, DF_EIO, "connection is broken; reconnect");
    if (len > DF_MAX_FRAME_PAYLOAD)
        return df_error_set(err, DF_EINVAL, "payload of %zu bytes exceeds the frame limit %u", len,
                            DF_MAX_FRAME_PAYLOAD);
    if (id == 0)
        id = c->next_id++;
    df_frame_header h = {DF_FRAME_MAGIC, DF_PROTO_VERSION, type, flags, 0, id, (uint32_t)len};
    uint8_t raw[DF_FRAME_HEADER_SIZE];
    int rc = df_frame_header_encode(&h, raw, err);
    if (rc)
        return rc;
    rc = dc_io_write2(c, raw, sizeof raw, payload, len, err);
    if (rc) {
        int why = why_closed(c, err);
        c->broken = 1;
        return why ? why : rc;
    }
    if (id_out)
        *id_out = id;
    return DF_OK;
}

/* Ensures at least `need` unread bytes in rbuf (need <= DF_CLIENT_READ_BUF). The first wait
 * uses `first_timeout`, later ones c->timeout_ms; a timeout after a partial frame breaks the
 * stream. */
static int fill(df_client *c, size_t need, int first_timeout, df_error *err)
{
    if (c->rlen - c->rpos >= need)
        return DF_OK;
    if (c->rpos > 0) {
        memmove(c->rbuf, c->rbuf + c->rpos, c->rlen - c->rpos);
        c->rlen -= c->rpos;
        c->rpos = 0;
    }
    int started = c->rlen > 0;
    while (c->rlen < need) {
        long r = dc_io_read_some(c, c->rbuf + c->rlen, DF_CLIENT_READ_BUF - c->rlen,
                                  started ? c->timeout_ms : first_timeout, err);
        if (r == DF_ESTATE && !started)
            return DF_ESTATE;
        if (r < 0) {
            c->broken = 1;
            return r == DF_ESTATE ? df_error_set(err, DF_EIO, "timed out in the middle of a frame")
                                  : (int)r;
        }
        c->rlen += (size_t)r;
        started = 1;
    }
    return DF_OK;
}

int df_client_recv(df_client *c, int timeout_ms, df_frame_header *h, const uint8_t **payload,
                   df_error *err)
{
    if (c->broken)
        return df_error_set(err, DF_EIO, "connection is broken; reconnect");
    int rc = fill(c, DF_FRAME_HEADER_SIZE, timeout_ms, err);
    if (rc)
        return rc;
    df_frame_header t;
    rc = df_frame_header_decode(c->rbuf + c->rpos, DF_FRAME_HEADER_SIZE, &t, err);
    if (rc) {
        c->broken = 1;
        return rc;
    }
    c->rpos += DF_FRAME_HEADER_SIZE;
    size_t len = t.payload_len, have = c->rlen - c->rpos;
    if (len <= DF_CLIENT_READ_BUF) {
        rc = fill(c, len, c->timeout_ms, err);
        if (rc) {
            c->broken = 1;
            return rc == DF_ESTATE ? df_error_set(err, DF_EIO, "timed out in a frame payload") : rc;
        }
        *payload = c->rbuf + c->rpos;
        c->rpos += len;
    } else {
        if (c->pcap < len) {
            uint8_t *nb = realloc(c->pbuf, len);
            if (!nb) {
                c->broken = 1;
                return df_error_set(err, DF_ENOMEM, "out of memory for a %zu-byte frame", len);
            }
            c->pbuf = nb;
            c->pcap = len;
        }
        memcpy(c->pbuf, c->rbuf + c->rpos, have);
        c->rpos = c->rlen = 0;
        rc = dc_io_read_exact(c, c->pbuf + have, len - have, c->timeout_ms, err);
        if (rc) {
            c->broken = 1;
            return rc == DF_ESTATE ? df_error_set(err, DF_EIO, "timed out in a frame payload") : rc;
        }
        *payload = c->pbuf;
    }
    *h = t;
    return DF_OK;
}

static void dispatch_event(df_client *c, const df_frame_header *h, const uint8_t *p)
{
    if (h->type == DF_MSG_SHM_REF && c->nshm > 0) {
        dc_shm_dispatch(c, h, p);
        return;
    }
    if (c->on_event)
        c->on_event(c->event_user, h, p);
}

int df_client_pump(df_client *c, int timeout_ms, df_error *err)
{
    int n = 0;
    double deadline = dc_now_us() + (timeout_ms > 0 ? timeout_ms * 1e3 : 0);
    for (;;) {
        int wait;
        if (timeout_ms < 0)
            wait = n > 0 ? 0 : -1;
        else {
            double left = (deadline - dc_now_us()) / 1e3;
            wait = left > 0 ? (int)left + 1 : 0;
        }
        df_frame_header h;
        const uint8_t *p;
        int rc = df_client_recv(c, wait, &h, &p, err);
        if (rc == DF_ESTATE)
            return n;
        if (rc)
            return rc;
        if (h.flags & DF_FLAG_EVENT) {
            dispatch_event(c, &h, p);
            n++;
        } else if (h.type == DF_MSG_ERROR && (h.flags & DF_FLAG_ERROR) && h.request_id == 0) {
            df_error e;
            df_error_clear(&e);
            df_msg_error_decode(p, h.payload_len, &e, NULL);
            c->remote_err = 1;
            c->broken = 1; /* the server closes after a connection-level error */
            return df_error_set(err, e.code ? e.code : DF_EINTERNAL, "%s", e.msg);
        }
    }
}

int df_client_transact(df_client *c, uint16_t type, const void *payload, size_t len,
                       df_client_reply_fn on_reply, void *user, df_error *err)
{
    c->remote_err = 0;
    uint64_t id = 0;
    int rc = df_client_send(c, type, 0, 0, payload, len, &id, err);
    if (rc)
        return rc;
    return dc_wait_reply(c, type, id, on_reply, user, err);
}

int dc_wait_reply(df_client *c, uint16_t type, uint64_t id, df_client_reply_fn on_reply,
                  void *user, df_error *err)
{
    int rc;
    c->remote_err = 0;
    int result = DF_OK;
    df_error first;
    df_error_clear(&first);
    for (;;) {
        df_frame_header h;
        const uint8_t *p;
        rc = df_client_recv(c, c->timeout_ms, &h, &p, err);
        if (rc)
            return rc;
        if (h.flags & DF_FLAG_EVENT) {
            dispatch_event(c, &h, p);
            continue;
        }
        if ((h.flags & DF_FLAG_ERROR) && h.type == DF_MSG_ERROR && h.request_id == 0) {
            df_error e;
            df_error_clear(&e);
            if (df_msg_error_decode(p, h.payload_len, &e, err))
                return df_error_set(err, DF_EFORMAT, "malformed error frame from the server");
            c->remote_err = 1;
            c->broken = 1;
            return df_error_set(err, e.code, "%s", e.msg);
        }
        if (!(h.flags & DF_FLAG_REPLY) || h.request_id != id)
            continue; /* a late reply to an abandoned request */
        if (h.flags & DF_FLAG_ERROR) {
            df_error e;
            df_error_clear(&e);
            if (df_msg_error_decode(p, h.payload_len, &e, err)) {
                c->broken = 1;
                return df_error_set(err, DF_EFORMAT, "malformed error reply to %s",
                                    df_msg_type_name(type));
            }
            c->remote_err = 1;
            return df_error_set(err, e.code, "%s", e.msg);
        }
        if (h.type != type) {
            c->broken = 1;
            return df_error_set(err, DF_EPROTO_BADTYPE, "reply type %s to a %s request",
                                df_msg_type_name(h.type), df_msg_type_name(type));
        }
        if (result == DF_OK && on_reply) {
            result = on_reply(user, &h, p, &first);
            if (result == DF_OK && first.code)
                result = first.code;
        }
        if (!(h.flags & DF_FLAG_MORE))
            break;
    }
    if (result) {
        if (err)
            *err = first;
        return result;
    }
    return DF_OK;
}

int dc_request(df_client *c, uint16_t type, dc_encode_fn enc, const void *msg,
               df_client_reply_fn on_reply, void *user, df_error *err)
{
    df_buf_reset(&c->out);
    int rc = enc ? enc(msg, &c->out, err) : DF_OK;
    if (rc) {
        c->remote_err = 0;
        return rc;
    }
    rc = df_client_transact(c, type, c->out.data, c->out.len, on_reply, user, err);
    if (rc == DF_EMOVED && c->remote_err && c->follow_moved && type != DF_MSG_HELLO &&
        type != DF_MSG_AUTH) {
        df_error moved = *err; /* the owner's address; retried there once (dc_move.c) */
        if (dc_move(c, moved.msg, err) != DF_OK) return rc == DF_EMOVED ? err->code : rc;
        df_buf_reset(&c->out);
        if ((rc = enc ? enc(msg, &c->out, err) : DF_OK) != DF_OK) return rc;
        rc = df_client_transact(c, type, c->out.data, c->out.len, on_reply, user, err);
    }
    return rc;
}

static int reply_hello(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    return df_msg_hello_reply_decode(p, h->payload_len, user, err);
}

static int enc_hello(const void *m, df_buf *out, df_error *err)
{
    return df_msg_hello_encode(m, out, err);
}

/* the hello of a redirected connection (dc_move.c) asks for the stream encoding the first
 * connection was granted, so the replica's stream keeps its form */
int dc_hello(df_client *c, const char *name, df_error *err)
{
    uint8_t enc = c->server.has_stream ? c->server.stream_encoding : 0;
    double bound = c->server.has_stream ? c->server.error_bound : 0;
    return hello(c, name, c->server.has_stream, enc, bound, err);
}

static int hello(df_client *c, const char *name, int trailer, uint8_t enc, double bound,
                 df_error *err)
{
    df_msg_hello m;
    memset(&m, 0, sizeof m);
    m.has_stream = trailer || enc != 0; /* else the original hello, no trailer */
    m.stream_encoding = enc;
    m.error_bound = enc ? bound : 0;
    m.min_version = DF_PROTO_VERSION_MIN;
    m.max_version = DF_PROTO_VERSION;
    m.features = DF_FEAT_ALL;
    const char *n = name ? name : DF_CLIENT_NAME;
    size_t nl = strlen(n);
    if (nl > DF_MAX_NAME_LEN)
        return df_error_set(err, DF_EINVAL, "client name longer than %u bytes", DF_MAX_NAME_LEN);
    memcpy(m.client_name, n, nl + 1);
    return dc_request(c, DF_MSG_HELLO, enc_hello, &m, reply_hello, &c->server, err);
}
