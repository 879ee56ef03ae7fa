/* cmd_watch.c — deformctl watch: subscribe to a session and print one line per version (and per
 * brush state / cursor / device event), in the stream encoding asked with --encoding (PROTOCOL.md
 * 6.3), with the bytes each version took on the wire. */
#include <inttypes.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "client/deformctl/ctl.h"

typedef struct watch_state {
    const ctl_ctx *ctx;
    uint64_t session;
    uint64_t rows;       /* rows of the version being received (sum over chunks) */
    uint64_t bytes;      /* wire bytes of the version being received (frames as received) */
    long printed;        /* complete versions printed */
    int closed;          /* session closed event seen */
    int bad;             /* a malformed event was received */
    long lost;           /* frames lost to the shared-memory ring (--shm) */
} watch_state;

/* One version line; `enc` names how it came ("dense", "sparse", "quantized"). */
static void watch_line(watch_state *w, uint64_t sid, uint64_t version, uint8_t kind,
                       const char *enc, const df_msg_progress *p)
{
    const ctl_ctx *ctx = w->ctx;
    if (ctx->json) {
        printf("{\"session\":%" PRIu64 ",\"version\":%" PRIu64 ",\"kind\":\"%s\",\"vertices\":%"
               PRIu64 ",\"encoding\":\"%s\",\"bytes\":%" PRIu64, sid, version,
               ctl_change_name(kind), w->rows, enc, w->bytes);
        if (p) {
            printf(",\"iteration\":%u,\"residual\":", p->iteration);
            ctl_json_num(stdout, p->residual);
            printf(",\"objective\":");
            ctl_json_num(stdout, p->objective);
            printf(",\"final\":%s", p->final ? "true" : "false");
        }
        printf("}\n");
    } else {
        printf("version %" PRIu64 " %s %" PRIu64 " vertices", version, ctl_change_name(kind),
               w->rows);
        if (p)
            printf(" iteration %u residual %.3g objective %.9g%s", p->iteration, p->residual,
                   p->objective, p->final ? " final" : "");
        printf(" bytes %" PRIu64 "\n", w->bytes);
    }
    fflush(stdout);
    w->printed++;
    w->rows = 0;
    w->bytes = 0;
}

static void watch_frame(watch_state *w, const df_frame_header *h, const uint8_t *payload);

static void watch_event(void *user, const df_frame_header *h, const uint8_t *payload)
{
    watch_state *w = user;
    if (h->type == DF_MSG_DISPLACEMENT || h->type == DF_MSG_PROGRESS ||
        h->type == DF_MSG_QDISP || h->type == DF_MSG_ZFRAME)
        w->bytes += DF_FRAME_HEADER_SIZE + (uint64_t)h->payload_len;
    if (h->type == DF_MSG_ZFRAME) { /* --encoding zstd: the frame it stands for */
        df_frame_header in;
        uint8_t *raw = NULL;
        if (df_client_zframe_unwrap(h, payload, &in, &raw, NULL) != DF_OK) {
            w->bad = 1;
            return;
        }
        watch_frame(w, &in, raw);
        free(raw);
        return;
    }
    watch_frame(w, h, payload);
}

