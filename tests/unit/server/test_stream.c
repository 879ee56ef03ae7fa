/* Unit tests for server/session/stream.c: the displacement stream a session publishes. A simulated
 * client decodes every frame with the proto decoder and applies it; after each version its
 * float32 positions must be byte-identical to the server's (df_stream_positions) and to an
 * independent computation fl32(fl32(X) + fl32(x - X)). Also: sparse vs dense choice, consecutive
 * versions, chunking with DF_FLAG_MORE, empty changes, refusal of non-finite positions (nothing
 * changes), progress frames and snapshots. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "server/session/stream.h"

typedef struct fake {
    df_session s;
    double *cur;
} fake;

static void fake_init(fake *f, int32_t nv, unsigned seed)
{
    memset(f, 0, sizeof *f);
    size_t n = 3 * (size_t)nv;
    f->s.id = 42;
    f->s.nv = nv;
    f->s.mesh.nv = nv;
    f->s.mesh.V = malloc(n * sizeof(double));
    f->s.basef = malloc(n * sizeof(float));
    f->s.uf = calloc(n, sizeof(float));
    f->cur = malloc(n * sizeof(double));
    assert_non_null(f->s.mesh.V);
    assert_non_null(f->cur);
    srand(seed);
    for (size_t i = 0; i < n; i++) {
        f->s.mesh.V[i] = (double)rand() / RAND_MAX * 2.0 - 1.0 + 1e-9 * (double)(i % 13);
        f->s.basef[i] = (float)f->s.mesh.V[i];
        f->cur[i] = f->s.mesh.V[i];
    }
    atomic_init(&f->s.version, 0);
}

static void fake_free(fake *f)
{
    free(f->s.mesh.V);
    free(f->s.basef);
    free(f->s.uf);
    free(f->s.scratch_u);
    free(f->s.scratch_idx);
    free(f->s.scratch_rows);
    free(f->s.scratch_pos);
    free(f->s.scratch_disp);
    free(f->cur);
}

/* The client: applies the frames of one version to u; checks header/version fields. */
static void client_apply(df_frames *fr, float *u, uint64_t want_version, uint8_t want_kind,
                         uint16_t want_type, uint8_t *encoding, uint32_t *rows)
{
    uint32_t total_rows = 0;
    for (size_t k = 0; k < fr->n; k++) {
        df_frame_header h;
        df_error e;
        const uint8_t *p = fr->v[k]->data;
        assert_int_equal(df_frame_header_decode(p, fr->v[k]->len, &h, &e), DF_OK);
        assert_int_equal(h.payload_len + DF_FRAME_HEADER_SIZE, fr->v[k]->len);
        assert_int_equal(h.type, want_type);
        assert_true(h.flags & DF_FLAG_EVENT);
        assert_int_equal(!!(h.flags & DF_FLAG_MORE), k + 1 < fr->n);
        df_msg_disp d;
        df_msg_progress pr;
        if (want_type == DF_MSG_PROGRESS) {
            assert_int_equal(df_msg_progress_decode(p + 24, h.payload_len, &pr, &e), DF_OK);
            d = pr.disp;
            assert_int_equal(pr.iteration, 17);
        } else {
            assert_int_equal(df_msg_disp_decode(p + 24, h.payload_len, &d, &e), DF_OK);
        }
        assert_true(d.version == want_version);
        assert_true(d.base_version == want_version - 1);
        assert_int_equal(d.kind, want_kind);
        assert_int_equal(d.offset, total_rows);
        *encoding = d.encoding;
        for (uint32_t r = 0; r < d.count; r++) {
            uint32_t vtx = d.encoding == DF_DISP_SPARSE ? (uint32_t)d.idx[r] : d.offset + r;
            memcpy(u + 3 * (size_t)vtx, d.xyz + 3 * (size_t)r, 12);
        }
        total_rows += d.count;
        if (want_type == DF_MSG_PROGRESS) df_msg_progress_free(&pr);
        else df_msg_disp_free(&d);
    }
    *rows = total_rows;
}

