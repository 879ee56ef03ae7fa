/* bench_load_conn.h — the client side of bench_load.c (header-only, static; included once):
 * one epoll set of non-blocking connections to deformd, each a small state machine speaking raw
 * frames encoded with proto/:
 *   well-behaved (TCP): connect, HELLO, then strokes on session idx % N_SESSIONS: BRUSH_BEGIN
 *     (small grab load at a random centre) -> ack -> BRUSH_UPDATE -> ack -> BRUSH_END -> ack,
 *     optionally a pause (G.think_s), a new connection every RECONNECT strokes; any close by the
 *     server counts as dropped;
 *   slowloris (TCP): the 24-byte header of a HELLO trickled one byte per interval (trickle),
 *     never the last byte; reconnected when the server closes it (its ERROR event is kept);
 *   non-reader (Unix socket): HELLO, SUBSCRIBE, then never reads again (epoll reports only
 *     hang-ups); reconnected when the server drops it.
 * Latencies go to G (samples, seconds). Single-threaded: everything runs from the caller's
 * epoll loop (on_event for each ready connection, trickle and next_stroke on timers). */
#ifndef DF_BENCH_LOAD_CONN_H
#define DF_BENCH_LOAD_CONN_H

#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include "proto/frame_codec.h"
#include "proto/messages.h"

#define N_SESSIONS 10
#define GRID_N 32              /* 1,024-vertex sessions */
#define RECONNECT 5            /* strokes per connection before it reconnects */

enum kind { K_GOOD, K_SLOW, K_DEAF };
enum state { S_IDLE, S_CONNECTING, S_HELLO, S_SUB, S_BEGIN, S_UPDATE, S_END, S_THINK, S_TRICKLE,
             S_DEAF };

typedef struct lconn {
    int fd, kind, state, idx;
    uint8_t *rb;
    size_t rlen, rcap;
    uint8_t wb[512];           /* pending output (requests are small) */
    size_t wlen, woff;
    uint64_t next_id, wait_id;
    int strokes;               /* on this connection */
    uint32_t rng;
    double t_open, t_req, t_stroke, t_next;
    int slow_sent;             /* slowloris: header bytes sent */
    char why[DF_ERROR_MSG_MAX + 8]; /* last ERROR event the server sent */
} lconn;

typedef struct samples {
    double *v;
    size_t n, cap;
} samples;

static struct {
    int ep, port;
    char sock[96];
    double hs_timeout_s;
    const char *durability;    /* the store's: full (default), normal, off */
    const char *queue;         /* the daemon's output_queue_limit */
    uint64_t sid[N_SESSIONS];
    int running;
    double think_s;            /* a well-behaved client's pause between strokes (0: closed loop) */
    long strokes, requests, handshakes, req_errors, dropped, refused;
    long slow_closed, slow_closed_error, deaf_closed, deaf_subscribed;
    double slow_life_sum;
    char first_error[DF_ERROR_MSG_MAX + 32], slow_why[DF_ERROR_MSG_MAX + 8];
    samples lat_stroke, lat_req, lat_hs;
    samples win_stroke, win_hs; /* this second's (DF_BENCH_LOAD_VERBOSE) */
    int verbose;
    const char *dir;           /* the daemon's temporary directory */
    char load0[16], load1[16]; /* the machine's load average at the start / end (bench_load.c) */
} G;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void sample_add(samples *s, double v)
{
    if (s->n == s->cap) {
        size_t nc = s->cap ? 2 * s->cap : 4096;
        double *nv = realloc(s->v, nc * sizeof *nv);
        if (!nv) return;
        s->v = nv, s->cap = nc;
    }
    s->v[s->n++] = v;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* p in [0, 1] of s (sorted in place); 0 when empty. */
static double pct(samples *s, double p)
{
    if (!s->n) return 0;
    qsort(s->v, s->n, sizeof *s->v, cmp_double);
    return s->v[(size_t)((double)(s->n - 1) * p)];
}

/* ---- connections ---------------------------------------------------------------------------- */

static void conn_close(lconn *c)
{
    if (c->fd >= 0) close(c->fd);
    c->fd = -1;
    c->state = S_IDLE;
    c->rlen = c->wlen = c->woff = 0;
}

/* Opens c's socket (TCP for good and slowloris, Unix for non-readers) and starts connecting. */
static int conn_open(lconn *c)
{
    int unix_sock = c->kind == K_DEAF;
    c->fd = socket(unix_sock ? AF_UNIX : AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (c->fd < 0) {
        fprintf(stderr, "bench_load: socket: %s\n", strerror(errno));
        return -1;
    }
    int rc;
    if (unix_sock) {
        struct sockaddr_un sa = {.sun_family = AF_UNIX};
        memcpy(sa.sun_path, G.sock, strlen(G.sock) + 1); /* G.sock: < 108 bytes (start_daemon) */
        rc = connect(c->fd, (struct sockaddr *)&sa, sizeof sa);
    } else {
        int one = 1;
        setsockopt(c->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)G.port)};
        sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        rc = connect(c->fd, (struct sockaddr *)&sa, sizeof sa);
    }
    if (rc != 0 && errno != EINPROGRESS && errno != EAGAIN) {
        fprintf(stderr, "bench_load: connect: %s\n", strerror(errno));
        conn_close(c);
        return -1;
    }
    c->state = S_CONNECTING;
    c->t_open = now_s();
    c->next_id = 1;
    c->strokes = 0;
    c->slow_sent = 0;
    c->why[0] = '\0';
    struct epoll_event ev = {.events = EPOLLIN | EPOLLOUT | EPOLLRDHUP, .data.ptr = c};
    return epoll_ctl(G.ep, EPOLL_CTL_ADD, c->fd, &ev);
}