static void watch_frame(watch_state *w, const df_frame_header *h, const uint8_t *payload)
{
    int last = !(h->flags & DF_FLAG_MORE);
    if (h->type == DF_MSG_SESSION_CLOSED) {
        df_msg_session_ref r;
        if (df_msg_session_ref_decode(payload, h->payload_len, &r, NULL) == DF_OK &&
            r.session_id == w->session) {
            w->closed = 1;
            if (w->ctx->json)
                printf("{\"session\":%" PRIu64 ",\"kind\":\"closed\"}\n", r.session_id);
            else
                printf("session %" PRIu64 " closed\n", r.session_id);
            fflush(stdout);
        }
    } else if (h->type == DF_MSG_BRUSH_STATE || h->type == DF_MSG_BRUSH_CURSOR) {
        df_msg_brush_state s;
        df_msg_brush_cursor k;
        int rc = h->type == DF_MSG_BRUSH_STATE
                     ? df_msg_brush_state_decode(payload, h->payload_len, &s, NULL)
                     : df_msg_brush_cursor_decode(payload, h->payload_len, &k, NULL);
        if (rc != DF_OK)
            w->bad = 1;
        else if (h->type == DF_MSG_BRUSH_STATE && s.session_id == w->session)
            ctl_brush_state_print(w->ctx, &s, 1);
        else if (h->type == DF_MSG_BRUSH_CURSOR && k.session_id == w->session)
            ctl_brush_cursor_print(w->ctx, &k);
    } else if (h->type == DF_MSG_DEVICE_STATE) { /* a device that drives this session */
        df_msg_device_info *dv = malloc(sizeof *dv);
        if (!dv || df_msg_device_info_decode(payload, h->payload_len, dv, NULL) != DF_OK)
            w->bad = dv != NULL;
        else
            ctl_device_state_print(w->ctx, dv);
        free(dv);
    } else if (h->type == DF_MSG_SHM_REF) { /* --shm: a frame overwritten before it was read */
        w->lost++;
        w->rows = 0;
        w->bytes = 0;
        if (w->ctx->json)
            printf("{\"session\":%" PRIu64 ",\"kind\":\"lost\"}\n", w->session);
        else
            printf("lost a frame (the shared-memory ring overtook this watcher)\n");
        fflush(stdout);
    } else if (h->type == DF_MSG_DISPLACEMENT) {
        df_msg_disp d;
        if (df_msg_disp_decode(payload, h->payload_len, &d, NULL) != DF_OK) {
            w->bad = 1;
            return;
        }
        if (d.session_id == w->session) {
            w->rows += d.count;
            if (last)
                watch_line(w, d.session_id, d.version, d.kind,
                           d.encoding == DF_DISP_SPARSE ? "sparse" : "dense", NULL);
        }
        df_msg_disp_free(&d);
    } else if (h->type == DF_MSG_PROGRESS) {
        df_msg_progress p;
        if (df_msg_progress_decode(payload, h->payload_len, &p, NULL) != DF_OK) {
            w->bad = 1;
            return;
        }
        if (p.disp.session_id == w->session) {
            w->rows += p.disp.count;
            if (last)
                watch_line(w, p.disp.session_id, p.disp.version, p.disp.kind,
                           p.disp.encoding == DF_DISP_SPARSE ? "sparse" : "dense", &p);
        }
        df_msg_progress_free(&p);
    } else if (h->type == DF_MSG_QDISP) { /* --encoding quantized */
        df_msg_qdisp q;
        if (df_msg_qdisp_decode(payload, h->payload_len, &q, NULL) != DF_OK) {
            w->bad = 1;
            return;
        }
        if (q.session_id == w->session) {
            w->rows += q.count;
            df_msg_progress pr; /* a handle-move iterate: its progress trailer (4.40) */
            memset(&pr, 0, sizeof pr);
            pr.status = q.status;
            pr.final = q.final;
            pr.iteration = q.iteration;
            pr.objective = q.objective;
            pr.residual = q.residual;
            pr.elapsed_ms = q.elapsed_ms;
            if (last)
                watch_line(w, q.session_id, q.version, q.kind, "quantized",
                           q.has_progress ? &pr : NULL);
        }
        df_msg_qdisp_free(&q);
    }
}

/* --encoding NAME [--error E] into (enc, bound); a usage error message into err. */
static int parse_encoding(const char *name, const char *error, uint8_t *enc, double *bound,
                          df_error *err)
{
    static const struct { const char *name; uint8_t enc; } NAMES[] = {
        {"exact", 0}, {"quantized", DF_STREAM_ENC_QUANTIZED}, {"zstd", DF_STREAM_ENC_ZSTD},
        {"quantized+zstd", DF_STREAM_ENC_QUANTIZED | DF_STREAM_ENC_ZSTD}};
    *enc = 0;
    *bound = 0;
    int found = !name;
    for (size_t i = 0; name && i < sizeof NAMES / sizeof NAMES[0]; i++)
        if (!strcmp(name, NAMES[i].name)) {
            *enc = NAMES[i].enc;
            found = 1;
        }
    if (!found)
        return df_error_set(err, DF_EINVAL, "--encoding %s: not exact, quantized, zstd or "
                            "quantized+zstd", name);
    if (error) {
        char *end = NULL;
        *bound = strtod(error, &end);
        if (end == error || *end || !(*bound >= DF_STREAM_ERROR_LO && *bound <= DF_STREAM_ERROR_HI))
            return df_error_set(err, DF_EINVAL, "--error %s: not a number in [%g, %g] (mesh "
                                "units)", error, DF_STREAM_ERROR_LO, DF_STREAM_ERROR_HI);
    }
    if ((*enc & DF_STREAM_ENC_QUANTIZED) && !error)
        return df_error_set(err, DF_EINVAL, "--encoding %s needs --error E (the absolute error "
                            "bound, mesh units)", name);
    if (!(*enc & DF_STREAM_ENC_QUANTIZED) && error)
        return df_error_set(err, DF_EINVAL, "--error applies to --encoding quantized or "
                            "quantized+zstd only");
    return DF_OK;
}

