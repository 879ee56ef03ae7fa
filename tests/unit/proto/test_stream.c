/* Unit tests for the displacement stream contract (PROTOCOL.md sections 5 and 6): a writer
 * publishes versions as chunked dense/sparse frames, the byte stream is cut at arbitrary points
 * (partial reads), a reader reassembles frames, decodes them and applies x = X + u in float32;
 * every reader ends byte-identical to the writer's float32 state. Also chunk helpers, progress
 * chunks, get-mesh reassembly of a real mesh (MESHES) and a 1M-vertex dense frame. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <cmocka.h>

#include "core/mesh/mesh_io.h"
#include "proto/messages.h"
#include "tests/unit/unit_skip.h"

static uint32_t rng_state = 12345;
static uint32_t rnd(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    return rng_state >> 8;
}

/* Writer: appends one version (rows = changed vertices of u_new vs u_old) as chunk frames. */
static void publish(df_buf *out, uint64_t sid, uint64_t version, uint8_t kind, uint32_t nv,
                    const float *u_old, const float *u_new, size_t max_payload)
{
    int32_t *idx = malloc(sizeof(int32_t) * nv);
    float *val = malloc(sizeof(float) * 3 * nv);
    uint32_t changed = 0;
    for (uint32_t i = 0; i < nv; i++)
        if (memcmp(u_old + 3 * i, u_new + 3 * i, 12)) {
            idx[changed] = (int32_t)i;
            memcpy(val + 3 * changed, u_new + 3 * i, 12);
            changed++;
        }
    uint8_t enc = df_msg_disp_choose(changed, nv);
    uint32_t total = enc == DF_DISP_DENSE ? nv : changed;
    uint32_t per = df_msg_disp_rows_per_chunk(enc, max_payload);
    uint32_t off = 0;
    do {
        uint32_t cnt = total - off < per ? total - off : per;
        df_msg_disp d = {sid, version, version - 1, kind, enc, nv, total, off, cnt,
                         enc == DF_DISP_SPARSE ? idx + off : NULL,
                         enc == DF_DISP_SPARSE ? val + 3 * (size_t)off : (float *)u_new + 3 * (size_t)off};
        size_t start;
        uint16_t flags = DF_FLAG_EVENT | (off + cnt < total ? DF_FLAG_MORE : 0);
        df_error e;
        assert_int_equal(df_frame_begin(out, DF_MSG_DISPLACEMENT, flags, 0, &start, &e), DF_OK);
        assert_int_equal(df_msg_disp_encode(&d, out, &e), DF_OK);
        assert_int_equal(df_frame_end(out, start, &e), DF_OK);
        assert_true(out->len - start - DF_FRAME_HEADER_SIZE <= max_payload);
        off += cnt;
    } while (off < total);
    free(idx);
    free(val);
}

typedef struct reader {
    df_buf in;          /* bytes received, not yet consumed */
    float *u;           /* displacement state, nv x 3 */
    uint64_t version;
    uint32_t frames, sparse_frames, dense_frames, more_frames;
} reader;

/* Feeds `n` bytes and consumes every complete frame. */
static void reader_feed(reader *r, const uint8_t *p, size_t n)
{
    df_error e;
    assert_int_equal(df_buf_append(&r->in, p, n, &e), DF_OK);
    size_t pos = 0;
    for (;;) {
        df_frame_header h;
        if (r->in.len - pos < DF_FRAME_HEADER_SIZE)
            break;
        assert_int_equal(df_frame_header_decode(r->in.data + pos, r->in.len - pos, &h, &e), DF_OK);
        if (r->in.len - pos - DF_FRAME_HEADER_SIZE < h.payload_len)
            break;
        df_msg_any m;
        const uint8_t *pl = r->in.data + pos + DF_FRAME_HEADER_SIZE;
        assert_int_equal(df_msg_any_decode(h.type, h.flags, pl, h.payload_len, &m, &e), DF_OK);
        assert_int_equal(m.which, DF_BODY_DISP);
        const df_msg_disp *d = &m.u.disp;
        if (d->offset == 0) {
            assert_true(d->base_version == r->version); /* no version missed */
            r->version = d->version;
        }
        for (uint32_t i = 0; i < d->count; i++) {
            uint32_t v = d->encoding == DF_DISP_DENSE ? d->offset + i : (uint32_t)d->idx[i];
            memcpy(r->u + 3 * (size_t)v, d->xyz + 3 * (size_t)i, 12);
        }
        r->frames++;
        r->sparse_frames += d->encoding == DF_DISP_SPARSE;
        r->dense_frames += d->encoding == DF_DISP_DENSE;
        r->more_frames += (h.flags & DF_FLAG_MORE) != 0;
        df_msg_any_free(&m);
        pos += DF_FRAME_HEADER_SIZE + h.payload_len;
    }
    memmove(r->in.data, r->in.data + pos, r->in.len - pos);
    r->in.len -= pos;
}