/* Appends one frame (type, body from `enc`) to c's output and writes what the socket takes. */
typedef int (*enc_fn)(const void *m, df_buf *out, df_error *err);
static int conn_send(lconn *c, uint16_t type, enc_fn enc, const void *m)
{
    df_buf b;
    df_error e;
    size_t start;
    df_buf_init(&b);
    uint64_t id = c->next_id++;
    int rc = df_frame_begin(&b, type, 0, id, &start, &e);
    rc = rc ? rc : enc(m, &b, &e);
    rc = rc ? rc : df_frame_end(&b, start, &e);
    if (rc || c->wlen + b.len > sizeof c->wb) {
        fprintf(stderr, "bench_load: encoding type %u: %s\n", type, rc ? e.msg : "too long");
        df_buf_free(&b);
        return -1;
    }
    memcpy(c->wb + c->wlen, b.data, b.len);
    c->wlen += b.len;
    df_buf_free(&b);
    c->wait_id = id;
    c->t_req = now_s();
    while (c->woff < c->wlen) {
        ssize_t w = send(c->fd, c->wb + c->woff, c->wlen - c->woff, MSG_NOSIGNAL);
        if (w < 0) return errno == EAGAIN ? 0 : -1; /* EPOLLOUT continues it */
        c->woff += (size_t)w;
    }
    c->wlen = c->woff = 0;
    return 0;
}

static int enc_hello(const void *m, df_buf *o, df_error *e) { return df_msg_hello_encode(m, o, e); }
static int enc_brush(const void *m, df_buf *o, df_error *e) { return df_msg_brush_encode(m, o, e); }
static int enc_update(const void *m, df_buf *o, df_error *e)
{
    return df_msg_brush_update_encode(m, o, e);
}
static int enc_ref(const void *m, df_buf *o, df_error *e)
{
    return df_msg_session_ref_encode(m, o, e);
}
static int enc_sub(const void *m, df_buf *o, df_error *e)
{
    return df_msg_subscribe_encode(m, o, e);
}

static int send_hello(lconn *c)
{
    df_msg_hello h = {.min_version = DF_PROTO_VERSION_MIN, .max_version = DF_PROTO_VERSION};
    snprintf(h.client_name, sizeof h.client_name, "bench-load-%d", c->idx);
    c->state = S_HELLO;
    return conn_send(c, DF_MSG_HELLO, enc_hello, &h);
}

static double rnd(lconn *c)
{
    c->rng = c->rng * 1664525u + 1013904223u;
    return (double)(c->rng >> 8) / (double)(1u << 24);
}

static uint64_t sid_of(const lconn *c) { return G.sid[c->idx % N_SESSIONS]; }

static int stroke_begin(lconn *c)
{
    df_msg_brush b;
    df_msg_brush_defaults(&b);
    b.session_id = sid_of(c);
    b.type = DF_BRUSH_GRAB;
    b.radius = 0.1;
    b.nu = 0.45;
    b.center[0] = 0.1 + 0.8 * rnd(c);
    b.center[1] = 0.1 + 0.8 * rnd(c);
    b.move[2] = 0.0005;
    c->state = S_BEGIN;
    c->t_stroke = now_s();
    return conn_send(c, DF_MSG_BRUSH_BEGIN, enc_brush, &b);
}

/* A well-behaved connection between strokes: closes when the run is over, reconnects every
 * RECONNECT strokes (a new handshake), else begins the next stroke. */
