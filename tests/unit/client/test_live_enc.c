/* Live test of libdeformclient's stream encodings (PROTOCOL.md 6.3) against the real daemon
 * (skipped when it is not built): one exact subscriber records the displacements of every
 * version of a grab stroke, a twist stroke and a handle move with progress iterates; replicas
 * connected with df_client_connect_enc (quantized, quantized+zstd, zstd) must hold, at every
 * version they complete, displacements within the error bound of the recorded exact ones (zstd:
 * bit-identical), and equal GET_MESH byte for byte after df_client_replica_resync. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

#include "client/deformclient.h"
#include "tests/unit/client/live_daemon.h"
#include "tests/unit/unit_skip.h"

#define GRID 24            /* 576 vertices on the unit square */
#define MAX_VERSIONS 64
#define WAIT_MS 10000

typedef struct rec {       /* the exact subscriber: u of every version */
    df_client_replica r;
    float *u[MAX_VERSIONS];
} rec;

typedef struct enc_client {
    df_client *c;
    df_client_replica r;
    const rec *exact;
    double bound;          /* error bound (0: zstd, bit-identical) */
    int checked;           /* versions compared */
    double worst;          /* largest |u - u_exact| seen */
    int failures;
    long rows_sent;        /* QDISP rows received (all versions) */
} enc_client;

static void on_exact(void *user, const df_frame_header *h, const uint8_t *p)
{
    rec *x = user;
    if (df_client_replica_feed(&x->r, h, p, NULL) == 1 && x->r.version < MAX_VERSIONS) {
        size_t n = (size_t)x->r.nv * 3;
        free(x->u[x->r.version]);
        x->u[x->r.version] = malloc(n * sizeof(float));
        memcpy(x->u[x->r.version], x->r.u, n * sizeof(float));
    }
}

static void on_enc(void *user, const df_frame_header *h, const uint8_t *p)
{
    enc_client *q = user;
    if (h->type == DF_MSG_QDISP) {
        df_msg_qdisp d;
        if (df_msg_qdisp_decode(p, h->payload_len, &d, NULL) == DF_OK) {
            q->rows_sent += d.count;
            df_msg_qdisp_free(&d);
        }
    }
    int rc = df_client_replica_feed(&q->r, h, p, NULL);
    if (rc < 0) {
        q->failures++;
        return;
    }
    const float *ue = q->r.version < MAX_VERSIONS ? q->exact->u[q->r.version] : NULL;
    if (rc != 1 || !ue)
        return;
    for (size_t i = 0; i < (size_t)q->r.nv * 3; i++) {
        double d = fabs((double)q->r.u[i] - (double)ue[i]);
        double slack = ldexp(fmax(fabs(q->r.u[i]), fabs(ue[i])), -23); /* float32 rounding */
        if (d > q->worst) q->worst = d;
        if (d > q->bound + slack) q->failures++;
    }
    q->checked++;
}

static void pump_to(df_client *c, const df_client_replica *r, uint64_t version)
{
    for (int t = 0; t < WAIT_MS / 10 && r->version < version; t++)
        assert_true(df_client_pump(c, 10, NULL) >= 0);
    assert_true(r->version == version);
}

/* A grab stroke of 4 updates, a twist stroke of 3, a handle move with iterates every 2. */
static uint64_t edit(df_client *c, uint64_t sid)
{
    df_error e;
    df_msg_ack ack;
    df_msg_brush b;
    df_msg_brush_defaults(&b);
    b.session_id = sid;
    b.radius = 0.25;
    b.center[0] = b.center[1] = 0.4;
    assert_int_equal(df_client_brush_begin(c, &b, NULL, &e), DF_OK);
    for (int i = 1; i <= 4; i++) {
        df_msg_brush_update u;
        memset(&u, 0, sizeof u);
        u.session_id = sid;
        u.move[0] = 0.01 * i;
        u.move[2] = 0.004 * i;
        assert_int_equal(df_client_brush_update(c, &u, NULL, &e), DF_OK);
    }
    assert_int_equal(df_client_brush_end(c, sid, NULL, &e), DF_OK);
    b.type = DF_BRUSH_TWIST;
    b.center[0] = 0.7;
    assert_int_equal(df_client_brush_begin(c, &b, NULL, &e), DF_OK);
    for (int i = 1; i <= 3; i++) {
        df_msg_brush_update u;
        memset(&u, 0, sizeof u);
        u.session_id = sid;
        u.twist[2] = 0.1 * i;
        assert_int_equal(df_client_brush_update(c, &u, NULL, &e), DF_OK);
    }
    assert_int_equal(df_client_brush_end(c, sid, &ack, &e), DF_OK);
    df_msg_handles h;
    df_msg_handles_defaults(&h, DF_ENERGY_ARAP);
    int32_t idx[3] = {0, GRID - 1, GRID * GRID / 2 + 3};
    h.session_id = sid;
    h.n_handles = 3;
    h.handles = idx;
    h.max_iters = 6;
    assert_int_equal(df_client_handles_set(c, &h, &e), DF_OK);
    df_client_mesh m;
    assert_int_equal(df_client_get_mesh(c, sid, 0, &m, &e), DF_OK);
    double t[9];
    for (int k = 0; k < 3; k++)
        for (int d = 0; d < 3; d++) t[3 * k + d] = m.positions[3 * (size_t)idx[k] + d];
    t[7] += 0.05;
    df_client_mesh_free(&m);
    df_msg_handle_move mv = {sid, 6, 0, 2, 3, t, 0, 0};
    df_msg_move_result res;
    assert_int_equal(df_client_handles_move(c, &mv, &res, &e), DF_OK);
    return res.version;
}