static void test_stream_reassembly_with_partial_reads(void **state)
{
    (void)state;
    const uint32_t nv = 1000;
    const size_t max_payload = 600; /* forces many chunks */
    float *X = malloc(sizeof(float) * 3 * nv), *u = calloc(3 * nv, sizeof(float));
    float *u_prev = calloc(3 * nv, sizeof(float));
    for (uint32_t i = 0; i < 3 * nv; i++)
        X[i] = (float)(rnd() % 20000) * 1e-3f - 10.0f;
    df_buf wire;
    df_buf_init(&wire);
    for (uint64_t v = 1; v <= 40; v++) {
        memcpy(u_prev, u, sizeof(float) * 3 * nv);
        /* small local edits (sparse) most of the time, a global one every 10th version */
        uint32_t touched = v % 10 == 0 ? nv : 5 + rnd() % 40;
        uint32_t base = rnd() % nv;
        for (uint32_t k = 0; k < touched; k++) {
            uint32_t i = (base + k) % nv;
            for (int c = 0; c < 3; c++)
                u[3 * i + c] += (float)((int)(rnd() % 2001) - 1000) * 1e-4f;
        }
        publish(&wire, 9, v, DF_CHANGE_BRUSH, nv, u_prev, u, max_payload);
    }
    /* three readers, each receiving the same bytes cut at different points */
    for (int rd = 0; rd < 3; rd++) {
        reader r = {0};
        df_buf_init(&r.in);
        r.u = calloc(3 * nv, sizeof(float));
        size_t pos = 0;
        while (pos < wire.len) {
            size_t step = rd == 0 ? 1 : rd == 1 ? 1 + rnd() % 97 : 1 + rnd() % 5000;
            if (step > wire.len - pos)
                step = wire.len - pos;
            reader_feed(&r, wire.data + pos, step);
            pos += step;
        }
        assert_int_equal(r.in.len, 0);
        assert_true(r.version == 40);
        assert_true(r.sparse_frames > 0 && r.dense_frames > 0 && r.more_frames > 0);
        if (rd == 0)
            printf("stream: 40 versions, %zu bytes, %u frames (%u sparse, %u dense, %u MORE)\n",
                   wire.len, r.frames, r.sparse_frames, r.dense_frames, r.more_frames);
        /* x = X + u in float32 is byte-identical to the writer's */
        for (uint32_t i = 0; i < 3 * nv; i++) {
            float xr = X[i] + r.u[i], xw = X[i] + u[i];
            assert_memory_equal(&xr, &xw, sizeof xr);
        }
        free(r.u);
        df_buf_free(&r.in);
    }
    df_buf_free(&wire);
    free(X);
    free(u);
    free(u_prev);
}