static void check_identical(fake *f, const float *client_u)
{
    size_t n = 3 * (size_t)f->s.nv;
    float *server = malloc(n * sizeof *server), *client = malloc(n * sizeof *client);
    assert_non_null(server);
    assert_non_null(client);
    df_stream_positions(&f->s, server);
    for (size_t i = 0; i < n; i++) {
        client[i] = f->s.basef[i] + client_u[i];
        float indep = (float)f->s.mesh.V[i] + (float)(f->cur[i] - f->s.mesh.V[i]);
        if (memcmp(&indep, &client[i], 4) != 0) fail_msg("coordinate %zu differs", i);
    }
    assert_memory_equal(server, client, n * sizeof(float));
    free(server);
    free(client);
}

static void test_stream_sparse_dense_byte_identical(void **state)
{
    (void)state;
    fake f;
    fake_init(&f, 5000, 1);
    float *u = calloc(3 * 5000, sizeof *u);
    assert_non_null(u);
    df_error e;
    for (int step = 1; step <= 40; step++) {
        /* even steps: a local change of ~50 vertices; odd: everything moves a little */
        int local = step % 2 == 0;
        for (int32_t v = 0; v < f.s.nv; v++) {
            if (local && (v % 100) != step % 100) continue;
            for (int k = 0; k < 3; k++) f.cur[3 * v + k] += 1e-3 * sin(step * 0.7 + v + k);
        }
        df_frames fr = {0};
        uint32_t changed = 0;
        assert_int_equal(df_stream_publish(&f.s, f.cur, DF_CHANGE_BRUSH, NULL, 0, &fr, &changed, &e),
                         DF_OK);
        assert_true(atomic_load(&f.s.version) == (uint64_t)step);
        uint8_t enc = 0;
        uint32_t rows = 0;
        client_apply(&fr, u, (uint64_t)step, DF_CHANGE_BRUSH, DF_MSG_DISPLACEMENT, &enc, &rows);
        assert_int_equal(fr.n, 1);
        if (local) {
            assert_int_equal(enc, DF_DISP_SPARSE);
            assert_int_equal(changed, 50);
            assert_int_equal(rows, 50);
        } else {
            assert_int_equal(enc, DF_DISP_DENSE);
            assert_int_equal(rows, 5000);
            assert_true(changed > 4900);
        }
        check_identical(&f, u);
        df_frames_clear(&fr);
    }
    /* publishing the same positions again: a version with no rows */
    df_frames fr = {0};
    uint32_t changed = 99;
    assert_int_equal(df_stream_publish(&f.s, f.cur, DF_CHANGE_RESET_REST, NULL, 0, &fr, &changed, &e),
                     DF_OK);
    uint8_t enc;
    uint32_t rows;
    client_apply(&fr, u, 41, DF_CHANGE_RESET_REST, DF_MSG_DISPLACEMENT, &enc, &rows);
    assert_int_equal(changed, 0);
    assert_int_equal(rows, 0);
    df_frames_clear(&fr);
    /* non-finite positions are refused and change nothing */
    float *before = malloc(3 * 5000 * sizeof *before);
    assert_non_null(before);
    memcpy(before, f.s.uf, 3 * 5000 * sizeof *before);
    double saved = f.cur[777];
    f.cur[777] = NAN;
    assert_int_equal(df_stream_publish(&f.s, f.cur, DF_CHANGE_BRUSH, NULL, 0, &fr, NULL, &e),
                     DF_EINVAL);
    f.cur[777] = 1e300; /* finite double, but its float32 displacement overflows */
    assert_int_equal(df_stream_publish(&f.s, f.cur, DF_CHANGE_BRUSH, NULL, 0, &fr, NULL, &e),
                     DF_EINVAL);
    f.cur[777] = saved;
    assert_int_equal(fr.n, 0);
    assert_true(atomic_load(&f.s.version) == 41);
    assert_memory_equal(before, f.s.uf, 3 * 5000 * sizeof *before);
    free(before);
    free(u);
    fake_free(&f);
}