static void test_encoded_replicas_within_bound(void **state)
{
    (void)state;
    char exe[PATH_MAX];
    if (live_daemon_path(exe, sizeof exe) != 0)
        unit_skip("deformd is not built next to this test (make -j2 builds it)");
    live_daemon d;
    assert_int_equal(live_daemon_start(&d, exe, "enc"), 0);
    df_error e;
    df_client *ed, *xc;
    assert_int_equal(df_client_connect_unix(d.sock, "editor", &ed, &e), DF_OK);
    assert_int_equal(df_client_connect_unix(d.sock, "exact", &xc, &e), DF_OK);
    assert_int_equal(df_client_server_info(xc)->has_stream, 0); /* the original hello */
    size_t len;
    char *off = live_grid_off(GRID, &len);
    df_msg_session_info info;
    assert_int_equal(df_client_load_mesh_bytes(ed, "enc", DF_FMT_OFF, off, len, 0, &info, &e),
                     DF_OK);
    free(off);
    uint64_t sid = info.session_id;
    df_client_mesh m;
    assert_int_equal(df_client_get_mesh(ed, sid, DF_GET_MESH_BASE, &m, &e), DF_OK);
    static rec x;
    memset(&x, 0, sizeof x);
    assert_int_equal(df_client_replica_init(&x.r, sid, m.nv, m.base, NULL, 0, &e), DF_OK);
    x.u[0] = calloc((size_t)m.nv * 3, sizeof(float));
    df_client_set_event_callback(xc, on_exact, &x);
    assert_int_equal(df_client_subscribe(xc, sid, 0, NULL, &e), DF_OK);
    /* bound: 1e-3 of the bounding-box diagonal (sqrt 2 + the small z range) */
    const double bound = 1e-3 * sqrt(2.0);
    const uint8_t encs[3] = {DF_STREAM_ENC_QUANTIZED, DF_STREAM_ENC_QUANTIZED | DF_STREAM_ENC_ZSTD,
                             DF_STREAM_ENC_ZSTD};
    static enc_client q[3];
    for (int k = 0; k < 3; k++) {
        memset(&q[k], 0, sizeof q[k]);
        double b = encs[k] & DF_STREAM_ENC_QUANTIZED ? bound : 0;
        assert_int_equal(df_client_connect_enc(d.sock, NULL, 0, NULL, "enc", encs[k], b, &q[k].c,
                                               &e), DF_OK);
        const df_msg_hello_reply *hr = df_client_server_info(q[k].c);
        assert_true(hr->has_stream && hr->stream_encoding == encs[k] && hr->error_bound == b);
        q[k].exact = &x;
        q[k].bound = b;
        assert_int_equal(df_client_replica_init(&q[k].r, sid, m.nv, m.base, NULL, 0, &e), DF_OK);
        df_client_set_event_callback(q[k].c, on_enc, &q[k]);
        assert_int_equal(df_client_subscribe(q[k].c, sid, 0, NULL, &e), DF_OK);
    }
    /* a bad request is refused before connecting, naming the field */
    df_client *bad = NULL;
    assert_int_equal(df_client_connect_enc(d.sock, NULL, 0, NULL, "bad", DF_STREAM_ENC_QUANTIZED,
                                           0, &bad, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "error_bound"));
    df_client_mesh_free(&m);
    uint64_t last = edit(ed, sid);
    assert_true(last >= 8 && last < MAX_VERSIONS);
    pump_to(xc, &x.r, last);
    for (int k = 0; k < 3; k++) {
        pump_to(q[k].c, &q[k].r, last);
        assert_int_equal(q[k].failures, 0);
        assert_int_equal(q[k].checked, (int)last); /* every version compared */
        printf("enc %u: %d versions within %g (worst %.3g), %ld quantized rows of %llu\n",
               encs[k], q[k].checked, q[k].bound, q[k].worst, q[k].rows_sent,
               (unsigned long long)last * (GRID * GRID));
    }
    assert_true(q[2].worst == 0); /* zstd is lossless */
    assert_true(q[0].worst > 0 && q[0].worst <= bound * (1 + 1e-9) + 1e-6);
    /* the far field rounds to zero: fewer rows than a dense stream */
    assert_true(q[0].rows_sent < (long)last * GRID * GRID);
    /* a resync is exact */
    assert_int_equal(df_client_get_mesh(ed, sid, 0, &m, &e), DF_OK);
    float *pos = malloc((size_t)m.nv * 3 * sizeof(float));
    for (int k = 0; k < 2; k++) {
        assert_int_equal(df_client_replica_resync(q[k].c, &q[k].r, &e), DF_OK);
        df_client_replica_positions(&q[k].r, pos);
        assert_memory_equal(pos, m.positions, (size_t)m.nv * 3 * sizeof(float));
    }
    free(pos);
    df_client_mesh_free(&m);
    for (int k = 0; k < 3; k++) {
        df_client_replica_free(&q[k].r);
        df_client_close(q[k].c);
    }
    for (int v = 0; v < MAX_VERSIONS; v++) free(x.u[v]);
    df_client_replica_free(&x.r);
    df_client_close(xc);
    df_client_close(ed);
    live_daemon_stop(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_encoded_replicas_within_bound),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