static int run_watch(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    long long count = 0, from = -1;
    df_error e;
    uint8_t enc;
    double bound;
    if (a->val[CTL_NGLOBAL] &&
        dc_cli_int(a->val[CTL_NGLOBAL], "--count", 1, 1000000000, &count, &e))
        return ctl_usage_error(ctx, cmd, e.msg);
    if (a->val[CTL_NGLOBAL + 2] &&
        dc_cli_int(a->val[CTL_NGLOBAL + 2], "--from-version", 0, LLONG_MAX, &from, &e))
        return ctl_usage_error(ctx, cmd, e.msg);
    if (a->val[CTL_NGLOBAL + 1] && ctx->tcp)
        return ctl_usage_error(ctx, cmd, "--shm needs the daemon's Unix socket, not --tcp");
    if (parse_encoding(a->val[CTL_NGLOBAL + 3], a->val[CTL_NGLOBAL + 4], &enc, &bound, &e))
        return ctl_usage_error(ctx, cmd, e.msg);
    if (a->val[CTL_NGLOBAL + 1] && enc)
        return ctl_usage_error(ctx, cmd, "--shm carries the exact stream: not with --encoding "
                               "other than exact");
    /* any --encoding (exact included) sends the stream trailer: coalesced when slow */
    df_client *c = ctl_connect_enc(ctx, cmd, a->val[CTL_NGLOBAL + 3] != NULL, enc, bound);
    if (!c)
        return CTL_EXIT_SERVER;
    watch_state w = {ctx, 0, 0, 0, 0, 0, 0, 0};
    df_msg_session_info info;
    int rc = ctl_session_id(c, a->pos[0], &w.session, &e);
    if (rc == DF_OK) {
        df_client_set_event_callback(c, watch_event, &w);
        rc = from >= 0 ? df_client_subscribe_from(c, w.session, (uint64_t)from, &info, &e)
                       : df_client_subscribe(c, w.session, 0, &info, &e);
    }
    if (rc == DF_OK && a->val[CTL_NGLOBAL + 1]) /* --shm */
        rc = df_client_stream_shm(c, w.session, NULL, &e);
    const char *ename = a->val[CTL_NGLOBAL + 3] ? a->val[CTL_NGLOBAL + 3] : "exact";
    if (rc == DF_OK && ctx->json) { /* subscribed: events from here on are printed */
        printf("{\"session\":%" PRIu64 ",\"kind\":\"watching\",\"name\":", w.session);
        ctl_json_str(stdout, info.name);
        printf(",\"version\":%" PRIu64 ",\"shm\":%s,\"stream_encoding\":\"%s\"", info.version,
               a->val[CTL_NGLOBAL + 1] ? "true" : "false", ename);
        if (enc & DF_STREAM_ENC_QUANTIZED) {
            printf(",\"error\":");
            ctl_json_num(stdout, bound);
        }
        if (from >= 0)
            printf(",\"from_version\":%lld", from);
        printf("}\n");
        fflush(stdout);
    } else if (rc == DF_OK) {
        printf("watching session %" PRIu64 " (%s) at version %" PRIu64 "%s", w.session,
               info.name[0] ? info.name : "-", info.version,
               a->val[CTL_NGLOBAL + 1] ? " through shared memory" : "");
        if (enc)
            printf(", encoding %s", ename);
        if (enc & DF_STREAM_ENC_QUANTIZED)
            printf(" error %g", bound);
        if (from >= 0) /* the versions after it (or a snapshot) print first */
            printf(", resyncing from version %lld", from);
        printf("\n");
        fflush(stdout);
    }
    while (rc == DF_OK && !w.closed && !w.bad && (count == 0 || w.printed < count)) {
        int n = df_client_pump(c, -1, &e);
        if (n < 0)
            rc = n;
    }
    if (rc == DF_OK && w.bad)
        rc = df_error_set(&e, DF_EFORMAT, "malformed event from the server");
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    df_client_close(c);
    return CTL_EXIT_OK;
}

static const dc_cli_opt WATCH_OPTS[] = {
    CTL_GLOBAL_OPTS,
    {"count", 1, "--count N          exit after N versions (default: until the session closes;"
                 " brush\n                     events print but do not count)"},
    {"shm", 0, "--shm              read the stream from the daemon's shared-memory ring (Unix "
               "socket, same host)"},
    {"from-version", 1, "--from-version V   resync from version V first: the versions after "
                        "V as broadcast, or one\n                     snapshot when the daemon "
                        "no longer keeps them (they count for --count)"},
    {"encoding", 1, "--encoding ENC     exact (default), quantized, zstd or quantized+zstd: "
                    "the stream encoding\n                     asked in the hello (quantized "
                    "needs --error)"},
    {"error", 1, "--error E          the absolute error bound of a quantized stream, mesh "
                 "units (e.g. 1e-5\n                     of the bounding-box diagonal)"},
};
#define N(x) ((int)(sizeof x / sizeof x[0]))

const ctl_cmd ctl_cmds_watch[] = {
    {"watch", "watch SESSION [--count N] [--shm] [--from-version V] [--encoding ENC] [--error E]",
     "Subscribe to a session and print one line per version (version, kind, vertices changed, "
     "bytes on the wire) and per brush_state / brush_cursor event (--count counts versions "
     "only).",
     WATCH_OPTS, N(WATCH_OPTS), 1, run_watch},
    {NULL, NULL, NULL, NULL, 0, 0, NULL},
};