static void test_chunk_helpers(void **state)
{
    (void)state;
    assert_int_equal(df_msg_disp_row_bytes(DF_DISP_DENSE), 12);
    assert_int_equal(df_msg_disp_row_bytes(DF_DISP_SPARSE), 16);
    assert_int_equal(df_msg_disp_row_bytes(0), 0);
    /* 16 MiB minus the 44 + 32 byte headers, 12 bytes per dense row */
    assert_int_equal(df_msg_disp_rows_per_chunk(DF_DISP_DENSE, DF_STREAM_CHUNK_BYTES),
                     (DF_STREAM_CHUNK_BYTES - 76) / 12);
    assert_int_equal(df_msg_disp_rows_per_chunk(DF_DISP_SPARSE, 1076), 62);
    assert_int_equal(df_msg_disp_rows_per_chunk(DF_DISP_SPARSE, 10), 1);
    /* sparse iff 16 changed < 12 nv */
    assert_int_equal(df_msg_disp_choose(749, 1000), DF_DISP_SPARSE);
    assert_int_equal(df_msg_disp_choose(750, 1000), DF_DISP_DENSE);
    assert_int_equal(df_msg_disp_choose(0, 1), DF_DISP_SPARSE);
    assert_int_equal(df_msg_disp_choose(DF_MAX_MESH_VERTICES, DF_MAX_MESH_VERTICES), DF_DISP_DENSE);
    /* a 1M-vertex dense version fits one frame at the recommended chunk size */
    assert_true(df_msg_disp_rows_per_chunk(DF_DISP_DENSE, DF_STREAM_CHUNK_BYTES) >= 1000000);
}