static void test_stream_chunked_progress_and_snapshot(void **state)
{
    (void)state;
    /* enough vertices that one dense version needs two chunks */
    uint32_t per = df_msg_disp_rows_per_chunk(DF_DISP_DENSE, DF_STREAM_CHUNK_BYTES);
    int32_t nv = (int32_t)per + 1000;
    fake f;
    fake_init(&f, nv, 7);
    float *u = calloc(3 * (size_t)nv, sizeof *u);
    assert_non_null(u);
    for (size_t i = 0; i < 3 * (size_t)nv; i++) f.cur[i] += 0.25;
    df_msg_progress pr;
    memset(&pr, 0, sizeof pr);
    pr.status = DF_MOVE_RUNNING;
    pr.iteration = 17;
    pr.objective = 1.5;
    pr.residual = 1e-3;
    df_frames fr = {0};
    df_error e;
    assert_int_equal(df_stream_publish(&f.s, f.cur, DF_CHANGE_HANDLE_MOVE, &pr, 1234, &fr, NULL, &e),
                     DF_OK);
    assert_int_equal(fr.n, 2);
    df_frame_header h;
    assert_int_equal(df_frame_header_decode(fr.v[0]->data, fr.v[0]->len, &h, &e), DF_OK);
    assert_true(h.request_id == 1234); /* progress carries the move's request id */
    uint8_t enc;
    uint32_t rows;
    client_apply(&fr, u, 1, DF_CHANGE_HANDLE_MOVE, DF_MSG_PROGRESS, &enc, &rows);
    assert_int_equal(enc, DF_DISP_DENSE);
    assert_int_equal(rows, (uint32_t)nv);
    check_identical(&f, u);
    df_frames_clear(&fr);
    /* a snapshot reply reproduces the same u from scratch */
    assert_int_equal(df_stream_snapshot(&f.s, DF_MSG_SNAPSHOT, 99, &fr, &e), DF_OK);
    assert_int_equal(fr.n, 2);
    float *u2 = calloc(3 * (size_t)nv, sizeof *u2);
    assert_non_null(u2);
    uint32_t off = 0;
    for (size_t k = 0; k < fr.n; k++) {
        assert_int_equal(df_frame_header_decode(fr.v[k]->data, fr.v[k]->len, &h, &e), DF_OK);
        assert_true(h.flags & DF_FLAG_REPLY);
        assert_true(h.request_id == 99);
        df_msg_disp d;
        assert_int_equal(df_msg_disp_decode(fr.v[k]->data + 24, h.payload_len, &d, &e), DF_OK);
        assert_int_equal(d.kind, DF_CHANGE_SNAPSHOT);
        assert_true(d.version == 1 && d.base_version == 0);
        assert_int_equal(d.offset, off);
        memcpy(u2 + 3 * (size_t)off, d.xyz, 12 * (size_t)d.count);
        off += d.count;
        df_msg_disp_free(&d);
    }
    assert_int_equal(off, (uint32_t)nv);
    assert_memory_equal(u, u2, 12 * (size_t)nv);
    df_frames_clear(&fr);
    free(u);
    free(u2);
    fake_free(&f);
}

/* Issue 9 item 14: a result whose float32 displacement is finite but whose float32 position
 * (load-time float32 position + displacement, what GET_MESH and every replica compute) is not
 * is refused, and nothing changes: such a version used to kill the session for everyone. */
static void test_stream_refuses_float32_position_overflow(void **state)
{
    (void)state;
    fake f;
    fake_init(&f, 64, 7);
    f.s.mesh.V[30] = 3.0e38;
    f.s.basef[30] = 3.0e38f;
    f.cur[30] = 3.0e38;
    df_frames fr = {0};
    df_error e;
    f.cur[30] = 6.0e38;  /* displacement 3e38: finite in float32; position 6e38: not */
    assert_true(isfinite((float)(f.cur[30] - f.s.mesh.V[30])));
    assert_int_equal(df_stream_publish(&f.s, f.cur, DF_CHANGE_BRUSH, NULL, 0, &fr, NULL, &e),
                     DF_EINVAL);
    assert_non_null(strstr(e.msg, "vertex 10 component 0"));
    assert_non_null(strstr(e.msg, "float32"));
    assert_int_equal(fr.n, 0);
    assert_true(atomic_load(&f.s.version) == 0);
    for (size_t i = 0; i < 3 * 64; i++)
        assert_true(f.s.uf[i] == 0.0f);
    f.cur[30] = 3.3e38;  /* still in range: accepted */
    assert_int_equal(df_stream_publish(&f.s, f.cur, DF_CHANGE_BRUSH, NULL, 0, &fr, NULL, &e),
                     DF_OK);
    assert_true(atomic_load(&f.s.version) == 1);
    df_frames_clear(&fr);
    fake_free(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stream_sparse_dense_byte_identical),
        cmocka_unit_test(test_stream_chunked_progress_and_snapshot),
        cmocka_unit_test(test_stream_refuses_float32_position_overflow),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