static int next_stroke(lconn *c)
{
    if (!G.running) {
        conn_close(c);
        return 0;
    }
    if (c->strokes >= RECONNECT) {
        conn_close(c);
        return conn_open(c);
    }
    return stroke_begin(c);
}

/* Next step of a well-behaved connection after the ack of its request (ok: 1 acked, 0 an error
 * reply). Returns -1 when the connection must be closed as failed. */
static int good_next(lconn *c, int ok)
{
    double t = now_s();
    if (c->state == S_HELLO) {
        if (!ok) return -1;
        sample_add(&G.lat_hs, t - c->t_open);
        if (G.verbose) sample_add(&G.win_hs, t - c->t_open);
        G.handshakes++;
        if (G.think_s > 0 && G.running) { /* paced: start at a random moment, not all at once */
            c->state = S_THINK;
            c->t_next = t + G.think_s * rnd(c);
            return 0;
        }
        return next_stroke(c);
    }
    sample_add(&G.lat_req, t - c->t_req);
    G.requests++;
    if (c->state == S_BEGIN && ok) {
        df_msg_brush_update u;
        memset(&u, 0, sizeof u);
        u.session_id = sid_of(c);
        u.move[2] = 0.001;
        c->state = S_UPDATE;
        return conn_send(c, DF_MSG_BRUSH_UPDATE, enc_update, &u);
    }
    if (c->state == S_UPDATE) {
        df_msg_session_ref r = {sid_of(c)};
        c->state = S_END;
        return conn_send(c, DF_MSG_BRUSH_END, enc_ref, &r);
    }
    if (c->state == S_END && ok) {
        sample_add(&G.lat_stroke, t - c->t_stroke);
        if (G.verbose) sample_add(&G.win_stroke, t - c->t_stroke);
        G.strokes++;
        c->strokes++;
    }
    if (G.think_s > 0 && G.running) { /* paced: the next stroke after a randomized pause */
        c->state = S_THINK;
        c->t_next = t + G.think_s * (0.5 + rnd(c));
        return 0;
    }
    return next_stroke(c);
}

/* One complete frame for c. Returns -1 when c must be closed as failed. */
static int on_frame(lconn *c, const df_frame_header *h, const uint8_t *p)
{
    if (h->type == DF_MSG_ERROR && h->request_id == 0) { /* an ERROR event: why we are closed */
        df_error e;
        if (df_msg_error_decode(p, h->payload_len, &e, NULL) == DF_OK)
            snprintf(c->why, sizeof c->why, "%s", e.msg);
        return 0;
    }
    if (!(h->flags & DF_FLAG_REPLY) || h->request_id != c->wait_id || (h->flags & DF_FLAG_MORE))
        return 0; /* stream frames (before a non-reader stops reading) */
    int ok = !(h->flags & DF_FLAG_ERROR);
    if (!ok) {
        df_error e;
        if (df_msg_error_decode(p, h->payload_len, &e, NULL) != DF_OK)
            snprintf(e.msg, sizeof e.msg, "(undecodable error body)");
        if (!G.first_error[0])
            snprintf(G.first_error, sizeof G.first_error, "type 0x%04x: %s", h->type, e.msg);
        G.req_errors++;
    }
    if (c->kind == K_GOOD) return good_next(c, ok);
    if (c->state == S_HELLO && ok) { /* a non-reader: subscribe, then stop reading */
        df_msg_subscribe s = {sid_of(c), 0, 0};
        c->state = S_SUB;
        return conn_send(c, DF_MSG_SUBSCRIBE, enc_sub, &s);
    }
    if (c->state == S_SUB && ok) {
        c->state = S_DEAF;
        G.deaf_subscribed++;
        struct epoll_event ev = {.events = EPOLLRDHUP, .data.ptr = c}; /* never EPOLLIN again */
        return epoll_ctl(G.ep, EPOLL_CTL_MOD, c->fd, &ev);
    }
    return ok ? 0 : -1;
}