static void test_progress_chunks(void **state)
{
    (void)state;
    float xyz[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    df_buf b;
    df_buf_init(&b);
    df_error e;
    for (uint32_t off = 0; off < 3; off++) {
        df_msg_progress p = {off == 2 ? DF_MOVE_CONVERGED : DF_MOVE_RUNNING, off == 2, 50,
                             12.5, 1e-12, 3.0,
                             {4, 8, 7, DF_CHANGE_HANDLE_MOVE, DF_DISP_DENSE, 3, 3, off, 1, NULL,
                              xyz + 3 * off}};
        df_buf_reset(&b);
        assert_int_equal(df_msg_progress_encode(&p, &b, &e), DF_OK);
        assert_int_equal(b.len, 32 + 44 + 12);
        df_msg_progress q;
        assert_int_equal(df_msg_progress_decode(b.data, b.len, &q, &e), DF_OK);
        assert_int_equal(q.iteration, 50);
        assert_true(q.objective == 12.5 && q.residual == 1e-12 && q.elapsed_ms == 3.0);
        assert_int_equal(q.final, off == 2);
        assert_int_equal(q.disp.offset, off);
        assert_true(q.disp.xyz[2] == xyz[3 * off + 2]);
        df_msg_progress_free(&q);
        assert_null(q.disp.xyz);
    }
    df_buf_free(&b);
}

static const char *meshes_dir(void)
{
    const char *m = getenv("MESHES");
    return m && *m ? m : "../shared/meshes";
}

static void test_get_mesh_reassembly_of_real_mesh(void **state)
{
    (void)state;
    char path[1024];
    snprintf(path, sizeof path, "%s/bunny.mesh", meshes_dir());
    FILE *f = fopen(path, "rb");
    if (!f)
        unit_skip("%s not found (set MESHES to the shared meshes folder)", path);
    fclose(f);
    df_mesh mesh;
    df_mesh_init(&mesh);
    df_error e;
    assert_int_equal(df_mesh_read_file(path, NULL, &mesh, NULL, &e), DF_OK);
    assert_int_equal(mesh.kind, DF_MESH_TET);
    assert_int_equal(mesh.nv, 5433);
    assert_int_equal(mesh.ne, 34055);
    size_t nvf = 3 * (size_t)mesh.nv;
    float *pos = malloc(sizeof(float) * nvf);
    for (size_t i = 0; i < nvf; i++)
        pos[i] = (float)mesh.V[i];
    /* writer: POSITIONS then ELEMENTS in 4 KiB chunks */
    df_buf wire;
    df_buf_init(&wire);
    const size_t max_payload = 4096;
    for (int sec = 0; sec < 2; sec++) {
        uint32_t rows = sec ? (uint32_t)mesh.ne : (uint32_t)mesh.nv;
        uint32_t per = (uint32_t)((max_payload - 40) / (sec ? 16 : 12));
        for (uint32_t off = 0; off < rows; off += per) {
            uint32_t cnt = rows - off < per ? rows - off : per;
            df_msg_mesh_chunk c = {1, 0, DF_MESH_TET, 0,
                                   sec ? DF_SECTION_ELEMENTS : DF_SECTION_POSITIONS,
                                   (uint32_t)mesh.nv, (uint32_t)mesh.ne, 0, off, cnt,
                                   sec ? NULL : pos + 3 * (size_t)off,
                                   sec ? mesh.E + 4 * (size_t)off : NULL};
            int last = sec == 1 && off + cnt == rows;
            size_t start;
            assert_int_equal(df_frame_begin(&wire, DF_MSG_GET_MESH,
                                            DF_FLAG_REPLY | (last ? 0 : DF_FLAG_MORE), 5, &start,
                                            &e), DF_OK);
            assert_int_equal(df_msg_mesh_chunk_encode(&c, &wire, &e), DF_OK);
            assert_int_equal(df_frame_end(&wire, start, &e), DF_OK);
        }
    }
    /* reader */
    float *rpos = calloc(nvf, sizeof(float));
    int32_t *relem = calloc(4 * (size_t)mesh.ne, sizeof(int32_t));
    size_t pos_i = 0, frames = 0;
    int done = 0;
    while (pos_i < wire.len) {
        df_frame_header h;
        assert_int_equal(df_frame_header_decode(wire.data + pos_i, wire.len - pos_i, &h, &e), DF_OK);
        assert_true(h.request_id == 5);
        df_msg_mesh_chunk c;
        assert_int_equal(df_msg_mesh_chunk_decode(wire.data + pos_i + 24, h.payload_len, &c, &e),
                         DF_OK);
        if (c.section == DF_SECTION_POSITIONS)
            memcpy(rpos + 3 * (size_t)c.offset, c.xyz, 12 * (size_t)c.count);
        else
            memcpy(relem + 4 * (size_t)c.offset, c.idx, 16 * (size_t)c.count);
        done = !(h.flags & DF_FLAG_MORE);
        df_msg_mesh_chunk_free(&c);
        pos_i += 24 + h.payload_len;
        frames++;
    }
    assert_true(done);
    printf("bunny.mesh: %d v / %d tets in %zu frames of <= %zu bytes\n", mesh.nv, mesh.ne, frames,
           max_payload);
    assert_memory_equal(rpos, pos, sizeof(float) * nvf);
    assert_memory_equal(relem, mesh.E, sizeof(int32_t) * 4 * (size_t)mesh.ne);
    free(rpos);
    free(relem);
    free(pos);
    df_buf_free(&wire);
    df_mesh_free(&mesh);
}

/* A 1M-vertex dense frame encodes and decodes exactly (its speed: tests/bench/bench_server.c). */
static void test_dense_1m_encode_decode(void **state)
{
    (void)state;
    const uint32_t nv = 1000000;
    float *u = malloc(sizeof(float) * 3 * nv);
    assert_non_null(u);
    for (uint32_t i = 0; i < 3 * nv; i++)
        u[i] = (float)(i % 1000) * 1e-3f;
    df_msg_disp d = {1, 2, 1, DF_CHANGE_BRUSH, DF_DISP_DENSE, nv, nv, 0, nv, NULL, u};
    df_buf b;
    df_buf_init(&b);
    df_error e;
    assert_int_equal(df_msg_disp_encode(&d, &b, &e), DF_OK);
    assert_int_equal(b.len, 44 + 12 * (size_t)nv);
    df_msg_disp q;
    assert_int_equal(df_msg_disp_decode(b.data, b.len, &q, &e), DF_OK);
    assert_memory_equal(q.xyz, u, sizeof(float) * 3 * nv);
    df_msg_disp_free(&q);
    df_buf_free(&b);
    free(u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stream_reassembly_with_partial_reads),
        cmocka_unit_test(test_chunk_helpers),
        cmocka_unit_test(test_progress_chunks),
        cmocka_unit_test(test_get_mesh_reassembly_of_real_mesh),
        cmocka_unit_test(test_dense_1m_encode_decode),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