/* Reads what is there and handles every complete frame. 1: the peer closed, -1: failed, 0. */
static int conn_read(lconn *c)
{
    for (;;) {
        if (c->rcap - c->rlen < 4096) {
            size_t nc = c->rcap ? 2 * c->rcap : 16384;
            uint8_t *nb = realloc(c->rb, nc);
            if (!nb) return -1;
            c->rb = nb, c->rcap = nc;
        }
        ssize_t n = recv(c->fd, c->rb + c->rlen, c->rcap - c->rlen, 0);
        if (n == 0) return 1;
        if (n < 0) return errno == EAGAIN ? 0 : 1;
        c->rlen += (size_t)n;
        size_t off = 0;
        while (c->rlen - off >= DF_FRAME_HEADER_SIZE) {
            df_frame_header h;
            df_error e;
            int rc = df_frame_header_decode(c->rb + off, c->rlen - off, &h, &e);
            if (rc != DF_OK && rc != DF_EPROTO_TRUNCATED) {
                fprintf(stderr, "bench_load: bad frame from the daemon: %s\n", e.msg);
                return -1;
            }
            size_t total = DF_FRAME_HEADER_SIZE + (size_t)h.payload_len;
            if (c->rlen - off < total) break;
            int st = c->state;
            if (on_frame(c, &h, c->rb + off + DF_FRAME_HEADER_SIZE) < 0) return -1;
            off += total;
            if (c->fd < 0 || c->state == S_CONNECTING || (st != S_DEAF && c->state == S_DEAF))
                return 0; /* closed, reconnected, or a non-reader that stops reading here */
        }
        memmove(c->rb, c->rb + off, c->rlen - off);
        c->rlen -= off;
        if (c->rcap - c->rlen < 4096 && c->rlen > (64u << 20)) return -1;
    }
}

/* The server closed (or reset) c: count it by kind, then reconnect while the run lasts. */
static void on_peer_closed(lconn *c)
{
    double life = now_s() - c->t_open;
    if (c->kind == K_GOOD) {
        if (c->state != S_IDLE) {
            G.dropped++;
            if (strstr(c->why, "max_clients") || strstr(c->why, "file descriptors")) G.refused++;
            fprintf(stderr, "bench_load: well-behaved client %d dropped in state %d after %.2f s"
                    "%s%s\n", c->idx, c->state, life, c->why[0] ? ": " : "", c->why);
        }
    } else if (c->kind == K_SLOW) {
        G.slow_closed++;
        G.slow_life_sum += life;
        if (c->why[0]) {
            G.slow_closed_error++;
            snprintf(G.slow_why, sizeof G.slow_why, "%s", c->why);
        }
    } else {
        G.deaf_closed++;
    }
    conn_close(c);
    if (G.running && c->kind != K_GOOD) conn_open(c);
}

static void on_event(lconn *c, uint32_t ev)
{
    if (c->state == S_CONNECTING && (ev & (EPOLLOUT | EPOLLERR | EPOLLHUP))) {
        int err = 0;
        socklen_t el = sizeof err;
        getsockopt(c->fd, SOL_SOCKET, SO_ERROR, &err, &el);
        if (err) {
            fprintf(stderr, "bench_load: connect (%s client %d): %s\n",
                    c->kind == K_DEAF ? "unix" : "tcp", c->idx, strerror(err));
            c->why[0] = '\0';
            on_peer_closed(c);
            return;
        }
        struct epoll_event e2 = {.events = EPOLLIN | EPOLLRDHUP, .data.ptr = c};
        epoll_ctl(G.ep, EPOLL_CTL_MOD, c->fd, &e2);
        if (c->kind == K_SLOW) {
            c->state = S_TRICKLE;
            c->t_next = now_s();
        } else if (send_hello(c) < 0) {
            on_peer_closed(c);
            return;
        }
    }
    if (c->state == S_DEAF) { /* only hang-ups are reported for a non-reader */
        if (ev & (EPOLLRDHUP | EPOLLHUP | EPOLLERR)) on_peer_closed(c);
        return;
    }
    if ((ev & EPOLLOUT) && c->woff < c->wlen) {
        ssize_t w = send(c->fd, c->wb + c->woff, c->wlen - c->woff, MSG_NOSIGNAL);
        if (w > 0) c->woff += (size_t)w;
        if (c->woff == c->wlen) c->wlen = c->woff = 0;
    }
    if (ev & (EPOLLIN | EPOLLRDHUP | EPOLLHUP | EPOLLERR)) {
        int rc = conn_read(c);
        if (rc != 0 && c->fd >= 0) on_peer_closed(c);
    }
}

/* Slowloris: the next header byte of a HELLO, one per interval, never the 24th. */
static void trickle(lconn *c, double t, double interval)
{
    if (c->state != S_TRICKLE || t < c->t_next || c->slow_sent >= (int)DF_FRAME_HEADER_SIZE - 1)
        return;
    uint8_t hdr[DF_FRAME_HEADER_SIZE];
    df_frame_header h = {DF_FRAME_MAGIC, DF_PROTO_VERSION, DF_MSG_HELLO, 0, 0, 1, 8};
    df_frame_header_encode(&h, hdr, NULL);
    if (send(c->fd, hdr + c->slow_sent, 1, MSG_NOSIGNAL) == 1) c->slow_sent++;
    c->t_next = t + interval;
}

#endif
